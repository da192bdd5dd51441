"""Tutorial 4: the search, first passage in position x0 = 0 -> x = 1 (tan
drag, Sigma = 3, lambda = 0.5, v0 = 0).

(a) Full resetting (v -> 0 and x -> 0 at rate r): the mean search time
from the 2-D backward equation (a coarse mesh here, its Richardson error
estimate shaded) against the exact event-driven sampler.
(b) Velocity-only resetting (x kept): the mean is infinite; the sampler's
Kaplan-Meier survival S(t) decays as the power law t^-theta it reports.
"""

import matplotlib.pyplot as plt
import numpy as np
from tutorial import run, run_out, save, table

model = ["--drag", "tan", "--sigma", 3, "--lambda", 0.5, "--xt", 1, "--v0", 0]
# a coarse mesh (seconds); its Richardson error estimate is drawn with it
mesh = ["--cells-x", 16, "--cells-v", 8]
fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.8))

d, _ = run_out("mfpt", "scan", *model, "--reset-position", 0, *mesh, "--over", "rate",
               "--from", 0.1, "--to", 3, "--points", 11, "--log")
scan = table(f"{d}/mfpt_scan.csv")
a.plot(scan["rate"], scan["tau"], "C3-", label="2-D backward equation")
a.fill_between(scan["rate"], scan["tau"] - scan["error_estimate"],
               scan["tau"] + scan["error_estimate"], color="C3", alpha=0.2,
               label="its error estimate")
# (the sampler pays for tau ~ e^{rT} at large r: r = 8 costs a minute)
for rate in [0.1, 0.5, 2]:
    s = run("mfpt", *model, "--reset-position", 0, "--rate", rate, "--method", "exact",
            "--particles", 20000, "--seed", 1)
    a.errorbar(rate, s["tau"], yerr=s["tau_err"], fmt="ko", mfc="none",
               label="exact sampler" if rate == 0.1 else None)
# (a 32 x 16 mesh gives the same r* to 1e-3, in half a minute)
opt = run("mfpt", "optimize", *model, "--reset-position", 0, *mesh, "--r-min", 0.05, "--r-max", 5)
a.plot(opt["r_opt"], opt["tau_opt"], "C3*", ms=12, label=f"r* = {opt['r_opt']:.2f}")
a.set_xscale("log")
a.set_yscale("log")
a.set_xlabel("resetting rate r")
a.set_ylabel("mean search time $\\tau$")
a.set_title("(a) full resetting: x and v reset")
a.legend(fontsize=7)

d, s = run_out("mfpt", *model, "--method", "exact", "--t-max", 100, "--seed", 1)
surv = table(f"{d}/survival.csv")
keep = surv["t"] > 0
b.plot(surv["t"][keep], surv["survival"][keep], "k.", ms=4, label="exact sampler: S(t)")
theta, fit = s["tail_exponent"]["theta"], s["tail_exponent"]
t = np.logspace(np.log10(fit["t_from"]), np.log10(fit["t_to"]), 20)
anchor = np.interp(fit["t_from"], surv["t"], surv["survival"])
b.plot(t, anchor * (t / fit["t_from"]) ** -theta, "C0-",
       label=f"$t^{{-\\theta}}$, $\\theta$ = {theta:.3f} $\\pm$ {fit['theta_err']:.3f}")
b.set_xscale("log")
b.set_yscale("log")
b.set_xlabel("t")
b.set_ylabel("survival S(t)")
b.set_title("(b) velocity-only resetting, r = 2: infinite mean")
b.legend(fontsize=7)
save(fig, "search")
