"""The public functions, one per CLI command.

Their keywords, defaults, help texts and choices are read at import time
from the Rust CLI definitions (``_irtp.describe``, ``_irtp.about``): the
flags have one home, and ``help(irtp.simulate)`` shows them. Only the
paper references, the table descriptions and the examples are written here.
"""

from __future__ import annotations

import inspect
import keyword
import warnings
import numbers
import os
import re
from typing import Any, Callable, Dict, List, Mapping, Optional, Tuple, Union

from . import _irtp
from ._model import Drag, Noise, Params, Reset
from ._progress import reporter
from ._results import Result, wrap

# Python function name -> CLI command.
COMMANDS = {
    "simulate": "simulate",
    "analytic": "analytic",
    "fp_stationary": "fp stationary",
    "fp_transient": "fp transient",
    "fp_msd": "fp msd",
    "mfpt": "mfpt",
    "mfpt_scan": "mfpt scan",
    "mfpt_optimize": "mfpt optimize",
    "mfpt_distribution": "mfpt distribution",
    "reproduce": "reproduce",
}

# Former names of a CLI choice: still accepted, with a FutureWarning.
_ALIASES = {"method": {"ode": "backward"}}

_KINDS: Dict[str, Any] = {"float": float, "int": int, "bool": bool, "str": str}

_EXTRAS_DOC = """\
params : Params or mapping, optional
    Model parameters (drag, sigma, lambda_, rate, reset_velocity) as one
    object; a field also given as its own keyword raises ValueError.
reset : PoissonReset, optional
    The reset rule; sets ``rate`` and ``reset_velocity``."""

_RUN_DOC = """\
progress : bool or callable, default False
    True: a progress bar (tqdm.auto if installed, else a line on stderr);
    a callable is called as ``progress(label, done, total)``.
threads : int, optional
    Worker threads for this call (default: all cores). Results are
    bit-identical for any number of threads."""


class Option:
    """One CLI flag, as ``_irtp.describe`` lists it, with its Python keyword."""

    def __init__(self, d: Mapping[str, Any]) -> None:
        self.name: str = d["name"]
        self.py: str = self.name + "_" if keyword.iskeyword(self.name) else self.name
        self.flag: str = d.get("flag") or "--" + self.name.replace("_", "-")
        self.help: str = d.get("help") or ""
        self.kind: str = d.get("kind") or "str"
        self.cli_default: Optional[str] = d.get("default")
        choices = d.get("choices")
        self.choices: Optional[Tuple[str, ...]] = tuple(choices) if choices else None
        self.required: bool = bool(d.get("required"))
        self.aliases: Dict[str, str] = {
            a: t for a, t in _ALIASES.get(self.name, {}).items()
            if self.choices and t in self.choices
        }

    def default(self) -> Any:
        """The CLI default as a Python value (None: no default)."""
        s = self.cli_default
        if self.kind == "bool":
            return s is not None and s.lower() == "true"
        if s is None:
            return None
        try:
            if self.kind == "float":
                return float(s)
            if self.kind == "int":
                return int(s)
        except ValueError:
            return s
        return s

    def annotation(self) -> Any:
        if self.name == "drag":
            return Union[str, Drag]
        if self.name == "noise":
            return Optional[Union[str, Noise]]
        if self.kind == "path":
            return Optional[Union[str, os.PathLike]]
        if self.kind == "list":
            return str
        base = _KINDS.get(self.kind, Any)
        if self.choices and self.kind == "str":
            from typing import Literal  # Python >= 3.8

            base = Literal[self.choices + tuple(self.aliases)]  # type: ignore[misc]
        if self.default() is None and not self.required and self.kind != "bool":
            return Optional[base]
        return base

    def convert(self, value: Any) -> Any:
        """A Python value → what ``_irtp.run`` takes for this option."""
        if self.name == "drag":
            return Drag(value).name
        if self.name == "noise" and isinstance(value, Noise):
            return value.spec
        if self.kind == "float" and isinstance(value, numbers.Real) and not isinstance(value, bool):
            return float(value)
        if self.kind == "int" and not isinstance(value, bool):
            if isinstance(value, numbers.Integral):
                return int(value)
            if isinstance(value, float) and value.is_integer():
                return int(value)
        if self.kind == "path":
            return os.fspath(value)
        if self.kind == "list":
            return [value] if isinstance(value, str) else [str(v) for v in value]
        if self.kind == "str" and self.choices and isinstance(value, str):
            if value in self.aliases:
                new = self.aliases[value]
                warnings.warn(
                    f"{self.py}={value!r} is the former name of {self.py}={new!r}; it runs {new!r}",
                    FutureWarning,
                    stacklevel=4,
                )
                value = new
            if value not in self.choices:
                allowed = ", ".join(self.choices + tuple(self.aliases))
                raise ValueError(f"invalid {self.py} = {value!r}: allowed one of {allowed}")
        if self.kind in ("float", "int"):
            # A string is never read as a number ('3' is a typo for 3 or a bug).
            what = "a real number" if self.kind == "float" else "an integer"
            raise TypeError(f"{self.py} must be {what}, not {type(value).__name__} {value!r}")
        return value


