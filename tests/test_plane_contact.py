"""Ground-plane contact: support, static friction and kinetic sliding on an incline.

The incline is a tilting table: the rod first rests on the plane, then gravity is turned
slowly to the incline angle (the same physics as tilting the plane, with the contact loaded
quasi-statically as a real rod placed on a slope would be), then held there.
"""

from __future__ import annotations

import numpy as np
import pytest

import deformx as dx

G = 9.81
MU_S, MU_K = 0.5, 0.3
TILT_TIME = 0.3


def _rod_on_ground(dt: float = 1e-4, **plane):
    radius = 0.005
    rod = dx.Rod.straight(n_elements=10, start=(0, -0.15, radius), direction=(0, 1, 0),
                          normal=(1, 0, 0), length=0.3, radius=radius, density=1200.0,
                          youngs_modulus=1e6)
    world = dx.World(gravity=(0, 0, -G), dt=dt)
    world.add_rod(rod)
    world.add_plane(point=(0, 0, 0), normal=(0, 0, 1), **plane)
    return world, rod


def _tilt_and_hold(world, rod, angle, hold, every=0.01):
    """Tilt gravity to ``angle`` over TILT_TIME, then hold; returns times and mean x."""
    times, x = [], []
    n_tilt = int(round(TILT_TIME / every))
    for i in range(n_tilt + int(round(hold / every))):
        a = angle * min(1.0, (i + 1) / n_tilt)
        world.gravity = np.array([G * np.sin(a), 0.0, -G * np.cos(a)])
        world.run(every)
        times.append(world.time)
        x.append(float(rod.positions[:, 0].mean()))
    return np.array(times), np.array(x)


def test_rod_resting_on_ground_is_supported_by_its_weight():
    world, rod = _rod_on_ground(static_friction=MU_S, kinetic_friction=MU_K)
    world.run(0.5)
    total = world.contact_forces(rod).sum(axis=0)
    assert np.allclose(total, [0.0, 0.0, rod.mass * G], rtol=1e-6, atol=1e-9)
    assert np.abs(rod.velocities).max() < 1e-6
    gap = rod.positions[:, 2] - rod.radius
    assert np.all(gap < 0) and np.all(gap > -1e-4)  # penetration is tiny


@pytest.mark.parametrize("tan_angle", [0.2, 0.45])
def test_static_friction_holds_below_the_limit(tan_angle):
    world, rod = _rod_on_ground(static_friction=MU_S, kinetic_friction=MU_K)
    world.run(0.2)
    start = rod.positions[:, 0].mean()
    _, x = _tilt_and_hold(world, rod, np.arctan(tan_angle), hold=1.0)
    assert np.abs(x - start).max() < 1e-6


@pytest.mark.parametrize("tan_angle", [0.6, 1.0])
def test_sliding_acceleration_follows_coulomb(tan_angle):
    angle = np.arctan(tan_angle)
    world, rod = _rod_on_ground(static_friction=MU_S, kinetic_friction=MU_K)
    world.run(0.2)
    times, x = _tilt_and_hold(world, rod, angle, hold=0.5)
    held = times > times[0] + TILT_TIME + 0.05
    accel = 2.0 * np.polyfit(times[held], x[held], 2)[0]
    expected = G * (np.sin(angle) - MU_K * np.cos(angle))
    assert accel == pytest.approx(expected, rel=0.03)


def test_frictionless_plane_lets_the_rod_slide_freely():
    world, rod = _rod_on_ground(friction=0.0)
    world.run(0.2)
    angle = np.arctan(0.3)
    times, x = _tilt_and_hold(world, rod, angle, hold=0.3)
    held = times > times[0] + TILT_TIME + 0.05
    accel = 2.0 * np.polyfit(times[held], x[held], 2)[0]
    assert accel == pytest.approx(G * np.sin(angle), rel=0.01)
