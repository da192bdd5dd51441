"""What the tutorial scripts share: run the `irtp` binary, read its CSV
files, save the figure.

The binary is $IRTP_BIN (default target/debug/irtp, run from the
repository root); the figure goes to $IRTP_DOCS_FIGURES (default the
current directory). Every run writes into a temporary directory.
"""

import csv
import json
import os
import subprocess
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

BIN = os.environ.get("IRTP_BIN", "target/debug/irtp")
FIGURES = os.environ.get("IRTP_DOCS_FIGURES", ".")
_WORK = tempfile.mkdtemp(prefix="irtp-docs-")


def run(*args):
    """Run `irtp ARGS --json`; the `results` object of its summary."""
    out = subprocess.run([BIN, *map(str, args), "--json"], capture_output=True, text=True)
    if out.returncode != 0:
        raise SystemExit(f"irtp {' '.join(map(str, args))}: exit {out.returncode}: {out.stderr}")
    return json.loads(out.stdout)["results"]


def run_out(*args):
    """Run `irtp ARGS --out DIR` into a fresh directory; (DIR, results)."""
    d = tempfile.mkdtemp(dir=_WORK)
    os.rmdir(d)
    res = run(*args, "--out", d)
    return d, res


def table(path):
    """A CSV file irtp wrote, as a dict of float arrays by column."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    cols = {}
    for key in rows[0]:
        try:
            cols[key] = np.array([float(r[key]) if r[key] != "" else np.nan for r in rows])
        except ValueError:
            cols[key] = [r[key] for r in rows]
    return cols


def save(fig, name):
    """Write the figure as FIGURES/NAME.png and say where."""
    os.makedirs(FIGURES, exist_ok=True)
    path = os.path.join(FIGURES, f"{name}.png")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print(f"{name}: {path}")
