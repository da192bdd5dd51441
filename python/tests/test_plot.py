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


def tick_boxes(ax):
    """Window extents of the visible, non-empty tick labels of ``ax``'s x and
    y axes (after drawing), per axis."""
    out = []
    for labels in (ax.get_xticklabels(), ax.get_yticklabels()):
        out.append([t.get_window_extent() for t in labels
                    if t.get_visible() and t.get_text() and ax.get_window_extent().width > 0
                    and _shown(ax, t)])
    return out


def _shown(ax, label):
    """Whether a tick label lies within its axis (matplotlib keeps some outside, not drawn)."""
    x, y = label.get_position()
    lo, hi = sorted(ax.get_xlim() if label in ax.get_xticklabels() else ax.get_ylim())
    v = x if label in ax.get_xticklabels() else y
    return lo - 1e-9 * abs(hi - lo) <= v <= hi + 1e-9 * abs(hi - lo)


def assert_no_overlap(fig):
    """No two tick labels of an axis overlap (window extents after drawing),
    in every Axes of ``fig`` (colour bars included)."""
    fig.canvas.draw()
    for ax in fig.axes:
        for boxes in tick_boxes(ax):
            for i, a in enumerate(boxes):
                for b in boxes[i + 1:]:
                    assert not a.overlaps(b), (ax.get_title(), a, b)


@pytest.mark.parametrize("function,command,kwargs,panels", KINDS, ids=IDS)
def test_tick_labels_never_overlap(function, command, kwargs, panels):
    ax = getattr(irtp, function)(**kwargs).plot()
    assert_no_overlap(ax.figure)
    plt.close(ax.figure)


def test_readme_density_is_not_a_flat_line(tmp_path):
    """The edge cells (p up to 530) are cut and marked, not the range: the
    central 98 % of the density spans more than a quarter of the y axis;
    states named as the noise names them; parameters in the title."""
    res = irtp.fp_stationary(drag="tan", sigma=3.0, lambda_=0.9, rate=2.0, cells=400)
    ax = res.plot()
    lo, hi = ax.get_ylim()
    q = np.quantile(res.tables["density"]["p"], [0.01, 0.9])
    assert hi < 5 < res.tables["density"]["p"].max()
    assert q[1] - q[0] > 0.25 * (hi - lo)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "η = +Σ" in labels and any(s.startswith("beyond the axis") for s in labels), labels
    assert ax.figure._suptitle.get_text() == "irtp fp stationary: tan drag, Σ = 3, λ = 0.9, r = 2"
    assert_drawn(ax, tmp_path / "fp.png")
    rpt = irtp.fp_stationary(noise="rpt:sigma=1,alpha=1,beta=1", drag="tan", rate=2.0, cells=200)
    labels = [t.get_text() for t in rpt.plot().get_legend().get_texts()]
    assert "pause (η = 0)" in labels and "run (η = −1)" in labels, labels
    assert not any("₊" in s or "p_" in s for s in labels), labels


def test_an_atom_is_drawn_as_an_atom():
    """The reset into the pause of rpt noise is a point mass (pi_0 r/(r +
    beta) = 1/3 here, within 4 of its errors): a stem inside the axis
    range, its mass in the legend, not a cell."""
    rpt = irtp.fp_stationary(noise="rpt:sigma=1,alpha=1,beta=1", drag="tan", rate=2.0, cells=200)
    (atom,) = rpt.summary["atoms"]
    assert abs(atom["mass"] - 1 / 3) <= 4 * atom["err"], atom
    ax = rpt.plot()
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(s.startswith("atom at v = 0: mass 0.33") for s in labels), labels
    lo, hi = ax.get_ylim()
    stems = [c for c in ax.collections if c.get_gid() == "atom"]
    assert len(stems) == 1
    (seg,) = stems[0].get_segments()
    assert seg[0][0] == atom["v"] and lo <= seg[:, 1].min() and seg[:, 1].max() <= hi


def test_a_runaway_tau_does_not_hide_the_optimum():
    """τ(r) on a sparse grid reaches 10⁷⁹ at r = 1000: cut and marked, the
    optimum in view."""
    res = irtp.mfpt_optimize(v0=-0.249, vt=0.5, cells=1000, grid_points=7)
    ax = res.plot()
    lo, hi = ax.get_ylim()
    assert lo < res.summary["tau_opt"] < hi < 3 * res.summary["tau_opt"], (lo, hi)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(s.startswith("beyond the axis") for s in labels), labels
    assert any(s.startswith("optimum: τ = ") for s in labels), labels


