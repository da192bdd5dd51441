"""Result objects: the dict returned by the extension, with the table columns
as numpy attributes (the extension's own arrays, never copied)."""

from __future__ import annotations

from typing import Any, Dict, List, Optional

import numpy as np

# The command's Python function name, for messages and reprs.
FUNCTION = {
    "simulate": "simulate",
    "analytic": "analytic",
    "fp stationary": "fp_stationary",
    "fp transient": "fp_transient",
    "fp msd": "fp_msd",
    "mfpt": "mfpt",
    "mfpt scan": "mfpt_scan",
    "mfpt optimize": "mfpt_optimize",
    "reproduce": "reproduce",
}

# Summary numbers a repr shows first, per command (others: the first few scalars).
_KEY_NUMBERS = {
    "simulate": ("particles", "v2", "v2_err", "v_mean", "v_mean_err", "d_eff_msd"),
    "analytic": ("regime", "v2", "v4", "v_lower", "v_upper"),
    "fp stationary": ("v2", "v_mean", "d_eff", "cells"),
    "fp transient": ("v2_final", "v_mean_final", "mass_error_max", "steps", "cells"),
    "mfpt": ("tau", "tau_err", "error_estimate", "tau_plus", "tau_minus", "censored",
             "censored_fraction", "tau_lower_bound", "rmst_err"),
    "mfpt optimize": ("r_opt", "tau_opt", "tau_r0", "interior", "at_upper_bound"),
    "reproduce": ("figures",),
}

_SCALARS = (bool, int, float, str, type(None))


def _plain(value: Any) -> bool:
    """A summary value exposed as an attribute: a scalar, or a short list of
    scalars (a range such as ``r_opt_range``)."""
    if isinstance(value, _SCALARS):
        return True
    return isinstance(value, list) and len(value) <= 4 and all(isinstance(x, _SCALARS) for x in value)


def _fmt(x: Any) -> str:
    if isinstance(x, float):
        return f"{x:.6g}"
    if isinstance(x, list):
        return "[" + ", ".join(_fmt(y) for y in x) + "]"
    return repr(x)


