"""A sweep directory as one xarray Dataset (``irtp.load_sweep``) and its
export (``irtp.collect``: netCDF, zarr, CSV).

The plan is read back from ``sweep.json`` (its ``plan``: the TOML text as
given; ``plan.toml`` is the same text). Its axes are expanded as
``irtp sweep`` expands them (lists as written; ranges by the formulas of
``crates/irtp/src/numerics/grid.rs``), and each finished point of
``workspace/`` is placed on the grid by the parameters its
``signac_statepoint.json`` records, never by its position in a listing.

Stacking rules (docs/python.md, "Labelled arrays and sweeps as one dataset"):

- a crossed axis is a dimension with its values as coordinate; the k-th
  ``[[zip]]`` group is one dimension ``zip_<k>`` with each zipped parameter
  as a coordinate along it;
- every point's ``to_xarray()`` variables stack over (axes..., their own
  dims); scalar results become variables over the axes;
- a per-point dimension coordinate (``v``, ``t``) shared bit for bit by every
  point stays a coordinate; one that differs between points (the graded
  ``v`` mesh depends on the model) becomes the variable ``<dim>_grid`` over
  (axes..., dim), the dimension keeping its name without an index;
  shorter tables are padded with NaN;
- missing, failed and damaged points (a file whose checksum differs from
  the one its result.json records) are NaN ("" for strings) and listed in
  the attributes ``missing_points``, ``failed_points``, ``damaged_points``
  (JSON lists of {point, parameters[, id, error]}), never dropped.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import os
import pathlib
import shutil
import warnings
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from ._load import PathLike, load, read_json
from ._xarray import UNITS_NOTE, attr_value, flat_attrs, require_xarray, same, var_attrs

FORMATS = ("netcdf", "zarr", "csv")


def toml_loads(text: str) -> Dict[str, Any]:
    """Parse TOML (tomllib from Python 3.11, else the tomli package)."""
    try:
        import tomllib
    except ImportError:  # Python < 3.11
        try:
            import tomli as tomllib  # type: ignore[no-redef]
        except ImportError as e:
            raise ImportError("reading a sweep plan on Python < 3.11 needs tomli: "
                              "pip install './python[xarray]' in the irtp repository (or pip install tomli)") from e
    return tomllib.loads(text)


def linspace(a: float, b: float, n: int) -> List[float]:
    """``n`` points from a to b, the endpoints exact (as grid.rs's linspace)."""
    m = n - 1
    return [a if i == 0 else b if i == m else (a * (m - i) + b * i) / m for i in range(n)]


def axis_values(spec: Any) -> List[Any]:
    """An axis of the plan: a list as written, or a ``{from, to, points,
    spacing}`` range expanded as the sweep expands it."""
    if isinstance(spec, list):
        return spec
    a, b, n = float(spec["from"]), float(spec["to"]), int(spec["points"])
    if n == 1:
        return [a]
    if spec.get("spacing", "linear") == "log":
        inner = linspace(math.log10(a), math.log10(b), n)[1:-1]
        return [a, *(10.0 ** e for e in inner), b]
    return linspace(a, b, n)


class Grid:
    """The plan's axes: groups of names advancing together (a crossed axis
    is a group of one), the first group varying slowest."""

    def __init__(self, plan: Dict[str, Any]) -> None:
        axes, zips = plan.get("axes") or {}, plan.get("zip") or []
        self.groups: List[Tuple[List[str], List[Tuple[Any, ...]]]] = [
            ([k], [(v,) for v in axis_values(spec)]) for k, spec in axes.items()
        ]
        for z in zips:
            columns = [axis_values(spec) for spec in z.values()]
            self.groups.append((list(z), list(zip(*columns))))
        self.dims = [*axes, *(f"zip_{k}" for k in range(len(zips)))]
        self.shape = tuple(len(rows) for _, rows in self.groups)
        self.lookup = [{tuple(key(v) for v in row): i for i, row in enumerate(rows)}
                       for _, rows in self.groups]

    def place(self, params: Dict[str, Any]) -> Optional[Tuple[int, ...]]:
        """The grid position of a point's parameters (None: not this plan's)."""
        pos = []
        for (names, _), lookup in zip(self.groups, self.lookup):
            if any(n not in params for n in names):
                return None
            i = lookup.get(tuple(key(params[n]) for n in names))
            if i is None:
                return None
            pos.append(i)
        return tuple(pos)

    def parameters(self, pos: Tuple[int, ...]) -> Dict[str, Any]:
        """The axis parameters at a grid position."""
        out: Dict[str, Any] = {}
        for (names, rows), i in zip(self.groups, pos):
            out.update(zip(names, rows[i]))
        return out

    def coords(self) -> Dict[str, Any]:
        """The axis coordinates: a crossed axis its own, a zip group one per name."""
        out: Dict[str, Any] = {}
        for dim, (names, rows) in zip(self.dims, self.groups):
            for j, name in enumerate(names):
                out[name] = ((dim,), coord_array([r[j] for r in rows]), var_attrs(name))
        return out


def key(value: Any) -> Tuple[bool, Any]:
    """A parameter value as a dict key: 1 and 1.0 match, True and 1 do not."""
    return (isinstance(value, bool), value)


def coord_array(values: Sequence[Any]) -> np.ndarray:
    """Axis values as an array (strings as objects: variable-length in files)."""
    if any(isinstance(v, str) for v in values):
        return np.array(values, dtype=object)
    return np.asarray(values)


class Point:
    """One finished, failed or damaged point directory of the workspace."""

    def __init__(self, path: pathlib.Path, pos: Tuple[int, ...]) -> None:
        self.path, self.pos = path, pos
        result = path / "result.json"
        self.record: Optional[Dict[str, Any]] = (
            json.loads(result.read_text()) if result.is_file() else None)
        # The files are hashed once, here.
        self.damaged: Optional[str] = self.damage() if self.ok_record() else None

    def ok_record(self) -> bool:
        """Whether result.json says the point finished."""
        return self.record is not None and self.record.get("status") == "ok"

    @property
    def status(self) -> str:
        """"ok", "failed", "damaged" or "missing" (no result.json: killed)."""
        if self.record is None:
            return "missing"
        if not self.ok_record():
            return "failed"
        return "ok" if self.damaged is None else "damaged"

    def damage(self) -> Optional[str]:
        """The first file whose SHA-256 differs from result.json's record."""
        for name, checksum in (self.record or {}).get("files", {}).items():
            f = self.path / name
            if not f.is_file():
                return f"{name} deleted"
            if "sha256:" + hashlib.sha256(f.read_bytes()).hexdigest() != checksum:
                return f"{name} changed"
        return None


def scan(workspace: pathlib.Path, grid: Grid, plan: Dict[str, Any]) -> Dict[Tuple[int, ...], Point]:
    """The plan's point directories by grid position (hidden entries,
    leftovers of killed runs, and points of another plan are skipped)."""
    fixed = {k: key(v) for k, v in (plan.get("fixed") or {}).items()}
    points: Dict[Tuple[int, ...], Point] = {}
    if not workspace.is_dir():
        return points
    for d in sorted(workspace.iterdir()):
        sp = d / "signac_statepoint.json"
        if d.name.startswith(".") or not sp.is_file():
            continue
        state = json.loads(sp.read_text())
        params = state.get("parameters") or {}
        if state.get("command") != plan.get("command"):
            continue
        if any(key(params.get(k)) != v for k, v in fixed.items()):
            continue
        pos = grid.place(params)
        if pos is not None:
            points[pos] = Point(d, pos)
    return points


def stacked(values: Dict[Tuple[int, ...], np.ndarray], shape: Tuple[int, ...],
            complete: bool) -> np.ndarray:
    """Per-point arrays stacked over the grid (NaN or "" where absent, NaN
    padding for shorter rows; numbers as float64 unless every point has the
    variable with one dtype)."""
    arrays = list(values.values())
    inner = tuple(max(a.shape[k] for a in arrays) for k in range(arrays[0].ndim))
    dtypes = {a.dtype for a in arrays}
    text = any(a.dtype.kind in "OUS" for a in arrays)
    ragged = any(a.shape != inner for a in arrays)
    if text:
        out = np.full(shape + inner, "", dtype=object)
    elif complete and len(dtypes) == 1 and not ragged:
        out = np.empty(shape + inner, dtype=dtypes.pop())
    else:
        out = np.full(shape + inner, np.nan)
    for pos, a in values.items():
        # A 0-d object array assigned into an object array would be stored
        # as the array itself: assign its element.
        out[pos + tuple(slice(0, n) for n in a.shape)] = a if a.ndim else a.item()
    return out


def stack_coords(datasets: Dict[Tuple[int, ...], Any], grid: Grid) -> Dict[str, Any]:
    """The per-point dimension coordinates: shared (the same bit for bit at
    every point) as they are, else as ``<dim>_grid`` over (axes..., dim)."""
    coords: Dict[str, Any] = {}
    dims = dict.fromkeys(str(d) for ds in datasets.values() for d in ds.sizes)
    for dim in dims:
        have = {pos: ds[dim].values for pos, ds in datasets.items() if dim in ds.coords}
        if not have:
            continue
        first = next(iter(have.values()))
        if len(have) == len(datasets) and all(same(v, first) for v in have.values()):
            attrs = dict(next(ds for ds in datasets.values() if dim in ds.coords)[dim].attrs)
            coords[dim] = ((dim,), first, attrs)
        else:
            attrs = {**var_attrs(dim), "note": f"the {dim} grid of each point (they differ)"}
            coords[f"{dim}_grid"] = ((*grid.dims, dim), stacked(have, grid.shape, False), attrs)
    return coords


def stack_vars(datasets: Dict[Tuple[int, ...], Any], grid: Grid) -> Dict[str, Any]:
    """The data variables of every point over (axes..., their own dims)."""
    n, axes = math.prod(grid.shape), set(grid.coords())
    data: Dict[str, Any] = {}
    for name in dict.fromkeys(str(v) for ds in datasets.values() for v in ds.data_vars):
        have = {pos: ds[name].values for pos, ds in datasets.items() if name in ds.data_vars}
        first = next(ds for ds in datasets.values() if name in ds.data_vars)[name]
        dims = (*grid.dims, *(str(d) for d in first.dims))
        # A summary value named as a swept parameter (analytic's sigma) is
        # the command's own record of it: kept as summary_<name>.
        out = f"summary_{name}" if name in axes else name
        data[out] = (dims, stacked(have, grid.shape, len(have) == n), dict(first.attrs))
    return data


def listing(points: Sequence[Tuple[Tuple[int, ...], Optional[Point]]], grid: Grid,
            with_error: bool = False) -> str:
    """Points as a JSON list of {point, id, parameters[, error]} (attribute-safe)."""
    out = []
    for pos, p in points:
        entry: Dict[str, Any] = {"point": int(np.ravel_multi_index(pos, grid.shape)),
                                 "parameters": grid.parameters(pos)}
        if p is not None:
            entry["id"] = p.path.name
            if with_error:
                rec = p.record or {}
                entry["error"] = rec.get("error") if p.status == "failed" else p.damaged
        out.append(entry)
    return json.dumps(out)


def sweep_attrs(sweep: Dict[str, Any], plan: Dict[str, Any], grid: Grid,
                points: Dict[Tuple[int, ...], Point], methods: List[str]) -> Dict[str, Any]:
    """The Dataset's attributes: the plan, its provenance and the point lists."""
    attrs: Dict[str, Any] = {
        "title": f"irtp sweep: {plan.get('command')}",
        "command": str(plan.get("command")),
        "method": methods[0] if len(methods) == 1 else json.dumps(methods),
        "units": UNITS_NOTE,
        "plan": str(sweep.get("plan", "")),
        "plan_seed": attr_value(sweep.get("plan_seed")),
        "irtp_version": str(sweep.get("version", "")),
        "git_revision": str(sweep.get("git_revision", "")),
        "points": math.prod(grid.shape),
    }
    flat_attrs("fixed", plan.get("fixed") or {}, attrs)
    every = list(itertools.product(*(range(s) for s in grid.shape)))
    for status in ("missing", "failed", "damaged"):
        chosen = [(pos, points.get(pos)) for pos in every
                  if (points[pos].status if pos in points else "missing") == status]
        attrs[f"{status}_points"] = listing(chosen, grid, with_error=status != "missing")
        attrs[f"{status}_count"] = len(chosen)
    return attrs


def load_sweep(path: PathLike) -> Any:
    """Every point of a sweep directory (``irtp sweep run --out DIR``) stacked
    into one ``xarray.Dataset`` over the plan's axes.

    Crossed axes are dimensions (their values the coordinates); the k-th
    ``[[zip]]`` group is the dimension ``zip_<k>`` with its parameters as
    coordinates. Each point's ``to_xarray()`` variables (densities, moments,
    survival curves, and the scalar results: tau, d_eff, ...) stack over
    (axes..., their own dims); a per-point grid that differs between points
    becomes the variable ``<dim>_grid``. The coordinate ``point`` is the
    plan index (the ``point`` column of results.csv). Missing, failed and
    damaged points are NaN and listed in the attributes ``missing_points``,
    ``failed_points``, ``damaged_points`` (with ``*_count``).
    """
    xr = require_xarray()
    d = pathlib.Path(path)
    if not d.is_dir():
        raise FileNotFoundError(f"{d}: no such directory (a sweep directory holds sweep.json, "
                                "plan.toml and workspace/: irtp sweep run PLAN --out DIR)")
    sweep = read_json(d / "sweep.json") if (d / "sweep.json").is_file() else None
    if sweep is None:
        raise ValueError(f"{d} is not a sweep directory: it has no sweep.json (a sweep "
                         "directory holds sweep.json, plan.toml and workspace/, as "
                         "irtp sweep run PLAN --out DIR writes them)")
    plan = toml_loads(sweep.get("plan") or (d / "plan.toml").read_text())
    grid = Grid(plan)
    points = scan(d / "workspace", grid, plan)
    ok = {pos: p for pos, p in points.items() if p.status == "ok"}
    datasets = {pos: load(p.path).to_xarray() for pos, p in ok.items()}
    data, coords = stack_vars(datasets, grid), stack_coords(datasets, grid)
    coords.update(grid.coords())
    coords["point"] = (tuple(grid.dims), np.arange(math.prod(grid.shape)).reshape(grid.shape),
                       {"long_name": "point index in plan order (results.csv's point)"})
    methods = sorted({str(ds.attrs.get("method")) for ds in datasets.values()})
    return xr.Dataset(data_vars=data, coords=coords,
                      attrs=sweep_attrs(sweep, plan, grid, points, methods))


def netcdf_engine() -> str:
    """h5netcdf (with h5py) when installed, else netCDF4."""
    for engine, modules in (("h5netcdf", ("h5netcdf", "h5py")), ("netcdf4", ("netCDF4",))):
        try:
            for m in modules:
                __import__(m)
            return engine
        except ImportError:
            continue
    raise ImportError("writing netCDF needs h5netcdf and h5py (or netCDF4): "
                      "pip install './python[xarray]' in the irtp repository")


def write_csv(ds: Any, out: pathlib.Path, axes: Sequence[str]) -> None:
    """``ds`` as CSV files in the new directory ``out``: ``scalars.csv``
    (the variables over the axes alone, one row per point), one
    ``<dims>.csv`` per further set of dimensions (long format), and
    ``attrs.json``."""
    out.mkdir()
    groups: Dict[Tuple[str, ...], List[str]] = {}
    for name, var in ds.data_vars.items():
        groups.setdefault(tuple(str(d) for d in var.dims), []).append(str(name))
    for dims, names in groups.items():
        extra = [d for d in dims if d not in axes]
        stem = "_".join(extra) if extra else "scalars"
        ds[names].to_dataframe().to_csv(out / f"{stem}.csv")
    attrs = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in ds.attrs.items()}
    (out / "attrs.json").write_text(json.dumps(attrs, indent=1) + "\n")


