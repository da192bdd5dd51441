"""Same parameters and seed: bit-identical numbers through Python and through
the CLI, for every function (summary vs ``--json``, tables and CSV bytes vs
``--out``, run.json parameters, and the provenance's equivalent command line)."""

from __future__ import annotations

import json
import pathlib

import pytest

import irtp
from conftest import argv_for, difference, read_csv, same_bits, strip

# (function, CLI command, keywords): small sizes, every method.
CASES = [
    ("simulate", "simulate",
     dict(particles=300, t_max=5.0, samples=11, burn_in=2.0, bins=20, rate=1.5, seed=7)),
    ("simulate", "simulate",
     dict(drag="tanh", sigma=0.6, lambda_=0.85, rate=1.0, particles=100, t_max=2.0,
          samples=11, burn_in=1.0, bins=20, method="euler", dt=0.002, seed=3)),
    ("simulate", "simulate",
     dict(particles=200, grid="log", t_min=0.01, t_max=10.0, samples=12, burn_in=2.0,
          bins=16, reset_velocity=0.2)),
    ("simulate", "simulate",
     dict(particles=64, t_max=2.0, samples=5, burn_in=1.0, bins=8, method="euler",
          events="bernoulli", dt=0.001)),
    ("analytic", "analytic", dict(drag="tan", sigma=3.0, lambda_=0.9, points=51)),
    ("analytic", "analytic", dict(drag="tanh", sigma=0.6, lambda_=1.2, points=33)),
    ("fp_stationary", "fp stationary", dict(lambda_=0.9, rate=2.0, cells=400)),
    ("fp_stationary", "fp stationary",
     dict(drag="tanh", sigma=0.6, lambda_=0.5, rate=0.2, cells=300, mesh="uniform",
          no_extrapolate=True)),
    ("fp_transient", "fp transient",
     dict(t_max=1.0, scheme="paper", cells=200, samples=11, snapshots=2, cfl=0.5)),
    ("fp_transient", "fp transient",
     dict(t_max=1.0, cells=200, samples=11, snapshots=2, rtol=1e-5)),
    ("mfpt", "mfpt", dict(v0=-0.249, vt=0.5, cells=1000)),
    ("mfpt", "mfpt", dict(v0=-0.249, vt=0.5, method="exact", particles=400, seed=5)),
    ("mfpt", "mfpt", dict(v0=-0.249, vt=0.5, method="euler", particles=100, dt=0.001)),
    ("mfpt", "mfpt", dict(v0=0.0, vt=0.5, rate=60.0, t_max=1.0, method="exact", particles=500)),
    # The search problem (first passage in position): backward, exact, renewal, euler.
    ("mfpt", "mfpt", dict(v0=0.0, xt=0.5, reset_position=0.0, cells_x=16, cells_v=8)),
    ("mfpt", "mfpt", dict(v0=0.0, interval="-0.5,0.5", method="exact", particles=400, seed=2)),
    ("mfpt", "mfpt", dict(v0=0.0, xt=0.5, reset_position=0.0, method="renewal", cells_x=16,
                          cells_v=8, time_steps=40, horizon_tail=1e-6)),
    ("mfpt", "mfpt", dict(v0=0.0, xt=0.5, reset_position=0.0, method="euler", dt=0.01,
                          particles=400, seed=3)),
    ("mfpt_distribution", "mfpt distribution",
     dict(v0=0.0, xt=0.5, reset_position=0.0, cells_x=16, cells_v=8, points=51)),
    ("mfpt_scan", "mfpt scan",
     dict(v0=-0.249, vt=0.5, over="rate", from_=0.1, to=10.0, points=5, log=True, cells=1000)),
    ("mfpt_scan", "mfpt scan",
     dict(v0=-0.249, over="vt", from_=0.1, to=0.9, points=3, method="exact",
          particles=200, cells=500)),
    ("mfpt_optimize", "mfpt optimize", dict(v0=-0.249, vt=0.5, cells=1000, grid_points=11)),
    # The search's scan and optimum: the same keywords as the CLI flags.
    ("mfpt_scan", "mfpt scan",
     dict(v0=0.0, xt=0.5, reset_position=0.0, over="rate", from_=0.5, to=2.0, points=3,
          cells_x=8, cells_v=4)),
    ("mfpt_scan", "mfpt scan",
     dict(v0=0.0, interval="-0.5,1", rate=1.0, over="x0", from_=-0.2, to=0.2, points=3,
          cells_x=8, cells_v=4, method="exact", particles=200, seed=4)),
    ("mfpt_optimize", "mfpt optimize",
     dict(v0=0.0, xt=0.5, reset_position=0.0, cells_x=8, cells_v=4, r_min=0.05, r_max=20.0,
          grid_points=9)),
]