class Result:
    """What a computation returned.

    Attributes
    ----------
    command : str
        The CLI command ("simulate", "fp stationary", ...).
    method : str
        The numerical method (as in run.json).
    seed : int or None
        Master seed of stochastic methods.
    summary : dict or list
        Exactly what ``irtp <command> ... --json`` prints.
    params : dict
        The "parameters" object of run.json.
    provenance : dict
        run.json's content (software, version, argv: the equivalent CLI
        command line, method, seed, parameters, wall_time_s, threads, ...).
    tables : dict of dict of numpy.ndarray
        ``{table: {column: float64 array}}``; table names are the CSV file
        stems the CLI writes with ``--out``.
    text : str
        The CLI's text-mode report.
    out, files : str or None, list of str or None
        Output directory and written files, when ``out=`` was given.

    Every table column is also an attribute (``res.t``, ``res.v2``, ...;
    when two tables share a column name the first table's wins). Top-level
    scalars of ``summary`` (and short lists of them, such as
    ``r_opt_range``) are attributes too when no column or attribute
    of the same name exists (``res.d_eff``); ``res.summary[key]`` always
    works.
    """

    # Whether summary scalars shadow columns of the same name (mfpt: ``res.tau``
    # is the answer, the profile's column stays in ``res.tables``).
    _summary_first = False

    def __init__(self, raw: Dict[str, Any]) -> None:
        self.command: str = raw["command"]
        self.method: str = raw.get("method") or ""
        self.seed: Optional[int] = raw.get("seed")
        self.summary: Any = raw.get("summary")
        self.params: Dict[str, Any] = raw.get("parameters") or {}
        self.provenance: Dict[str, Any] = raw.get("provenance") or {}
        self.tables: Dict[str, Dict[str, np.ndarray]] = raw.get("tables") or {}
        self.text: str = raw.get("text") or ""
        self.out: Optional[str] = raw.get("out")
        self.files: Optional[List[str]] = raw.get("files")
        columns: Dict[str, np.ndarray] = {}
        for table in self.tables.values():
            for name, column in table.items():
                columns.setdefault(name, column)
        self._columns = columns

    def __getattr__(self, name: str) -> Any:
        # Only reached when ordinary lookup failed.
        if name.startswith("_"):
            raise AttributeError(name)
        columns = self.__dict__.get("_columns", {})
        summary = self.__dict__.get("summary")
        scalar = isinstance(summary, dict) and _plain(summary.get(name))
        if scalar and name in summary and self._summary_first:
            return summary[name]
        if name in columns:
            return columns[name]
        if scalar and name in summary:
            return summary[name]
        raise AttributeError(
            f"{type(self).__name__} of irtp.{FUNCTION.get(self.__dict__.get('command', ''), '?')} "
            f"has no column or summary value {name!r} (columns: {', '.join(columns) or 'none'})"
        )

    def __dir__(self) -> List[str]:
        names = set(super().__dir__()) | set(self._columns)
        if isinstance(self.summary, dict):
            names |= {k for k, v in self.summary.items() if _plain(v)}
        return sorted(names)

    def _key_numbers(self) -> List[str]:
        s = self.summary
        if isinstance(s, list):
            return [f"{len(s)} points"]
        if not isinstance(s, dict):
            return []
        keys = [k for k in _KEY_NUMBERS.get(self.command, ()) if s.get(k) is not None]
        if not keys:
            keys = [k for k, v in s.items() if isinstance(v, (int, float)) and k != "wall_time_s"][:4]
        return [f"{k} = {_fmt(s[k])}" for k in keys]

    def __repr__(self) -> str:
        head = f"<{type(self).__name__} irtp.{FUNCTION.get(self.command, self.command)}"
        head += f" method={self.method!r}"
        if self.seed is not None:
            head += f" seed={self.seed}"
        lines = [head]
        numbers = self._key_numbers()
        if numbers:
            lines.append("  " + ", ".join(numbers))
        for name, table in self.tables.items():
            shapes = {np.shape(c) for c in table.values()}
            shape = " x ".join(str(n) for n in shapes.pop()) if len(shapes) == 1 else "mixed"
            lines.append(f"  {name} [{shape}]: {', '.join(table)}")
        if self.files:
            lines.append(f"  wrote {len(self.files)} files to {self.out}")
        return "\n".join(lines) + ">"

    def to_dict(self, lists: bool = False) -> Dict[str, Any]:
        """Everything as one dict (keys: command, method, seed, summary, params,
        provenance, tables, text, out, files). Arrays stay numpy arrays (the
        same objects) unless ``lists=True``, which converts them to lists of
        floats (JSON-serialisable)."""
        tables: Dict[str, Dict[str, Any]] = {
            name: {col: (arr.tolist() if lists else arr) for col, arr in table.items()}
            for name, table in self.tables.items()
        }
        return {
            "command": self.command,
            "method": self.method,
            "seed": self.seed,
            "summary": self.summary,
            "params": self.params,
            "provenance": self.provenance,
            "tables": tables,
            "text": self.text,
            "out": self.out,
            "files": self.files,
        }

    def to_pandas(self, table: Optional[str] = None) -> Any:
        """The tables as pandas DataFrames (pandas is imported only here).

        One table (or ``table=name``): that DataFrame. Several: a dict
        ``{name: DataFrame}``. No table: a DataFrame of the summary (one row
        per scan point, or one row of the summary's scalars).
        """
        import pandas as pd

        if table is not None:
            return pd.DataFrame(self.tables[table])
        if len(self.tables) == 1:
            return pd.DataFrame(next(iter(self.tables.values())))
        if self.tables:
            return {name: pd.DataFrame(t) for name, t in self.tables.items()}
        if isinstance(self.summary, list):
            return pd.DataFrame(self.summary)
        scalars = {k: v for k, v in (self.summary or {}).items() if isinstance(v, _SCALARS)}
        return pd.DataFrame([scalars])

    def to_xarray(self) -> Any:
        """The result as an ``xarray.Dataset`` (xarray is imported only here;
        ``pip install './python[xarray]'``).

        Each table's first column is a dimension coordinate (``t``, ``v``,
        ``x``, ``v0``, ...) and its other columns are variables along it,
        standard errors as their own variables (``v2_err``); ``fp_transient``'s
        snapshots are 2-D over (``t_snapshot``, ``v``). The summary's scalars
        are 0-d variables (null as NaN; one named like a column is
        ``summary_<name>``, except for ``mfpt``, whose profile columns become
        ``profile_<name>``). Variables carry ``long_name``, ``symbol`` (the
        paper's) and ``units`` ("1": the model is dimensionless). Attributes:
        command, method, seed, irtp_version, ``param.*``, ``provenance.*``,
        ``result.*`` (non-scalar summary entries), flattened to strings and
        numbers so ``to_netcdf`` works.
        """
        from ._xarray import to_dataset

        return to_dataset(self)

    def plot(self, panel: Optional[int] = None, ax: Any = None) -> Any:
        """Draw the result's natural figure with matplotlib (imported only
        here; ``pip install './python[plot]'``): the figure ``irtp plot DIR``
        draws (densities with ±1 standard-error bands, moments on log axes,
        snapshots, survival curves, tau against the scanned quantity).

        Without arguments: every panel side by side in a new figure. With
        ``panel=k`` (0-based) or ``ax=``: one panel (the first by default)
        in a new Axes or in ``ax``. Returns the (first) Axes drawn into;
        ``ax.figure`` is its figure (``ax.figure.savefig("plot.png")``).
        Raises ValueError for a ``reproduce`` result (its figures are
        files already) or a panel out of range.
        """
        from ._plot import plot_result

        return plot_result(self, panel=panel, ax=ax)


