"""Progress reporting for ``progress=``.

The extension calls ``callback(label, done, total)`` from the calling thread
about every 100 ms while it works and once at the end. ``progress=True``
shows a bar: ``tqdm.auto`` when tqdm is installed (a widget in Jupyter, text
in a terminal), else one self-overwriting line on stderr.
"""

from __future__ import annotations

import sys
from typing import Any, Callable, Optional

Callback = Callable[[str, int, int], None]


class _TqdmBars:
    """One tqdm bar per label (``reproduce`` runs one stage after another)."""

    def __init__(self, tqdm: Any) -> None:
        self._tqdm = tqdm
        self._label: Optional[str] = None
        self._bar: Any = None

    def __call__(self, label: str, done: int, total: int) -> None:
        if label != self._label or self._bar is None:
            self.close()
            self._label = label
            self._bar = self._tqdm(total=total, desc=label, leave=True)
        if self._bar.total != total:
            self._bar.total = total
        self._bar.n = done
        self._bar.refresh()

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None


class _TextLine:
    """``label: done/total (pct%)`` on stderr, rewritten in place."""

    def __init__(self, stream: Any = None) -> None:
        self._stream = stream
        self._open = False

    def __call__(self, label: str, done: int, total: int) -> None:
        stream = self._stream or sys.stderr
        pct = 100.0 * done / total if total else 100.0
        stream.write(f"\r{label}: {done}/{total} ({pct:.0f}%)")
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
