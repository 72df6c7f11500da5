"""Co-simulation with MuJoCo (Algorithm 1, two-way): static loads reach MuJoCo, momentum is
conserved across the coupling, the SE(3) predictor matches MuJoCo's integrator, a light body
on a stiff wire stays stable and settles to the analytical stretch."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

import deformx as dx
from deformx import cosim

G = 9.81


def _rope(start, direction, length=0.5, n=20, radius=0.005, density=1000.0, E=1e6,
          damping=0.0):
    return dx.Rod.straight(n_elements=n, start=start, direction=direction, length=length,
                           radius=radius, density=density, youngs_modulus=E, damping=damping)


def test_rope_hanging_from_a_spring_slide_stretches_it_by_the_total_weight():
    k, M = 100.0, 1.0
    xml = f"""<mujoco><option timestep="0.002"/><worldbody>
      <body name="carriage" pos="0 0 1">
        <joint type="slide" axis="0 0 1" stiffness="{k}" damping="4"/>
        <geom type="box" size="0.02 0.02 0.02" mass="{M}" contype="0" conaffinity="0"/>
      </body></worldbody></mujoco>"""
    world = dx.World(dt=2e-3, integrator="stable")
    rod = world.add_rod(_rope((0, 0, 1), (0, 0, -1), damping=2.0))
    backend = cosim.MujocoBackend(xml)
    sim = cosim.CoSimulation(world, backend)
    att = sim.attach(rod, "start", body="carriage")
    assert att.coupling == "kinematic"  # a jointed body
    sim.run(4.0)
    expected = -(M + rod.mass) * G / k
    assert backend.data.qpos[0] == pytest.approx(expected, rel=0.02)
    # the mean wrench of the last step is the rope's weight, and the rope follows the body
    assert sim.wrench("carriage")[2] == pytest.approx(-rod.mass * G, rel=0.02)
    assert abs(sim.time - world.time) < 1e-9


def _floor_force_on(backend, body):
    m, d = backend.model, backend.data
    mujoco.mj_forward(m, d)
    total, f = 0.0, np.zeros(6)
    bid = backend.body_id(body)
    for i in range(d.ncon):
        c = d.contact[i]
        if bid in (m.geom_bodyid[c.geom1], m.geom_bodyid[c.geom2]):
            mujoco.mj_contactForce(m, d, i, f)
            total += f[0] * c.frame[2]  # normal force along the contact normal, world z part
    return abs(total)


def test_rope_resting_on_a_free_box_loads_mujocos_floor_with_its_weight():
    M = 0.25  # the rope (60 g) is a quarter of it: the wrench must reach MuJoCo
    xml = f"""<mujoco><option timestep="0.002"/><worldbody>
      <geom name="floor" type="plane" size="0 0 1"/>
      <body name="box" pos="0 0 0.05"><freejoint/>
        <geom type="box" size="0.25 0.25 0.05" mass="{M}"/></body>
      </worldbody></mujoco>"""
    world = dx.World(dt=2e-3, integrator="stable")
    rod = world.add_rod(_rope((-0.15, 0, 0.12), (1, 0, 0), length=0.3, n=15, radius=0.008,
                              damping=2.0))
    backend = cosim.MujocoBackend(xml)
    sim = cosim.CoSimulation(world, backend)
    sim.add_colliders("box")
    sim.run(2.0)
    assert rod.positions[:, 2].max() < 0.11  # the rope lies on the box's top face (z = 0.1)
    assert _floor_force_on(backend, "box") == pytest.approx((M + rod.mass) * G, rel=0.02)
    assert sim.wrench("box")[2] == pytest.approx(-rod.mass * G, rel=0.02)


@pytest.mark.parametrize("coupling", ["kinematic", "inertial"])
def test_momentum_of_rope_and_body_equals_the_applied_impulse(coupling):
    M, F = 0.5, np.array([0.3, 0.0, 0.1])
    xml = f"""<mujoco><option timestep="0.002" gravity="0 0 0"/><worldbody>
      <body name="puck" pos="0 0 0"><freejoint/>
        <geom type="sphere" size="0.03" mass="{M}" contype="0" conaffinity="0"/></body>
      </worldbody></mujoco>"""
    world = dx.World(dt=2e-3, integrator="stable", gravity=(0, 0, 0))
    rod = world.add_rod(_rope((0, 0, 0), (1, 0, 0), length=0.4, n=16))
    backend = cosim.MujocoBackend(xml)
    sim = cosim.CoSimulation(world, backend)
    sim.attach(rod, "start", body="puck", coupling=coupling)
    rod.external_forces[-1] = F
    duration = 0.5
    sim.run(duration)
    own = rod.masses.copy()
    for node, m in rod.point_masses.items():
        own[node] -= m
    p_rope = (own[:, None] * rod.velocities).sum(axis=0)
    res = np.zeros(6)
    mujoco.mj_forward(backend.model, backend.data)
    mujoco.mj_objectVelocity(backend.model, backend.data, mujoco.mjtObj.mjOBJ_BODY,
                             backend.body_id("puck"), res, 0)
    p_total = p_rope + M * res[3:]
    np.testing.assert_allclose(p_total, F * duration, rtol=0.0, atol=0.01 * np.linalg.norm(F) * duration)


def test_predictor_equals_mujocos_integration_of_a_free_body():
    """Constant acceleration (gravity) and constant twist (a sphere spinning about an axis):
    the collider's driver after one macro step sits where MuJoCo puts the body."""
    xml = """<mujoco><option timestep="0.002"/><worldbody>
      <body name="ball" pos="0.1 0.2 1.0"><freejoint/>
        <geom type="sphere" size="0.05" mass="1.0"/></body></worldbody></mujoco>"""
    world = dx.World(dt=2e-3, integrator="stable")
    world.add_rod(_rope((5, 5, 0.5), (1, 0, 0), length=0.2, n=4))  # far away: no contact
    backend = cosim.MujocoBackend(xml)
    backend.data.qvel[:] = [0.3, -0.2, 1.0, 0.0, 0.0, 7.0]  # linear (world), angular (local)
    sim = cosim.CoSimulation(world, backend)
    (ball,) = sim.add_colliders("ball")
    for _ in range(25):
        sim.step()
        mujoco.mj_kinematics(backend.model, backend.data)
        i = backend.body_id("ball")
        np.testing.assert_allclose(ball.position, backend.data.xpos[i], rtol=0, atol=1e-12)
        np.testing.assert_allclose(ball.rotation, backend.data.xmat[i].reshape(3, 3), rtol=0,
                                   atol=1e-12)
    assert np.all(sim.wrench("ball") == 0.0)


