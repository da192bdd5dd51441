"""Pictures of results: ``Result.plot()`` and :func:`irtp.plot_sweep`.

matplotlib is an optional dependency (``pip install './python[plot]'``),
imported only when a picture is asked for, as pandas is for
``to_pandas()``. The figures are those of ``irtp plot DIR`` (the CLI), with
the same look: axes and legends in the paper's (dimensionless) symbols, the
parameters (drag, noise, Σ, λ, r) in the title, vertical ranges that a few
extreme values (an integrable singularity at the edge of the velocity
range, an atom) do not set (they are cut and marked ▲), points on log time
axes thinned to even steps in log t, and guides where the physics has a law:

- ``simulate``: the stationary velocity density with its standard errors
  (and the density at t_max), the moments ⟨v²⟩(t), ⟨x²⟩(t) with their
  errors on log axes beside the early power law and ∝ t, and P(x) with
  ``reset_position``;
- ``analytic``, ``fp_stationary``: P_s(v) (with its part in each noise
  state, named as the noise model names them);
- ``fp_transient``: density snapshots, and the moments in time;
- ``fp_msd``: ⟨x²⟩(t) on log axes with its power laws, and its exponent α(t);
- ``mfpt``: τ(v₀) (backward equations) or the survival curve S(t)
  (particles); ``mfpt_distribution``: S(t) and the density f(t);
- ``mfpt_scan``, ``mfpt_optimize``: τ against the scanned quantity, the
  optimum marked.

:func:`plot_sweep` draws one axis as a line with error bars, two as a heat
map on cells edged between the plan's values (geometric means on a
log-spaced axis), more as small multiples on one colour scale.
"""

from __future__ import annotations

from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

Table = Dict[str, np.ndarray]
Drawer = Callable[[Any], None]

# The most snapshots fp_transient's picture shows (evenly picked).
MAX_SNAPSHOTS = 8
# About how many points a moment curve on a log time axis shows.
LOG_POINTS = 40
# The most panels of a sweep's small multiples.
MAX_PANELS = 12

PARAM_SYMBOLS = {
    "sigma": "Σ", "lambda": "λ", "rate": "r", "reset_velocity": "$v_r$",
    "reset_position": "$x_r$", "reset_period": "$T_r$", "temperature": "T", "alpha": "α",
    "beta": "β", "v0": "$v_0$", "vt": "$v_t$", "xt": "$x_t$", "t_max": "$t_{max}$",
    "particles": "N", "dt": "Δt",
}
RESULT_SYMBOLS = {
    "d_eff": "$D_{eff}$", "d_eff_msd": "$D_{eff}$ (from ⟨x²⟩)", "v2": "⟨v²⟩", "v_mean": "⟨v⟩",
    "v2_final": "⟨v²⟩($t_{max}$)", "x2_final": "⟨x²⟩($t_{max}$)", "x_final": "⟨x⟩($t_{max}$)",
    "tau": "τ", "tau_plus": "$τ_+$", "tau_minus": "$τ_-$", "tau_opt": "$τ_{opt}$",
    "r_opt": "$r_{opt}$",
}
MODEL_KEYS = ("drag", "noise", "sigma", "lambda", "rate", "reset_velocity", "reset_period",
              "temperature")


def param_symbol(name: str) -> str:
    """The symbol of a parameter: ``sigma`` → Σ, ``rate`` → r."""
    return PARAM_SYMBOLS.get(name, name.replace("_", " "))


def result_symbol(name: str) -> str:
    """The symbol of a result: ``d_eff`` → D_eff, ``v2`` → ⟨v²⟩."""
    name = name[len("result."):] if name.startswith("result.") else name
    return RESULT_SYMBOLS.get(name, name.replace("_", " "))


def _num(x: float) -> str:
    """A number as a title writes it (at most 4 significant digits)."""
    return f"{x:.4g}"


