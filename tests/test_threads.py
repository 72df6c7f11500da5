"""Rods advanced on worker threads give the same result as on one thread, bit for bit.

Each thread works in its rods' own rows of the packed buffers (the stable integrator's Newton
system included): a shared scratch row would show up here as a difference.
"""

from __future__ import annotations

import numpy as np
import pytest

import deformx as dx
from deformx.engine.threads import MIN_THREADED_WORK


def _ropes(integrator: str, dt: float, threads: int) -> dx.World:
    world = dx.World(dt=dt, integrator=integrator, threads=threads, rod_contact=False)
    world.add_plane()
    for k in range(4):  # different lengths and drops: the rods' solves differ
        rod = world.add_rod(dx.Rod.straight(
            n_elements=40 + 5 * k, start=(0.0, 0.1 * k, 0.05 + 0.02 * k), direction=(1, 0, 0),
            length=0.4 + 0.05 * k, radius=3e-3, density=1200.0, youngs_modulus=1e6,
            damping=0.5))
        if k % 2:
            rod.fix_start()
    return world


@pytest.mark.parametrize("integrator,dt,n", [("stable", 2e-3, 150), ("verlet", 2e-5, 600)])
def test_threads_match_one_thread_bit_for_bit(integrator, dt, n):
    one, many = _ropes(integrator, dt, 1), _ropes(integrator, dt, 2)
    assert n * sum(r.n_elements for r in many.rods) >= MIN_THREADED_WORK[integrator]  # threaded
    for world in (one, many):
        for _ in range(3):
            world.step(n)
    assert len(many._groups) == 2 and len(one._groups) == 1
    for a, b in zip(one.rods, many.rods):
        np.testing.assert_array_equal(a.positions, b.positions)
        np.testing.assert_array_equal(a.velocities, b.velocities)
    assert one.time == many.time


def test_stable_steps_one_at_a_time_match_one_call():
    """step() n times and step(n) take the same path through the solver (its warm starts and
    work rows persist between calls)."""
    a, b = _ropes("stable", 2e-3, 1), _ropes("stable", 2e-3, 1)
    for _ in range(60):
        a.step()
    b.step(60)
    for ra, rb in zip(a.rods, b.rods):
        np.testing.assert_array_equal(ra.positions, rb.positions)
    assert a.time == pytest.approx(b.time, abs=1e-12)
