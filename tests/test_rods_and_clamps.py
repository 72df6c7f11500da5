"""Rod construction (straight, from points, rings), clamps, pins, driven ends and recording."""

from __future__ import annotations

import numpy as np
import pytest

import deformx as dx
from deformx.engine.kernels.so3 import axis_angle_matrix

MAT = dict(radius=0.005, density=1000.0, youngs_modulus=1e6)


def _helix(n=60, turns=1.5, radius=0.1, pitch=0.05):
    s = np.linspace(0, 2 * np.pi * turns, n + 1)
    return np.stack([radius * np.cos(s), radius * np.sin(s), pitch * s / (2 * np.pi)], axis=1)


def test_straight_rod_geometry_and_mass():
    rod = dx.Rod.straight(n_elements=20, start=(1, 2, 3), direction=(0, 3, 4), length=2.0, **MAT)
    assert rod.n_nodes == 21 and rod.n_elements == 20
    assert np.allclose(rod.positions[-1], np.array([1, 2, 3]) + 2.0 * np.array([0, 0.6, 0.8]))
    assert np.isclose(rod.length, 2.0) and np.isclose(rod.masses.sum(), rod.mass)
    assert np.isclose(rod.mass, 1000.0 * np.pi * 0.005**2 * 2.0)
    Q = rod.directors
    assert np.allclose(np.einsum("kij,klj->kil", Q, Q), np.eye(3))
    assert np.allclose(Q[:, 2], [0, 0.6, 0.8])


def test_curve_with_given_rest_shape_stays_at_rest():
    """A helix whose rest shape is itself: no forces, nothing moves (gravity off)."""
    world = dx.World(gravity=(0, 0, 0), dt=2e-5)
    rod = world.add_rod(dx.Rod.from_points(_helix(), rest_shape="given", **MAT))
    start = rod.positions.copy()
    world.run(0.05)
    assert np.abs(rod.positions - start).max() < 1e-12
    assert max(rod.elastic_energy().values()) < 1e-20


def test_curve_with_straight_rest_shape_unbends():
    """A quarter circle of wire that is straight at rest springs back straight."""
    s = np.linspace(0, np.pi / 2, 31)
    arc = np.stack([0.1 * np.sin(s), 0.1 * (1 - np.cos(s)), 0 * s], axis=1)
    world = dx.World(gravity=(0, 0, 0), dt=2e-5)
    rod = world.add_rod(dx.Rod.from_points(arc, rest_shape="straight", damping=5.0, **MAT))
    assert rod.elastic_energy()["bend"] > 0
    chord0 = np.linalg.norm(rod.positions[-1] - rod.positions[0])
    world.run(1.0)
    chord = np.linalg.norm(rod.positions[-1] - rod.positions[0])
    assert chord0 < 0.91 * rod.length and chord > 0.99 * rod.length


def test_ring_keeps_its_shape_and_momentum():
    s = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    ring = np.stack([0.2 * np.cos(s), 0.2 * np.sin(s), 0 * s], axis=1)
    world = dx.World(gravity=(0, 0, 0), dt=2e-5)
    rod = world.add_rod(dx.Rod.from_points(ring, closed=True, **MAT))
    assert rod.closed and rod.n_nodes == rod.n_elements == 40
    rod.velocities[:] = (0.1, 0.0, 0.0)
    rod.velocities[:, 2] = 0.05 * np.sin(s)  # a wobble
    p0 = (rod.masses[:, None] * rod.velocities).sum(axis=0)
    world.run(0.1)
    p1 = (rod.masses[:, None] * rod.velocities).sum(axis=0)
    assert np.allclose(p0, p1, atol=1e-12)
    radii = np.linalg.norm(rod.positions[:, :2] - rod.positions[:, :2].mean(axis=0), axis=1)
    assert np.allclose(radii, 0.2, rtol=0.05)


def test_ring_with_given_shape_is_stress_free():
    s = np.linspace(0, 2 * np.pi, 30, endpoint=False)
    ring = np.stack([0.2 * np.cos(s), 0.2 * np.sin(s), 0 * s], axis=1)
    rod = dx.Rod.from_points(ring, closed=True, **MAT)
    assert max(rod.elastic_energy().values()) < 1e-20
    bent = dx.Rod.from_points(ring, closed=True, rest_shape="straight", **MAT)
    # A ring bent from a straight rod stores (1/2) E I (1/R)^2 per unit length.
    expected = 0.5 * 1e6 * np.pi * 0.005**4 / 4 / 0.2**2 * bent.length
    assert bent.elastic_energy()["bend"] == pytest.approx(expected, rel=0.01)