def _assignment(name: str, v: Any) -> Optional[str]:
    """``Σ = 3`` from a parameter and its value; None for one saying nothing."""
    if v is None or isinstance(v, (dict, list)):
        return None
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        if v == 0 and name in ("reset_velocity", "temperature"):
            return None
        v = _num(float(v))
    if name == "drag":
        return f"{v} drag"
    if name == "noise":
        kind, _, rest = str(v).partition(":")
        if not rest or "[" in rest:
            return f"{kind} noise"
        pairs = (kv.partition("=") for kv in rest.split(","))
        keys = [f"{param_symbol(k)} = {x}" for k, _, x in pairs]
        return f"{kind} noise ({', '.join(keys)})"
    return f"{param_symbol(name)} = {v}"


def _model(params: Any) -> Optional[Dict[str, Any]]:
    """The model object of a run's parameters (the one with a drag)."""
    if isinstance(params, dict):
        if "drag" in params:
            return params
        for v in params.values():
            m = _model(v)
            if m is not None:
                return m
    return None


def title_parameters(params: Dict[str, Any], scanned: Sequence[str] = ()) -> str:
    """The parameters a title names: drag, noise, Σ, λ, r, v_r, T, then a
    search's v₀, v_t, x_t; not those in ``scanned``."""
    out: List[str] = []
    model = _model(params) or {}
    for k in MODEL_KEYS:
        if k not in scanned and k in model:
            a = _assignment(k, model[k])
            if a:
                out.append(a)
    search = params.get("problem") or params.get("base") or params
    for k in ("v0", "vt", "xt", "reset_position"):
        v = search.get(k, params.get(k)) if isinstance(search, dict) else None
        a = _assignment(k, v) if k not in scanned else None
        if a:
            out.append(a)
    return ", ".join(out)


def _robust_ylim(values: Sequence[Tuple[np.ndarray, np.ndarray]], log: bool,
                 xlog: bool = False) -> Optional[Tuple[float, float]]:
    """The vertical range cutting extreme values, or None when the data's
    own range is fine: (x, y) arrays of the drawn data, each weighing one,
    a value weighted by the share of the horizontal extent it covers; an end
    further than twice the spread of the central 98 % from it is cut."""
    us, ws = [], []
    for x, y in values:
        x, y = np.asarray(x, float), np.asarray(y, float)
        ok = np.isfinite(x) & np.isfinite(y) & ((y > 0) if log else True)
        x, y = x[ok], y[ok]
        if y.size == 0:
            continue
        u = np.log10(y) if log else y
        if xlog:
            keep = x > 0
            x, u = np.log10(x[keep]), u[keep]
            if u.size == 0:
                continue
        w = np.gradient(x) if x.size > 2 else np.ones_like(x)
        w = np.abs(w)
        w = w / w.sum() if w.sum() > 0 else np.full_like(u, 1.0 / u.size)
        us.append(u)
        ws.append(w)
    if not us:
        return None
    u, w = np.concatenate(us), np.concatenate(ws)
    order = np.argsort(u)
    u, w = u[order], w[order]
    a, b = _main_cluster(u, w)
    full = (u[0], u[-1])
    u, w = u[a:b + 1], w[a:b + 1]
    cum = np.cumsum(w) / w.sum()
    qlo, qhi = u[np.searchsorted(cum, 0.01)], u[min(np.searchsorted(cum, 0.99), u.size - 1)]
    span = max(qhi - qlo, 1e-9 * (1 + abs(qhi)))
    cut_lo, cut_hi = qlo - full[0] > 2 * span, full[1] - qhi > 2 * span
    if not (cut_lo or cut_hi):
        return None
    lo = qlo - 0.15 * span if cut_lo else full[0]
    hi = qhi + 0.15 * span if cut_hi else full[1]
    m = 0.04 * (hi - lo)
    lo, hi = lo - m, hi + m
    return (10 ** lo, 10 ** hi) if log else (lo, hi)


def _main_cluster(u: np.ndarray, w: np.ndarray) -> Tuple[int, int]:
    """Sorted values ``u`` (weights ``w``) without outlying groups at the
    ends: a group of at most 30 % of the weight cut off by a gap more than
    ten times the (non-zero) extent of the rest, repeatedly (a τ(r) running
    away to 10⁷⁹ on a sparse grid, an atom); the first and last index kept."""
    total, a, b = w.sum(), 0, u.size - 1
    while True:
        a0, b0 = a, b
        above = 0.0
        for j in range(b - 1, a - 1, -1):
            above += w[j + 1]
            if above > 0.3 * total:
                break
            rest = u[j] - u[a]
            if rest > 0 and u[j + 1] - u[j] > 10 * rest:
                b = j
                break
        below = 0.0
        for j in range(a + 1, b + 1):
            below += w[j - 1]
            if below > 0.3 * total:
                break
            rest = u[b] - u[j]
            if rest > 0 and u[j] - u[j - 1] > 10 * rest:
                a = j
                break
        if (a, b) == (a0, b0):
            return a, b


