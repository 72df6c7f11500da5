"""Kinematic drivers: clamps and colliders follow the semi-implicit recursion inside step(n)
and report the load the rods put on them."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import deformx as dx

G = 9.81


def _exp(w: np.ndarray, tau: float) -> np.ndarray:
    """Exp(tau [w]) by Rodrigues' formula."""
    phi = np.asarray(w, dtype=float) * tau
    theta = np.linalg.norm(phi)
    if theta == 0.0:
        return np.eye(3)
    k = phi / theta
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(theta) * K + (1.0 - np.cos(theta)) * K @ K


def _recursion(p, R, v, w, a, alpha, dt, n):
    """MuJoCo's / PhysX's semi-implicit Euler, n steps."""
    p, R, v, w = (np.array(x, dtype=float) for x in (p, R, v, w))
    for _ in range(n):
        v = v + dt * np.asarray(a)
        w = w + dt * np.asarray(alpha)
        p = p + dt * v
        R = _exp(w, dt) @ R
    return p, R, v, w


@pytest.mark.parametrize("integrator,dt", [("verlet", 1e-4), ("stable", 1e-3)])
def test_box_and_clamp_follow_the_semi_implicit_recursion(integrator, dt):
    world = dx.World(dt=dt, integrator=integrator)
    rod = world.add_rod(dx.Rod.straight(10, start=(0, 0, 1), direction=(1, 0, 0), length=0.3,
                                        radius=0.005, youngs_modulus=1e6, damping=2.0))
    clamp = rod.fix_start()
    box = world.add_box((0.1, 0.1, 0.05), pose=(2.0, 0.0, 0.0))  # far from the rod
    v, w = np.array([0.3, -0.1, 0.2]), np.array([0.0, 0.5, 1.0])
    a, alpha = np.array([1.0, 0.5, -2.0]), np.array([0.7, -0.3, 0.2])
    box.set_velocity(v, w)
    box.set_acceleration(a, alpha)
    clamp.set_velocity(velocity=0.5 * v, angular_velocity=w)
    clamp.set_acceleration(linear=-a, angular=alpha)
    p_box, R_box = box.position, box.rotation
    p_clamp, R_clamp = clamp.position, clamp.directors.T
    n = 250
    world.step(n)
    world.step(1)
    p, R, vb, wb = _recursion(p_box, R_box, v, w, a, alpha, dt, n + 1)
    assert np.abs(box.position - p).max() < 1e-12
    assert np.abs(box.rotation - R).max() < 1e-12
    assert np.abs(box.velocity - vb).max() < 1e-12
    assert np.abs(box.angular_velocity - wb).max() < 1e-12
    p, R, _, _ = _recursion(p_clamp, R_clamp, 0.5 * v, w, -a, alpha, dt, n + 1)
    assert np.abs(clamp.position - p).max() < 1e-12
    assert np.abs(clamp.directors - R.T).max() < 1e-12
    # The rod's clamped end is where the clamp is.
    assert np.abs(rod.positions[0] - p).max() < 1e-12
    assert np.abs(rod.directors[0] - R.T).max() < 1e-12


def test_constant_velocity_clamp_moves_as_pos0_plus_v_t_while_spinning():
    world = dx.World(dt=1e-4)
    rod = world.add_rod(dx.Rod.straight(10, length=0.2, radius=0.005, youngs_modulus=1e6))
    clamp = rod.fix_start()
    start = clamp.position
    clamp.set_velocity(velocity=(0.1, 0.2, 0.0), angular_velocity=(3.0, 0.0, 0.0))
    world.run(0.2)
    assert np.allclose(rod.positions[0], start + 0.2 * np.array([0.1, 0.2, 0.0]), atol=1e-12)
    # d1 turned by 0.6 rad about x (the rod's axis).
    assert np.allclose(rod.directors[0, 0], _exp([3.0, 0, 0], 0.2) @ [0, 0, 1], atol=1e-9)


