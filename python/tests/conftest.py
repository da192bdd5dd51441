"""Shared helpers: the irtp CLI binary and exact comparison of results.

The tests run against the installed extension (``pip install ./python``) and
the CLI binary of the same crate: ``$IRTP_BIN``, default
``target/release/irtp`` in the repository root (built by CI beforehand;
nothing is built here). Tests that need the binary are skipped when it is
missing (set ``IRTP_REQUIRE_CLI=1`` to make that an error).
"""

from __future__ import annotations

import json
import math
import os
import pathlib
import subprocess
from typing import Any, Dict, List, Optional, Sequence

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]

# Summary keys that measure time or echo the output path: everything else
# must be bit-identical between Python and the CLI.
VOLATILE = {"wall_time_s", "particle_steps_per_s", "events_per_s", "out"}


def irtp_bin() -> pathlib.Path:
    path = pathlib.Path(os.environ.get("IRTP_BIN") or REPO / "target" / "release" / "irtp")
    return path if path.is_absolute() else REPO / path


def flag(keyword: str) -> str:
    """The CLI flag of a Python keyword, by the documented rule:
    drop one trailing underscore, ``_`` -> ``-``, prefix ``--``."""
    name = keyword[:-1] if keyword.endswith("_") else keyword
    return "--" + name.replace("_", "-")


def argv_for(command: str, kwargs: Dict[str, Any]) -> List[str]:
    """The CLI arguments equivalent to a Python call's keywords."""
    argv = command.split()
    for key, value in kwargs.items():
        if isinstance(value, bool):
            if value:
                argv.append(flag(key))
        else:
            argv += [flag(key), repr(value) if isinstance(value, float) else str(value)]
    return argv


class Cli:
    def __init__(self, path: pathlib.Path) -> None:
        self.path = path

    def run(self, argv: Sequence[str], check: bool = True) -> subprocess.CompletedProcess:
        p = subprocess.run([str(self.path), *argv], capture_output=True, text=True, timeout=300)
        if check and p.returncode != 0:
            raise AssertionError(f"irtp {' '.join(argv)} failed: {p.stderr}")
        return p

    def json(self, argv: Sequence[str]) -> Any:
        return json.loads(self.run([*argv, "--json"]).stdout)

    def error(self, argv: Sequence[str]) -> str:
        """The one-line error message of a rejected command, without the prefix."""
        p = self.run(argv, check=False)
        assert p.returncode == 2, (p.returncode, p.stderr)
        line = p.stderr.strip().splitlines()[-1]
        return line.split("error: ", 1)[1]


@pytest.fixture(scope="session")
def cli() -> Cli:
    path = irtp_bin()
    if not path.exists():
        if os.environ.get("IRTP_REQUIRE_CLI"):
            pytest.fail(f"irtp CLI not found at {path} (set IRTP_BIN)")
        pytest.skip(f"irtp CLI not found at {path} (set IRTP_BIN)")
    return Cli(path)


def strip(summary: Any) -> Any:
    """The summary without the volatile keys (top level and in rows)."""
    if isinstance(summary, dict):
        return {k: v for k, v in summary.items() if k not in VOLATILE}
    if isinstance(summary, list):
        return [strip(x) for x in summary]
    return summary


def difference(a: Any, b: Any, path: str = "") -> Optional[str]:
    """None when ``a`` (Python) and ``b`` (parsed CLI JSON) are the same
    numbers bit for bit, else where they first differ. JSON writes NaN and
    infinities as null, so a null matches a non-finite float."""
    if isinstance(a, dict) and isinstance(b, dict):
        if set(a) != set(b):
            return f"{path}: keys {sorted(set(a) ^ set(b))} differ"
        for k in a:
            d = difference(a[k], b[k], f"{path}.{k}")
            if d:
                return d
        return None
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        if len(a) != len(b):
            return f"{path}: lengths {len(a)} != {len(b)}"
        for i, (x, y) in enumerate(zip(a, b)):
            d = difference(x, y, f"{path}[{i}]")
            if d:
                return d
        return None
    if b is None and isinstance(a, float) and not math.isfinite(a):
        return None
    if isinstance(a, bool) or isinstance(b, bool):
        return None if a is b else f"{path}: {a!r} != {b!r}"
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
            return None
        same = a == b and math.copysign(1.0, a) == math.copysign(1.0, b)
        return None if same else f"{path}: {a!r} != {b!r}"
    return None if a == b else f"{path}: {a!r} != {b!r}"


def read_csv(path: pathlib.Path) -> Dict[str, np.ndarray]:
    """A CLI CSV file as float64 columns (Python's float() is correctly
    rounded, and the CLI writes shortest round-trip decimals)."""
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    rows = [[float(x) for x in line.split(",")] for line in lines[1:]]
    data = np.array(rows, dtype=np.float64).reshape(len(rows), len(header))
    return {h: data[:, i] for i, h in enumerate(header)}


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal bit for bit (any NaN matches any NaN: CSV writes them as "nan")."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if a.shape != b.shape:
        return False
    na, nb = np.isnan(a), np.isnan(b)
    return bool(np.array_equal(na, nb)) and a[~na].tobytes() == b[~nb].tobytes()