def _fit_y(ax: Any) -> None:
    """Set the Axes' vertical range robustly (:func:`_robust_ylim`) over
    its lines and points (guides, labelled ``_guide``, left out) and mark
    values beyond it with ▲ (▼ below) at the edge, in their colour."""
    log = ax.get_yscale() == "log"
    data = []
    for line in ax.get_lines():
        if line.get_gid() == "guide":
            continue
        x, y = line.get_xdata(), line.get_ydata()
        data.append((np.asarray(x, float), np.asarray(y, float), line.get_color()))
    lim = _robust_ylim([(x, y) for x, y, _ in data], log, ax.get_xscale() == "log")
    if lim is None:
        return
    ax.set_ylim(*lim)
    far = 0.0
    for x, y, color in data:
        for side, marker in ((y > lim[1], "^"), (y < lim[0], "v")):
            if side.any():
                edge = lim[1] if marker == "^" else lim[0]
                ax.plot(x[side], np.full(side.sum(), edge), marker, color=color, ms=7,
                        clip_on=False, gid="clip")
                far = max(far, float(np.nanmax(np.abs(y[side]))))
    ax.plot([], [], "^", color="0.4", label=f"beyond the axis (to {far:.3g})")


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


def log_thin(t: np.ndarray, n: int = LOG_POINTS) -> np.ndarray:
    """Indices of positive times about evenly spaced in log t (each once),
    so a linear time grid does not crowd its points into the last decade."""
    pos = np.flatnonzero((t > 0) & np.isfinite(t))
    if pos.size <= n:
        return pos
    targets = np.geomspace(t[pos[0]], t[pos[-1]], n) * (1 - 1e-12)
    k = np.minimum(np.searchsorted(t[pos], targets), pos.size - 1)
    return pos[np.unique(k)]


def _guide(ax: Any, x: np.ndarray, y: np.ndarray, text: str) -> None:
    """A grey dashed guide labelled below its middle."""
    ax.plot(x, y, "--", color="0.45", lw=1, gid="guide")
    mid = len(x) // 2
    ax.annotate(text, (x[mid], y[mid] / 6), color="0.4")


def power_law_guides(ax: Any, t: np.ndarray, x2: np.ndarray) -> Optional[int]:
    """Beside ⟨x²⟩(t) on log axes: the early power law (t² from a stationary
    velocity, t⁴ from rest: the integer 2 to 4 nearest the slope over the
    first decade) through the first value, ∝ t through the last; the early
    exponent."""
    ok = np.flatnonzero((t > 0) & (x2 > 0) & np.isfinite(x2))
    if ok.size < 2 or t[ok[-1]] < 10 * t[ok[0]]:
        return None
    a, b = ok[0], ok[-1]
    c = next((i for i in ok if t[i] >= 10 * t[a]), b)
    early = int(np.clip(round(np.log(x2[c] / x2[a]) / np.log(t[c] / t[a])), 2, 4))
    span = min(t[b] / t[a], 10 ** 1.5)
    xs = np.geomspace(t[a], t[a] * span, 11)
    _guide(ax, xs, x2[a] * (xs / t[a]) ** early, "∝ " + ["", "", "t²", "t³", "t⁴"][early])
    xs = np.geomspace(t[b] / span, t[b], 11)
    _guide(ax, xs, x2[b] * (xs / t[b]), "∝ t")
    return early


def _survival(t: Table) -> Drawer:
    def draw(ax: Any) -> None:
        _band(ax, t, "t", "survival", "survival_err", "Kaplan-Meier", drawstyle="steps-post")
        ax.set(xscale="symlog", xlabel="t", ylabel="S(t)", title="survival")
    return draw


