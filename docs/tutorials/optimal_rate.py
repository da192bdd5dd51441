"""Tutorial 3: the optimal resetting rate of the velocity first passage
v0 = -0.249 -> vt = 0.5 (Fig. 7), in tan (shear-thickening) and tanh
(shear-thinning) drag.

Lines: the backward equations (exact up to a Richardson error estimate of
~1e-10). Points: the exact event-driven first-passage sampler. The dashed
tangent at r = 0 has the slope dtau/dr(0) that `mfpt optimize` reports: a
negative slope is the mark that a little resetting helps.
"""

import matplotlib.pyplot as plt
import numpy as np
from tutorial import run, run_out, save, table

problem = ["--v0", -0.249, "--vt", 0.5, "--reset-velocity", 0]
# (medium, its flags, the rates of the sampler's points: tanh's tau grows
# like e^{rT} and costs the sampler that much more)
media = [
    ("tan, $\\Sigma$ = 3", ["--drag", "tan", "--sigma", 3, "--lambda", 0.5], [0.5, 2, 6]),
    ("tanh, $\\Sigma$ = 0.6", ["--drag", "tanh", "--sigma", 0.6, "--lambda", 0.5], [0.5, 2]),
]
fig, ax = plt.subplots(figsize=(6.5, 4.2))
for (name, model, points), colour in zip(media, ["C3", "C0"]):
    d, _ = run_out("mfpt", "scan", *model, *problem, "--over", "rate",
                   "--from", 0, "--to", 8, "--points", 81)
    scan = table(f"{d}/mfpt_scan.csv")
    opt = run("mfpt", "optimize", *model, *problem)
    tau0 = opt["tau_r0"]
    ax.plot(scan["rate"], scan["tau"] / tau0, "-", color=colour, label=f"{name}: backward equations")
    r = np.linspace(0, 3, 10)
    ax.plot(r, 1 + r * opt["dtau_dr_r0"] / tau0, "--", color=colour, lw=0.8,
            label=f"{name}: slope at r = 0: {opt['dtau_dr_r0']:.3f}")
    if opt["interior"]:
        ax.plot(opt["r_opt"], opt["tau_opt"] / tau0, "*", ms=12, color=colour,
                label=f"{name}: r* = {opt['r_opt']:.3f}, $\\tau^*/\\tau_0$ = {opt['tau_opt'] / tau0:.3f}")
    for rate in points:
        s = run("mfpt", *model, *problem, "--rate", rate, "--method", "exact",
                "--particles", 20000, "--seed", 1)
        ax.errorbar(rate, s["tau"] / tau0, yerr=s["tau_err"] / tau0, fmt="o", color=colour,
                    mfc="none", label=f"{name}: exact sampler" if rate == 0.5 else None)
ax.set_xlim(0, 8)
ax.set_ylim(0.7, 1.6)
ax.axhline(1, color="grey", lw=0.5)
ax.set_xlabel("resetting rate r")
ax.set_ylabel("$\\tau(r) / \\tau(0)$")
ax.set_title("mean first-passage time $v_0$ = -0.249 $\\to$ $v_t$ = 0.5, $\\lambda$ = 0.5")
ax.legend(fontsize=7)
save(fig, "optimal_rate")
