"""``World.run``: advance by a duration in chunks, calling callbacks at their times."""

from __future__ import annotations

import warnings
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any, Callable, Iterator, Sequence

from . import validation as check

if TYPE_CHECKING:
    from .world import World

CHUNK = 2000  # steps per kernel call between callbacks: bounds the Python overhead


def run(world: "World", duration: float, progress: bool = False, recorder: Any = None,
        callbacks: Sequence[Any] = ()) -> None:
    """Advance ``world`` by ``duration`` s (rounded to whole steps).

    A callback is a callable with an ``every`` attribute (s): it is called with the world at
    the run's start and then every ``every`` s of simulated time (rounded to whole steps),
    the last time at or before the run's end. ``recorder`` is one more callback.
    """
    duration = check.non_negative("duration", duration, "s")
    dt = world.dt
    n_total = int(round(duration / dt))
    if duration > 0.0 and n_total == 0:
        warnings.warn(f"run: duration {duration:g} s is shorter than half a step (dt = {dt:g} s); "
                      "nothing is simulated", stacklevel=3)
    cbs = list(callbacks) + ([recorder] if recorder is not None else [])
    periods = callback_periods(cbs, dt)
    # Each callback's next firing, in steps from now; a recorder does not repeat the sample
    # it already holds of this instant.
    due = [0] * len(cbs)
    for k, cb in enumerate(cbs):
        if getattr(cb, "times", None) and abs(cb.times[-1] - world.time) < 0.5 * dt:
            due[k] = periods[k]
    with progress_bar(f"simulating {duration:g} s", n_total, progress) as update:
        done = 0
        while True:
            for k, cb in enumerate(cbs):
                if due[k] == done:
                    cb(world)
                    due[k] += periods[k]
            if done >= n_total:
                break
            n = min(CHUNK, n_total - done, *(d - done for d in due)) if due else min(
                CHUNK, n_total - done)
            world.step(n)
            done += n
            update(done)


def callback_periods(callbacks: Sequence[Any], dt: float) -> list[int]:
    """Each callback's period in steps of ``dt`` (its ``every``, s, rounded; at least 1);
    ``ValueError`` for anything that is not a callable with an ``every``."""
    periods = []
    for cb in callbacks:
        if not callable(cb) or not hasattr(cb, "every"):
            raise ValueError("callbacks must be callables with an `every` attribute (s), got "
                             f"{cb!r}")
        every = check.positive("callback.every", cb.every, "s")
        periods.append(max(1, int(round(every / dt))))
    return periods


@contextmanager
def progress_bar(description: str, total: int, enabled: bool = True
                 ) -> Iterator[Callable[[int], None]]:
    """A transient progress bar (rich) while the block runs; yields ``update(completed)``,
    a no-op when not ``enabled``."""
    if not enabled:
        yield lambda completed: None
        return
    from rich.progress import Progress

    bar = Progress(transient=True)
    bar.start()
    task = bar.add_task(description, total=total)
    try:
        yield lambda completed: bar.update(task, completed=completed)
    finally:
        bar.stop()
