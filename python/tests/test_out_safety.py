"""No writer loses data: ``irtp sweep collect`` / ``python -m irtp collect``
/ ``irtp.collect`` (every format) and ``irtp plot`` write only a new path or
their own earlier output, never into a sweep or any of its parts, and a
refusal is one line naming the argument (exit 2) with nothing written or
removed; ``irtp.load`` / ``irtp.load_sweep`` answer or raise a one-line
ValueError / FileNotFoundError.

The fuzz test draws (fixed seed) commands over input directories and output
paths (the sweep itself, its parts, another sweep, the user's files and
directories, missing parents, a read-only directory, new paths) and checks
each against a snapshot of the whole tree taken before it.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import os
import pathlib
import random
import shutil
import stat
import sys
import time
from typing import Dict, List, Optional, Tuple

import pytest

import irtp
from irtp.__main__ import main as module_main

xr = pytest.importorskip("xarray")

PLAN = """\
command = "fp stationary"

[fixed]
cells = 40

[axes]
sigma = [2.0, 3.0]
rate = [0.5, 1.0]
"""

Snapshot = Dict[str, Tuple[str, str]]


def snapshot(root: pathlib.Path) -> Snapshot:
    """Every entry under ``root``: kind and content hash (files), target (links)."""
    out: Snapshot = {}
    for p in sorted(root.rglob("*")):
        rel = str(p.relative_to(root))
        if p.is_symlink():
            out[rel] = ("link", os.readlink(p))
        elif p.is_dir():
            out[rel] = ("dir", "")
        else:
            out[rel] = ("file", hashlib.sha256(p.read_bytes()).hexdigest())
    return out


@pytest.fixture(scope="module")
def tree(cli, tmp_path_factory) -> pathlib.Path:
    """A finished sweep, a second sweep, and the user's own files."""
    root = tmp_path_factory.mktemp("safety")
    (root / "plan.toml").write_text(PLAN)
    cli.run(["sweep", "run", str(root / "plan.toml"), "--out", str(root / "sw")])
    shutil.copytree(root / "sw", root / "other")
    (root / "user" / "sub").mkdir(parents=True)
    (root / "user" / "a.txt").write_text("the user's")
    (root / "user" / "sub" / "b.txt").write_text("the user's too")
    (root / "user.nc").write_text("not a dataset")
    (root / "user.png").write_bytes(b"\x89PNG not irtp's")
    (root / "empty").mkdir()
    (root / "notsweep").mkdir()
    (root / "notsweep" / "notes.txt").write_text("notes")
    (root / "ro").mkdir()
    (root / "ro").chmod(stat.S_IRUSR | stat.S_IXUSR)
    return root


def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert len(lines[0]) < 400, lines[0]
    return lines[0]


def test_collect_refusals_name_out_and_keep_the_sweep(tree, cli):
    """The reported cases: --out equal to the sweep, its workspace, a
    user's directory, a missing parent."""
    sw = tree / "sw"
    before = snapshot(tree)
    cases = [(sw, "zarr"), (sw / "workspace", "zarr"), (sw / "x.nc", "netcdf"),
             (tree / "user", "csv"), (tree / "missing" / "dir" / "x.nc", "netcdf"),
             (tree, "zarr")]
    for out, fmt in cases:
        p = cli.run(["sweep", "collect", str(sw), "--format", fmt, "--out", str(out),
                     "--python", sys.executable], check=False)
        line = one_line(p.stderr)
        assert p.returncode == 2 and "invalid --out" in line, (out, p.stderr)
        with pytest.raises(irtp._sweep.OutError, match="invalid out"):
            irtp.collect(sw, out, format=fmt)
    assert snapshot(tree) == before
    p = cli.run(["sweep", "status", str(sw)])
    assert "complete" in p.stdout


def test_load_sweep_of_a_directory_that_is_no_sweep(tree):
    with pytest.raises(ValueError, match="sweep.json, plan.toml and workspace"):
        irtp.load_sweep(tree / "notsweep")
    with pytest.raises(FileNotFoundError, match="no such directory"):
        irtp.load_sweep(tree / "missing")
    with pytest.raises(ValueError, match="load_sweep"):
        irtp.load(tree / "sw")


def test_an_earlier_export_is_replaced_whole(tree, tmp_path):
    for fmt, name in (("netcdf", "s.nc"), ("zarr", "s.zarr"), ("csv", "s")):
        out = tmp_path / name
        irtp.collect(tree / "sw", out, format=fmt)
        first = snapshot(tmp_path)
        irtp.collect(tree / "sw", out, format=fmt)
        assert sorted(snapshot(tmp_path)) == sorted(first), fmt  # no leftovers
    (tmp_path / "s" / "mine.txt").write_text("kept")
    with pytest.raises(ValueError, match="invalid out"):
        irtp.collect(tree / "sw", tmp_path / "s", format="csv")
    assert (tmp_path / "s" / "mine.txt").read_text() == "kept"