def _atoms(ax: Any, summary: Any) -> None:
    """The point masses of the stationary law (``summary["atoms"]``:
    ``[{"v", "mass", "err"}]``; the density holds the law without them),
    drawn as atoms after the range is set: a stem at v to 90 % of the axis
    height, a marker on it, the mass and its error in the legend."""
    atoms = summary.get("atoms") if isinstance(summary, dict) else None
    lo, hi = ax.get_ylim()
    top = lo + 0.9 * (hi - lo)
    for k, a in enumerate(atoms or []):
        err = a.get("err")
        mass = f"{a['mass']:.4g}" + ("" if err is None else f" ± {err:.2g}")
        label = f"atom at v = {_num(a['v'])}: mass {mass}".replace("= -", "= −")
        color = f"C{4 + k}"
        ax.vlines(a["v"], max(lo, 0.0), top, color=color, lw=1.5, gid="atom")
        ax.plot([a["v"]], [top], "o", color=color, gid="atom", label=label)
    ax.set_ylim(lo, hi)


def _simulate(tables: Dict[str, Table], summary: Any = None) -> List[Drawer]:
    d, m = tables["density"], tables["moments"]

    def density(ax: Any) -> None:
        _band(ax, d, "v", "p", "p_err", "time average")
        ax.plot(d["v"], d["p_final"], "--", lw=1, label="at $t_{max}$")
        ax.set(xlabel="v", ylabel="$P_s(v)$", title="velocity density")
        _fit_y(ax)
        _atoms(ax, summary)

    def moments(ax: Any) -> None:
        keep = log_thin(m["t"])
        for y, label, color in (("v2", "⟨v²⟩", "C0"), ("x2", "⟨x²⟩", "C3")):
            ax.errorbar(m["t"][keep], m[y][keep], yerr=np.nan_to_num(m[y + "_err"][keep]),
                        fmt="o", ms=3, color=color, label=label)
        ax.set(xscale="log", yscale="log", xlabel="t", ylabel="⟨v²⟩, ⟨x²⟩", title="moments")
        power_law_guides(ax, m["t"], m["x2"])

    drawers = [density, moments]
    if "position" in tables:
        pos = tables["position"]

        def position(ax: Any) -> None:
            _band(ax, pos, "x", "p", "p_err", "x($t_{max}$)")
            ax.set(xlabel="x", ylabel="P(x)", title="position density")
            _fit_y(ax)
        drawers.append(position)
    return drawers


def state_names(res: Any, n: int) -> List[str]:
    """Legend names of the noise states: η = ±Σ of the telegraph noise, the
    levels of the summary otherwise (pause and run for rpt noise)."""
    summary = res.summary if isinstance(res.summary, dict) else {}
    levels = summary.get("levels") or []
    noise = str((_model(res.params) or {}).get("noise") or "")
    names = []
    for k in range(n):
        if k >= len(levels):
            names.append(f"state {k}")
            continue
        eta = f"η = {_num(levels[k])}".replace("= -", "= −")
        if noise.startswith("rpt:"):
            eta = f"pause ({eta})" if levels[k] == 0 else f"run ({eta})"
        names.append(eta)
    return names


def _exact_r0(ax: Any, res: Any) -> None:
    """The exact density without resetting (``irtp.analytic``) of the run's
    telegraph noise and drag, a grey guide beside a density at r > 0; not
    for another noise, a thermal noise, a drag without it, or r = 0."""
    m = _model(res.params) or {}
    if m.get("noise") or m.get("temperature") or not m.get("rate") or "sigma" not in m:
        return
    from . import analytic
    try:
        exact = analytic(drag=m["drag"], sigma=m["sigma"], lambda_=m["lambda"], points=400)
    except Exception:  # a drag or parameters without the closed form: no guide
        return
    d = exact.tables["density"]
    ax.plot(d["v"], d["p"], ":", color="0.4", gid="guide", label="exact at r = 0")


