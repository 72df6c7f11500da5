"""Co-simulation speed: the authors' RL rope held by a UR5e in MuJoCo, DeformX (stable
integrator, one substep per 2 ms control step, MuJoCo and coupling included) against PyElastica
stepping the same rope 200 times at 1e-5 s per control step (the authors' setting), side by
side in one run; and the coupling's own cost per macro step for 1, 8 and 64 coupled bodies.

Rope: 1 m, 20 elements, r 6.35 mm, 700 kg/m^3, E 2e5 Pa, damping 0.1 1/s. DeformX: the rope
hangs from the UR5e's 0.65 m stick (base at z = 1.7 m turned -90 deg about x, the authors'
home pose), shoulder and elbow servos tracking a 1 Hz sinusoid. PyElastica: the same rope with
its top node driven along the same kind of sinusoid by a boundary condition (PositionVerlet,
gravity, AnalyticalLinearDamper). Rounds interleave the two engines; the table gives min-max
over rounds of the median control step, and DeformX's split (rods, MuJoCo, coupling, Python).

    python benchmarks/bench_cosim.py              # 3 rounds
    python benchmarks/bench_cosim.py --quick      # 1 round, fewer steps
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from statistics import median

import numpy as np
from rich.console import Console
from rich.table import Table

import deformx as dx
from deformx import cosim, robots

ROPE = dict(n_elements=20, length=1.0, radius=6.35e-3, density=700.0, youngs_modulus=2e5,
            damping=0.1)
CONTROL_DT = 2e-3
SUBSTEPS_PE = 200  # 1e-5 s


def deformx_rope_on_ur5e():
    R = np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])
    xml = robots.ur5e(tool_length=0.65, base_position=(0, 0, 1.7), base_rotation=R,
                      ur_base_link=True, q0=robots.HOME, timestep=CONTROL_DT)
    backend = cosim.MujocoBackend(xml, keyframe="home")
    tip = backend.motion("tool_tip").position
    world = dx.World(dt=CONTROL_DT, integrator="stable")
    rod = world.add_rod(dx.Rod.straight(start=tip, direction=(0, 0, -1), **ROPE))
    sim = cosim.CoSimulation(world, backend)
    sim.attach(rod, "start", body="tool_tip")
    home = np.array(robots.HOME)

    def control_step():
        t = backend.time
        backend.data.ctrl[:] = home + 0.3 * math.sin(2 * math.pi * t) * np.array(
            [0, 1, -1, 0, 0, 0])
        sim.step()

    return sim, control_step


def elastica_rope():
    import elastica as ea

    class Driven(ea.ConstraintBase):
        """The top node follows x = x0 + A sin(2 pi t), frames held."""

        def __init__(self, start, directors, **kwargs):
            super().__init__(**kwargs)
            self.start = np.array(start, dtype=np.float64)
            self.directors = np.array(directors)

        def constrain_values(self, system, time):
            rod = system
            rod.position_collection[:, 0] = self.start
            rod.position_collection[0, 0] += 0.2 * math.sin(2 * math.pi * time)
            rod.director_collection[..., 0] = self.directors

        def constrain_rates(self, system, time):
            rod = system
            rod.velocity_collection[:, 0] = 0.0
            rod.velocity_collection[0, 0] = 0.4 * math.pi * math.cos(2 * math.pi * time)
            rod.omega_collection[:, 0] = 0.0

    class Sim(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.Damping):
        pass

    sim = Sim()
    E = ROPE["youngs_modulus"]
    rod = ea.CosseratRod.straight_rod(ROPE["n_elements"], np.array([0.0, 0.0, 1.7]),
                                      np.array([0.0, 0.0, -1.0]), np.array([1.0, 0.0, 0.0]),
                                      ROPE["length"], ROPE["radius"], ROPE["density"],
                                      youngs_modulus=E, shear_modulus=E / 3.0)
    sim.append(rod)
    sim.constrain(rod).using(Driven, start=rod.position_collection[:, 0].copy(),
                             directors=rod.director_collection[..., 0].copy())
    sim.add_forcing_to(rod).using(ea.GravityForces, acc_gravity=np.array([0.0, 0.0, -9.81]))
    dt = CONTROL_DT / SUBSTEPS_PE
    sim.dampen(rod).using(ea.AnalyticalLinearDamper, uniform_damping_constant=ROPE["damping"],
                          time_step=dt)
    sim.finalize()
    stepper = ea.PositionVerlet()
    state = {"t": np.float64(0.0)}

    def control_step():
        t = state["t"]
        for _ in range(SUBSTEPS_PE):
            t = stepper.step(sim, t, np.float64(dt))
        state["t"] = t

    return rod, control_step


def time_steps(step, n: int, repeats: int) -> float:
    """Median over ``repeats`` of the mean seconds per call over ``n`` calls."""
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(n):
            step()
        out.append((time.perf_counter() - t0) / n)
    return median(out)


def coupling_cost(n_bodies: int, steps: int) -> tuple[float, float]:
    """Seconds per macro step of the coupling (reading motions, drivers, wrenches) and of the
    whole step, ``n_bodies`` bodies on slide springs each holding a 5-element rope."""
    bodies = "".join(
        f'<body name="b{k}" pos="{0.3 * (k % 8)} {0.3 * (k // 8)} 1">'
        '<joint type="slide" axis="0 0 1" stiffness="200" damping="5"/>'
        '<geom type="sphere" size="0.02" mass="0.5" contype="0" conaffinity="0"/></body>'
        for k in range(n_bodies))
    backend = cosim.MujocoBackend(f'<mujoco><option timestep="{CONTROL_DT}"/>'
                                  f"<worldbody>{bodies}</worldbody></mujoco>")
    world = dx.World(dt=CONTROL_DT, integrator="stable", rod_contact=False)
    sim = cosim.CoSimulation(world, backend)
    for k in range(n_bodies):
        p = backend.motion(f"b{k}").position
        rod = world.add_rod(dx.Rod.straight(n_elements=5, start=p, direction=(0, 0, -1),
                                            length=0.2, radius=0.004, youngs_modulus=1e6,
                                            damping=1.0))
        sim.attach(rod, "start", body=f"b{k}")
    for _ in range(5):
        sim.step()
    sim.profile = True
    sim.reset_timings()
    t0 = time.perf_counter()
    for _ in range(steps):
        sim.step()
    total = (time.perf_counter() - t0) / steps
    return sim.timings["coupling"] / steps, total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="1 round, fewer steps")
    parser.add_argument("--rounds", type=int, default=None)
    args = parser.parse_args()
    rounds = args.rounds or (1 if args.quick else 3)
    n_ours, n_pe, repeats = (200, 5, 3) if args.quick else (1000, 20, 5)
    console = Console()
    console.print("building and compiling (first run: numba compiles the stable integrator)...")
    sim, ours = deformx_rope_on_ur5e()
    for _ in range(10):
        ours()
    _, theirs = elastica_rope()
    theirs()
    t_ours, t_pe, splits = [], [], []
    for r in range(rounds):
        sim.profile = True
        sim.reset_timings()
        t_ours.append(time_steps(ours, n_ours, repeats))
        tm = sim.timings
        splits.append({k: tm[k] / tm["steps"] for k in ("rods", "backend", "coupling")}
                      | {"total": t_ours[-1]})
        sim.profile = False
        t_pe.append(time_steps(theirs, n_pe, repeats))
        console.print(f"round {r + 1}: DeformX {t_ours[-1] * 1e6:.0f} us, "
                      f"PyElastica {t_pe[-1] * 1e3:.2f} ms per control step")

    def span(values, scale, fmt):
        lo, hi = min(values) * scale, max(values) * scale
        return f"{lo:{fmt}}" if len(values) == 1 else f"{lo:{fmt}}-{hi:{fmt}}"

    ratios = [p / o for p, o in zip(t_pe, t_ours)]
    table = Table(title="RL rope on a UR5e, seconds per 2 ms control step "
                        f"(min-max of {rounds} rounds' medians)")
    for col in ("engine", "per control step", "speed-up", "target"):
        table.add_column(col, justify="right")
    table.add_row("DeformX stable, 1 substep, + MuJoCo + coupling", span(t_ours, 1e6, ".0f") + " us",
                  span(ratios, 1, ".0f") + "x", ">= 50x")
    table.add_row(f"PyElastica, {SUBSTEPS_PE} x 1e-5 s", span(t_pe, 1e3, ".2f") + " ms", "1x", "")
    console.print(table)
    split = Table(title="DeformX control step, split (min-max over rounds)")
    for col in ("rods (world.step)", "MuJoCo (forward + step)", "coupling", "Python, rest"):
        split.add_column(col, justify="right")
    rest = [s["total"] - s["rods"] - s["backend"] - s["coupling"] for s in splits]
    split.add_row(*(span([s[k] for s in splits], 1e6, ".1f") + " us"
                    for k in ("rods", "backend", "coupling")), span(rest, 1e6, ".1f") + " us")
    console.print(split)
    ctable = Table(title="Coupling cost per macro step (bodies on slide springs, one 5-element "
                         "rope each)")
    for col in ("coupled bodies", "coupling", "whole step", "coupling per body"):
        ctable.add_column(col, justify="right")
    for n in (1, 8, 64):
        c, total = coupling_cost(n, 100 if args.quick else 400)
        ctable.add_row(str(n), f"{c * 1e6:.0f} us", f"{total * 1e6:.0f} us",
                       f"{c / n * 1e6:.1f} us")
    console.print(ctable)
    console.print(f"[dim]{time.strftime('%Y-%m-%d %H:%M')}, python {sys.version.split()[0]}, "
                  f"{os.cpu_count()} cores[/dim]")


if __name__ == "__main__":
    main()
