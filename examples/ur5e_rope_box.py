"""A UR5e swings a rope into a box lying on a table: co-simulation with MuJoCo, two-way.

The robot, the table and the box live in MuJoCo; the rope is a DeformX rod held by the robot's
tool (kinematic attachment) that touches the table and the box (their geoms become rod
colliders). The rope's contact pushes the box: watch its position change.

    python examples/ur5e_rope_box.py                 # writes examples/scenes/ur5e_box.xml, runs 3 s
    deformx run examples/scenes/ur5e_rope_box.yaml   # the same scene from YAML
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

import deformx as dx
from deformx import cosim, robots
from deformx.robots.ik import solve_position

TOOL = 0.3
START_TIP = (-0.55, 0.0, 1.0)  # the tool tip above the table (m, DH base frame = world)
REST = (0.0, -1.9, 1.9, -1.57, -1.57, 0.0)


def mjcf() -> str:
    """UR5e + a table + a 50 g box on it, the robot starting with its tool above the table."""
    arm = robots.ur5e(tool_length=TOOL, floor=True)
    q = solve_position(mujoco.MjModel.from_xml_string(arm), "tool_tip", START_TIP, REST,
                       rest=REST, iterations=300)
    spec = mujoco.MjSpec.from_string(robots.ur5e(tool_length=TOOL, floor=True, q0=q))
    spec.worldbody.add_geom(name="table", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.3, 0.4, 0.2],
                            pos=[-0.6, 0.0, 0.2], rgba=[0.55, 0.4, 0.25, 1.0])
    box = spec.worldbody.add_body(name="box", pos=[-0.55, 0.12, 0.45])
    box.add_freejoint()
    box.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.05, 0.05, 0.05], mass=0.05,
                 friction=[0.3, 0.005, 0.0001],
                 rgba=[0.2, 0.5, 0.85, 1.0])
    return spec.to_xml()


def main(duration: float = 3.0) -> None:
    path = Path(__file__).parent / "scenes" / "ur5e_box.xml"
    path.write_text(mjcf())
    backend = cosim.MujocoBackend(str(path), keyframe="home")
    tip = backend.motion("tool_tip").position
    world = dx.World(dt=backend.dt, integrator="stable")
    rope = world.add_rod(dx.Rod.straight(n_elements=24, start=tip, direction=(0, 0, -1),
                                         length=0.58, radius=0.006, density=1100.0,
                                         youngs_modulus=5e6, damping=0.5))
    sim = cosim.CoSimulation(world, backend)
    sim.add_colliders("world")  # floor and table
    sim.add_colliders("box")
    sim.attach(rope, "start", body="tool_tip")
    pan = backend.model.actuator("shoulder_pan").id
    box0 = backend.motion("box").position
    for k in range(int(duration / sim.dt)):
        backend.data.ctrl[pan] = 0.4 * np.sin(2 * np.pi * 0.4 * sim.time)  # swing across
        sim.step()
        if k % 250 == 0:
            b = backend.motion("box").position
            print(f"t = {sim.time:4.2f} s  rope tip {np.round(rope.positions[-1], 3)}  "
                  f"box moved {1e3 * np.linalg.norm(b - box0):6.1f} mm  "
                  f"rope on box {np.round(sim.wrench('box')[:3], 3)} N")
    print(f"box moved {1e3 * np.linalg.norm(backend.motion('box').position - box0):.1f} mm in "
          f"{duration:g} s")


if __name__ == "__main__":
    main()