class OutError(ValueError):
    """A refused output path (``out=``; ``--out`` on the command line):
    nothing was written and nothing removed."""

    def __init__(self, path: PathLike, allowed: str) -> None:
        self.path, self.allowed = str(path), allowed
        super().__init__(f"invalid out = {self.path!r}: allowed {allowed}")

    def cli(self) -> str:
        """The message as the command line names the flag."""
        return f"invalid --out {self.path!r}: allowed {self.allowed}"


def is_sweep_dir(d: pathlib.Path) -> bool:
    """Whether ``d`` is (or is being made into) an irtp sweep directory."""
    return (d / "sweep.json").is_file() or (
        (d / "plan.toml").is_file() and (d / "workspace").is_dir())


def ours_attrs(attrs: Any) -> bool:
    """Whether dataset attributes are those :func:`load_sweep` writes."""
    return (isinstance(attrs, dict) and str(attrs.get("title", "")).startswith("irtp sweep: ")
            and "plan" in attrs and "missing_points" in attrs)


def written_here(target: pathlib.Path, format: str) -> bool:
    """Whether the existing ``target`` is a ``format`` export this module
    wrote, holding nothing else (so replacing it loses nothing of the user's)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return written_as(target, format)
    except Exception:  # unreadable: not an export of this module
        return False


def written_as(target: pathlib.Path, format: str) -> bool:
    """:func:`written_here`'s checks (they may raise on foreign data)."""
    if format == "netcdf":
        if not target.is_file():
            return False
        xr = require_xarray()
        with xr.open_dataset(target, engine=netcdf_engine()) as ds:
            return ours_attrs(dict(ds.attrs))
    if not target.is_dir() or any(p.is_symlink() for p in target.rglob("*")):
        return False
    if format == "csv":
        names = [p.name for p in target.iterdir()]
        plain = all(p.is_file() for p in target.iterdir())
        return (plain and "attrs.json" in names and all(
            n == "attrs.json" or n.endswith(".csv") for n in names)
            and ours_attrs(json.loads((target / "attrs.json").read_text())))
    xr = require_xarray()
    with xr.open_zarr(target) as ds:
        known = {*map(str, ds.variables), "zarr.json", ".zgroup", ".zattrs", ".zmetadata"}
        return ours_attrs(dict(ds.attrs)) and all(
            p.name in known for p in target.iterdir())


