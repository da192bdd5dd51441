"""Tutorial 6: a sweep run, loaded as an xarray Dataset over its axes.

The plan examples/sweeps/fp_stationary.toml crosses Sigma (3 values) with
r (5, log-spaced) and zips lambda with v_r (2 pairs): 30 points. The
sweep's results.csv becomes a Dataset with pandas and xarray alone (what
irtp.load_sweep does, with the Python package installed, adding units
and provenance). Dotted: the r^-2 law through each curve's last point.
"""

import os
import subprocess
import tempfile

import matplotlib.pyplot as plt
import pandas as pd
from tutorial import BIN, save

out = os.path.join(tempfile.mkdtemp(prefix="irtp-docs-"), "sweep")
subprocess.run([BIN, "sweep", "run", "examples/sweeps/fp_stationary.toml", "--out", out],
               check=True, capture_output=True)
table = pd.read_csv(os.path.join(out, "results.csv"))
ds = table.set_index(["sigma", "rate", "lambda"])[["result.d_eff", "result.v2"]].to_xarray()
print(ds)

fig, axes = plt.subplots(1, 2, figsize=(9, 3.8), sharey=True)
for ax, lam in zip(axes, ds["lambda"].values):
    for sigma in ds["sigma"].values:
        d = ds["result.d_eff"].sel(sigma=sigma, **{"lambda": lam})
        line, = ax.plot(d["rate"], d, "o-", label=f"$\\Sigma$ = {sigma:g}")
        r = d["rate"].values[d["rate"].values >= 1]
        ax.plot(r, d.values[-1] * (r / r[-1]) ** -2.0, ":", color=line.get_color())
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("resetting rate r")
    ax.set_title(f"tan drag, $\\lambda$ = {lam:g}")
axes[0].set_ylabel("$D_{eff}$ (Fokker-Planck, from the sweep)")
axes[0].legend(fontsize=7)
save(fig, "sweep_xarray")