def _density(res: Any, parts: bool) -> List[Drawer]:
    t = res.tables["density"]

    def draw(ax: Any) -> None:
        if not parts:
            ax.plot(t["v"], t["p"], "k", label="$P_s(v)$, exact (r = 0)")
        else:
            ax.plot(t["v"], t["p"], "k", label="$P_s(v)$, all states")
            if "p_plus" in t:
                cols, names = ["p_plus", "p_minus"], ["η = +Σ", "η = −Σ"]
            else:
                cols = [c for c in t if c.startswith("p_") and c[2:].isdigit()]
                names = state_names(res, len(cols))
            for k, (c, name) in enumerate(zip(cols, names)):
                ax.plot(t["v"], t[c], ("--", ":")[k % 2], color=f"C{k}", label=name)
            _exact_r0(ax, res)
        ax.set(xlabel="v", ylabel="$P_s(v)$", title="stationary velocity density")
        _fit_y(ax)
        _atoms(ax, res.summary)
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
        ax.set(xlabel="v", ylabel="P(v, t)", title="density snapshots")
        _fit_y(ax)

    def moments(ax: Any) -> None:
        _lines(ax, m, "t", ("v2", "v_mean"), ("⟨v²⟩", "⟨v⟩"))
        ax.set(xlabel="t", ylabel="⟨v²⟩, ⟨v⟩", title="moments")
    return [snapshots, moments]


def _fp_msd(tables: Dict[str, Table]) -> List[Drawer]:
    m = {k: c[tables["moments"]["t"] > 0] for k, c in tables["moments"].items()}
    early: List[Optional[int]] = [None]

    def msd(ax: Any) -> None:
        _band(ax, m, "t", "x2", "x2_err", "⟨x²⟩")
        ax.set(xscale="log", yscale="log", xlabel="t", ylabel="⟨x²⟩",
               title="mean squared displacement")
        early[0] = power_law_guides(ax, m["t"], m["x2"])

    def alpha(ax: Any) -> None:
        ax.plot(m["t"], m["alpha"], color="C3", label="α = d ln⟨x²⟩ / d ln t")
        x2 = m["x2"]
        k = early[0] if early[0] is not None else power_law_guides_exponent(m["t"], x2)
        levels = [(2, "ballistic, α = 2"), (1, "diffusive, α = 1")]
        if k not in (None, 2):
            levels.append((k, f"early, α = {k}"))
        for level, text in levels:
            ax.axhline(level, ls="--", color="0.45", lw=1, gid="guide")
            ax.annotate(text, (m["t"][0] * 1.3, level + 0.05), color="0.4")
        ax.set(xscale="log", xlabel="t", ylabel="α", title="exponent")
    return [msd, alpha]


def power_law_guides_exponent(t: np.ndarray, x2: np.ndarray) -> Optional[int]:
    """The early exponent :func:`power_law_guides` draws, without drawing."""
    ok = np.flatnonzero((t > 0) & (x2 > 0) & np.isfinite(x2))
    if ok.size < 2 or t[ok[-1]] < 10 * t[ok[0]]:
        return None
    a = ok[0]
    c = next((i for i in ok if t[i] >= 10 * t[a]), ok[-1])
    return int(np.clip(round(np.log(x2[c] / x2[a]) / np.log(t[c] / t[a])), 2, 4))


def _mfpt(tables: Dict[str, Table]) -> List[Drawer]:
    if "profile" not in tables:
        return [_survival(tables["survival"])]
    t = tables["profile"]

    def profile(ax: Any) -> None:
        _lines(ax, t, "v0", ("tau", "tau_plus", "tau_minus"), ("τ", "$τ_+$", "$τ_-$"))
        ax.set(xlabel="$v_0$", ylabel="τ", title="mean first-passage time")
    return [profile]