class Command:
    """A CLI command seen from Python: its options, signature and docstring."""

    def __init__(self, function: str, command: str) -> None:
        self.function = function
        self.command = command
        self.options: List[Option] = [Option(d) for d in _irtp.describe(command)]
        self.by_name: Dict[str, Option] = {o.name: o for o in self.options}
        self.by_py: Dict[str, Option] = {o.py: o for o in self.options}
        self.has_model = "sigma" in self.by_name
        self.has_reset = "rate" in self.by_name
        self.positional = self.by_name.get("figures")

    def extras(self) -> List[str]:
        out = ["params"] if self.has_model else []
        if self.has_reset:
            out.append("reset")
        return out + ["progress", "threads"]

    def known(self) -> str:
        return ", ".join([o.py for o in self.options if o is not self.positional] + self.extras())

    def signature(self) -> inspect.Signature:
        P = inspect.Parameter
        params: List[inspect.Parameter] = []
        if self.positional is not None:
            params.append(P(self.positional.py, P.VAR_POSITIONAL, annotation=str))
        for o in self.options:
            if o is self.positional:
                continue
            default = P.empty if o.required else o.default()
            params.append(P(o.py, P.KEYWORD_ONLY, default=default, annotation=o.annotation()))
        if self.has_model:
            params.append(P("params", P.KEYWORD_ONLY, default=None,
                            annotation=Optional[Union[Params, Mapping[str, Any]]]))
        if self.has_reset:
            params.append(P("reset", P.KEYWORD_ONLY, default=None, annotation=Optional[Reset]))
        params.append(P("progress", P.KEYWORD_ONLY, default=False,
                        annotation=Union[bool, Callable[[str, int, int], None]]))
        params.append(P("threads", P.KEYWORD_ONLY, default=None, annotation=Optional[int]))
        from . import _results

        ret = _results.RESULT_CLASS.get(self.command, Result)
        return inspect.Signature(params, return_annotation=ret)

    def flags_to_keywords(self, text: str) -> str:
        """``--t-max`` → ``t_max``, ``--lambda`` → ``lambda_`` for this command's flags."""
        flags = {o.flag: o for o in self.options}

        def sub(m: "re.Match[str]") -> str:
            o = flags.get(m.group(1))
            if o is None:
                return m.group(0)
            word = m.group(2)
            if word is not None and o.choices and word in o.choices:
                return f"{o.py}={word!r}"
            return o.py + (f" {word}" if word is not None else "")

        return re.sub(r"(--[a-z][a-z0-9-]*)(?: ([a-z][a-z0-9_]*))?", sub, text)

    def message(self, text: str) -> str:
        """An error message of the extension, naming the keyword the user typed
        (``invalid lambda = -1`` → ``invalid lambda_ = -1``)."""
        for o in self.options:
            if o.py != o.name:
                text = re.sub(rf"\binvalid {o.name} =", f"invalid {o.py} =", text)
                # In the allowed range too: a name next to a comparison.
                cmp = "[<>=\u2264\u2265\u2260]"
                text = re.sub(rf"(?<![\w-]){o.name}\b(?=\s*{cmp})", o.py, text)
                text = re.sub(rf"(?<={cmp} ){o.name}\b", o.py, text)
        return self.flags_to_keywords(text)

    def collect(self, figures: Tuple[Any, ...], kwargs: Dict[str, Any]) -> Dict[str, Any]:
        """Keywords and model objects → the options dict of ``_irtp.run``."""
        given: Dict[str, Tuple[Any, str]] = {}

        def put(name: str, value: Any, source: str) -> None:
            if value is None:
                return
            if name in given:
                py = self.by_name[name].py if name in self.by_name else name
                raise ValueError(f"{py} given twice (by {given[name][1]} and by {source})")
            given[name] = (value, source)

        params = kwargs.pop("params", None) if self.has_model else None
        reset = kwargs.pop("reset", None) if self.has_reset else None
        for key, value in kwargs.items():
            put(self.option_for(key).name, value, f"{key}=")
        if self.positional is not None and figures:
            put(self.positional.name, list(figures), "position")
        if reset is not None:
            if not isinstance(reset, Reset):
                raise TypeError(f"reset must be a reset rule such as PoissonReset, not {reset!r}")
            for name, value in reset.options().items():
                self.put_model(put, name, value, "reset=")
        if params is not None:
            if not isinstance(params, Params):
                params = Params.from_mapping(params)
            for name, value in params.options().items():
                self.put_model(put, name, value, "params=")
        return self.converted({name: value for name, (value, _) in given.items()})

    def option_for(self, key: str) -> Option:
        """The option a keyword names: ``lambda_`` and ``lambda`` both give ``lambda``."""
        if key in self.by_py and self.by_py[key] is not self.positional:
            return self.by_py[key]
        if key in self.by_name and self.by_name[key] is not self.positional:
            return self.by_name[key]
        raise ValueError(
            f"unknown keyword '{key}' for irtp.{self.function} (known: {self.known()})"
        )

    def put_model(self, put: Callable[[str, Any, str], None], name: str, value: Any,
                  source: str) -> None:
        """A field of a model object; a reset velocity 0 is dropped by commands
        without that flag (``analytic``)."""
        if name not in self.by_name:
            if name == "reset_velocity" and value == 0.0:
                return
            raise ValueError(f"irtp.{self.function} takes no {name} (given by {source})")
        put(name, value, source)

    def converted(self, options: Dict[str, Any]) -> Dict[str, Any]:
        out = {name: self.by_name[name].convert(value) for name, value in options.items()}
        missing = [o.py for o in self.options if o.required and o.name not in out]
        if missing:
            raise TypeError(
                f"irtp.{self.function}() missing required keyword argument"
                f"{'s' if len(missing) > 1 else ''}: {', '.join(repr(m) for m in missing)}"
            )
        return out

    def __call__(self, figures: Tuple[Any, ...], kwargs: Dict[str, Any]) -> Result:
        progress = kwargs.pop("progress", False)
        threads = kwargs.pop("threads", None)
        options = self.collect(figures, kwargs)
        if threads is not None and (
            isinstance(threads, bool) or not isinstance(threads, numbers.Integral) or threads < 1
        ):
            raise ValueError(f"invalid threads = {threads!r}: allowed threads >= 1")
        rep = reporter(progress)
        try:
            raw = _irtp.run(self.command, options, progress=rep,
                            threads=None if threads is None else int(threads))
        except ValueError as e:
            raise ValueError(self.message(str(e))) from None
        except _irtp.NumericalError as e:
            raise type(e)(self.message(str(e))) from None
        finally:
            if rep is not None:
                rep.close()
        return wrap(raw)


