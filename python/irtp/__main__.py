"""``python -m irtp collect DIR --format netcdf|zarr|csv --out FILE``: a sweep
directory as one dataset file (the Rust CLI writes CSV and JSON only; netCDF
and zarr are written by the libraries of the Python ecosystem, xarray with
h5netcdf and zarr).

Exit codes as ``irtp sweep merge``: 0 when every point is finished, 3 when
points are missing, failed or damaged (the file is written all the same,
with NaN there and the points listed in its attributes), 2 for bad input
(one line; nothing written): a directory that is not a sweep, or an
``--out`` that is not new nor an earlier export of this format, that lies
in a sweep directory or contains this one, or whose directory is missing or
not writable (``irtp.collect``'s rules).
"""

from __future__ import annotations

import argparse
import sys
from typing import List, Optional

from ._sweep import FORMATS, OutError, load_sweep, write


def parser() -> argparse.ArgumentParser:
    """The command line: one subcommand, ``collect``."""
    p = argparse.ArgumentParser(prog="python -m irtp",
                                description="Tools of the irtp Python module.")
    sub = p.add_subparsers(dest="command", required=True)
    c = sub.add_parser("collect", help="a sweep directory as one netCDF, zarr or CSV dataset",
                       description="Stack every point of a sweep directory (irtp sweep run "
                                   "--out DIR) over the plan's axes and write it (irtp.collect).")
    c.add_argument("dir", help="the sweep directory")
    c.add_argument("--format", choices=FORMATS, default="netcdf",
                   help="netcdf (a .nc file), zarr (a store directory) or csv (a directory)")
    c.add_argument("--out", required=True, help="the file (netcdf) or directory (zarr, csv)")
    c.add_argument("--engine", choices=("h5netcdf", "netcdf4"), default=None,
                   help="netCDF engine (default: h5netcdf if installed, else netcdf4)")
    return p


def fail(message: str) -> int:
    """Print a refusal as one line; the exit code of bad input (2)."""
    print(f"python -m irtp: error: {message}", file=sys.stderr)
    return 2


def main(argv: Optional[List[str]] = None) -> int:
    """Run the command line; returns the exit code."""
    args = parser().parse_args(argv)
    try:
        ds = load_sweep(args.dir)
        written = write(ds, args.out, args.format, args.engine, sweep=args.dir)
    except OutError as e:
        return fail(e.cli())
    except (OSError, ValueError) as e:
        return fail(str(e).replace("\n", " "))
    print(f"wrote {written} ({ds.attrs['points']} points)")
    unfinished = {k: ds.attrs[f"{k}_count"] for k in ("missing", "failed", "damaged")}
    if any(unfinished.values()):
        counts = ", ".join(f"{n} {k}" for k, n in unfinished.items() if n)
        print(f"python -m irtp: {counts} (NaN in the dataset; listed in its attributes "
              "missing_points, failed_points, damaged_points)", file=sys.stderr)
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main())