def _scan(tables: Dict[str, Table], summary: Any) -> List[Drawer]:
    if "rate_grid" in tables:
        t, axis = tables["rate_grid"], "rate"
    else:
        t = tables["mfpt_scan"]
        axis = next(iter(t))

    def draw(ax: Any) -> None:
        labels = ("τ (backward equations)", "$τ_+$", "$τ_-$")
        _lines(ax, t, axis, ("tau", "tau_plus", "tau_minus"), labels)
        if "tau_sim" in t:
            ax.errorbar(t[axis], t["tau_sim"], yerr=np.nan_to_num(t["tau_sim_err"]), fmt="o",
                        label="τ (sampled)")
        if isinstance(summary, dict) and summary.get("r_opt") is not None:
            r, tau = summary["r_opt"], summary["tau_opt"]
            ax.plot([r], [tau], "o", color="C3", label=f"optimum: τ = {_num(tau)} at r = {_num(r)}")
        elif np.isfinite(t["tau"]).any():
            i = int(np.nanargmin(t["tau"]))
            ax.plot([t[axis][i]], [t["tau"][i]], "o", color="C3",
                    label=f"smallest τ = {_num(t['tau'][i])} at {param_symbol(axis)} = "
                          f"{_num(t[axis][i])}")
        x = t[axis][np.isfinite(t[axis])]
        if x.size and x.min() > 0 and x.max() / x.min() > 30:
            ax.set_xscale("log")
        ax.set(xlabel=param_symbol(axis), ylabel="τ", title="mean first-passage time")
        _fit_y(ax)
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
        _fit_y(ax)
    return [survival, density]


def drawers(res: Any) -> List[Drawer]:
    """The panels of ``res``'s picture, each a function drawing into an Axes."""
    tables, command = res.tables, res.command
    if command == "simulate":
        return _simulate(tables, res.summary)
    if command in ("analytic", "fp stationary"):
        return _density(res, command == "fp stationary")
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


def figure_title(res: Any) -> str:
    """``irtp COMMAND: parameters`` (the scanned one left out)."""
    params = res.params if isinstance(res.params, dict) else {}
    scanned = {"mfpt optimize": ["rate"], "mfpt scan": [params.get("over", "")]}
    p = title_parameters(params, scanned.get(res.command, []))
    return f"irtp {res.command}" + (f": {p}" if p else "")


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
        fig.suptitle(figure_title(res))
    for draw, a in zip(chosen, axes):
        draw(a)
        if a.get_legend_handles_labels()[0]:
            a.legend(fontsize="small")
    axes[0].figure.tight_layout()
    return axes[0]


def distinct_labels(values: Sequence[float]) -> List[str]:
    """Labels rounded to the fewest significant digits that keep them
    distinct and within 5 % (0.31622776601683794 reads 0.32 beside 0.1)."""
    for d in range(1, 9):
        labels = [f"{v:.{d}g}" for v in values]
        close = all(abs(float(s) - v) <= 0.05 * abs(v) for s, v in zip(labels, values))
        if close and len(set(labels)) == len(labels):
            return labels
    return [f"{v:.9g}" for v in values]


def log_spaced(values: Sequence[float]) -> bool:
    """Whether increasing positive values are evenly spaced in log rather
    than in value (a plan's ``spacing = "log"``); two a factor 10 apart too."""
    v = np.asarray(values, float)
    if v.size < 2 or not np.all(np.isfinite(v) & (v > 0)):
        return False
    if v.size == 2:
        return v[1] / v[0] >= 10

    def even(u: np.ndarray) -> bool:
        d = np.diff(u)
        return bool(np.all(np.abs(d - d.mean()) <= 0.02 * abs(d.mean())))
    ratio = v[-1] / v[0]
    return ratio >= 4 and not even(v) and (even(np.log10(v)) or ratio >= 100)


def edges(values: Sequence[float], log: bool) -> np.ndarray:
    """Cell edges around increasing values: midpoints (geometric when
    ``log``), the outer ones half a step beyond."""
    u = np.log10(np.asarray(values, float)) if log else np.asarray(values, float)
    if u.size == 1:
        h = 0.15 if log else 0.5 * (1 + abs(u[0]))
        e = np.array([u[0] - h, u[0] + h])
    else:
        mid = (u[1:] + u[:-1]) / 2
        e = np.concatenate([[u[0] - (u[1] - u[0]) / 2], mid, [u[-1] + (u[-1] - u[-2]) / 2]])
    return 10 ** e if log else e