def test_pinned_node_holds_and_frames_rotate_freely():
    world = dx.World(dt=5e-5)
    rod = world.add_rod(dx.Rod.straight(n_elements=20, start=(0, 0, 1), direction=(1, 0, 0), length=0.4, **MAT))
    pin = rod.pin(0)
    world.run(0.2)
    assert np.allclose(rod.positions[0], (0, 0, 1), atol=1e-15)
    assert np.allclose(pin.position, (0, 0, 1))
    assert rod.positions[-1, 2] < 0.9  # it swung down
    assert np.abs(rod.directors[0, 2] - (1, 0, 0)).max() > 0.1  # first frame turned


def test_driven_clamp_follows_a_prescribed_trajectory():
    """The clamp moves at its set velocity and spin; the end node and frame follow exactly."""
    world = dx.World(dt=5e-5)
    rod = world.add_rod(dx.Rod.straight(n_elements=20, start=(0, 0, 1), direction=(1, 0, 0), length=0.4, **MAT))
    clamp = rod.fix_start()
    Q0 = rod.directors[0].copy()
    v, w = np.array([0.2, 0.0, 0.1]), np.array([0.0, 0.0, 1.5])
    clamp.set_velocity(v, w)
    world.run(0.2)
    t = world.time
    assert np.allclose(rod.positions[0], np.array([0, 0, 1]) + v * t, atol=1e-12)
    expected_Q = Q0 @ axis_angle_matrix(w, np.linalg.norm(w) * t).T
    assert np.allclose(rod.directors[0], expected_Q, atol=1e-10)
    assert np.allclose(rod.velocities[0], v)
    assert np.allclose(rod.directors[0].T @ rod.angular_velocities[0], w)  # back to lab frame
    # Re-posing moves the clamp; the rod's end follows from the next step on.
    target = clamp.position + (0.0, 0.0005, 0.0)
    turned = axis_angle_matrix((1, 0, 0), 0.01) @ clamp.directors.T
    clamp.set_pose(position=target, directors=turned.T)
    clamp.set_velocity((0, 0, 0), (0, 0, 0))
    world.step(10)
    assert np.allclose(rod.positions[0], target) and np.allclose(rod.directors[0], turned.T)


def test_fix_end_clamps_both_ends():
    world = dx.World(dt=5e-5)
    rod = world.add_rod(dx.Rod.straight(n_elements=30, start=(0, 0, 1), direction=(1, 0, 0), length=0.6,
                                        damping=5.0, **MAT))
    rod.fix_start()
    rod.fix_end()
    world.run(0.5)
    assert np.allclose(rod.positions[[0, -1]], [(0, 0, 1), (0.6, 0, 1)], atol=1e-14)
    mid = rod.positions[15, 2]
    assert 0.9 < mid < 1.0  # sags between the clamps


def test_recorder_samples_at_the_requested_rate(tmp_path):
    world = dx.World(dt=1e-4)
    rod = world.add_rod(dx.Rod.straight(n_elements=10, start=(0, 0, 1), **MAT))
    rec = dx.Recorder(world, every=0.01)
    world.run(0.1, recorder=rec)
    path = rec.save(tmp_path / "run.npz")
    data = np.load(path)
    assert np.allclose(data["time"], np.arange(11) * 0.01)
    assert data["rod0_positions"].shape == (11, 11, 3)
    assert data["rod0_directors"].shape == (11, 10, 3, 3)
    assert np.allclose(data["rod0_positions"][-1], rod.positions)
    # Free fall of the whole rod: z(t) = 1 - g t^2 / 2.
    assert np.allclose(data["rod0_positions"][:, 0, 2], 1 - 0.5 * 9.81 * data["time"] ** 2, atol=1e-9)


def test_adding_a_rod_keeps_the_state_of_the_others():
    world = dx.World(dt=1e-4)
    a = world.add_rod(dx.Rod.straight(n_elements=10, start=(0, 0, 1), **MAT))
    world.run(0.01)
    before = a.positions.copy(), a.velocities.copy()
    world.add_rod(dx.Rod.straight(n_elements=5, start=(0, 1, 1), **MAT))
    assert np.array_equal(a.positions, before[0]) and np.array_equal(a.velocities, before[1])