def test_light_body_on_a_stiff_steel_wire_settles_to_the_static_stretch():
    """50 g on 1 m of steel wire (E 2e11, r 0.5 mm) at MuJoCo's 2 ms: the axial mode's
    period is 3.5 ms, so the body's mass has to ride in the rod's implicit solve."""
    M, E, r, L, rho = 0.05, 2e11, 5e-4, 1.0, 7850.0
    xml = f"""<mujoco><option timestep="0.002"/><worldbody>
      <body name="weight" pos="0 0 0"><freejoint/>
        <geom type="sphere" size="0.01" mass="{M}" contype="0" conaffinity="0"/></body>
      </worldbody></mujoco>"""
    world = dx.World(dt=2e-3, integrator="stable", tolerance=1e-8)
    rod = world.add_rod(dx.Rod.straight(n_elements=20, start=(0, 0, L), direction=(0, 0, -1),
                                        length=L, radius=r, density=rho, youngs_modulus=E))
    rod.fix_start()
    backend = cosim.MujocoBackend(xml)
    backend.data.qvel[2] = -0.05  # a kick: 5 cm/s down
    sim = cosim.CoSimulation(world, backend)
    att = sim.attach(rod, "end", body="weight", frame=False)
    assert att.coupling == "inertial"
    sim.run(1.0)
    stretch = (M + rod.mass / 2) * G * L / (E * math.pi * r * r)
    assert -rod.positions[-1, 2] == pytest.approx(stretch, rel=0.05)
    mujoco.mj_kinematics(backend.model, backend.data)
    assert -backend.data.xpos[backend.body_id("weight"), 2] == pytest.approx(stretch, rel=0.05)
    assert abs(backend.data.qvel[2]) < 1e-6


