"""How accurately each integrator and step follows the hit-target task's rope at the 2 ms
control rate: tip error against a converged explicit run (1e-5 s), and cost per control step.

The task rope (1 m, 20 elements, r 6.35 mm, rho 700, E 2e5, damping 0.1) hangs from a frame
clamp that traces the calibration motion (1.2 Hz, 0.2 m amplitude), vertically ("vertical")
or sideways in the swing plane ("swing"); the clamp's pose, velocity and acceleration are set
every 2 ms control step, as the co-simulation does. Chooses the task's default rope.

    python benchmarks/bench_rope_accuracy.py                 # 3 s, both motions
    python benchmarks/bench_rope_accuracy.py --duration 1 --motion swing
    python benchmarks/bench_rope_accuracy.py --motion vertical --stretch-modulus 2e7 \
        --shear-modulus 6.7e6 --cases stable:2e-3 stable:5e-4 explicit:1e-4
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time

import numpy as np
from rich.console import Console
from rich.table import Table

import deformx as dx

CONTROL_DT = 2e-3
FREQ, AMP = 1.2, 0.2
CASES = [("explicit", 1e-5), ("stable", 2e-3), ("stable", 1e-3), ("stable", 5e-4),
         ("stable", 2.5e-4), ("explicit", 1e-3), ("explicit", 5e-4), ("explicit", 2.5e-4),
         ("explicit", 1e-4)]


def clamp_motion(t: float, axis: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    w = 2.0 * math.pi * FREQ
    p = np.array([0.0, 0.0, 1.0]) + AMP * math.sin(w * t) * axis
    return p, AMP * w * math.cos(w * t) * axis, -AMP * w * w * math.sin(w * t) * axis


def run(integrator: str, dt: float, motion: str, duration: float,
        moduli: dict | None = None) -> tuple[np.ndarray, float]:
    """Tip positions at every control step and wall seconds per control step; ``moduli``:
    stretch_modulus / shear_modulus / twist_modulus of the rope (default: from E, as the
    authors')."""
    world = dx.World(dt=dt, integrator={"explicit": "verlet", "bdf2": "stable"}.get(
        integrator, integrator), order=2 if integrator == "bdf2" else 1)
    rod = world.add_rod(dx.Rod.straight(n_elements=20, start=(0, 0, 1), direction=(0, 0, -1),
                                        length=1.0, radius=0.00635, density=700.0,
                                        youngs_modulus=2e5, damping=0.1, normal=(1, 0, 0),
                                        **(moduli or {})))
    clamp = rod.fix_start()
    axis = np.array([0.0, 0.0, 1.0]) if motion == "vertical" else np.array([0.0, 1.0, 0.0])
    substeps = int(round(CONTROL_DT / dt))
    n = int(round(duration / CONTROL_DT))
    tips = np.empty((n, 3))
    world.step(1)  # compile (or load the cache) outside the timing
    world.time = 0.0
    rod.positions[:] = np.column_stack([np.zeros(21), np.zeros(21), np.linspace(1, 0, 21)])
    rod.velocities[:] = 0.0
    t0 = time.perf_counter()
    for k in range(n):
        p, v, a = clamp_motion(k * CONTROL_DT, axis)
        clamp.set_pose(p)
        clamp.set_velocity(v)
        clamp.set_acceleration(a)
        world.step(substeps)
        tips[k] = rod.positions[-1]
    return tips, (time.perf_counter() - t0) / n


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=3.0, help="simulated s")
    parser.add_argument("--motion", choices=("vertical", "swing", "both"), default="both")
    parser.add_argument("--stretch-modulus", type=float, default=None, help="Pa (default E)")
    parser.add_argument("--shear-modulus", type=float, default=None, help="Pa (default E/3)")
    parser.add_argument("--twist-modulus", type=float, default=None,
                        help="Pa (default: the shear modulus)")
    parser.add_argument("--cases", nargs="+", default=None,
                        help="integrator:dt pairs, e.g. stable:5e-4 bdf2:2e-3 explicit:1e-4")
    args = parser.parse_args()
    moduli = {k: v for k, v in (("stretch_modulus", args.stretch_modulus),
                                ("shear_modulus", args.shear_modulus),
                                ("twist_modulus", args.twist_modulus)) if v is not None}
    cases = CASES if args.cases is None else [("explicit", 1e-5)] + [
        (c.split(":")[0], float(c.split(":")[1])) for c in args.cases]
    console = Console()
    motions = ("vertical", "swing") if args.motion == "both" else (args.motion,)
    for motion in motions:
        table = Table(title=f"task rope {moduli or ''}, {motion} clamp motion {FREQ} Hz {AMP} "
                            f"m, {args.duration:g} s: tip error vs explicit 1e-5 s")
        for col in ("integrator", "dt (s)", "substeps / 2 ms", "mean (cm)", "max (cm)",
                    "us / control step"):
            table.add_column(col, justify="right")
        ref = None
        for integrator, dt in cases:
            try:
                tips, cost = run(integrator, dt, motion, args.duration, moduli)
            except dx.SimulationDiverged as err:
                table.add_row(integrator, f"{dt:g}", f"{round(CONTROL_DT / dt)}", "diverged",
                              str(err).split(".")[0][:40], "-")
                continue
            if ref is None:
                ref = tips
            err = np.linalg.norm(tips - ref, axis=1)
            table.add_row(integrator, f"{dt:g}", f"{round(CONTROL_DT / dt)}",
                          f"{100 * err.mean():.2f}", f"{100 * err.max():.2f}",
                          f"{1e6 * cost:.1f}")
        console.print(table)
    console.print(f"[dim]{time.strftime('%Y-%m-%d %H:%M')}, python {sys.version.split()[0]}, "
                  f"{os.cpu_count()} cores[/dim]")


if __name__ == "__main__":
    main()
