"""Stable integrator, resting contact: a rod whose contacts neither engage nor let go during a
step stops after one Newton iteration (as a rod in free flight does) and moves as a tightly
converged solve does.

The hit-target task's rope (1 m, 20 elements, soft ground at 100 N/m per node) hangs from a
clamp with its last 20 cm lying on the ground and is dragged back and forth by the clamp:
before, every step of a rod near a contact plane took at least two iterations.
"""

from __future__ import annotations

import math

import numpy as np

import deformx as dx

R = 6.35e-3


def _dragged_rope(tolerance: float) -> tuple[np.ndarray, float, int]:
    """Tip positions every 2 ms over 0.6 s, Newton iterations per step, nodes lying."""
    hanging = [(0.0, 0.0, 0.8 - z) for z in np.linspace(0.0, 0.8 - R, 17)]
    lying = [(x, 0.0, R) for x in np.linspace(0.05, 0.2, 4)]
    world = dx.World(dt=5e-4, integrator="stable", rod_contact=False, tolerance=tolerance)
    rod = world.add_rod(dx.Rod.from_points(
        np.array(hanging + lying), radius=R, density=700.0, youngs_modulus=2e5, damping=0.1,
        stretch_modulus=2e7, shear_modulus=6.7e6))
    world.add_plane(stiffness=100.0, friction=0.5)
    clamp = rod.fix_start()
    world.run(0.3)
    before = world.solver_stats()
    tips = []
    for k in range(300):
        clamp.set_velocity(velocity=(0.3 * math.cos(2.0 * math.pi * 1.2 * k * 2e-3), 0.0, 0.0))
        world.step(4)
        tips.append(rod.positions[-1].copy())
    after = world.solver_stats()
    steps = after["steps"] - before["steps"]
    its = (after["mean_iterations"] * after["steps"]
           - before["mean_iterations"] * before["steps"]) / steps
    return np.array(tips), its, int((rod.positions[:, 2] < 2.0 * R).sum())


def test_resting_contact_takes_one_iteration_and_matches_a_tight_solve():
    tips, its, lying = _dragged_rope(1e-4)  # the default tolerance
    tight, tight_its, tight_lying = _dragged_rope(1e-9)
    assert lying >= 3 and tight_lying == lying  # the end really lies on the ground
    assert its < 1.2 < tight_its
    # 1e-4 of an element length is 5 um per step; the tip's whole path stays within that.
    assert np.linalg.norm(tips - tight, axis=1).max() < 2e-5