def test_setting_a_driver_does_not_rebuild_the_world():
    world = dx.World(dt=1e-3, integrator="stable")
    rod = world.add_rod(dx.Rod.straight(10, length=0.3, radius=0.005))
    clamp = rod.fix_start()
    box = world.add_box((0.1, 0.1, 0.1), pose=(0, 0, -1))
    world.step()
    bufs = world._bufs
    clamp.set_velocity(velocity=(0.1, 0, 0))
    clamp.set_pose(position=(0.0, 0.0, 0.01))
    box.set_velocity((0, 0, 0.1))
    world.set_drivers([clamp, box], velocity=[[0.2, 0, 0], [0, 0, 0.2]])
    world.step()
    assert world._bufs is bufs
    assert np.allclose(box.velocity, [0, 0, 0.2]) and np.allclose(clamp.velocity, [0.2, 0, 0])


@pytest.mark.parametrize("integrator,dt", [("verlet", 5e-5), ("stable", 2e-3)])
def test_impulse_on_a_clamp_holding_a_hanging_rope_is_its_weight_times_time(integrator, dt):
    world = dx.World(dt=dt, integrator=integrator)
    rod = world.add_rod(dx.Rod.straight(20, start=(0, 0, 1), direction=(0, 0, -1), length=0.5,
                                        radius=0.005, density=1200.0, youngs_modulus=1e6,
                                        damping=20.0))
    clamp = rod.fix_start()
    world.run(0.5)  # settle the stretch (at rest to ~1e-8 m/s)
    clamp.reset_impulse()
    world.run(1.0)
    weight = rod.mass * G
    assert clamp.impulse[:3] == pytest.approx([0.0, 0.0, -weight * 1.0], rel=5e-3, abs=1e-6)
    assert np.abs(clamp.impulse[3:]).max() < 1e-6 * weight
    assert clamp.force == pytest.approx([0.0, 0.0, -weight], rel=5e-3, abs=1e-6)


@pytest.mark.parametrize("integrator,dt", [("verlet", 1e-4), ("stable", 1e-3)])
def test_rope_on_a_box_accelerating_below_the_friction_limit_is_carried_along(integrator, dt):
    world = dx.World(dt=dt, integrator=integrator, rod_contact=False)
    box_mesh = trimesh.creation.box(extents=(0.6, 0.3, 0.1))
    box = world.add_mesh(box_mesh, pose=(0.0, 0.0, 0.05), friction=0.6)
    rod = world.add_rod(dx.Rod.straight(20, start=(-0.2, 0, 0.105), direction=(1, 0, 0),
                                        length=0.4, radius=0.005, density=1200.0,
                                        youngs_modulus=1e6, damping=2.0))
    world.run(0.2)
    x0 = rod.positions[:, 0].mean()
    start = box.position
    box.set_acceleration(linear=(1.5, 0.0, 0.0))  # well below mu g = 5.9 m/s^2
    world.run(0.5)
    moved = box.position[0] - start[0]
    assert moved == pytest.approx(0.5 * 1.5 * 0.5 ** 2, rel=0.01)
    assert rod.positions[:, 0].mean() - x0 == pytest.approx(moved, abs=2e-3)
    assert np.abs(rod.velocities[:, 0] - box.velocity[0]).max() < 0.05
    # The box feels the rope's drag (backwards) and weight.
    assert box.force[0] < 0.0 and box.force[2] == pytest.approx(-rod.mass * G, rel=0.05)


def test_array_form_sets_many_drivers_and_checks_shapes():
    world = dx.World(dt=1e-3, integrator="stable", rod_contact=False)
    rods = [world.add_rod(dx.Rod.straight(5, start=(0, y, 1), length=0.1)) for y in (0, 1, 2)]
    clamps = [r.fix_start() for r in rods]
    world.set_drivers(clamps, velocity=np.arange(9.0).reshape(3, 3) * 0.01)
    assert np.allclose(clamps[2].velocity, [0.06, 0.07, 0.08])
    with pytest.raises(ValueError, match="velocity"):
        world.set_drivers(clamps, velocity=np.zeros((2, 3)))
    with pytest.raises(ValueError, match="rotation"):
        world.set_drivers(clamps, rotation=np.ones((3, 3, 3)))
