"""Labelled arrays: ``Result.to_xarray()``, ``irtp.load`` of CLI output
directories (the same Dataset as the in-process result, value for value),
``irtp.load_sweep`` of a sweep workspace (the per-point files stacked over
the plan's axes, bit for bit; missing, failed and damaged points NaN and
listed), and ``irtp.collect`` / ``python -m irtp collect`` (netCDF, zarr and
CSV files that reopen to the same values)."""

from __future__ import annotations

import json
import pathlib
import shutil
import subprocess
import sys

import numpy as np
import pytest

import irtp
from conftest import argv_for, read_csv, same_bits

xr = pytest.importorskip("xarray")

# (function, CLI command, keywords, the Dataset's dimensions): every command
# kind and method with a table layout of its own, tiny.
KINDS = [
    ("simulate", "simulate",
     dict(particles=200, t_max=3.0, samples=7, burn_in=1.0, bins=10, seed=4), {"t", "v"}),
    ("simulate", "simulate",
     dict(particles=100, t_max=2.0, samples=5, burn_in=1.0, bins=8, reset_position=0.0),
     {"t", "v", "x"}),
    ("analytic", "analytic", dict(drag="tanh", sigma=0.6, lambda_=1.2, points=33), {"v"}),
    ("fp_stationary", "fp stationary", dict(lambda_=0.9, rate=2.0, cells=200), {"v"}),
    ("fp_transient", "fp transient", dict(t_max=0.5, cells=64, samples=5, snapshots=3),
     {"t", "t_snapshot", "v"}),
    ("fp_msd", "fp msd",
     dict(drag="tanh", sigma=0.6, rate=1.0, t_min=0.5, t_max=2.0, samples=6, cells=32, levels=2),
     {"t"}),
    ("mfpt", "mfpt", dict(v0=-0.249, vt=0.5, cells=200), {"v0"}),
    ("mfpt", "mfpt", dict(v0=-0.249, vt=0.5, method="exact", particles=200, seed=5), {"t"}),
    ("mfpt_scan", "mfpt scan",
     dict(v0=-0.249, vt=0.5, over="rate", from_=0.1, to=10.0, points=4, log=True, cells=200),
     {"rate"}),
    ("mfpt_optimize", "mfpt optimize", dict(v0=-0.249, vt=0.5, cells=1000, grid_points=7),
     {"rate"}),
    ("mfpt_distribution", "mfpt distribution", dict(v0=-0.249, vt=0.5, cells=200, points=11),
     {"t"}),
    ("mfpt_distribution", "mfpt distribution",
     dict(v0=-0.249, vt=0.5, method="exact", particles=200), {"t_lo", "t"}),
]
IDS = [f"{fn}-{i}" for i, (fn, _, _, _) in enumerate(KINDS)]

# Attributes that time or place the run: they differ between two runs.
VOLATILE_ATTRS = ("wall_time_s", "particle_steps_per_s", "events_per_s", "out")


