"""A one-line notice on stderr while numba compiles kernels that are not in its cache yet.

The first run after an install compiles the numerical kernels (tens of seconds on a laptop); later
runs load them from numba's on-disk cache. Without a word the first run looks hung. The command
line calls :func:`announce_compilation` once at start-up. It does not import numba (the CLI must
start fast): it waits until something else imports numba and then listens to numba's
``numba:compile`` event, which fires only on a cache miss, i.e. a real compilation.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import Any, TextIO

from jointwear._lazy import after_import

__all__ = ["announce_compilation", "NOTICE"]

#: The line printed before the first compilation of a process.
NOTICE = (
    "jointwear: compiling numerical kernels this command uses for the first time (each once "
    "per install; later runs of any command load it from the cache)..."
)


def _area(event: Any) -> str:
    """Where a compiled kernel lives: ``jointwear.sim.kernels`` (a package of jointwear, to
    three levels), else the top module."""
    dispatcher = (getattr(event, "data", None) or {}).get("dispatcher")
    module = str(getattr(getattr(dispatcher, "py_func", None), "__module__", None) or "?")
    parts = module.split(".")
    return ".".join(parts[:3] if parts[0] == "jointwear" else parts[:1])


class _Listener:
    """numba event listener: notice at the first compile, a summary line when the command ends."""

    def __init__(self, stream: TextIO | None) -> None:
        self.stream = stream  # None: whatever sys.stderr is when a compile starts
        self.active = True
        self.count = 0
        self.seconds = 0.0
        self.areas: dict[str, int] = {}  # kernels compiled per package
        self._started: list[float] = []

    def on_start(self, event: Any) -> None:
        if not self.active:
            return
        if self.count == 0 and not self._started:
            try:  # a notice must never break the compilation it announces
                print(NOTICE, file=self.stream or sys.stderr, flush=True)
            except (OSError, ValueError):
                pass
        self._started.append(time.perf_counter())

    def on_end(self, event: Any) -> None:
        if not self.active:
            return
        if self._started:
            start = self._started.pop()
            if not self._started:  # only outermost compiles count towards the time
                self.seconds += time.perf_counter() - start
        self.count += 1
        area = _area(event)
        self.areas[area] = self.areas.get(area, 0) + 1

    def summary(self) -> str | None:
        if not self.count:
            return None
        where = ", ".join(f"{a} {n}" for a, n in sorted(self.areas.items(), key=lambda x: -x[1]))
        return (
            f"jointwear: compiled {self.count} kernel(s) in {self.seconds:.0f} s ({where}); "
            "cached now"
        )


def _install(stream: TextIO | None) -> _Listener:
    from numba.core import event

    listener = _Listener(stream)

    class _NumbaListener(event.Listener):
        def on_start(self, ev: Any) -> None:
            listener.on_start(ev)

        def on_end(self, ev: Any) -> None:
            listener.on_end(ev)

    event.register("numba:compile", _NumbaListener())
    return listener


_STATE: dict[str, Any] = {}


def announce_compilation(stream: TextIO | None = None) -> Callable[[], str | None]:
    """Print :data:`NOTICE` on ``stream`` (default stderr) before the first numba compilation.

    Returns a function that gives the summary line (``None`` when nothing was compiled), for
    the caller to print when the command ends; calling it also ends the announcement, so that a
    process which goes on (a test runner calling ``main`` in-process) is never written to after
    its command returned. Calling :func:`announce_compilation` again re-arms the same listener.
    """
    if "summary" in _STATE:
        listener = _STATE.get("listener")
        if listener is not None:
            listener.stream, listener.active = stream, True
            listener.count, listener.seconds, listener._started = 0, 0.0, []
            listener.areas = {}
        return _STATE["summary"]

    def start() -> None:
        _STATE["listener"] = _install(stream)

    def summary() -> str | None:
        listener = _STATE.get("listener")
        if listener is None:
            return None
        listener.active = False
        return listener.summary()

    after_import("numba", start)
    _STATE["summary"] = summary
    return summary
