"""The UR5e MJCF against UR's DH kinematics, its limits and servos; the capsule rope."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from deformx import cosim, robots
from deformx.robots import ur


def _model(**kw):
    m = mujoco.MjModel.from_xml_string(robots.ur5e(**kw))
    return m, mujoco.MjData(m)


def _random_q(rng):
    q = rng.uniform(-2 * math.pi, 2 * math.pi, 6)
    q[2] = rng.uniform(-math.pi, math.pi)
    return q


@pytest.mark.parametrize("tool_length", [0.0, 0.65])
def test_flange_and_tool_tip_follow_the_dh_forward_kinematics(tool_length):
    m, d = _model(tool_length=tool_length)
    rng = np.random.default_rng(7)
    body = "tool_tip" if tool_length else "flange"
    for _ in range(50):
        q = _random_q(rng)
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        T = robots.forward_kinematics(q, tool_length=tool_length)
        np.testing.assert_allclose(d.body(body).xpos, T[:3, 3], rtol=0, atol=1e-6)
        np.testing.assert_allclose(d.body(body).xmat.reshape(3, 3), T[:3, :3], rtol=0, atol=1e-9)


def test_ur_base_link_is_the_dh_base_turned_half_a_turn_about_z():
    R = np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])  # the authors' base: -90 deg about x
    m, d = _model(base_position=(0, 0, 1.7), base_rotation=R, ur_base_link=True)
    q = np.array(robots.HOME)
    d.qpos[:] = q
    mujoco.mj_kinematics(m, d)
    Rz = np.diag([-1.0, -1.0, 1.0])
    T = robots.forward_kinematics(q)
    np.testing.assert_allclose(d.body("flange").xpos, np.array([0, 0, 1.7]) + R @ Rz @ T[:3, 3],
                               atol=1e-9)


def test_joint_names_limits_masses_and_actuators_are_urs():
    m, _ = _model()
    assert [m.joint(i).name for i in range(m.njnt)] == list(robots.JOINTS)
    for i, (lo, hi) in enumerate(ur.JOINT_RANGES):
        np.testing.assert_allclose(m.jnt_range[i], (lo, hi))
    np.testing.assert_allclose(m.jnt_range[2], (-math.pi, math.pi))
    for name, mass in ur.MASSES.items():
        assert m.body(name).mass[0] == pytest.approx(mass)
    np.testing.assert_allclose(m.actuator_forcerange[:, 1], [150, 150, 150, 28, 28, 28])
    assert m.numeric("max_joint_speed").data[0] == pytest.approx(math.pi)


def test_position_servos_settle_on_a_step_command():
    m, d = _model(tool_length=0.0, q0=robots.HOME)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    target = np.array(robots.HOME) + np.array([0.3, -0.2, 0.25, 0.2, -0.3, 0.4])
    d.ctrl[:] = target
    for _ in range(int(2.0 / m.opt.timestep)):
        mujoco.mj_step(m, d)
    np.testing.assert_allclose(d.qpos, target, atol=1e-3)
    assert np.abs(d.qvel).max() < 1e-3


def test_capsule_rope_hangs_straight_and_reads_like_a_rod():
    xml = robots.capsule_rope(length=1.0, n_segments=10, radius=0.005, density=700.0,
                              start=(0, 0, 1.5), direction=(1, 0, 0), damping=0.02)
    backend = cosim.MujocoBackend(xml)
    m = backend.model
    mass = sum(m.body(f"rope_{i}").mass[0] for i in range(10))
    assert mass == pytest.approx(700.0 * math.pi * 0.005 ** 2 * 1.0, rel=1e-5)  # MJCF: 6 digits
    rope = cosim.CapsuleRope(backend)
    assert rope.positions.shape == (11, 3)
    np.testing.assert_allclose(rope.positions[-1], [1.0, 0, 1.5], atol=1e-12)
    for _ in range(8000):  # 16 s: released horizontal, it swings down and settles
        backend.step()
    p = rope.positions
    np.testing.assert_allclose(p[-1], rope.tip_position)
    # hanging: a vertical chain of length 1 below the pivot, at rest
    np.testing.assert_allclose(p[-1], [0, 0, 0.5], atol=0.05)
    np.testing.assert_allclose(np.linalg.norm(np.diff(p, axis=0), axis=1), 0.1, rtol=1e-3)
    assert np.linalg.norm(rope.tip_velocity) < 0.1
