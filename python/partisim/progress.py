"""Progress display for long calls, on a terminal and in Jupyter.

:func:`make_progress` returns an object with ``update(n)`` (``n`` more steps done) and
``close()``; it is also a context manager. With ``tqdm`` installed it is a ``tqdm.auto`` bar
(a widget in Jupyter, a text bar on a terminal); without it, one line on standard error,
rewritten in place at most every 0.2 s (wall clock) and finished by a newline on ``close``.

``enabled=None`` means "on when standard error is a terminal or the code runs in a Jupyter
kernel"; ``True`` and ``False`` force it on or off. A disabled display does nothing.
"""

from __future__ import annotations

import sys
import time
from typing import Any, Optional

__all__ = ["make_progress", "in_jupyter", "progress_wanted"]

_MIN_INTERVAL_S = 0.2  # between two rewrites of the plain line (wall clock)


def in_jupyter() -> bool:
    """True inside a Jupyter (IPython kernel) session, whose standard error is no terminal."""
    ipython = sys.modules.get("IPython")
    if ipython is None:
        return False
    try:
        shell = ipython.get_ipython()
    except Exception:  # an IPython too old or half imported: not a kernel we know
        return False
    return shell is not None and "IPKernelApp" in getattr(shell, "config", {})


def progress_wanted(enabled: Optional[bool]) -> bool:
    """Resolves ``enabled``: ``None`` means on when stderr is a terminal or in Jupyter."""
    if enabled is not None:
        return bool(enabled)
    try:
        tty = sys.stderr is not None and sys.stderr.isatty()
    except (AttributeError, ValueError):  # replaced or closed stderr
        tty = False
    return tty or in_jupyter()


class _Display:
    """The display when progress is off (every call does nothing), and the context-manager
    part every display shares."""

    def update(self, n: int = 1) -> None:
        pass

    def close(self) -> None:
        pass

    def __enter__(self) -> "_Display":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


class _PlainLine(_Display):
    """``desc: done/total`` on standard error, rewritten in place (``\\r``), throttled."""

    def __init__(self, total: Optional[int], desc: str) -> None:
        self.total = total
        self.desc = desc
        self.done = 0
        self._last = 0.0
        self._closed = False
        self._start = time.monotonic()
        self._write()

    def _write(self) -> None:
        elapsed = time.monotonic() - self._start
        of = f"/{self.total}" if self.total is not None else ""
        prefix = f"{self.desc}: " if self.desc else ""
        try:
            sys.stderr.write(f"\r{prefix}{self.done}{of} ({elapsed:.1f} s)")
            sys.stderr.flush()
        except (AttributeError, ValueError, OSError):  # no usable stderr: stay silent
            pass
        self._last = time.monotonic()

    def update(self, n: int = 1) -> None:
        self.done += n
        if time.monotonic() - self._last >= _MIN_INTERVAL_S or self.done == self.total:
            self._write()

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        self._write()
        try:
            sys.stderr.write("\n")
            sys.stderr.flush()
        except (AttributeError, ValueError, OSError):
            pass


class _Tqdm(_Display):
    """A ``tqdm.auto`` bar behind the same two calls."""

    def __init__(self, bar: Any) -> None:
        self._bar = bar

    def update(self, n: int = 1) -> None:
        self._bar.update(n)

    def close(self) -> None:
        self._bar.close()


def make_progress(total: Optional[int], enabled: Optional[bool] = None, desc: str = "") -> Any:
    """A progress display for ``total`` steps (``None``: unknown total).

    Parameters
    ----------
    total : int or None
        Number of steps expected (frames, years, ...).
    enabled : bool or None
        ``True``/``False`` force the display on or off; ``None`` (default) shows it when
        standard error is a terminal or in Jupyter.
    desc : str
        Label shown before the count.

    Returns
    -------
    An object with ``update(n=1)`` and ``close()``, usable as a context manager.
    """
    if not progress_wanted(enabled):
        return _Display()
    try:
        from tqdm.auto import tqdm

        # In Jupyter without ipywidgets, tqdm's notebook bar raises ImportError here.
        return _Tqdm(tqdm(total=total, desc=desc or None, file=sys.stderr))
    except ImportError:
        return _PlainLine(total, desc)
