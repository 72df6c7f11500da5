"""A word while numba compiles DeformX's kernels (tens of seconds on a first run).

A listener on numba's ``"numba:compile"`` event, installed once when ``deformx.engine`` is
imported. When a kernel of the ``deformx`` package starts compiling while nothing else is
compiling, it logs :data:`START_MESSAGE` at INFO on the ``"deformx"`` logger, and when that
outermost compile ends, how long it took. Kernels it calls compile inside it and add nothing.

It costs nothing on warm runs: numba fires compile events only when it compiles, never when
it calls a compiled kernel or loads one from its on-disk cache. Front ends hook in with
:func:`on_compile` (the CLI shows a spinner). numba fires the events in the compiling thread,
under its global compiler lock, so one compile is reported at a time.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from numba.core import event

__all__ = ["START_MESSAGE", "install", "on_compile"]

START_MESSAGE = "compiling numba kernels (first run; cached afterwards) ..."
PACKAGE = "deformx"

logger = logging.getLogger(PACKAGE)

StartHook = Callable[[], None]
EndHook = Callable[[float], None]


def _is_ours(ev: event.Event) -> bool:
    """True if the event's dispatcher compiles a function of the deformx package."""
    data = ev.data if isinstance(ev.data, dict) else {}
    func = getattr(data.get("dispatcher"), "py_func", None)
    module = getattr(func, "__module__", None) or ""
    return module == PACKAGE or module.startswith(PACKAGE + ".")


class _Notice(event.Listener):
    """Counts nested compiles; reports the outermost one when it compiles a deformx kernel."""

    def __init__(self) -> None:
        self.depth = 0
        self.started: float | None = None  # perf_counter() at the reported compile's start
        self.hooks: list[tuple[StartHook, EndHook]] = []

    def on_start(self, ev: event.Event) -> None:
        self.depth += 1
        if self.depth == 1 and _is_ours(ev):
            self.started = time.perf_counter()
            logger.info(START_MESSAGE)
            for start, _ in list(self.hooks):
                _call(start)

    def on_end(self, ev: event.Event) -> None:
        self.depth = max(self.depth - 1, 0)
        if self.depth == 0 and self.started is not None:
            seconds = time.perf_counter() - self.started
            self.started = None
            logger.info("compiled numba kernels in %.1f s", seconds)
            for _, end in list(self.hooks):
                _call(end, seconds)


def _call(hook: Callable, *args: float) -> None:
    # A failing front end must never break numba's compilation.
    try:
        hook(*args)
    except Exception:  # noqa: BLE001
        logger.debug("compile notice hook %r failed", hook, exc_info=True)


_notice = _Notice()
_installed = False


def install() -> None:
    """Register the listener with numba (once; later calls do nothing)."""
    global _installed
    if not _installed:
        event.register("numba:compile", _notice)
        _installed = True


@contextmanager
def on_compile(start: StartHook, end: EndHook) -> Iterator[None]:
    """Within the block, call ``start()`` when an outermost deformx compile begins and
    ``end(seconds)`` when it ends. Exceptions in the hooks are logged at DEBUG and ignored."""
    install()
    pair = (start, end)
    _notice.hooks.append(pair)
    try:
        yield
    finally:
        _notice.hooks.remove(pair)


install()
