"""Call overhead of the Python interface: a 2000-cell fp_stationary.

Times the call from Python (``irtp.fp_stationary`` and the bare
``irtp._irtp.run``) against the time the Rust solver itself reports
(``summary["wall_time_s"]``, measured inside Rust around the solve, as the
CLI reports it), and, when the CLI binary is found, the CLI's own
``wall_time_s``. The target: Python within 1 ms of Rust.

    python python/bench_overhead.py [--repeat 200] [--cells 2000]

Not a unit test (timings depend on the machine); prints medians in ms.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import time

# Run as `python python/bench_overhead.py`, Python puts python/ first on
# sys.path, where the source tree's irtp/ (without the compiled extension)
# would shadow the installed package.
_HERE = pathlib.Path(__file__).resolve().parent
sys.path[:] = [p for p in sys.path if pathlib.Path(p or ".").resolve() != _HERE]

import irtp  # noqa: E402
from irtp import _irtp  # noqa: E402


def median_ms(xs):
    return 1e3 * statistics.median(xs)


def time_calls(call, repeat):
    """(wall time of each call from Python, wall_time_s Rust reported)."""
    outer, inner = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        summary = call()
        outer.append(time.perf_counter() - t0)
        inner.append(summary["wall_time_s"])
    return outer, inner


def cli_wall(cells, repeat):
    root = pathlib.Path(__file__).resolve().parents[1]
    path = pathlib.Path(os.environ.get("IRTP_BIN") or root / "target" / "release" / "irtp")
    if not path.exists():
        return None
    argv = [str(path), "fp", "stationary", "--cells", str(cells), "--json"]
    return [json.loads(subprocess.run(argv, capture_output=True, text=True, check=True).stdout)
            ["wall_time_s"] for _ in range(repeat)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=200)
    ap.add_argument("--cells", type=int, default=2000)
    args = ap.parse_args()
    cells, repeat = args.cells, args.repeat

    for _ in range(10):  # warm up: caches, thread pool, first-call costs
        irtp.fp_stationary(cells=cells)
    public_outer, public_inner = time_calls(
        lambda: irtp.fp_stationary(cells=cells).summary, repeat)
    raw_outer, raw_inner = time_calls(
        lambda: _irtp.run("fp stationary", {"cells": cells})["summary"], repeat)
    cli = cli_wall(cells, min(repeat, 50))

    rust = median_ms(public_inner + raw_inner)
    print(f"fp_stationary, {cells} cells, {repeat} calls each (medians)")
    print(f"  Rust solve (summary wall_time_s):     {rust:8.3f} ms")
    if cli is not None:
        print(f"  CLI solve (its wall_time_s):          {median_ms(cli):8.3f} ms")
    print(f"  Python irtp.fp_stationary(...):       {median_ms(public_outer):8.3f} ms")
    print(f"  Python _irtp.run(...):                {median_ms(raw_outer):8.3f} ms")
    diff_public = median_ms([o - i for o, i in zip(public_outer, public_inner)])
    diff_raw = median_ms([o - i for o, i in zip(raw_outer, raw_inner)])
    print(f"  overhead, irtp.fp_stationary:         {diff_public:8.3f} ms")
    print(f"  overhead, _irtp.run:                  {diff_raw:8.3f} ms")
    verdict = "within" if diff_public <= 1.0 else "NOT within"
    print(f"  -> Python is {verdict} 1 ms of Rust")


if __name__ == "__main__":
    main()
