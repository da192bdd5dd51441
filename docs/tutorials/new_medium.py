"""Tutorial 7: a new medium without writing Rust: the drag law
g(v) = sinh(v) typed as an expression.

irtp differentiates the expression, checks that it is odd and increasing,
and runs every method on it. The exact r = 0 density (quadrature of the
closed form for any drag) is the reference for the sampler; with
resetting the Fokker-Planck solver and the sampler must agree.
"""

import matplotlib.pyplot as plt
import numpy as np
from tutorial import run_out, save, table

model = ["--drag", "expr:sinh(v)", "--sigma", 3, "--lambda", 0.5]
fig, ax = plt.subplots(figsize=(6.5, 4.2))
d, res = run_out("analytic", *model)
exact = table(f"{d}/density.csv")
v_u = np.arcsinh(3.0)
ax.plot(exact["v"], exact["p"], "k-", label=f"r = 0: exact density (regime {res['regime']})")
top = exact["p"][np.abs(exact["v"]) < 0.85 * v_u].max()
for rate, colour in [(0, "k"), (2, "C3")]:
    if rate:
        d, _ = run_out("fp", "stationary", *model, "--rate", rate, "--cells", 2000)
        dens = table(f"{d}/density.csv")
        ax.plot(dens["v"], dens["p"], "-", color=colour, label=f"r = {rate}: Fokker-Planck")
        top = max(top, dens["p"][np.abs(dens["v"]) < 0.85 * v_u].max())
    d, _ = run_out("simulate", *model, "--rate", rate, "--particles", 20000, "--seed", 1)
    sim = table(f"{d}/density.csv")
    ax.errorbar(sim["v"], sim["p"], yerr=sim["p_err"], fmt="o", ms=3, color=colour,
                label=f"r = {rate}: exact sampler")
ax.set_ylim(0, 1.3 * top)
ax.set_xlabel("v")
ax.set_ylabel("$P_s(v)$")
ax.set_title("the medium g(v) = sinh(v), $\\Sigma$ = 3, $\\lambda$ = 0.5")
ax.legend(fontsize=7)
save(fig, "new_medium")
