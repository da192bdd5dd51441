"""Progress reporting for ``progress=``.

The extension calls ``callback(label, done, total)`` from the calling thread
about every 100 ms while it works and once at the end. ``progress=True``
shows a bar: ``tqdm.auto`` when tqdm is installed (a widget in Jupyter, text
in a terminal), else one self-overwriting line on stderr. Either names the
unit of the stage (particles, points, time steps, per cent of a figure...) and estimates
the time left from the average rate since the stage began, shown once 5 %
is done and a second has passed (a recent-rate estimate jumps when chunks
take uneven time).
"""

from __future__ import annotations

import sys
import time
from typing import Any, Callable, Optional

Callback = Callable[[str, int, int], None]


def unit_of(label: str) -> str:
    """What the stage ``label`` counts ("%" for a figure's progress); the
    same table as the command-line bars."""
    if label in ("simulate", "simulate part", "mfpt") or label.startswith("point "):
        return "particles"
    if label in ("mfpt scan", "points"):
        return "points"
    if label == "mfpt optimize":
        return "grid points"
    if label == "fp transient":
        return "time steps"
    if label.startswith("fig"):
        return "%"
    return "steps"


def time_left(elapsed: float, fraction: float) -> Optional[float]:
    """Seconds left at ``fraction`` done after ``elapsed`` seconds (average
    rate so far); None until 5 % is done and a second has passed."""
    if not (0.05 <= fraction < 1.0) or elapsed < 1.0:
        return None
    return elapsed * (1.0 - fraction) / fraction


class _TqdmBars:
    """One tqdm bar per label (``reproduce`` runs one stage after another)."""

    def __init__(self, tqdm: Any) -> None:
        self._tqdm = tqdm
        self._label: Optional[str] = None
        self._bar: Any = None

    def __call__(self, label: str, done: int, total: int) -> None:
        unit = unit_of(label)
        if unit == "%":
            # A figure's progress: per cent of the figure.
            done, total = (100 * done // total if total else 100), 100
        if label != self._label or self._bar is None:
            self.close()
            self._label = label
            # smoothing=0: the rate averaged since the start, not the recent one.
            self._bar = self._tqdm(
                total=total, desc=label, unit=f" {unit}", leave=True, smoothing=0
            )
        if self._bar.total != total:
            self._bar.total = total
        self._bar.n = done
        self._bar.refresh()

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None


class _TextLine:
    """``label: done/total unit (pct%), ~N s left`` on stderr, rewritten in place."""

    def __init__(self, stream: Any = None) -> None:
        self._stream = stream
        self._open = False
        self._label: Optional[str] = None
        self._t0 = 0.0

    def __call__(self, label: str, done: int, total: int) -> None:
        stream = self._stream or sys.stderr
        if label != self._label:
            self._label, self._t0 = label, time.monotonic()
        frac = done / total if total else 1.0
        unit = unit_of(label)
        counts = f"{100 * frac:.0f}% of the figure" if unit == "%" else (
            f"{done}/{total} {unit} ({100 * frac:.0f}%)"
        )
        left = time_left(time.monotonic() - self._t0, frac)
        eta = f", ~{left:.0f} s left" if left is not None else ""
        stream.write(f"\r{label}: {counts}{eta}\033[K")
        stream.flush()
        self._open = True

    def close(self) -> None:
        if self._open:
            stream = self._stream or sys.stderr
            stream.write("\n")
            stream.flush()
            self._open = False


class _Plain:
    """A user's callable, passed through unchanged."""

    def __init__(self, fn: Callback) -> None:
        self._fn = fn

    def __call__(self, label: str, done: int, total: int) -> None:
        self._fn(label, done, total)

    def close(self) -> None:
        pass


def _tqdm() -> Any:
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return None
    return tqdm


def reporter(progress: Any) -> Any:
    """``progress=`` → an object with ``__call__(label, done, total)`` and
    ``close()``, or None for no reporting."""
    if progress is None or progress is False:
        return None
    if progress is True:
        tqdm = _tqdm()
        return _TqdmBars(tqdm) if tqdm is not None else _TextLine()
    if callable(progress):
        return _Plain(progress)
    raise TypeError(
        f"progress must be True, False or a callable(label, done, total), not {progress!r}"
    )