def check_out(sweep: Optional[PathLike], out: PathLike, format: str) -> bool:
    """Refuse (:class:`OutError`) an output path that would touch a sweep
    directory or the user's files: one inside or equal to a sweep directory
    or any of its parts, one containing the sweep, one in a missing or
    unwritable directory, an existing file or directory this module did not
    write. Returns whether ``out`` exists (an earlier export, to replace)."""
    target = pathlib.Path(out)
    text = str(out)
    if not text or any(ord(c) < 32 or ord(c) == 127 for c in text):
        raise OutError(out, "a path without control characters (newline, tab, ...)")
    real = target.resolve()
    root = pathlib.Path(sweep).resolve() if sweep is not None else None
    for d in (real, *real.parents):
        if d == root or is_sweep_dir(d):
            raise OutError(out, f"a path outside the sweep directory {d} (collect never "
                                "writes into a sweep or any of its parts)")
    if root is not None and real in root.parents:
        raise OutError(out, f"a path that does not contain the sweep directory {root}")
    parent = real.parent
    if not parent.is_dir():
        raise OutError(out, f"a path in an existing directory ({parent} does not exist)")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise OutError(out, f"a path in a writable directory ({parent} is not)")
    if not os.path.lexists(target):
        return False
    kind = "file" if format == "netcdf" else "directory"
    if target.is_symlink() or not written_here(target, format):
        raise OutError(out, f"a new path, or a {format} {kind} irtp collect wrote (this one "
                            "holds other data; nothing was written: choose another path)")
    return True