class Doc:
    """The hand-written part of a function's docstring."""

    def __init__(self, title: str, notes: str, returns: str, example: str) -> None:
        self.title, self.notes, self.returns, self.example = title, notes, returns, example


DOCS: Dict[str, Doc] = {
    "simulate": Doc(
        "Simulate independent particles of the inertial run-and-tumble process with resetting.",
        "Each particle follows dv/dt = -g(v) + eta(t), dx/dt = v (Eq. (5)), with\n"
        "telegraph noise ±sigma flipping at rate lambda_ (Eq. (6)) and velocity\n"
        "resetting v -> reset_velocity at rate ``rate`` (Eq. (3)). method='exact'\n"
        "(default) advances from event to event with closed-form flows (no time\n"
        "step); method='euler' is the paper's scheme, Eqs. (30)-(32). The\n"
        "stationary <v²> (Eq. (33)) is a time average over [burn_in, t_max];\n"
        "d_eff_msd fits <x²> = 2 D_eff t + c (Eq. (36)) over the same window.",
        "SimulateResult\n"
        "    moments: t, v_mean, v_mean_err, v2, v2_err, x_mean, x_mean_err, x2, x2_err\n"
        "        (``samples`` rows); density: v, p, p_err, p_final, p_final_err\n"
        "        (``bins`` rows). ``summary`` holds v2, v2_err, v_mean, d_eff_msd, ...\n"
        "        (``res.v2`` is the moments column; the stationary value is\n"
        "        ``res.summary['v2']``).",
        ">>> res = irtp.simulate(particles=2000, t_max=10, burn_in=5, seed=1)\n"
        ">>> res.t.shape, res.p.shape\n"
        "((201,), (100,))",
    ),
    "analytic": Doc(
        "Exact stationary velocity density without resetting (r = 0), its regime and moments.",
        "The closed forms Eq. (34) (tan drag) and Eq. (35) (tanh drag),\n"
        "normalised by singularity-removing quadrature; ``regime`` is the paper's\n"
        "case (i)-(iv) (tan) or (a)-(d) (tanh).",
        "AnalyticResult\n"
        "    density: v, p, cdf (``points`` Chebyshev points). ``summary`` holds\n"
        "        regime, regime_description, v2, v4, v_lower, v_upper, extrema, ...",
        ">>> res = irtp.analytic(drag='tan', sigma=3, lambda_=0.9)\n"
        ">>> res.regime\n"
        "'i'",
    ),
    "fp_stationary": Doc(
        "Stationary Fokker-Planck solution P±(v) with resetting: density, <v²>, exact D_eff.",
        "Solves the stationary forward equations Eqs. (11)-(12) (equivalently\n"
        "Eqs. (17)-(18)) by a direct O(N) finite-volume solve on a mesh graded\n"
        "toward the possibly singular edges, Richardson-extrapolated over cells\n"
        "and cells/2; <v²> is Eq. (33), D_eff the exact Green-Kubo value (the\n"
        "slope of Eq. (36)).",
        "FpStationaryResult\n"
        "    density: v, p, p_plus, p_minus, dv (``cells`` rows); ``summary`` holds\n"
        "        v2, v_mean, d_eff, mass, fine/coarse mesh values.",
        ">>> res = irtp.fp_stationary(drag='tan', sigma=3, lambda_=0.9, rate=2, cells=2000)\n"
        ">>> round(res.d_eff, 3) > 0\n"
        "True",
    ),
    "fp_transient": Doc(
        "Time-dependent Fokker-Planck solution from the paper's initial condition.",
        "Integrates Eqs. (11)-(12) from P± = 1/2 at v = 0: by default with the\n"
        "adaptive, L-stable TR-BDF2 on the graded mesh (step set by rtol/atol,\n"
        "Richardson in the mesh), or with scheme='paper', the explicit upwind\n"
        "scheme of Sec. 3 on a uniform mesh (step set by cfl); records <v²>(t)\n"
        "and density snapshots.",
        "FpTransientResult\n"
        "    moments: t, v2, v_mean, mass (``samples`` rows); snapshots: t, v, p,\n"
        "        p_plus, p_minus (``snapshots`` x ``cells`` rows, long format).",
        ">>> res = irtp.fp_transient(t_max=5, cells=1000)\n"
        ">>> res.t[-1]\n"
        "5.0",
    ),
    "fp_msd": Doc(
        "<x>(t), <x v>(t), <x²>(t) and d ln<x²>/d ln t without sampling.",
        "Solves the chain of x-weighted densities M_k = ∫ x^k P dx (k = 0, 1, 2;\n"
        "docs/equations.md (D1)) of the forward equations Eqs. (11)-(12) with TR-BDF2 on nested graded meshes and\n"
        "Richardson extrapolation, from x = v = 0; output times: t = 0 and a log\n"
        "grid from t_min to t_max.",
        "FpMsdResult\n"
        "    moments: t, mass, v_mean, v2, x_mean, xv, x2, alpha (``samples`` rows);\n"
        "        ``summary`` holds d_eff_slope (-> D_eff) and the final values.",
        ">>> res = irtp.fp_msd(drag='tanh', sigma=0.6, rate=1, t_min=0.5, t_max=2, samples=6, cells=32, levels=2)\n"
        ">>> len(res.t)\n"
        "6",
    ),
    "mfpt": Doc(
        "Mean first-passage time tau from v0 to the target velocity vt (Sec. 2.2).",
        "method='ode' (alias 'backward', default) solves the backward equations\n"
        "Eqs. (26)-(27) of the simulated process (drift ±sigma - g(v); the paper\n"
        "prints g(v) ± sigma) by a second-order box scheme; tau = (tau+ + tau-)/2,\n"
        "Eq. (28). method='exact' and 'euler' estimate Eq. (24) from first-passage\n"
        "particles (exact event-driven sampler, or Eqs. (30)-(32)). Particles not\n"
        "arrived by t_max are censored: then tau is None (never a mean of the\n"
        "arrived ones) and rmst ± rmst_err, the restricted mean E[min(T, t_max)],\n"
        "is its lower bound tau_lower_bound. With xt=L (or interval='A,B', from x0)\n"
        "instead of vt the target is a position (the search problem): method\n"
        "'backward' solves the 2-D backward equation (cells_x, cells_v), 'exact'\n"
        "samples it, 'renewal' (full resetting: reset_position) renews the\n"
        "reset-free survival of the time-dependent backward equation (cells_x,\n"
        "cells_v, time_steps, horizon_tail), 'euler' runs the Euler scheme at dt\n"
        "and dt/2 extrapolated to dt -> 0; with velocity-only resetting and a\n"
        "level the mean is infinite (tau None, summary['infinite_mean'], the tail\n"
        "exponent of S(t)).",
        "MfptResult\n"
        "    ``summary`` holds tau, tau_plus, tau_minus and error_estimate (ode) or\n"
        "        tau_err, particles, censored, censored_fraction, rmst, rmst_err,\n"
        "        tau_lower_bound (particles). ode also returns the table profile:\n"
        "        v0, tau_plus, tau_minus, tau over the mesh (in\n"
        "        ``res.tables['profile']``; ``res.tau`` is the scalar answer);\n"
        "        particles the table survival: t, survival, survival_err, at_risk\n"
        "        (the Kaplan-Meier curve of the first-passage times).",
        ">>> res = irtp.mfpt(v0=-0.249, vt=0.5, method='backward')\n"
        ">>> res.summary['tau'] > 0\n"
        "True",
    ),
    "mfpt_scan": Doc(
        "Mean first-passage time against the target velocity or the reset rate (Fig. 7).",
        "Solves the backward equations Eqs. (26)-(27) at every point of\n"
        "from_..to (linear, or logarithmic with log=True); with method='exact'\n"
        "or 'euler' every point is also simulated (same seed at every point:\n"
        "common random numbers). With a search target (xt=, interval=) the\n"
        "2-D backward equation (cells_x, cells_v) against over='rate', 'x0'\n"
        "or 'xt', method='exact' adding the sampler.",
        "MfptScanResult\n"
        "    mfpt_scan: <vt, rate, x0 or xt>, tau, tau_plus, tau_minus, error_estimate\n"
        "        [+ tau_sim, tau_sim_err, tau_plus_sim, tau_plus_sim_err,\n"
        "        tau_minus_sim, tau_minus_sim_err, censored, censored_fraction,\n"
        "        rmst_sim, rmst_sim_err with particles; tau_sim* are nan where\n"
        "        censored > 0, rmst_sim bounds tau there]\n"
        "        (``points`` rows); ``summary`` is the list of rows.",
        ">>> res = irtp.mfpt_scan(v0=-0.249, vt=0.5, over='rate', from_=0.01, to=100,\n"
        "...                      points=41, log=True)\n"
        ">>> res.rate.shape\n"
        "(41,)",
    ),
    "mfpt_optimize": Doc(
        "The reset rate r minimising the mean first-passage time (Fig. 7(b)).",
        "Compares r = 0 with a coarse log grid over [r_min, r_max] and refines\n"
        "the best bracket by golden section (Brent's method for a search\n"
        "target); every tau from the backward\n"
        "equations Eqs. (26)-(28); with a search target (xt=, interval=) from\n"
        "the 2-D backward equation (velocity-only resetting with xt= is\n"
        "refused: tau is infinite at every r). ``rate`` is refused.",
        "MfptOptimizeResult\n"
        "    rate_grid: rate, tau (the coarse grid); ``summary`` holds r_opt,\n"
        "        tau_opt_err, r_opt_range (the rates r* lies between given the\n"
        "        error estimates),\n"
        "        tau_opt, tau_r0, dtau_dr_r0, interior, at_upper_bound.",
        ">>> res = irtp.mfpt_optimize(v0=-0.249, vt=0.5)\n"
        ">>> res.interior\n"
        "True",
    ),
    "mfpt_distribution": Doc(
        "First-passage-time distribution from v0 to vt: survival S(t), density f(t), variance.",
        "method='backward' (default) integrates the time-dependent backward\n"
        "equations dS/dt = L S of the simulated process (the operator of\n"
        "Eqs. (26)-(27) with drift ±sigma - g(v)) on a monotone upwind mesh\n"
        "(two meshes, mesh_error = their largest difference) by TR-BDF2; the\n"
        "+ start has an atom at the flow time (atom_time, atom_mass), split off\n"
        "exactly: S+ drops by it, density is f of the rest. The moments come\n"
        "from L T1 = -1 (tau, Eq. (28)) and L T2 = -2 T1 (variance, cv); the\n"
        "distribution's own mean (distribution_mean) agrees with tau.\n"
        "method='exact': the exact sampler's histogram and Kaplan-Meier curve.\n"
        "With xt=L (or interval='A,B', from x0) the target is a position: method\n"
        "'backward' integrates the 2-D backward equation with the resets\n"
        "(cells_x, cells_v; points - 1 fixed steps to t_max), giving\n"
        "distribution: t, survival, survival_err, density.",
        "MfptDistributionResult\n"
        "    distribution: t, survival, density, survival_plus, density_plus,\n"
        "        survival_minus, density_minus (backward); histogram: t_lo, t_hi,\n"
        "        density, density_err, count and survival: t, survival,\n"
        "        survival_err, at_risk (exact); ``summary`` holds tau,\n"
        "        second_moment, variance, cv (per start state too).",
        ">>> res = irtp.mfpt_distribution(v0=-0.249, vt=0.5, cells=2000, points=11)\n"
        ">>> abs(res.summary['distribution_mean'] / res.summary['tau'] - 1) < 1e-5\n"
        "True",
    ),
    "reproduce": Doc(
        "Regenerate the paper's figures 1, 2, 3, 5, 6, 7 into a directory.",
        "Fig. 1: <v²>(t) against the stationary value Eq. (33); Figs. 2-3:\n"
        "stationary densities (particles, Fokker-Planck Eqs. (11)-(12), and the\n"
        "r = 0 closed forms Eqs. (34)-(35)); Figs. 5-6: <x²>(t) and D_eff\n"
        "(Eq. (36)); Fig. 7: mean first-passage times, Eqs. (26)-(28). Writes\n"
        "data (CSV), plots (PNG, SVG when the extension was built with plotting),\n"
        "parameters.json, claims.json / claims.md, REPORT.md and run.json; the\n"
        "claims compare each figure with the paper's statements.",
        "ReproduceResult\n"
        "    no tables; ``summary`` holds figures, claims, files; ``files`` lists\n"
        "        the written files.",
        ">>> res = irtp.reproduce('fig2', quick=True, out='results/quick')",
    ),
}


