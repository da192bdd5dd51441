"""``irtp.load``: a run's ``--out`` directory as the Result its function returns.

The directory is read by its output contract (docs/output-formats.md):
``run.json`` (provenance: command, method, seed, parameters, the files in
order), ``summary.json`` (``params`` and ``results``) and the CSV tables
``run.json`` lists, in its order (the order the module's tables have).
CSV numbers are shortest round-trip decimals, so parsing them with
Python's correctly rounded ``float`` gives the computed float64 bit for bit.
"""

from __future__ import annotations

import json
import os
import pathlib
from typing import Any, Dict, List, Union

import numpy as np

from ._results import Result, wrap

PathLike = Union[str, "os.PathLike[str]"]


def read_csv(path: pathlib.Path) -> Dict[str, np.ndarray]:
    """A CSV table the CLI wrote as ``{column: float64 array}`` (bit for bit)."""
    lines = path.read_text().splitlines()
    if not lines:
        raise ValueError(f"{path}: empty file (a CLI table has a header line)")
    header = lines[0].split(",")
    rows = [line.split(",") for line in lines[1:] if line]
    data = np.empty((len(rows), len(header)), dtype=np.float64)
    for i, row in enumerate(rows):
        if len(row) != len(header):
            raise ValueError(f"{path}, line {i + 2}: {len(row)} fields, the header has {len(header)}")
        data[i] = [float(x) for x in row]
    return {name: np.ascontiguousarray(data[:, j]) for j, name in enumerate(header)}


def read_json(path: pathlib.Path) -> Any:
    """A JSON file, or a FileNotFoundError naming what the directory lacks."""
    if not path.is_file():
        raise FileNotFoundError(
            f"{path} not found: not an irtp --out directory (every command writes run.json"
            " and, but for reproduce, summary.json)")
    return json.loads(path.read_text())


def check_not_sweep(d: pathlib.Path) -> None:
    """A sweep directory or a failed sweep point: a clear error."""
    if (d / "sweep.json").is_file():
        raise ValueError(f"{d} is a sweep directory: read it with irtp.load_sweep({str(d)!r})")
    result = d / "result.json"
    if result.is_file() and not (d / "run.json").is_file():
        status = json.loads(result.read_text())
        raise ValueError(f"{d}: a sweep point with status {status.get('status')!r} and no "
                         f"output ({status.get('error')})")


def reproduce_summary(d: pathlib.Path, run: Dict[str, Any]) -> Dict[str, Any]:
    """What ``irtp.reproduce`` returns as its summary, from its index files."""
    params = run.get("parameters") or {}
    claims = d / "claims.json"
    return {
        "figures": list((params.get("figures") or {}) if isinstance(params, dict) else []),
        "claims": json.loads(claims.read_text()) if claims.is_file() else [],
        "files": [str(d / f) for f in run.get("files") or []],
    }


def load(path: PathLike) -> Result:
    """Open a run's ``--out`` directory (any command, CLI or ``out=``) as the
    Result the Python function returns: ``irtp.load(d).to_xarray()`` equals
    the in-process result's ``.to_xarray()``, value for value.

    The CLI's text report is not stored (``text`` is empty); ``out`` is the
    directory and ``files`` its files (run.json's list). Raises
    FileNotFoundError for a directory without run.json, ValueError for a
    sweep directory (use :func:`irtp.load_sweep`) or a failed sweep point.
    """
    d = pathlib.Path(path)
    if not d.is_dir():
        raise FileNotFoundError(f"{d}: no such directory")
    check_not_sweep(d)
    run = read_json(d / "run.json")
    files: List[str] = list(run.get("files") or [])
    command = str(run["command"])
    if command.split()[0] == "reproduce":
        command, summary, params = "reproduce", reproduce_summary(d, run), run.get("parameters")
        tables: Dict[str, Dict[str, np.ndarray]] = {}
    else:
        doc = read_json(d / "summary.json")
        summary, params = doc.get("results"), doc.get("params")
        tables = {f[:-4]: read_csv(d / f) for f in files if f.endswith(".csv")}
    raw = {
        "command": command,
        "method": run.get("method"),
        "seed": run.get("seed"),
        "summary": summary,
        "parameters": params,
        "provenance": run,
        "tables": tables,
        "text": "",
        "out": str(d),
        "files": [str(d / f) for f in files],
    }
    return wrap(raw)