def test_attach_checks_its_arguments():
    xml = """<mujoco><worldbody><body name="b" pos="0 0 1"><freejoint/>
      <geom type="sphere" size="0.01" mass="0.1"/></body></worldbody></mujoco>"""
    world = dx.World(dt=2e-3, integrator="stable")
    rod = world.add_rod(_rope((0, 0, 1), (1, 0, 0)))
    sim = cosim.CoSimulation(world, cosim.MujocoBackend(xml))
    with pytest.raises(ValueError, match="no body named 'nope'"):
        sim.attach(rod, "start", body="nope")
    with pytest.raises(ValueError, match="end must be"):
        sim.attach(rod, "middle", body="b")
    with pytest.raises(ValueError, match="from the attachment point"):
        sim.attach(rod, "end", body="b")
    with pytest.raises(ValueError, match="whole number"):
        cosim.CoSimulation(dx.World(dt=3e-4), cosim.MujocoBackend(xml))
    with pytest.raises(ValueError, match="MJCF"):
        cosim.MujocoBackend("/no/such/file.xml")


def test_rope_converges_as_substeps_grow_explicit_integrator():
    """A rope hanging from a sprung carriage (kinematic coupling, explicit steps): the tip
    after 0.2 s approaches the finest run as the substeps per 2 ms macro step grow, with the
    clamp jumped to the carriage at each macro step and, closer at every count (the default
    with substeps), carried on continuously (measured: 2.45 / 0.75 / 0.30 um against 0.58 /
    0.43 / 0.25 um at 10 / 20 / 40 substeps)."""
    xml = """<mujoco><option timestep="0.002"/><worldbody>
      <body name="carriage" pos="0 0 1"><joint type="slide" axis="1 0 0" stiffness="40"/>
        <geom type="sphere" size="0.02" mass="0.3" contype="0" conaffinity="0"/></body>
      </worldbody></mujoco>"""

    def tip(substeps, continuous):
        world = dx.World(dt=2e-3 / substeps)
        rod = world.add_rod(_rope((0, 0, 1), (0, 0, -1), length=0.3, n=10, damping=0.5))
        backend = cosim.MujocoBackend(xml)
        backend.data.qvel[0] = 0.5
        sim = cosim.CoSimulation(world, backend, continuous_drivers=continuous)
        sim.attach(rod, "start", body="carriage")
        sim.run(0.2)
        return rod.positions[-1].copy()

    errors = {}
    for continuous in (False, True):
        ref = tip(160, continuous)
        errors[continuous] = [np.linalg.norm(tip(n, continuous) - ref) for n in (10, 20, 40)]
        assert errors[continuous][0] > errors[continuous][1] > errors[continuous][2]
    assert errors[False][2] < 0.3 * errors[False][0]
    assert all(c < j for c, j in zip(errors[True], errors[False])), errors


def test_calibration_experiment_runs_with_both_rope_models(tmp_path):
    from deformx.apps import calibration as cal

    tables = {}
    for rope in ("cosserat", "capsule"):
        out = tmp_path / f"{rope}.csv"
        tables[rope] = cal.run(rope, duration=0.4, out=out, every=0.02)
        lines = out.read_text().splitlines()
        assert lines[0] == "time,marker,x,y,z"
        assert len(lines) == 1 + 21 * 20  # t = 0, 0.02, ..., 0.4 s; 20 markers
        t = tables[rope]
        last = t[t[:, 0] == t[:, 0].max()]
        s = cal.Setup()
        # the anchored end stays put; the held end follows the tool's sinusoid
        np.testing.assert_allclose(last[-1, 2:5], s.anchor, atol=0.01)
        target = np.array(s.start) + [0, 0, s.amplitude * math.sin(2 * math.pi * s.frequency
                                                                     * 0.4)]
        np.testing.assert_allclose(last[0, 2:5], target, atol=0.02)
    # the two rope models start alike and stay close over the first swing
    err = cal.marker_error(tables["cosserat"], tables["capsule"])
    assert err[0] < 1e-3 and err.max() < 0.15