def _axis_values(ds: Any, dim: str) -> Tuple[np.ndarray, List[str], bool, bool]:
    """Positions, tick labels, log and numeric of a sweep dimension: the
    values for a numeric increasing axis, else 0, 1, ... with the values
    (a zip group's joined) as labels."""
    raw = ds[dim].values
    numeric = raw.dtype.kind in "fiu" and not dim.startswith("zip_")
    if numeric and raw.size and np.all(np.diff(raw.astype(float)) > 0):
        v = raw.astype(float)
        return v, distinct_labels(v.tolist()), log_spaced(v), True
    labels = []
    coords = _zip_coords(ds, dim)
    for i in range(raw.size):
        parts = [f"{param_symbol(c)} = {ds[c].values[i]}" for c in coords] or [str(raw[i])]
        labels.append(", ".join(parts))
    return np.arange(raw.size, dtype=float), labels, False, False


def _zip_coords(ds: Any, dim: str) -> List[str]:
    """The parameters of a ``[[zip]]`` dimension (none for a crossed axis)."""
    if not dim.startswith("zip_"):
        return []
    return [str(c) for c, x in ds.coords.items() if x.dims == (dim,) and c not in (dim, "point")]


def _dim_label(ds: Any, dim: str) -> str:
    """A dimension's label: its symbol, or its zip group's symbols."""
    coords = _zip_coords(ds, dim)
    return ", ".join(param_symbol(c) for c in coords) if coords else param_symbol(dim)


def _set_axis(ax: Any, which: str, pos: np.ndarray, labels: List[str], log: bool,
              numeric: bool, label: str) -> None:
    set_scale = ax.set_xscale if which == "x" else ax.set_yscale
    set_label = ax.set_xlabel if which == "x" else ax.set_ylabel
    if log:
        set_scale("log")
    if not numeric or len(pos) <= 8:
        from matplotlib.ticker import FixedLocator, NullLocator
        axis = ax.xaxis if which == "x" else ax.yaxis
        axis.set_major_locator(FixedLocator(pos))
        axis.set_minor_locator(NullLocator())
        (ax.set_xticklabels if which == "x" else ax.set_yticklabels)(labels)
    set_label(label)


def plot_sweep(ds: Any, var: Optional[str] = None, ax: Any = None) -> Any:
    """The picture of ``var`` over a sweep's Dataset, as ``irtp plot DIR
    --var VAR`` draws it: one axis a line with error bars (``VAR_err``, log
    axes where the plan's values are log-spaced and the values span
    decades, the r⁻² law beside D_eff(r)); two axes a heat map on cells
    edged between the plan's values (geometric on log-spaced axes), the
    colour bar labelled with the quantity's symbol; more axes small
    multiples (one heat map per value of the further axes, at most 12, one
    colour scale). The Axes drawn into (the first panel's)."""
    import matplotlib.pyplot as plt

    dims = [str(d) for d in ds["point"].dims]
    scalars = [str(n) for n, v in ds.data_vars.items()
               if tuple(str(d) for d in v.dims) == tuple(dims) and v.dtype.kind in "fiu"
               and str(n) not in ("wall_time_s", "point") and not str(n).endswith("_err")]
    if var is None:
        if not scalars:
            raise ValueError("the sweep has no numeric variable over its axes")
        var = scalars[0]
    name = var[len("result."):] if var.startswith("result.") else var
    if name not in scalars:
        raise ValueError(f"var={var!r}: not a numeric variable over the axes; one of "
                         f"{', '.join(scalars)}")
    if len(dims) == 1:
        return _sweep_line(ds, dims[0], name, ax)
    return _sweep_heat(ds, dims, name, ax, plt)


SWEEP_TITLE_KEYS = ("drag", "noise", "sigma", "lambda", "rate", "reset_velocity", "reset_period",
                    "temperature", "v0", "vt", "xt", "reset_position")


def sweep_title(ds: Any, name: str) -> str:
    """``D_eff over a sweep of fp stationary: tan drag, Σ = 3`` from the
    Dataset's attributes (the plan's command and fixed parameters)."""
    head = f"{result_symbol(name)} over a sweep"
    command = ds.attrs.get("command")
    if command:
        head += f" of {command}"
    fixed = []
    for k in SWEEP_TITLE_KEYS:
        v = ds.attrs.get(f"fixed.{k}")
        if v is None:
            continue
        try:
            v = float(v)
        except ValueError:
            pass
        a = _assignment(k, v)
        if a:
            fixed.append(a)
    return head + (f": {', '.join(fixed)}" if fixed else "")


