"""Contact filters: rods of different contact groups never touch; a rod can ignore colliders."""

from __future__ import annotations

import numpy as np
import pytest

import deformx as dx


def _crossing(groups: tuple[int, int]) -> tuple[dx.World, dx.Rod, dx.Rod]:
    world = dx.World(dt=2e-3, integrator="stable")
    world.add_plane(friction=0.5)
    low = dx.Rod.straight(20, start=(-0.2, 0, 0.005), direction=(1, 0, 0), length=0.4,
                          radius=0.005, youngs_modulus=1e6, damping=1.0)
    high = dx.Rod.straight(20, start=(0, -0.2, 0.03), direction=(0, 1, 0), length=0.4,
                           radius=0.005, youngs_modulus=1e6, damping=1.0)
    low.contact_group, high.contact_group = groups
    world.add_rod(low)
    world.add_rod(high)
    world.run(0.5)
    return world, low, high


def test_rods_of_one_group_touch_and_of_different_groups_pass_through():
    _, _, high = _crossing((0, 0))
    assert high.positions[10, 2] == pytest.approx(0.015, abs=1e-3)  # lies on the other rope
    _, _, high = _crossing((0, 1))
    assert high.positions[10, 2] == pytest.approx(0.005, abs=1e-3)  # through it, on the floor


@pytest.mark.parametrize("integrator,dt", [("verlet", 1e-4), ("stable", 2e-3)])
def test_a_rod_ignoring_a_collider_falls_through_it(integrator, dt):
    heights = []
    for ignore in (False, True):
        world = dx.World(dt=dt, integrator=integrator)
        world.add_plane()
        box = world.add_box((0.3, 0.3, 0.05), pose=(0, 0, 0.05))
        rod = world.add_rod(dx.Rod.straight(10, start=(-0.1, 0, 0.12), length=0.2,
                                            radius=0.005, youngs_modulus=1e6, damping=2.0))
        if ignore:
            rod.ignore(box)
        world.run(0.4)
        heights.append(rod.positions[:, 2].mean())
        assert np.allclose(box.force, 0.0) == ignore
    assert heights[0] == pytest.approx(0.105, abs=1e-3)  # on the box
    assert heights[1] == pytest.approx(0.005, abs=1e-3)  # on the floor, through the box