def test_cosim_yaml_scene_runs_and_names_its_bad_fields(tmp_path):
    from pathlib import Path

    import yaml

    from deformx.apps import scenes

    path = Path(__file__).resolve().parents[1] / "examples" / "scenes" / "ur5e_rope_box.yaml"
    scene = scenes.load_scene(path).model_copy(update={"duration": 0.1})
    result = scenes.run_scene(scene, progress=False, out_dir=tmp_path)
    assert result["npz"].is_file() and result.sim_time == pytest.approx(0.1)
    data = yaml.safe_load(path.read_text())
    data["cosim"]["mjcf"] = str(path.parent / data["cosim"]["mjcf"])
    data["cosim"]["attach"][0]["body"] = "gripper"
    bad = scenes.parse_scene(data)
    world, rods = scenes.build_world(bad)
    with pytest.raises(ValueError, match=r"cosim.attach\[0\]: body: no body named 'gripper'"):
        scenes.build_cosim(bad, world, rods)
    data["cosim"]["attach"][0]["body"] = "tool_tip"
    data["cosim"]["controls"][0]["actuator"] = "pan"
    bad = scenes.parse_scene(data)
    world, rods = scenes.build_world(bad)
    with pytest.raises(ValueError, match=r"cosim.controls\[0\].actuator: no actuator 'pan'"):
        scenes.build_cosim(bad, world, rods)


def test_attached_frame_turns_with_the_body_and_detach_lets_go():
    """A rope held at an offset by a spinning body keeps its end's frame fixed in the body;
    after detach the end falls freely."""
    xml = """<mujoco><option timestep="0.002" gravity="0 0 0"/><worldbody>
      <body name="hub" pos="0 0 1"><joint name="spin" type="hinge" axis="0 0 1" damping="0"/>
        <geom type="cylinder" size="0.05 0.02" mass="5.0" contype="0" conaffinity="0"/></body>
      </worldbody></mujoco>"""
    world = dx.World(dt=2e-3, integrator="stable", gravity=(0, 0, 0))
    rod = world.add_rod(_rope((0.1, 0, 1), (1, 0, 0), length=0.3, n=12, damping=1.0))
    backend = cosim.MujocoBackend(xml)
    backend.data.qvel[0] = 2.0  # rad/s
    sim = cosim.CoSimulation(world, backend)
    att = sim.attach(rod, "start", body="hub", offset=(0.1, 0, 0))
    Q0 = rod.directors[0].copy()
    sim.run(0.5)
    mujoco.mj_kinematics(backend.model, backend.data)
    R = backend.data.xmat[backend.body_id("hub")].reshape(3, 3)
    # node at the offset in the hub's frame, material frame turned with the hub
    np.testing.assert_allclose(rod.positions[0], backend.data.xpos[1] + R @ [0.1, 0, 0],
                               atol=5e-3)  # the hub's pose after mj_step is one step stale
    angle = backend.data.qpos[0]
    Rz = np.array([[math.cos(angle), -math.sin(angle), 0], [math.sin(angle), math.cos(angle), 0],
                   [0, 0, 1]])
    np.testing.assert_allclose(rod.directors[0], Q0 @ Rz.T, atol=1e-9)
    assert abs(sim.wrench("hub")[5]) > 0  # the rope's drag slows the hub
    sim.detach(att)
    assert not rod.clamps and not sim.attachments
    spin = backend.data.qvel[0]
    sim.run(0.1)
    assert backend.data.qvel[0] == pytest.approx(spin, rel=1e-12)  # the hub spins freely
    assert np.all(sim.wrench("hub") == 0.0)


