"""Results as labelled arrays: ``Result.to_xarray()``.

xarray is an optional dependency (``pip install './python[xarray]'``), imported
only when a Dataset is asked for, as pandas is for ``to_pandas()``.

The rules (docs/python.md, "Labelled arrays and sweeps as one dataset"):

- every table's first column is its dimension and coordinate (``t``, ``v``,
  ``x``, ``v0``, ``rate``, ...), its other columns are variables along it;
  ``fp transient``'s long-format snapshots become 2-D over
  (``t_snapshot``, ``v``);
- a column whose name an earlier table already used is ``<table>_<column>``
  (``position_p``), as a dimension whose name is taken with other values is;
- the summary's scalars are 0-d variables (null -> NaN); one named like a
  column is ``summary_<name>`` (but for ``mfpt``, whose scalars are the
  answer: there the profile's columns are ``profile_tau``, ...);
- every variable has ``long_name``, ``symbol`` (the paper's) and ``units``
  ("1": the model is dimensionless);
- the Dataset's attributes hold command, method, seed, version, the
  parameters (``param.<key>``, nested keys joined by ``.``), the
  provenance (``provenance.<key>``) and the summary's non-scalar entries
  (``result.<key>``), all as strings or numbers so ``to_netcdf`` works.
"""

from __future__ import annotations

import json
from typing import Any, Dict, Tuple

import numpy as np

# Summary keys that time the run or echo the output path (provenance, not results).
VOLATILE = ("wall_time_s", "particle_steps_per_s", "events_per_s", "out")

UNITS_NOTE = ("dimensionless: the paper's units (velocity, position, time and rates in the "
              "model's own units; densities per unit velocity or position)")

# name -> (long_name, symbol); tables may override per (table, name).
SYMBOLS: Dict[str, Tuple[str, str]] = {
    "t": ("time", "t"),
    "t_snapshot": ("snapshot time", "t"),
    "v": ("velocity", "v"),
    "x": ("position", "x"),
    "v0": ("start velocity", "v₀"),
    "vt": ("target velocity", "v_t"),
    "x0": ("start position", "x₀"),
    "xt": ("target level", "L"),
    "rate": ("reset rate", "r"),
    "lambda": ("noise flip rate", "λ"),
    "sigma": ("noise amplitude", "Σ"),
    "reset_velocity": ("reset velocity", "v_r"),
    "v_mean": ("mean velocity", "⟨v⟩"),
    "v2": ("mean square velocity", "⟨v²⟩"),
    "v4": ("fourth velocity moment", "⟨v⁴⟩"),
    "x_mean": ("mean position", "⟨x⟩"),
    "x2": ("mean square position", "⟨x²⟩"),
    "xv": ("position-velocity correlation", "⟨xv⟩"),
    "alpha": ("local exponent d ln⟨x²⟩/d ln t", "α"),
    "mass": ("total probability", "∫P dv"),
    "p": ("velocity density", "P(v)"),
    "p_plus": ("velocity density in noise state +Σ", "P₊(v)"),
    "p_minus": ("velocity density in noise state −Σ", "P₋(v)"),
    "p_final": ("velocity density at t_max", "P(v, t_max)"),
    "dv": ("cell width", "Δv"),
    "cdf": ("cumulative distribution of v", "F(v)"),
    "d_eff": ("effective diffusion coefficient", "D_eff"),
    "d_eff_msd": ("effective diffusion coefficient (fit of Eq. (36))", "D_eff"),
    "tau": ("mean first-passage time", "τ"),
    "tau_plus": ("mean first-passage time from noise state +Σ", "τ₊"),
    "tau_minus": ("mean first-passage time from noise state −Σ", "τ₋"),
    "tau_sim": ("mean first-passage time (particles)", "τ"),
    "survival": ("survival probability", "S(t)"),
    "survival_plus": ("survival probability from noise state +Σ", "S₊(t)"),
    "survival_minus": ("survival probability from noise state −Σ", "S₋(t)"),
    "density": ("first-passage-time density", "f(t)"),
    "density_plus": ("first-passage-time density from noise state +Σ", "f₊(t)"),
    "density_minus": ("first-passage-time density from noise state −Σ", "f₋(t)"),
    "at_risk": ("particles not yet arrived", "N(t)"),
    "count": ("particles in the bin", "n"),
    "t_lo": ("bin start time", "t_lo"),
    "t_hi": ("bin end time", "t_hi"),
    "r_opt": ("optimal reset rate", "r*"),
    "tau_opt": ("mean first-passage time at r*", "τ(r*)"),
    "tau_r0": ("mean first-passage time at r = 0", "τ(0)"),
    "refractory_mass": ("held point mass", "q₊ + q₋"),
}

