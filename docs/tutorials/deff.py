"""Tutorial 2: the effective diffusion coefficient D_eff against the
resetting rate r, in a shear-thickening medium (tan) and a Newtonian one
(linear), and its r^-2 tail.

Linear drag has a closed form (irtp analytic, Eqs. (N3)-(N6)): the exact
line the Fokker-Planck points must lie on. For tan, the Fokker-Planck
D_eff (exact from the generator) is checked against the particles' MSD fit.
"""

import matplotlib.pyplot as plt
import numpy as np
from tutorial import run, save

rates = np.logspace(-1, 2, 13)
media = {
    "tan, $\\Sigma$ = 3": ["--drag", "tan", "--sigma", 3, "--lambda", 0.5],
    "linear, $\\Sigma$ = 1": ["--drag", "linear", "--sigma", 1, "--lambda", 0.5],
}
fig, ax = plt.subplots(figsize=(6.5, 4.2))
for (name, model), colour in zip(media.items(), ["C3", "C0"]):
    fp = [run("fp", "stationary", *model, "--rate", r, "--cells", 2000)["d_eff"] for r in rates]
    ax.plot(rates, fp, "o", color=colour, ms=4, label=f"{name}: Fokker-Planck")
    if "linear" in name:
        fine = np.logspace(-1, 2, 60)
        exact = [run("analytic", *model, "--rate", r)["d_eff"] for r in fine]
        ax.plot(fine, exact, "-", color=colour, label=f"{name}: closed form")
    else:
        for r in [0.3, 1, 3]:
            s = run("simulate", *model, "--rate", r, "--particles", 4000,
                    "--t-max", 200, "--burn-in", 50, "--seed", 1)
            ax.errorbar(r, s["d_eff_msd"], yerr=s["d_eff_msd_err"], fmt="s", mfc="none",
                        color=colour, label=f"{name}: particles (MSD fit)" if r == 0.3 else None)
    tail = fp[-1] * (rates / rates[-1]) ** -2.0
    ax.plot(rates[5:], tail[5:], ":", color="grey")
ax.plot([], [], ":", color="grey", label="$\\propto r^{-2}$")
ax.set_xscale("log")
ax.set_yscale("log")
ax.set_xlabel("resetting rate r")
ax.set_ylabel("$D_{eff}$")
ax.set_title("$D_{eff}(r)$, $\\lambda$ = 0.5, $v_r$ = 0")
ax.legend(fontsize=7)
save(fig, "deff")