class SimulateResult(Result):
    """Result of :func:`irtp.simulate`: tables "moments" and "density"."""


class AnalyticResult(Result):
    """Result of :func:`irtp.analytic`: table "density"."""


class FpStationaryResult(Result):
    """Result of :func:`irtp.fp_stationary`: table "density"."""


class FpTransientResult(Result):
    """Result of :func:`irtp.fp_transient`: tables "moments" and "snapshots"
    (long format; 2-D over (t_snapshot, v) in ``to_xarray()``)."""


class FpMsdResult(Result):
    """Result of :func:`irtp.fp_msd`: table "moments"."""


class MfptResult(Result):
    """Result of :func:`irtp.mfpt`: ``res.tau``, ``res.tau_plus``, ``res.tau_minus``
    are the answer (scalars); table "profile" (backward equations only) holds
    tau against the start velocity in ``res.tables["profile"]``. Particles:
    table "survival" (``res.t``, ``res.survival``, ``res.survival_err``,
    ``res.at_risk``: the Kaplan-Meier curve); when any particle is censored
    (``res.censored > 0``), ``res.tau`` is None and ``res.tau_lower_bound``
    (= ``res.rmst`` ± ``res.rmst_err``, the restricted mean) bounds it."""

    _summary_first = True


class MfptScanResult(Result):
    """Result of :func:`irtp.mfpt_scan`: table "mfpt_scan"."""


class MfptOptimizeResult(Result):
    """Result of :func:`irtp.mfpt_optimize`: table "rate_grid"."""


class MfptDistributionResult(Result):
    """Result of :func:`irtp.mfpt_distribution`: table "distribution"
    (backward) or "histogram" and "survival" (exact)."""


class ReproduceResult(Result):
    """Result of :func:`irtp.reproduce`: no tables; files in ``files``."""


RESULT_CLASS = {
    "simulate": SimulateResult,
    "analytic": AnalyticResult,
    "fp stationary": FpStationaryResult,
    "fp transient": FpTransientResult,
    "fp msd": FpMsdResult,
    "mfpt": MfptResult,
    "mfpt scan": MfptScanResult,
    "mfpt optimize": MfptOptimizeResult,
    "mfpt distribution": MfptDistributionResult,
    "reproduce": ReproduceResult,
}


def wrap(raw: Dict[str, Any]) -> Result:
    """The extension's dict as the command's Result class."""
    return RESULT_CLASS.get(raw["command"], Result)(raw)