_TABLE_SYMBOLS: Dict[Tuple[str, str], Tuple[str, str]] = {
    ("position", "p"): ("position density at t_max", "P(x)"),
    ("density", "p"): ("stationary velocity density", "P(v)"),
}


def require_xarray() -> Any:
    """The xarray module, or an ImportError naming the extra to install."""
    try:
        import xarray
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError(
            "irtp's labelled arrays need xarray: pip install './python[xarray]' "
            "in the irtp repository (xarray, pandas, h5netcdf, zarr), or pip install xarray"
        ) from e
    return xarray


def var_attrs(name: str, table: str = "") -> Dict[str, str]:
    """long_name, symbol and units of a column or summary value."""
    base, err = (name[:-4], True) if name.endswith("_err") else (name, False)
    long_name, symbol = _TABLE_SYMBOLS.get((table, base)) or SYMBOLS.get(
        base, (base.replace("_", " "), base))
    if err:
        long_name, symbol = f"standard error of {long_name}", f"σ[{symbol}]"
    return {"long_name": long_name, "symbol": symbol, "units": "1"}


def attr_value(value: Any) -> Any:
    """A JSON value as a netCDF-safe attribute: numbers and strings as they
    are, booleans as 0/1, numeric lists as arrays, anything else as JSON."""
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, int):
        return value if -(2**63) <= value < 2**63 else str(value)
    if isinstance(value, (float, str)):
        return value
    numeric = isinstance(value, list) and value and all(
        isinstance(x, (int, float)) and not isinstance(x, bool) for x in value)
    if numeric:
        return np.asarray(value, dtype=np.float64)
    return json.dumps(value)


def flat_attrs(prefix: str, value: Any, out: Dict[str, Any]) -> None:
    """``value`` into ``out``: nested dicts flattened to ``prefix.key.sub``."""
    if isinstance(value, dict) and value:
        for key, sub in value.items():
            flat_attrs(f"{prefix}.{key}", sub, out)
    else:
        out[prefix] = attr_value(value)


def is_scalar(value: Any) -> bool:
    """A summary value that becomes a 0-d variable."""
    return value is None or isinstance(value, (bool, int, float, str))


def scalar_array(value: Any) -> np.ndarray:
    """A summary scalar as a 0-d array (null -> NaN, huge ints as float)."""
    if value is None:
        return np.array(np.nan)
    if isinstance(value, int) and not isinstance(value, bool) and not -(2**63) <= value < 2**63:
        return np.array(float(value))
    # Strings as objects: netCDF and zarr write them as variable-length UTF-8.
    return np.array(value, dtype=object if isinstance(value, str) else None)


class Builder:
    """Collects a Dataset's variables and coordinates with the naming rules."""

    def __init__(self) -> None:
        self.data: Dict[str, Tuple[Tuple[str, ...], np.ndarray, Dict[str, str]]] = {}
        self.coords: Dict[str, Tuple[Tuple[str, ...], np.ndarray, Dict[str, str]]] = {}

    def taken(self, name: str) -> bool:
        return name in self.data or name in self.coords

    def dim(self, table: str, name: str, values: np.ndarray) -> str:
        """A dimension coordinate; renamed ``<table>_<name>`` when ``name``
        is taken with other values."""
        have = self.coords.get(name)
        if have is not None and have[0] == (name,) and same(have[1], values):
            return name
        dim = f"{table}_{name}" if self.taken(name) else name
        self.coords[dim] = ((dim,), values, var_attrs(name, table))
        return dim

    def add(self, table: str, name: str, dims: Tuple[str, ...], values: np.ndarray,
            attrs: Dict[str, str]) -> None:
        """A data variable; renamed ``<table>_<name>`` when taken."""
        if self.taken(name):
            name = f"{table}_{name}"
        self.data[name] = (dims, values, attrs)


