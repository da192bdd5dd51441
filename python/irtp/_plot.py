"""Pictures of results: ``Result.plot()`` and :func:`irtp.plot_sweep`.

matplotlib is an optional dependency (``pip install './python[plot]'``),
imported only when a picture is asked for, as pandas is for
``to_pandas()``. The figures are those of ``irtp plot DIR`` (the CLI):

- ``simulate``: the stationary velocity density with its standard errors
  (and the density at t_max), the moments ⟨v²⟩(t), ⟨x²⟩(t) with their
  errors on log axes, and P(x) with ``reset_position``;
- ``analytic``, ``fp_stationary``: p(v) (with p₊, p₋);
- ``fp_transient``: density snapshots, and the moments in time;
- ``fp_msd``: ⟨x²⟩(t) on log axes and its exponent α(t);
- ``mfpt``: τ(v₀) (backward equations) or the survival curve S(t)
  (particles); ``mfpt_distribution``: S(t) and the density f(t);
- ``mfpt_scan``, ``mfpt_optimize``: τ against the scanned quantity.
"""

from __future__ import annotations

from typing import Any, Callable, Dict, List, Optional, Sequence

import numpy as np

Table = Dict[str, np.ndarray]
Drawer = Callable[[Any], None]

# The most snapshots fp_transient's picture shows (evenly picked).
MAX_SNAPSHOTS = 8


def _band(ax: Any, t: Table, x: str, y: str, err: str, label: str, **kw: Any) -> None:
    """y against x with a ±err band (where the table has err)."""
    line, = ax.plot(t[x], t[y], label=label, **kw)
    if err in t:
        e = np.nan_to_num(t[err])
        ax.fill_between(t[x], t[y] - e, t[y] + e, color=line.get_color(), alpha=0.3, lw=0)


def _lines(ax: Any, t: Table, x: str, ys: Sequence[str], labels: Sequence[str]) -> None:
    """Several columns against x: solid, dashed, dotted."""
    for y, label, style in zip(ys, labels, ("-", "--", ":")):
        if y in t:
            ax.plot(t[x], t[y], style, label=label)


def _survival(t: Table) -> Drawer:
    def draw(ax: Any) -> None:
        _band(ax, t, "t", "survival", "survival_err", "Kaplan-Meier", drawstyle="steps-post")
        ax.set(xscale="symlog", xlabel="t", ylabel="S(t)", title="survival")
    return draw


def _simulate(tables: Dict[str, Table]) -> List[Drawer]:
    d, m = tables["density"], tables["moments"]

    def density(ax: Any) -> None:
        _band(ax, d, "v", "p", "p_err", "time average")
        ax.plot(d["v"], d["p_final"], "--", lw=1, label="at t_max")
        ax.set(xlabel="v", ylabel="P_s(v)", title="velocity density")

    def moments(ax: Any) -> None:
        keep = {k: c[m["t"] > 0] for k, c in m.items()}
        _band(ax, keep, "t", "v2", "v2_err", "⟨v²⟩")
        _band(ax, keep, "t", "x2", "x2_err", "⟨x²⟩")
        ax.set(xscale="log", yscale="log", xlabel="t", ylabel="moment", title="moments")

    drawers = [density, moments]
    if "position" in tables:
        pos = tables["position"]

        def position(ax: Any) -> None:
            _band(ax, pos, "x", "p", "p_err", "x(t_max)")
            ax.set(xlabel="x", ylabel="P(x)", title="position density")
        drawers.append(position)
    return drawers


def _density(t: Table, parts: bool) -> List[Drawer]:
    def draw(ax: Any) -> None:
        if parts:
            _lines(ax, t, "v", ("p", "p_plus", "p_minus"), ("p = p₊ + p₋", "p₊", "p₋"))
        else:
            ax.plot(t["v"], t["p"], "k", label="p(v), exact (r = 0)")
        ax.set(xlabel="v", ylabel="p(v)", title="stationary density")
    return [draw]


