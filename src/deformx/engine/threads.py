"""Worker threads for worlds of many independent rods (the kernels release the GIL)."""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from . import validation as check

# Element-steps below which one call is too short to be worth handing to threads (a hand-off
# costs ~50 us). A stable element-step costs ~0.5 us (Newton), an explicit one ~0.15 us.
# Measured on 2 cores (2026-12-04, 20-element ropes, 4 steps per call): stable, 8 ropes 1.2x,
# 16 ropes 1.5x, 64 ropes 1.7x faster threaded (2 ropes: 0.7x); explicit, 16 ropes 0.65x,
# 32-64 ropes 1.1-1.4x.
MIN_THREADED_WORK = {"stable": 1_000, "verlet": 20_000}
_POOL: ThreadPoolExecutor | None = None


def default_threads() -> int:
    """Worker threads for multi-rod worlds: ``DEFORMX_NUM_THREADS`` or the usable cores."""
    env = os.environ.get("DEFORMX_NUM_THREADS")
    if env:
        return check.integer_at_least("DEFORMX_NUM_THREADS", int(env), 1)
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def pool(n: int) -> ThreadPoolExecutor:
    global _POOL
    if _POOL is None or _POOL._max_workers < n:
        _POOL = ThreadPoolExecutor(max_workers=n, thread_name_prefix="deformx")
    return _POOL


def balanced_groups(rod_ne: np.ndarray, n_groups: int) -> list[tuple[int, int]]:
    """Split rods into at most ``n_groups`` contiguous ranges of similar element count."""
    n_rods = rod_ne.shape[0]
    n_groups = max(1, min(n_groups, n_rods))
    cuts = np.searchsorted(np.cumsum(rod_ne), np.arange(1, n_groups) * rod_ne.sum() / n_groups)
    bounds = [0, *sorted(set(int(c) + 1 for c in cuts)), n_rods]
    return [(a, b) for a, b in zip(bounds[:-1], bounds[1:]) if b > a]