def test_a_held_rope_ignores_the_holding_body_and_bodies_welded_to_it():
    from deformx import robots

    backend = cosim.MujocoBackend(robots.ur5e(tool_length=0.3))
    world = dx.World(dt=2e-3, integrator="stable")
    tip = backend.motion("tool_tip").position
    rod = world.add_rod(_rope(tip, (0, 0, -1), length=0.2, n=8))
    sim = cosim.CoSimulation(world, backend)
    stick = sim.add_colliders("flange")  # the stick's capsule: welded to tool_tip
    wrist = sim.add_colliders("wrist_2_link")  # across the wrist_3 joint: not welded
    att = sim.attach(rod, "start", body="tool_tip")
    ignored = {c for (r, c) in world._ignored}  # (rod, collider) indices
    assert stick and {c.index for c in stick} <= ignored
    assert not ({c.index for c in wrist} & ignored)
    sim.detach(att)
    assert not world._ignored


@pytest.mark.slow
def test_calibration_recovers_youngs_modulus_from_noisy_markers():
    """Markers made by a simulation (E 2e5 Pa, damping 0.1 1/s) plus 2 mm noise: CMA-ES
    started at E 1.2e5, damping 0.3 finds E within 5 %. The damping is weakly identified by a
    0.8 s run (it changes the markers by ~2 mm at 2x): its value is only reported."""
    from dataclasses import replace

    from deformx.apps import calibration as cal
    from deformx.apps import rope_fit as rf

    setup = cal.Setup()
    motion = rf.tool_motion(setup, 0.8, 0.01)
    truth = cal.run("cosserat", duration=0.8, setup=setup, every=0.02, motion=motion)
    noisy = truth.copy()
    noisy[:, 2:5] += np.random.default_rng(1).normal(scale=0.002, size=noisy[:, 2:5].shape)
    start = {"youngs_modulus": 1.2e5, "damping": 0.3}
    result = rf.calibrate(noisy, motion, "cosserat", setup=setup, start=start, max_evals=36)
    assert result.parameters["youngs_modulus"] == pytest.approx(2e5, rel=0.05)
    before = cal.marker_error(cal.run("cosserat", duration=0.8, every=0.02, motion=motion,
                                      setup=replace(setup, **start)), noisy).mean()
    assert result.error < 0.5 * before
    assert 1e-4 <= result.parameters["damping"] <= 10.0


def test_calibrate_command_fits_the_capsule_rope(tmp_path):
    """The CLI on files: markers of a Cosserat run, the capsule model fitted to them."""
    import json

    from typer.testing import CliRunner

    from deformx.apps import calibration as cal
    from deformx.apps import rope_fit as rf
    from deformx.cli import app

    setup = cal.Setup()
    motion = rf.tool_motion(setup, 0.3, 0.01)
    rf.write_motion(tmp_path / "motion.csv", *motion)
    cal.run("cosserat", duration=0.3, setup=setup, every=0.02, motion=motion,
            out=tmp_path / "markers.csv")
    res = CliRunner().invoke(app, ["calibrate", str(tmp_path / "markers.csv"), "--motion",
                                   str(tmp_path / "motion.csv"), "--rope", "capsule",
                                   "--evals", "6", "--out", str(tmp_path / "fit"),
                                   "--no-progress"])
    assert res.exit_code == 0, res.output
    fit = json.loads((tmp_path / "fit" / "fit.json").read_text())
    assert set(fit["parameters"]) == {"youngs_modulus", "capsule_damping"}
    assert fit["mean_error_m"] <= fit["mean_error_before_m"] + 1e-9
    assert (tmp_path / "fit" / "calibration.png").is_file()
    res = CliRunner().invoke(app, ["calibrate", str(tmp_path / "nope.csv"), "--motion",
                                   str(tmp_path / "motion.csv")])
    assert res.exit_code != 0 and "nope.csv" in res.output