def _fp_transient(tables: Dict[str, Table]) -> List[Drawer]:
    s, m = tables["snapshots"], tables["moments"]

    def snapshots(ax: Any) -> None:
        times = list(dict.fromkeys(s["t"].tolist()))
        if len(times) > MAX_SNAPSHOTS:
            picks = np.linspace(0, len(times) - 1, MAX_SNAPSHOTS).round().astype(int)
            times = [times[i] for i in picks]
        for t in times:
            rows = s["t"] == t
            ax.plot(s["v"][rows], s["p"][rows], label=f"t = {t:g}")
        ax.set(xlabel="v", ylabel="p(v, t)", title="density snapshots")

    def moments(ax: Any) -> None:
        _lines(ax, m, "t", ("v2", "v_mean"), ("⟨v²⟩", "⟨v⟩"))
        ax.set(xlabel="t", ylabel="moment", title="moments")
    return [snapshots, moments]


def _fp_msd(tables: Dict[str, Table]) -> List[Drawer]:
    m = {k: c[tables["moments"]["t"] > 0] for k, c in tables["moments"].items()}

    def msd(ax: Any) -> None:
        _band(ax, m, "t", "x2", "x2_err", "⟨x²⟩")
        ax.set(xscale="log", yscale="log", xlabel="t", ylabel="⟨x²⟩",
               title="mean squared displacement")

    def alpha(ax: Any) -> None:
        ax.plot(m["t"], m["alpha"], color="C3", label="α = d ln⟨x²⟩ / d ln t")
        ax.set(xscale="log", xlabel="t", ylabel="α", title="exponent")
    return [msd, alpha]


def _mfpt(tables: Dict[str, Table]) -> List[Drawer]:
    if "profile" not in tables:
        return [_survival(tables["survival"])]
    t = tables["profile"]

    def profile(ax: Any) -> None:
        _lines(ax, t, "v0", ("tau", "tau_plus", "tau_minus"), ("τ", "τ₊", "τ₋"))
        ax.set(xlabel="v₀", ylabel="τ", title="mean first-passage time")
    return [profile]


def _scan(tables: Dict[str, Table], summary: Any) -> List[Drawer]:
    if "rate_grid" in tables:
        t, axis = tables["rate_grid"], "rate"
    else:
        t = tables["mfpt_scan"]
        axis = next(iter(t))

    def draw(ax: Any) -> None:
        labels = ("τ (backward equations)", "τ₊", "τ₋")
        _lines(ax, t, axis, ("tau", "tau_plus", "tau_minus"), labels)
        if "tau_sim" in t:
            ax.errorbar(t[axis], t["tau_sim"], yerr=np.nan_to_num(t["tau_sim_err"]), fmt="o",
                        label="τ (sampled)")
        if isinstance(summary, dict) and summary.get("r_opt") is not None:
            ax.plot([summary["r_opt"]], [summary["tau_opt"]], "o", color="C3", label="optimum")
        x = t[axis][np.isfinite(t[axis])]
        if x.size and x.min() > 0 and x.max() / x.min() > 30:
            ax.set_xscale("log")
        ax.set(xlabel=axis, ylabel="τ", title="mean first-passage time")
    return [draw]


def _distribution(tables: Dict[str, Table]) -> List[Drawer]:
    if "distribution" not in tables:
        h = tables["histogram"]

        def histogram(ax: Any) -> None:
            mid = np.sqrt(h["t_lo"] * h["t_hi"])
            ax.errorbar(mid, h["density"], yerr=np.nan_to_num(h["density_err"]), fmt="o",
                        ms=3, label="sampled")
            ax.set(xscale="log", yscale="log", xlabel="t", ylabel="f(t)",
                   title="first-passage-time density")
        return [_survival(tables["survival"]), histogram]
    d = {k: c[tables["distribution"]["t"] > 0] for k, c in tables["distribution"].items()}
    names = ("mixture", "start +Σ", "start −Σ")

    def survival(ax: Any) -> None:
        _lines(ax, d, "t", ("survival", "survival_plus", "survival_minus"), names)
        ax.set(xscale="log", xlabel="t", ylabel="S(t)", title="survival")

    def density(ax: Any) -> None:
        _lines(ax, d, "t", ("density", "density_plus", "density_minus"), names)
        ax.set(xscale="log", yscale="log", xlabel="t", ylabel="f(t)",
               title="first-passage-time density")
    return [survival, density]