def collect(path: PathLike, out: PathLike, format: str = "netcdf",
            engine: Optional[str] = None) -> pathlib.Path:
    """Write :func:`load_sweep`'s Dataset of the sweep directory ``path``:
    ``format="netcdf"`` (a .nc file; ``engine`` h5netcdf by default, or
    netcdf4), ``"zarr"`` (a zarr store directory) or ``"csv"`` (a directory:
    scalars.csv, one CSV per set of per-point dimensions, attrs.json).
    Returns ``out`` as a Path. Reopen with ``xarray.open_dataset`` /
    ``xarray.open_zarr``.

    ``out`` must be new, or an earlier export of this format (replaced
    whole); it may not lie in a sweep directory (this one or another) nor
    contain this one, and its directory must exist: otherwise
    :class:`OutError` (a ValueError), nothing written or removed."""
    if format not in FORMATS:
        raise ValueError(f"invalid format = {format!r}: allowed {', '.join(FORMATS)}")
    check_out(path, out, format)
    return write(load_sweep(path), out, format, engine, sweep=path)


def write_new(ds: Any, target: pathlib.Path, format: str, engine: Optional[str]) -> None:
    """``ds`` written as ``format`` to the path ``target``, which is free."""
    if format == "netcdf":
        ds.to_netcdf(target, engine=engine or netcdf_engine())
    elif format == "zarr":
        with warnings.catch_warnings():
            # zarr 3 notes that consolidated metadata is not in its format 3
            # spec; xarray writes it for fast opening and reads either way.
            warnings.filterwarnings("ignore", message=".*[Cc]onsolidated metadata.*")
            ds.to_zarr(target, mode="w-")
    else:
        write_csv(ds, target, [str(d) for d in ds["point"].dims])


def remove(path: pathlib.Path) -> None:
    """Remove a file or directory tree, if there."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    elif os.path.lexists(path):
        path.unlink()


def write(ds: Any, out: PathLike, format: str, engine: Optional[str] = None,
          sweep: Optional[PathLike] = None) -> pathlib.Path:
    """``ds`` (a :func:`load_sweep` Dataset of the directory ``sweep``)
    written as ``format`` to ``out``, checked by :func:`check_out`: staged
    beside it (``.NAME.partial-PID``) and renamed into place, an earlier
    export moved aside first and removed only once the new one is there. A
    failure leaves ``out`` as it was."""
    if format not in FORMATS:
        raise ValueError(f"invalid format = {format!r}: allowed {', '.join(FORMATS)}")
    target = pathlib.Path(out)
    exists = check_out(sweep, target, format)
    pid = os.getpid()
    staging = target.with_name(f".{target.name}.partial-{pid}")
    old = target.with_name(f".{target.name}.old-{pid}")
    remove(staging)
    try:
        write_new(ds, staging, format, engine)
        if exists:
            os.rename(target, old)
        try:
            os.rename(staging, target)
        except OSError:
            if exists:
                os.rename(old, target)
            raise
    finally:
        remove(staging)
    remove(old)
    return target