def same(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal arrays bit for bit (NaN matches NaN)."""
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape or a.dtype != b.dtype:
        return False
    if a.dtype.kind == "f":
        return a.tobytes() == b.tobytes() or bool(np.array_equal(a, b, equal_nan=True))
    return bool(np.array_equal(a, b))


def add_table(b: Builder, table: str, columns: Dict[str, np.ndarray], command: str) -> None:
    """One table: its first column the dimension, the others along it."""
    names = list(columns)
    if not names:
        return
    if command == "fp transient" and table == "snapshots" and add_snapshots(b, columns):
        return
    dim = b.dim(table, names[0], np.asarray(columns[names[0]]))
    for name in names[1:]:
        b.add(table, name, (dim,), np.asarray(columns[name]), var_attrs(name, table))


def add_snapshots(b: Builder, columns: Dict[str, np.ndarray]) -> bool:
    """``fp transient``'s snapshots (blocks of rows, one per time, on one
    mesh) as 2-D variables over (t_snapshot, v); False when the rows are not
    such blocks (then they stay a 1-D table)."""
    t, v = np.asarray(columns["t"]), np.asarray(columns["v"])
    if t.size == 0:
        return False
    starts = np.flatnonzero(np.r_[True, t[1:] != t[:-1]])
    n = t.size // starts.size
    if t.size % starts.size or not np.array_equal(starts, np.arange(starts.size) * n):
        return False
    grid = v[:n]
    if not all(same(v[s:s + n], grid) for s in starts):
        return False
    b.coords["t_snapshot"] = (("t_snapshot",), t[starts], var_attrs("t_snapshot"))
    vdim = b.dim("snapshots", "v", grid)
    for name in list(columns)[2:]:
        values = np.asarray(columns[name]).reshape(starts.size, n)
        b.add("snapshots", name, ("t_snapshot", vdim), values, var_attrs(name))
    return True


def add_summary(b: Builder, summary: Any, rename_taken: bool) -> None:
    """The summary's scalars as 0-d variables (volatile ones and the seed
    are provenance). Taken names become ``summary_<name>`` when
    ``rename_taken``; otherwise the scalars are added first."""
    if not isinstance(summary, dict):
        return
    for key, value in summary.items():
        if key in VOLATILE or key == "seed" or not is_scalar(value):
            continue
        name = f"summary_{key}" if rename_taken and b.taken(key) else key
        b.data[name] = ((), scalar_array(value), {**var_attrs(key), "source": "summary"})


def dataset_attrs(res: Any) -> Dict[str, Any]:
    """The Dataset's attributes: what the run was, all netCDF-safe."""
    attrs: Dict[str, Any] = {
        "title": f"irtp {res.command}",
        "command": res.command,
        "method": res.method,
        "units": UNITS_NOTE,
        "model": "inertial run-and-tumble particle with velocity resetting (Howlader, "
                 "Mondal & Das, Velocity resetting of inertial run-and-tumble particles "
                 "in non-Newtonian media)",
    }
    if res.seed is not None:
        attrs["seed"] = attr_value(res.seed)
    version = res.provenance.get("version") if isinstance(res.provenance, dict) else None
    if version is not None:
        attrs["irtp_version"] = version
    flat_attrs("param", res.params, attrs)
    provenance = {k: v for k, v in (res.provenance or {}).items() if k != "parameters"}
    flat_attrs("provenance", provenance, attrs)
    if isinstance(res.summary, dict):
        for key, value in res.summary.items():
            if not is_scalar(value):
                flat_attrs(f"result.{key}", value, attrs)
            elif key in VOLATILE:
                attrs[f"result.{key}"] = attr_value(value)
    return attrs


def to_dataset(res: Any) -> Any:
    """``res`` (a Result) as an xarray.Dataset, by the module's rules."""
    xr = require_xarray()
    b = Builder()
    if res._summary_first:
        add_summary(b, res.summary, rename_taken=False)
    for table, columns in res.tables.items():
        add_table(b, table, columns, res.command)
    if not res._summary_first:
        add_summary(b, res.summary, rename_taken=True)
    return xr.Dataset(
        data_vars={k: (dims, v, a) for k, (dims, v, a) in b.data.items()},
        coords={k: (dims, v, a) for k, (dims, v, a) in b.coords.items()},
        attrs=dataset_attrs(res),
    )