def drawers(res: Any) -> List[Drawer]:
    """The panels of ``res``'s picture, each a function drawing into an Axes."""
    tables, command = res.tables, res.command
    if command == "simulate":
        return _simulate(tables)
    if command in ("analytic", "fp stationary"):
        return _density(tables["density"], command == "fp stationary")
    if command == "fp transient":
        return _fp_transient(tables)
    if command == "fp msd":
        return _fp_msd(tables)
    if command == "mfpt":
        return _mfpt(tables)
    if command in ("mfpt scan", "mfpt optimize"):
        return _scan(tables, res.summary)
    if command == "mfpt distribution":
        return _distribution(tables)
    raise ValueError(f"irtp.{command}: nothing to plot (reproduce drew its figures: "
                     "figN.png in its directory)")


def plot_result(res: Any, panel: Optional[int] = None, ax: Any = None) -> Any:
    """Draw ``res`` (see ``Result.plot``); the Axes drawn into."""
    import matplotlib.pyplot as plt

    panels = drawers(res)
    if panel is not None and not 0 <= panel < len(panels):
        raise ValueError(f"panel={panel}: this picture has panels 0 to {len(panels) - 1}")
    if ax is not None or panel is not None:
        ax = ax if ax is not None else plt.subplots(figsize=(6.4, 4.8))[1]
        chosen = [panels[panel or 0]]
        axes = [ax]
    else:
        fig, grid = plt.subplots(1, len(panels), figsize=(6.4 * len(panels), 4.8), squeeze=False)
        chosen, axes = panels, list(grid[0])
        fig.suptitle(f"irtp {res.command}" + (f": {res.out}" if res.out else ""))
    for draw, a in zip(chosen, axes):
        draw(a)
        if a.get_legend_handles_labels()[0]:
            a.legend(fontsize="small")
    axes[0].figure.tight_layout()
    return axes[0]


def _tick(v: Any) -> str:
    """A coordinate value as a tick label."""
    return f"{v:g}" if isinstance(v, float) else str(v)


def plot_sweep(ds: Any, var: Optional[str] = None, ax: Any = None) -> Any:
    """A heat map of ``var`` over the first two axes of a sweep's Dataset
    (further axes at their first value, named in the title), as
    ``irtp plot DIR --var VAR`` draws it."""
    import matplotlib.pyplot as plt

    dims = [str(d) for d in ds["point"].dims]
    if len(dims) < 2:
        raise ValueError(f"a heat map needs a sweep over at least two axes; this one has "
                         f"{len(dims)} ({', '.join(dims)}): use ds[var].plot() from xarray")
    scalars = [str(n) for n, v in ds.data_vars.items()
               if tuple(str(d) for d in v.dims) == tuple(dims) and v.dtype.kind in "fiu"
               and str(n) not in ("wall_time_s", "point")]
    if var is None:
        if not scalars:
            raise ValueError("the sweep has no numeric variable over its axes")
        var = scalars[0]
    name = var[len("result."):] if var.startswith("result.") else var
    if name not in scalars:
        raise ValueError(f"var={var!r}: not a numeric variable over the axes; one of "
                         f"{', '.join(scalars)}")
    rest = {d: 0 for d in dims[2:]}
    values = np.asarray(ds[name].isel(rest).transpose(*dims[:2]).values, dtype=float)
    if ax is None:
        ax = plt.subplots(figsize=(6.4, 4.8))[1]
    mesh = ax.pcolormesh(np.ma.masked_invalid(values), cmap="viridis")
    ax.figure.colorbar(mesh, ax=ax, label=name)
    ticks = [[_tick(v) for v in ds[d].values.tolist()] for d in dims[:2]]
    ax.set_yticks(np.arange(len(ticks[0])) + 0.5, ticks[0])
    ax.set_xticks(np.arange(len(ticks[1])) + 0.5, ticks[1])
    at = ", ".join(f"{d} = {_tick(ds[d].values.tolist()[0])}" for d in rest)
    ax.set(ylabel=dims[0], xlabel=dims[1], title=f"sweep: {name}" + (f" at {at}" if at else ""))
    return ax