def _sweep_line(ds: Any, dim: str, name: str, ax: Any) -> Any:
    import matplotlib.pyplot as plt

    if ax is None:
        ax = plt.subplots(figsize=(6.4, 4.8))[1]
    pos, labels, log, numeric = _axis_values(ds, dim)
    y = np.asarray(ds[name].values, float)
    err = np.asarray(ds[name + "_err"].values, float) if name + "_err" in ds else None
    ax.errorbar(pos, y, yerr=None if err is None else np.nan_to_num(err), fmt="o-",
                label=result_symbol(name))
    fin = y[np.isfinite(y)]
    ylog = fin.size > 0 and fin.min() > 0 and fin.max() / fin.min() > 30
    if ylog:
        ax.set_yscale("log")
    _set_axis(ax, "x", pos, labels, log, numeric, _dim_label(ds, dim))
    ax.set_ylabel(result_symbol(name))
    if dim == "rate" and name.startswith("d_eff") and log and ylog:
        k = np.flatnonzero(np.isfinite(y) & (y > 0))[-1]
        r1 = pos[k]
        r0 = max(r1 / 10, pos[0])
        xs = np.geomspace(r0, r1, 11)
        _guide(ax, xs, y[k] * (r1 / xs) ** 2, "∝ $r^{-2}$")
    if name.startswith("tau") and np.isfinite(y).any():
        i = int(np.nanargmin(y))
        ax.plot([pos[i]], [y[i]], "o", color="C3",
                label=f"smallest: {_num(y[i])} at {_dim_label(ds, dim)} = {labels[i]}")
    ax.legend(fontsize="small")
    ax.set_title(sweep_title(ds, name))
    ax.figure.tight_layout()
    return ax


def _sweep_heat(ds: Any, dims: List[str], name: str, ax: Any, plt: Any) -> Any:
    from matplotlib.colors import LogNorm, Normalize

    rest = dims[2:]
    sizes = [ds.sizes[d] for d in rest]
    combos = list(np.ndindex(*sizes))[:MAX_PANELS] if rest else [()]
    values = np.asarray(ds[name].values, float)
    fin = values[np.isfinite(values)]
    log = fin.size > 0 and fin.min() > 0 and fin.max() / fin.min() > 30
    lo, hi = (fin.min(), fin.max()) if fin.size else (0.0, 1.0)
    norm = LogNorm(lo, hi) if log else Normalize(lo, hi)
    if ax is not None:
        axes, combos = [ax], combos[:1]
    else:
        cols = min(len(combos), 3)
        rows = -(-len(combos) // cols)
        _, grid = plt.subplots(rows, cols, figsize=(6.4 * cols, 4.8 * rows), squeeze=False)
        axes = list(grid.flat)
        for extra in axes[len(combos):]:
            extra.remove()
    (ypos, ylab, ylog, ynum), (xpos, xlab, xlog, xnum) = (
        _axis_values(ds, dims[0]), _axis_values(ds, dims[1]))
    for a, combo in zip(axes, combos):
        sel = dict(zip(rest, combo))
        z = np.asarray(ds[name].isel(sel).transpose(*dims[:2]).values, dtype=float)
        xe = edges(xpos, xlog) if xnum else np.arange(len(xpos) + 1) - 0.5
        ye = edges(ypos, ylog) if ynum else np.arange(len(ypos) + 1) - 0.5
        mesh = a.pcolormesh(xe, ye, np.ma.masked_invalid(z), cmap="viridis", norm=norm,
                            shading="flat")
        a.figure.colorbar(mesh, ax=a, label=result_symbol(name))
        _set_axis(a, "x", xpos, xlab, xlog, xnum, _dim_label(ds, dims[1]))
        _set_axis(a, "y", ypos, ylab, ylog, ynum, _dim_label(ds, dims[0]))
        at = []
        for d, i in sel.items():
            _, labels, _, _ = _axis_values(ds, d)
            at.append(labels[i] if "=" in labels[i] else f"{_dim_label(ds, d)} = {labels[i]}")
        a.set_title(", ".join(at) if at else sweep_title(ds, name))
    if len(axes) > 1:
        axes[0].figure.suptitle(sweep_title(ds, name))
    axes[0].figure.tight_layout()
    return axes[0]
