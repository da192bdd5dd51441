"""Tutorial 1: the stationary velocity density P_s(v) of tan drag (Fig. 2).

The exact r = 0 density (irtp analytic) is the reference; the exact
sampler's histogram at r = 0 must lie on it. With resetting to v_r = 0 the
Fokker-Planck density (lines) and the sampler (points) grow a cusp at v_r.
"""

import matplotlib.pyplot as plt
import numpy as np
from tutorial import run_out, save, table

SIGMA, LAMBDA, PARTICLES = 3, 0.5, 20000
model = ["--drag", "tan", "--sigma", SIGMA, "--lambda", LAMBDA]
v_u = np.arctan(SIGMA)

fig, ax = plt.subplots(figsize=(7, 4.2))
d, res = run_out("analytic", *model)
exact = table(f"{d}/density.csv")
ax.plot(exact["v"], exact["p"], "k-", lw=1.5, label=f"r = 0: exact density (regime {res['regime']})")
bulk = np.abs(exact["v"]) < 0.85 * v_u
top = exact["p"][bulk].max()
for rate, colour in [(0, "k"), (0.5, "C0"), (2, "C3")]:
    if rate > 0:
        d, fp = run_out("fp", "stationary", *model, "--rate", rate, "--cells", 2000)
        dens = table(f"{d}/density.csv")
        ax.plot(dens["v"], dens["p"], "-", color=colour, label=f"r = {rate}: Fokker-Planck")
        top = max(top, dens["p"][np.abs(dens["v"]) < 0.85 * v_u].max())
    d, _ = run_out("simulate", *model, "--rate", rate, "--particles", PARTICLES, "--seed", 1)
    sim = table(f"{d}/density.csv")
    ax.errorbar(sim["v"], sim["p"], yerr=sim["p_err"], fmt="o", ms=3, color=colour,
                label=f"r = {rate}: exact sampler, {PARTICLES} particles")
ax.set_ylim(0, 1.3 * top)
ax.set_xlabel("v")
ax.set_ylabel("$P_s(v)$")
ax.set_title(f"tan drag, $\\Sigma$ = {SIGMA}, $\\lambda$ = {LAMBDA}, reset to $v_r$ = 0")
ax.legend(fontsize=7)
save(fig, "fig2")