def test_moments_on_log_axes_are_log_spaced_with_guides():
    res = irtp.simulate(particles=200, t_max=10.0, burn_in=3.0)
    ax = res.plot(panel=1)
    t = ax.get_lines()[0].get_xdata()
    late = np.sum(t > t[-1] / 10)
    assert late <= 40 / np.log10(t[-1] / t[0]) + 2, (late, len(t))
    notes = [a.get_text() for a in ax.texts]
    assert "∝ t" in notes and any(n in notes for n in ("∝ t²", "∝ t³", "∝ t⁴")), notes


SWEEP = """\
command = "fp stationary"

[fixed]
cells = 40

[axes]
"""


def test_plot_sweep_is_a_heat_map(cli, tmp_path):
    pytest.importorskip("xarray")
    (tmp_path / "plan.toml").write_text(PLAN)
    cli.run(["sweep", "run", str(tmp_path / "plan.toml"), "--out", str(tmp_path / "sw")])
    ds = irtp.load_sweep(tmp_path / "sw")
    ax = irtp.plot_sweep(ds)
    assert [t.get_text() for t in ax.get_xticklabels()] == ["2", "3", "4"]
    assert_no_overlap(ax.figure)
    assert_drawn(ax, tmp_path / "heat.png")
    ax = irtp.plot_sweep(ds, var="result.d_eff")
    assert ax.figure.axes[1].get_ylabel() == "$D_{eff}$"
    assert_drawn(ax, tmp_path / "d_eff.png")
    with pytest.raises(ValueError, match="var='nope'"):
        irtp.plot_sweep(ds, var="nope")


def test_plot_sweep_cells_follow_a_log_spaced_plan(cli, tmp_path):
    pytest.importorskip("xarray")
    rate = "rate = { from = 0.1, to = 10.0, points = 5, spacing = \"log\" }\n"
    plan = SWEEP + "sigma = [1.0, 2.0]\n" + rate
    (tmp_path / "plan.toml").write_text(plan)
    cli.run(["sweep", "run", str(tmp_path / "plan.toml"), "--out", str(tmp_path / "sw")])
    ax = irtp.plot_sweep(irtp.load_sweep(tmp_path / "sw"), var="d_eff")
    assert ax.get_xscale() == "log"
    mesh = ax.collections[0]
    xe = np.unique(np.asarray(mesh.get_coordinates())[..., 0])
    assert np.allclose(np.log10(xe), np.arange(-1.25, 1.26, 0.5)), xe
    assert [t.get_text() for t in ax.get_xticklabels()] == ["0.1", "0.32", "1", "3.2", "10"]
    assert_no_overlap(ax.figure)


def test_plot_sweep_of_one_axis_is_a_line_with_the_r_minus_two_law(cli, tmp_path):
    pytest.importorskip("xarray")
    plan = SWEEP + "rate = { from = 0.1, to = 30.0, points = 7, spacing = \"log\" }\n"
    (tmp_path / "plan.toml").write_text(plan)
    cli.run(["sweep", "run", str(tmp_path / "plan.toml"), "--out", str(tmp_path / "sw")])
    ax = irtp.plot_sweep(irtp.load_sweep(tmp_path / "sw"), var="d_eff")
    assert (ax.get_xscale(), ax.get_yscale()) == ("log", "log")
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("r", "$D_{eff}$")
    assert any(t.get_text() == "∝ $r^{-2}$" for t in ax.texts)
    assert ax.get_title() == "$D_{eff}$ over a sweep of fp stationary"
    assert_no_overlap(ax.figure)
    assert_drawn(ax, tmp_path / "line.png")


def test_plot_sweep_of_three_axes_is_small_multiples(cli, tmp_path):
    pytest.importorskip("xarray")
    plan = PLAN + "lambda = [0.5, 5.0]\n"
    (tmp_path / "plan.toml").write_text(plan)
    cli.run(["sweep", "run", str(tmp_path / "plan.toml"), "--out", str(tmp_path / "sw")])
    ds = irtp.load_sweep(tmp_path / "sw")
    ax = irtp.plot_sweep(ds, var="v2")
    heat = [a for a in ax.figure.axes if a.get_label() != "<colorbar>"]
    assert [a.get_title() for a in heat] == ["λ = 0.5", "λ = 5"]
    assert heat[0].collections[0].norm.vmax == heat[1].collections[0].norm.vmax
    assert_no_overlap(ax.figure)
    assert_drawn(ax, tmp_path / "three.png")
