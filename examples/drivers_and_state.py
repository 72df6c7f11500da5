"""Kinematic drivers, the loads they feel, callbacks and state snapshots.

A gripper (a clamp) lifts a rope off a conveyor (a box that accelerates under it), as a robot
controller would drive it: velocity and acceleration set once per 10 ms control step, the
world integrating both drivers inside each step. A callback logs the load on the gripper; a
state snapshot taken half-way is restored to replay the second half bit for bit.

    python examples/drivers_and_state.py
"""

from __future__ import annotations

import numpy as np

import deformx as dx


class GripperLog:
    """A callback: the gripper's load every ``every`` s."""

    def __init__(self, clamp: dx.Clamp, every: float = 0.05) -> None:
        self.clamp, self.every, self.rows = clamp, every, []

    def __call__(self, world: dx.World) -> None:
        self.rows.append((world.time, *self.clamp.force))


def main() -> None:
    world = dx.World(dt=1e-2, integrator="stable")
    world.add_plane(friction=0.5)
    belt = world.add_box((0.4, 0.1, 0.025), pose=(0.0, 0.0, 0.025), friction=0.8)
    rope = world.add_rod(dx.Rod.straight(
        30, start=(-0.3, 0.0, 0.055), direction=(1, 0, 0), length=0.6, radius=0.004,
        density=1100.0, youngs_modulus=5e6, damping=0.5))
    gripper = rope.fix_start()
    log = GripperLog(gripper)
    world.run(0.3, callbacks=[log])  # the rope settles on the belt

    belt.set_acceleration(linear=(0.5, 0.0, 0.0))  # the belt speeds up under the rope
    snapshot = None
    for k in range(100):  # 1 s of 10 ms control steps
        if k == 50:
            snapshot = world.get_state()
        gripper.set_velocity(velocity=(0.0, 0.0, 0.3 * np.cos(2.0 * k * world.dt)))
        world.step()
        if k % 5 == 4:
            log(world)
    tip = rope.positions[-1].copy()

    # Replay the second half from the snapshot: same commands, same result to the last bit.
    world.set_state(snapshot)
    for k in range(50, 100):
        gripper.set_velocity(velocity=(0.0, 0.0, 0.3 * np.cos(2.0 * k * world.dt)))
        world.step()
    assert np.array_equal(rope.positions[-1], tip), "a replay is bit-identical"

    print(f"belt moved {belt.position[0]:.3f} m, now at {belt.velocity[0]:.2f} m/s")
    print(f"rope tip at {np.round(tip, 4)} m; replay from t = 0.80 s matches bit for bit")
    print("gripper load (N):  t      Fx       Fy       Fz")
    for t, fx, fy, fz in log.rows[::2]:
        print(f"               {t:5.2f} {fx:8.4f} {fy:8.4f} {fz:8.4f}")
    print(f"rope weight: {rope.mass * 9.81:.4f} N; impulse on the gripper since the start: "
          f"{np.round(gripper.impulse[:3], 4)} N s")


if __name__ == "__main__":
    main()