def _type_name(o: Option) -> str:
    if o.name == "drag":
        return "str or Drag"
    if o.kind == "path":
        return "str or os.PathLike"
    if o.choices and o.kind == "str":
        return "{" + ", ".join(repr(c) for c in o.choices + tuple(o.aliases)) + "}"
    return o.kind


def _default_text(o: Option) -> str:
    if o.required:
        return "required"
    d = o.default()
    return "optional" if d is None else f"default {d!r}"


def _wrap(text: str, indent: str = "    ") -> List[str]:
    import textwrap

    return textwrap.wrap(text, 76, initial_indent=indent, subsequent_indent=indent,
                         break_on_hyphens=False, break_long_words=False) or [indent]


def docstring(cmd: Command) -> str:
    """The function's docstring: title, the CLI's about text, paper notes,
    every keyword with its type, default and the CLI's help."""
    doc = DOCS[cmd.function]
    about = cmd.flags_to_keywords(_irtp.about(cmd.command).strip())
    lines = [doc.title, "", *about.splitlines(), "", *doc.notes.splitlines(), "",
             f"Same as ``irtp {cmd.command}`` (flags become keywords: ``--t-max`` -> ``t_max``,",
             "``--lambda`` -> ``lambda_``, ``--from`` -> ``from_``); same numbers, bit for bit.",
             "", "Parameters", "----------"]
    for o in cmd.options:
        if o is cmd.positional:
            lines.append(f"*{o.py} : str")
        else:
            lines.append(f"{o.py} : {_type_name(o)}, {_default_text(o)}")
        help_text = cmd.flags_to_keywords(o.help)
        alias = "".join(f"; '{a}' is the same as '{t}'" for a, t in o.aliases.items())
        lines += _wrap(f"{help_text}{alias} (CLI: {o.flag})")
    if cmd.has_model:
        lines += _EXTRAS_DOC.splitlines()[:3]
    if cmd.has_reset:
        lines += _EXTRAS_DOC.splitlines()[3:]
    lines += _RUN_DOC.splitlines()
    lines += ["", "Returns", "-------", *doc.returns.splitlines(), "",
              "Raises", "------",
              "ValueError", "    Invalid input, with the CLI's message naming the keyword.",
              "irtp.NumericalError", "    A numerical failure (a RuntimeError).",
              "KeyboardInterrupt", "    Ctrl-C (checked every 50 ms); nothing is written.",
              "", "Examples", "--------", ">>> import irtp", *doc.example.splitlines()]
    return "\n".join(lines)


def make_function(function: str) -> Callable[..., Result]:
    """The public function ``irtp.<function>``."""
    cmd = Command(function, COMMANDS[function])

    if cmd.positional is not None:

        def run_positional(*figures: Any, **kwargs: Any) -> Result:
            return cmd(figures, kwargs)

        fn: Callable[..., Result] = run_positional
    else:

        def run_keywords(**kwargs: Any) -> Result:
            return cmd((), kwargs)

        fn = run_keywords
    fn.__name__ = fn.__qualname__ = function
    fn.__module__ = "irtp"
    fn.__doc__ = docstring(cmd)
    fn.__signature__ = cmd.signature()  # type: ignore[attr-defined]
    fn._command = cmd  # type: ignore[attr-defined]
    return fn


simulate = make_function("simulate")
analytic = make_function("analytic")
fp_stationary = make_function("fp_stationary")
fp_transient = make_function("fp_transient")
fp_msd = make_function("fp_msd")
mfpt = make_function("mfpt")
mfpt_scan = make_function("mfpt_scan")
mfpt_optimize = make_function("mfpt_optimize")
mfpt_distribution = make_function("mfpt_distribution")
reproduce = make_function("reproduce")