IDS = [f"{fn}-{i}" for i, (fn, _, _) in enumerate(CASES)]


@pytest.mark.parametrize("function,command,kwargs", CASES, ids=IDS)
def test_summary_equals_cli_json(cli, function, command, kwargs):
    res = getattr(irtp, function)(**kwargs)
    printed = cli.json(argv_for(command, kwargs))
    assert printed["schema"] == "irtp.summary/1"
    assert (printed["command"], printed["method"]) == (command, res.method)
    assert difference(res.params, printed["params"]) is None
    assert difference(strip(res.summary), strip(printed["results"])) is None
    assert res.command == command


@pytest.mark.parametrize("function,command,kwargs", CASES, ids=IDS)
def test_provenance_argv_is_the_equivalent_cli_call(cli, function, command, kwargs):
    res = getattr(irtp, function)(**kwargs)
    argv = list(res.provenance["argv"])
    assert argv[1:1 + len(command.split())] == command.split(), argv
    expected = cli.json(argv[1:])["results"]
    assert difference(strip(res.summary), strip(expected)) is None


@pytest.mark.parametrize("function,command,kwargs", CASES, ids=IDS)
def test_files_and_tables_equal_cli_out(cli, tmp_path, function, command, kwargs):
    py_dir, cli_dir = tmp_path / "py", tmp_path / "cli"
    res = getattr(irtp, function)(out=py_dir, **kwargs)
    cli.run([*argv_for(command, kwargs), "--out", str(cli_dir)])

    cli_files = sorted(p.name for p in cli_dir.iterdir())
    assert sorted(p.name for p in py_dir.iterdir()) == cli_files
    assert sorted(pathlib.Path(f).name for f in res.files) == cli_files
    assert pathlib.Path(res.out) == py_dir
    csvs = [name for name in cli_files if name.endswith(".csv")]
    assert sorted(res.tables) == sorted(name[:-4] for name in csvs)
    for name in csvs:
        assert (py_dir / name).read_bytes() == (cli_dir / name).read_bytes(), name
        columns = read_csv(cli_dir / name)
        table = res.tables[name[:-4]]
        assert list(table) == list(columns), name
        for col, values in columns.items():
            assert same_bits(table[col], values), (name, col)

    run_py = json.loads((py_dir / "run.json").read_text())
    run_cli = json.loads((cli_dir / "run.json").read_text())
    assert difference(run_py["parameters"], run_cli["parameters"]) is None
    assert difference(res.params, run_cli["parameters"]) is None
    for key in ("software", "version", "command", "method", "seed", "files"):
        assert run_py[key] == run_cli[key], key
        assert res.provenance[key] == run_cli[key], key
    for name in cli_files:
        if name.endswith(".json") and name != "run.json":
            a = json.loads((py_dir / name).read_text())
            b = json.loads((cli_dir / name).read_text())
            if name == "summary.json":
                # The provenance (command line, time) differs; the rest not.
                assert a.pop("provenance")["seed"] == b.pop("provenance")["seed"]
                a["results"], b["results"] = strip(a["results"]), strip(b["results"])
            assert difference(strip(a), strip(b)) is None, name


def test_reproduce_writes_the_cli_files(cli, tmp_path):
    """reproduce("fig2", quick=True) through Python and the CLI: the same data."""
    res = irtp.reproduce("fig2", quick=True, out=tmp_path / "py")
    cli.run(["reproduce", "fig2", "--quick", "--out", str(tmp_path / "cli")])
    names = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert sorted(p.name for p in (tmp_path / "py").iterdir()) == names
    assert sorted(pathlib.Path(f).name for f in res.files) == names
    for name in ("fig2.csv", "claims.json", "parameters.json"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()
    assert res.summary["figures"] == ["fig2"]
    assert res.tables == {}
