"""``Result.plot()`` and ``irtp.plot_sweep``: every result type (in process
and read back with ``irtp.load``) draws an Axes whose saved PNG matplotlib
reads back with drawn content; a sweep's Dataset gives a heat map."""

from __future__ import annotations

import pathlib

import numpy as np
import pytest

import irtp
from conftest import argv_for

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.image  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

# (function, CLI command, keywords, panels): tiny runs of every result type.
KINDS = [
    ("simulate", "simulate", dict(particles=100, t_max=2.0, samples=5, burn_in=1.0, bins=8), 2),
    ("simulate", "simulate",
     dict(particles=100, t_max=2.0, samples=5, burn_in=1.0, bins=8, reset_position=0.0), 3),
    ("analytic", "analytic", dict(drag="tanh", sigma=0.6, lambda_=1.2, points=33), 1),
    ("fp_stationary", "fp stationary", dict(lambda_=0.9, rate=2.0, cells=200), 1),
    ("fp_transient", "fp transient", dict(t_max=0.5, cells=64, samples=5, snapshots=3), 2),
    ("fp_msd", "fp msd",
     dict(drag="tanh", sigma=0.6, rate=1.0, t_min=0.5, t_max=2.0, samples=6, cells=32, levels=2),
     2),
    ("mfpt", "mfpt", dict(v0=-0.249, vt=0.5, cells=200), 1),
    ("mfpt", "mfpt", dict(v0=-0.249, vt=0.5, method="exact", particles=200, seed=5), 1),
    ("mfpt_scan", "mfpt scan",
     dict(v0=-0.249, vt=0.5, over="rate", from_=0.1, to=10.0, points=4, log=True, cells=200), 1),
    ("mfpt_optimize", "mfpt optimize", dict(v0=-0.249, vt=0.5, cells=1000, grid_points=7), 1),
    ("mfpt_distribution", "mfpt distribution", dict(v0=-0.249, vt=0.5, cells=200, points=11), 2),
    ("mfpt_distribution", "mfpt distribution",
     dict(v0=-0.249, vt=0.5, method="exact", particles=200), 2),
]
IDS = [f"{fn}-{i}" for i, (fn, _, _, _) in enumerate(KINDS)]


def assert_drawn(ax, path: pathlib.Path) -> None:
    """``ax`` is an Axes; its figure saved as a PNG reads back with at least
    1 % of its pixels not white."""
    assert isinstance(ax, matplotlib.axes.Axes)
    ax.figure.savefig(path)
    plt.close(ax.figure)
    img = matplotlib.image.imread(path)
    assert img.ndim == 3 and img.shape[2] in (3, 4)
    drawn = np.any(img[:, :, :3] < 0.98, axis=2).mean()
    assert drawn > 0.01, drawn


@pytest.mark.parametrize("function,command,kwargs,panels", KINDS, ids=IDS)
def test_every_result_plots(tmp_path, function, command, kwargs, panels):
    res = getattr(irtp, function)(**kwargs)
    ax = res.plot()
    assert len(ax.figure.axes) == panels
    assert_drawn(ax, tmp_path / "all.png")
    last = res.plot(panel=panels - 1)
    assert len(last.figure.axes) == 1
    assert_drawn(last, tmp_path / "last.png")


@pytest.mark.parametrize("function,command,kwargs,panels", KINDS, ids=IDS)
def test_loaded_cli_output_plots(cli, tmp_path, function, command, kwargs, panels):
    cli.run([*argv_for(command, kwargs), "--out", str(tmp_path / "cli")])
    res = irtp.load(tmp_path / "cli")
    fig, ax = plt.subplots()
    assert res.plot(ax=ax) is ax
    assert_drawn(ax, tmp_path / "loaded.png")


def test_plot_refuses_a_missing_panel_and_reproduce():
    res = irtp.analytic(points=9)
    with pytest.raises(ValueError, match="panel=3"):
        res.plot(panel=3)
    fake = irtp.ReproduceResult({"command": "reproduce"})
    with pytest.raises(ValueError, match="figN.png"):
        fake.plot()


PLAN = """\
command = "fp stationary"

[fixed]
cells = 40

[axes]
rate = [0.5, 2.0]
sigma = [2.0, 3.0, 4.0]
"""


def test_plot_sweep_is_a_heat_map(cli, tmp_path):
    pytest.importorskip("xarray")
    (tmp_path / "plan.toml").write_text(PLAN)
    cli.run(["sweep", "run", str(tmp_path / "plan.toml"), "--out", str(tmp_path / "sw")])
    ds = irtp.load_sweep(tmp_path / "sw")
    ax = irtp.plot_sweep(ds)
    assert [t.get_text() for t in ax.get_xticklabels()] == ["2", "3", "4"]
    assert_drawn(ax, tmp_path / "heat.png")
    assert_drawn(irtp.plot_sweep(ds, var="result.d_eff"), tmp_path / "d_eff.png")
    with pytest.raises(ValueError, match="var='nope'"):
        irtp.plot_sweep(ds, var="nope")


def test_plot_sweep_of_three_axes_fixes_the_third(cli, tmp_path):
    pytest.importorskip("xarray")
    plan = PLAN + "lambda = [0.5, 5.0]\n"
    (tmp_path / "plan.toml").write_text(plan)
    cli.run(["sweep", "run", str(tmp_path / "plan.toml"), "--out", str(tmp_path / "sw")])
    ds = irtp.load_sweep(tmp_path / "sw")
    ax = irtp.plot_sweep(ds, var="v2")
    assert ax.get_title() == "sweep: v2 at lambda = 0.5"
    assert_drawn(ax, tmp_path / "three.png")
    one = "command = \"fp stationary\"\n[fixed]\ncells = 40\n[axes]\nrate = [0.5, 2.0]\n"
    (tmp_path / "one.toml").write_text(one)
    cli.run(["sweep", "run", str(tmp_path / "one.toml"), "--out", str(tmp_path / "one")])
    with pytest.raises(ValueError, match="at least two axes"):
        irtp.plot_sweep(irtp.load_sweep(tmp_path / "one"))