def out_paths(tree: pathlib.Path, rng: random.Random) -> List[pathlib.Path]:
    """Output paths of every kind the fuzz test draws from."""
    sw = tree / "sw"
    point = sorted((sw / "workspace").iterdir())[0]
    fresh = f"new{rng.randrange(10**6)}"
    return [sw, sw / "x.nc", sw / "workspace", point, point / "x.png", sw / "runs" / "x",
            sw / ".signac", tree / "other" / "y.zarr", tree / "user", tree / "user" / "a.txt",
            tree / "user" / "n.nc", tree / "user.nc", tree / "user.png", tree / "empty",
            tree / "ro" / "x.nc", tree / "missing" / "x.nc", tree, tree / "notsweep",
            tree / f"{fresh}.nc", tree / f"{fresh}.zarr", tree / f"{fresh}.png",
            tree / f"{fresh}.svg", tree / fresh]


def run_module(argv: List[str]) -> Tuple[int, str]:
    """``python -m irtp`` in this process: (exit code, stderr)."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code = module_main(argv)
        except SystemExit as e:  # argparse
            code = int(e.code or 0)
    return code, err.getvalue()


def verify_collect(sweep: pathlib.Path, out: pathlib.Path, fmt: str) -> None:
    """A written export holds the sweep's Dataset."""
    ds = irtp.load_sweep(sweep)
    if fmt == "csv":
        assert (out / "attrs.json").is_file() and (out / "scalars.csv").is_file()
        return
    opened = xr.open_dataset(out) if fmt == "netcdf" else xr.open_zarr(out)
    with opened as back:
        xr.testing.assert_identical(back.load(), ds)


def check(before: Snapshot, after: Snapshot, tree: pathlib.Path, code: int, err: str,
          out: pathlib.Path, names: Tuple[str, ...]) -> None:
    """A refusal changed nothing and is one line naming an argument; a
    success changed only ``out``."""
    assert not [k for k in after if ".partial-" in k or ".old-" in k], after
    if code != 0:
        line = one_line(err)
        assert code == 2, (code, err)
        assert any(n in line for n in names), line
        assert after == before, line
        return
    rel = str(out.relative_to(tree))
    changed = {k for k in set(before) | set(after) if before.get(k) != after.get(k)}
    assert all(k == rel or k.startswith(rel + os.sep) for k in changed), (rel, changed)
    assert all(k in after for k in before if not k.startswith(rel + os.sep)), rel


def test_fuzz_writers_and_readers(tree, cli):
    rng = random.Random(20261206)
    inputs = [tree / "sw", tree / "sw" / "workspace", tree / "missing", tree / "notsweep",
              tree / "user", tree / "other"]
    names = ("--out", "sweep.json", "sweep directory", "DIR", "--var", "no such directory")
    t0 = time.monotonic()
    binary_runs = 0
    outcomes: Dict[Tuple[str, int], int] = {}
    for case in range(90):
        # Half the draws name the sweep and a new path: the answers that write.
        paths = out_paths(tree, rng)
        good = rng.random() < 0.5
        src = inputs[0] if good else rng.choice(inputs)
        out = rng.choice(paths[-5:] if good else paths)
        before = snapshot(tree)
        kind = rng.choice(["module", "module", "plot", "binary", "load"])
        if kind == "binary" and binary_runs >= 8:
            kind = "module"
        fmt = rng.choice(["netcdf", "zarr", "csv"])
        if kind in ("module", "binary"):
            argv = ["collect", str(src), "--format", fmt, "--out", str(out)]
            if kind == "module":
                code, err = run_module(argv)
            else:
                binary_runs += 1
                p = cli.run(["sweep", *argv, "--python", sys.executable], check=False)
                code, err = p.returncode, p.stderr
        elif kind == "plot":
            var: Optional[str] = rng.choice([None, "d_eff", "status", "nope", "sigma"])
            p = cli.run(["plot", str(src), "--out", str(out), *(["--var", var] if var else [])],
                        check=False)
            code, err = p.returncode, p.stderr
        else:
            loader = rng.choice([irtp.load, irtp.load_sweep])
            try:
                loader(src)
                code, err = 0, ""
            except (ValueError, FileNotFoundError) as e:
                code, err = 2, str(e)
            out = src
        after = snapshot(tree)
        outcomes[kind, code] = outcomes.get((kind, code), 0) + 1
        check(before, after, tree, code, err, out, names)
        if code == 0 and kind in ("module", "binary"):
            verify_collect(src, out, fmt)
        if code == 0 and kind == "plot":
            assert b"irtp plot" in out.read_bytes()
        assert kind == "load" or out.resolve() != (tree / "sw").resolve() or code != 0
    p = cli.run(["sweep", "status", str(tree / "sw")])
    assert "complete" in p.stdout, p.stdout
    # The draw reaches both answers of every kind.
    assert all(outcomes.get((k, c)) for k in ("module", "plot", "load") for c in (0, 2)), outcomes
    assert time.monotonic() - t0 < 60