def same_values(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal bit for bit (floats, NaN matching NaN) or equal (others)."""
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype.kind in "OUT" and b.dtype.kind in "OUT":  # strings: files may change the dtype
        return a.shape == b.shape and [str(x) for x in a.ravel()] == [str(x) for x in b.ravel()]
    if a.dtype.kind == "f" or b.dtype.kind == "f":
        return a.dtype == b.dtype and same_bits(a, b)
    return a.shape == b.shape and a.dtype == b.dtype and bool(np.all(a == b))


def stable_attrs(attrs: dict) -> dict:
    """A Dataset's attributes but the provenance and the run's timing."""
    return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in attrs.items()
            if not k.startswith("provenance.") and k.split(".")[-1] not in VOLATILE_ATTRS}


def assert_same_dataset(a, b) -> None:
    """The same variables, coordinates, dims, variable attributes and values
    bit for bit, and the same attributes but the provenance."""
    assert list(a.data_vars) == list(b.data_vars)
    assert sorted(a.coords) == sorted(b.coords)
    assert dict(a.sizes) == dict(b.sizes)
    for name in [*a.coords, *a.data_vars]:
        assert a[name].dims == b[name].dims, name
        assert a[name].attrs == b[name].attrs, name
        assert same_values(a[name].values, b[name].values), name
    assert stable_attrs(a.attrs) == stable_attrs(b.attrs)


@pytest.mark.parametrize("function,command,kwargs,dims", KINDS, ids=IDS)
def test_load_of_cli_output_equals_the_in_process_result(cli, tmp_path, function, command,
                                                         kwargs, dims):
    res = getattr(irtp, function)(**kwargs)
    cli.run([*argv_for(command, kwargs), "--out", str(tmp_path / "cli")])
    loaded = irtp.load(tmp_path / "cli")
    assert type(loaded) is type(res)
    assert (loaded.command, loaded.method, loaded.seed) == (res.command, res.method, res.seed)
    assert list(loaded.tables) == list(res.tables)
    assert_same_dataset(loaded.to_xarray(), res.to_xarray())


@pytest.mark.parametrize("function,command,kwargs,dims", KINDS, ids=IDS)
def test_to_xarray_has_the_documented_dims_and_attributes(tmp_path, function, command,
                                                          kwargs, dims):
    res = getattr(irtp, function)(**kwargs)
    ds = res.to_xarray()
    assert set(ds.sizes) == dims
    assert (ds.attrs["command"], ds.attrs["method"]) == (command, res.method)
    assert "dimensionless" in ds.attrs["units"]
    assert any(k.startswith("param.") for k in ds.attrs)
    for name in [*ds.coords, *ds.data_vars]:
        attrs = ds[name].attrs
        assert attrs["units"] == "1" and attrs["long_name"] and attrs["symbol"], name
        if str(name).endswith("_err"):
            assert attrs["long_name"].startswith("standard error of "), name
    for table, columns in res.tables.items():
        if (command, table) == ("fp transient", "snapshots"):
            continue
        dim = next(iter(columns))
        assert any(same_values(ds[d].values, columns[dim]) for d in ds.sizes), (table, dim)
    ds.to_netcdf(tmp_path / "one.nc", engine="h5netcdf")
    with xr.open_dataset(tmp_path / "one.nc") as back:
        assert dict(back.sizes) == dict(ds.sizes)


def test_to_xarray_names_errors_summary_values_and_snapshots():
    sim = irtp.simulate(particles=200, t_max=3.0, samples=7, burn_in=1.0, bins=10)
    ds = sim.to_xarray()
    assert ds.v2.dims == ("t",) and ds.v2_err.dims == ("t",)
    assert same_bits(ds.v2_err.values, sim.tables["moments"]["v2_err"])
    assert ds.v2.attrs["symbol"] == "⟨v²⟩"
    assert float(ds.summary_v2) == sim.summary["v2"]  # the stationary value
    assert ds.p.dims == ("v",) and ds.p.attrs["symbol"] == "P(v)"

    m = irtp.mfpt(v0=-0.249, vt=0.5, cells=200)
    dm = m.to_xarray()
    assert float(dm.tau) == m.tau and dm.tau.dims == ()
    assert same_bits(dm.profile_tau.values, m.tables["profile"]["tau"])

    tr = irtp.fp_transient(t_max=0.5, cells=64, samples=5, snapshots=3)
    dt = tr.to_xarray()
    snap = tr.tables["snapshots"]
    n = dt.sizes["v"]
    assert dt.p.dims == ("t_snapshot", "v") and dt.sizes["t_snapshot"] == 3
    assert same_bits(dt.p.values.ravel(), snap["p"])
    assert same_bits(dt.t_snapshot.values, snap["t"][::n])
    assert same_bits(dt.v.values, snap["v"][:n])


def test_load_of_reproduce_and_out_directories(tmp_path):
    res = irtp.reproduce("fig2", quick=True, out=tmp_path / "r")
    loaded = irtp.load(tmp_path / "r")
    assert isinstance(loaded, irtp.ReproduceResult)
    assert loaded.summary["figures"] == res.summary["figures"] == ["fig2"]
    assert loaded.summary["claims"] == res.summary["claims"]
    assert json.loads(loaded.to_xarray().attrs["result.figures"]) == ["fig2"]

    fp = irtp.fp_stationary(cells=200, out=tmp_path / "fp")
    assert_same_dataset(irtp.load(fp.out).to_xarray(), fp.to_xarray())


def test_load_refuses_what_is_not_a_run(tmp_path):
    with pytest.raises(FileNotFoundError, match="run.json"):
        irtp.load(tmp_path)
    (tmp_path / "sweep.json").write_text("{}")
    with pytest.raises(ValueError, match="load_sweep"):
        irtp.load(tmp_path)


def test_missing_xarray_names_the_extra(monkeypatch):
    res = irtp.fp_stationary(cells=200)
    monkeypatch.setitem(sys.modules, "xarray", None)
    # The install command that works from the repository (the package is
    # on no index): pip install './python[xarray]'.
    with pytest.raises(ImportError, match=r"pip install '\./python\[xarray\]' in the irtp repository"):
        res.to_xarray()


# A 2 x 3 sweep: rate (a list) x lambda (a log range, expanded as the CLI does).
PLAN = """\
command = "fp stationary"

[fixed]
drag = "tan"
sigma = 3.0
cells = 40

[axes]
rate = [0.5, 2.0]
lambda = { from = 0.5, to = 1.5, points = 3, spacing = "log" }
"""


@pytest.fixture(scope="module")
def sweep(cli, tmp_path_factory) -> pathlib.Path:
    """A finished sweep directory (the CLI's)."""
    root = tmp_path_factory.mktemp("sweep")
    (root / "plan.toml").write_text(PLAN)
    cli.run(["sweep", "run", str(root / "plan.toml"), "--out", str(root / "sw")])
    return root / "sw"


def copy_of(sweep: pathlib.Path, tmp_path: pathlib.Path) -> pathlib.Path:
    """A copy of the sweep to damage."""
    return pathlib.Path(shutil.copytree(sweep, tmp_path / "sw"))


def points(sweep: pathlib.Path):
    """(rate, lambda, point directory) of every point."""
    for d in sorted((sweep / "workspace").iterdir()):
        params = json.loads((d / "signac_statepoint.json").read_text())["parameters"]
        yield params["rate"], params["lambda"], d


def test_load_sweep_stacks_the_points_bit_for_bit(sweep):
    ds = irtp.load_sweep(sweep)
    assert ds.p.dims == ("rate", "lambda", "v")
    assert ds.d_eff.dims == ("rate", "lambda")
    assert dict(ds.sizes) == {"rate": 2, "lambda": 3, "v": 40}
    assert ds.attrs["missing_count"] == ds.attrs["failed_count"] == 0
    seen = set()
    for rate, lam, d in points(sweep):
        at = dict(rate=list(ds.rate.values).index(rate), **{"lambda": list(ds["lambda"].values).index(lam)})
        seen.add((at["rate"], at["lambda"]))
        density = read_csv(d / "density.csv")
        for col in ("p", "p_plus", "p_minus", "dv"):
            assert same_bits(ds[col].isel(at).values, density[col]), (rate, lam, col)
        # The graded mesh depends on the model: each point's v is kept.
        assert same_bits(ds.v_grid.isel(at).values, density["v"])
        results = json.loads((d / "summary.json").read_text())["results"]
        for key in ("v2", "v_mean", "d_eff", "mass"):
            assert same_bits(ds[key].isel(at).values, np.array(results[key])), key
    assert len(seen) == 6
    table = read_csv_rows(sweep / "results.csv")
    for row in table:
        at = np.argwhere(ds.point.values == int(row["point"]))[0]
        assert float(ds.d_eff.values[tuple(at)]) == float(row["result.d_eff"])
        assert float(ds.rate.values[at[0]]) == float(row["rate"])


def read_csv_rows(path: pathlib.Path):
    """results.csv as dicts of strings."""
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    return [dict(zip(header, line.split(","))) for line in lines[1:]]


def test_missing_failed_and_damaged_points_are_nan_and_listed(sweep, tmp_path):
    sw = copy_of(sweep, tmp_path)
    dirs = {(rate, lam): d for rate, lam, d in points(sw)}
    (dirs[(0.5, 0.5)] / "result.json").unlink()              # killed before it finished
    shutil.rmtree(dirs[(2.0, 1.5)])                           # never started
    (dirs[(2.0, 0.5)] / "result.json").write_text(json.dumps(
        {"status": "failed", "error": "numerical failure (test)"}))
    with open(dirs[(0.5, 1.5)] / "density.csv", "a") as f:    # edited afterwards
        f.write("0,0,0,0,0\n")
    ds = irtp.load_sweep(sw)
    full = irtp.load_sweep(sweep)
    assert dict(ds.sizes) == dict(full.sizes)
    assert ds.attrs["missing_count"] == 2 and ds.attrs["failed_count"] == 1
    assert ds.attrs["damaged_count"] == 1
    missing = json.loads(ds.attrs["missing_points"])
    assert sorted((m["parameters"]["rate"], m["parameters"]["lambda"]) for m in missing) == [
        (0.5, 0.5), (2.0, 1.5)]
    failed = json.loads(ds.attrs["failed_points"])
    assert failed[0]["error"] == "numerical failure (test)" and failed[0]["parameters"] == {
        "rate": 2.0, "lambda": 0.5}
    assert "density.csv" in json.loads(ds.attrs["damaged_points"])[0]["error"]
    lambdas = list(ds["lambda"].values)
    for rate, lam in [(0.5, 0.5), (2.0, 1.5), (2.0, 0.5), (0.5, 1.5)]:
        at = {"rate": [0.5, 2.0].index(rate), "lambda": lambdas.index(lam)}
        assert np.isnan(ds.d_eff.isel(at).values) and np.all(np.isnan(ds.p.isel(at).values))
        assert ds.mesh.isel(at).values.item() == ""
    at = {"rate": 0, "lambda": 1}
    assert same_bits(ds.p.isel(at).values, full.p.isel(at).values)
    assert same_bits(ds.d_eff.isel(at).values, full.d_eff.isel(at).values)


def test_zipped_axes_are_one_dimension_and_ragged_tables_are_padded(cli, tmp_path):
    plan = tmp_path / "zip.toml"
    plan.write_text('command = "analytic"\n[fixed]\ndrag = "tanh"\n[axes]\n'
                    'sigma = [0.3, 0.6]\n[[zip]]\nlambda = [0.5, 1.0, 2.0]\n'
                    'points = [17, 33, 9]\n')
    cli.run(["sweep", "run", str(plan), "--out", str(tmp_path / "z")])
    ds = irtp.load_sweep(tmp_path / "z")
    assert ds.p.dims == ("sigma", "zip_0", "v") and ds.sizes["v"] == 33
    assert ds["lambda"].dims == ("zip_0",) and list(ds["lambda"].values) == [0.5, 1.0, 2.0]
    assert list(ds["points"].values) == [17, 33, 9]
    assert ds.regime.dims == ("sigma", "zip_0") and ds.regime.values.dtype == object
    for rate_dir in (tmp_path / "z" / "workspace").iterdir():
        params = json.loads((rate_dir / "signac_statepoint.json").read_text())["parameters"]
        at = {"sigma": [0.3, 0.6].index(params["sigma"]),
              "zip_0": [0.5, 1.0, 2.0].index(params["lambda"])}
        n = params["points"]
        density = read_csv(rate_dir / "density.csv")
        assert same_bits(ds.p.isel(at).values[:n], density["p"])
        assert np.all(np.isnan(ds.p.isel(at).values[n:]))
        assert same_bits(ds.v_grid.isel(at).values[:n], density["v"])


@pytest.mark.parametrize("fmt", ["netcdf", "zarr"])
def test_collect_files_reopen_to_the_same_values(sweep, tmp_path, fmt):
    sw = copy_of(sweep, tmp_path)
    shutil.rmtree(next(points(sw))[2])
    ds = irtp.load_sweep(sw)
    out = irtp.collect(sw, tmp_path / ("s.nc" if fmt == "netcdf" else "s.zarr"), format=fmt)
    opened = xr.open_dataset(out) if fmt == "netcdf" else xr.open_zarr(out)
    with opened as back:
        back = back.load()
    xr.testing.assert_identical(back, ds)
    for name in [*ds.coords, *ds.data_vars]:
        assert same_values(back[name].values, ds[name].values), name


def test_collect_csv_and_the_command_line(sweep, tmp_path):
    ds = irtp.load_sweep(sweep)
    out = irtp.collect(sweep, tmp_path / "csv", format="csv")
    assert sorted(p.name for p in out.iterdir()) == ["attrs.json", "scalars.csv", "v.csv"]
    scalars = read_csv_rows(out / "scalars.csv")
    assert len(scalars) == 6
    for row in scalars:
        at = {"rate": list(ds.rate.values).index(float(row["rate"])),
              "lambda": list(ds["lambda"].values).index(float(row["lambda"]))}
        assert float(row["d_eff"]) == float(ds.d_eff.isel(at))
    assert len(read_csv_rows(out / "v.csv")) == 6 * 40
    with pytest.raises(ValueError, match="format"):
        irtp.collect(sweep, tmp_path / "x", format="hdf")

    run = [sys.executable, "-m", "irtp", "collect", str(sweep), "--format", "netcdf",
           "--out", str(tmp_path / "cli.nc")]
    p = subprocess.run(run, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    with xr.open_dataset(tmp_path / "cli.nc") as back:
        xr.testing.assert_identical(back.load(), ds)

    sw = copy_of(sweep, tmp_path)
    shutil.rmtree(next(points(sw))[2])
    run[4], run[6], run[-1] = str(sw), "zarr", str(tmp_path / "part.zarr")
    p = subprocess.run(run, capture_output=True, text=True)
    assert p.returncode == 3 and "1 missing" in p.stderr, (p.returncode, p.stderr)
    p = subprocess.run([*run[:3], "collect", str(tmp_path / "none"), "--out", "x.nc"],
                       capture_output=True, text=True)
    assert p.returncode == 2 and "sweep.json" in p.stderr


def test_irtp_sweep_collect_runs_the_module(cli, sweep, tmp_path):
    """The binary's `irtp sweep collect` is the module's collect (exit codes
    passed on); a Python without the module is refused naming --python."""
    ds = irtp.load_sweep(sweep)
    p = cli.run(["sweep", "collect", str(sweep), "--format", "netcdf",
                 "--out", str(tmp_path / "bin.nc"), "--python", sys.executable])
    assert p.returncode == 0, p.stderr
    with xr.open_dataset(tmp_path / "bin.nc") as back:
        xr.testing.assert_identical(back.load(), ds)
    sw = copy_of(sweep, tmp_path)
    shutil.rmtree(next(points(sw))[2])
    p = cli.run(["sweep", "collect", str(sw), "--format", "zarr",
                 "--out", str(tmp_path / "part.zarr"), "--python", sys.executable], check=False)
    assert p.returncode == 3, p.stderr
    err = cli.error(["sweep", "collect", str(sweep), "--out", str(tmp_path / "x.nc"),
                     "--python", str(tmp_path / "no-python")])
    assert err.startswith("invalid --python") and "xarray extra" in err
    assert not (tmp_path / "x.nc").exists()
