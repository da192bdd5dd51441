"""Tutorial 5: another active noise, run-pause-tumble (the force jumps
between +Sigma, 0 and -Sigma), in tan drag with resetting.

Lines: the Fokker-Planck density of the three coupled states (exact
D_eff and <v^2> from the generator). Points: the exact event-driven
sampler, whose flow reaches the pause's fixed point v = 0 exactly. Inset
numbers: the linear-drag closed form against the Fokker-Planck solver for
the same noise.
"""

import matplotlib.pyplot as plt
import numpy as np
from tutorial import run, run_out, save, table

noise = "rpt:sigma=3,alpha=1,beta=2"
fig, ax = plt.subplots(figsize=(6.5, 4.2))
top = 0
for rate, colour in [(0.2, "C0"), (1, "C3")]:
    model = ["--drag", "tan", "--noise", noise, "--rate", rate]
    d, fp = run_out("fp", "stationary", *model, "--cells", 2000)
    dens = table(f"{d}/density.csv")
    ax.plot(dens["v"], dens["p"], "-", color=colour, label=f"r = {rate}: Fokker-Planck")
    bulk = (np.abs(dens["v"]) > 0.05) & (np.abs(dens["v"]) < 0.85 * np.arctan(3))
    top = max(top, dens["p"][bulk].max())
    d, _ = run_out("simulate", *model, "--particles", 20000, "--seed", 1)
    sim = table(f"{d}/density.csv")
    ax.errorbar(sim["v"], sim["p"], yerr=sim["p_err"], fmt="o", ms=3, color=colour,
                label=f"r = {rate}: exact sampler")
ax.set_ylim(0, 1.6 * top)  # the pause piles up at v = 0: a spike off the frame
ax.set_xlabel("v")
ax.set_ylabel("$P_s(v)$")
ax.set_title(f"tan drag, run-pause-tumble noise {noise}")
lin = ["--drag", "linear", "--noise", "rpt:sigma=1,alpha=1,beta=2", "--rate", 1]
exact, fp = run("analytic", *lin), run("fp", "stationary", *lin)
ax.text(0.02, 0.02, f"linear drag, rpt:sigma=1, r = 1: <v²> exact {exact['v2']:.6f}, "
        f"Fokker-Planck {fp['v2']:.6f}", transform=ax.transAxes, fontsize=7)
ax.legend(fontsize=7, loc="upper center")
save(fig, "noise")
