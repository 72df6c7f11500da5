"""Coupling check (not a speed test): a light free body on a stiff steel wire, kinematic
against inertial coupling, for the table "Why: a light body on a stiff wire" in docs/cosim.md.

Setup as in tests/test_cosim.py (test_light_body_on_a_stiff_steel_wire_settles_to_the_static_
stretch): a 50 g free body ("weight", free joint) hanging from 1 m of steel wire (E 2e11 Pa,
r 0.5 mm, 7850 kg/m^3, 20 elements, top fixed at z = 1 m), MuJoCo at 2 ms, the body kicked
5 cm/s downwards. Each row co-simulates --duration s (default 1; the wall time excludes
compiling) and reports the time of divergence, or the end node's stretch against the static
stretch (M + m_rod/2) g L / (E pi r^2), the body's speed, and the stretch's range over the run.

    python benchmarks/bench_steel_wire.py             # all rows, 1 s each
    python benchmarks/bench_steel_wire.py --quick     # without the explicit 1000-substep rows
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
from deformx import cosim

M, E, R, L, RHO, N_EL = 0.05, 2e11, 5e-4, 1.0, 7850.0, 20
G = 9.81
MACRO_DT = 2e-3
XML = f"""<mujoco><option timestep="{MACRO_DT}"/><worldbody>
  <body name="weight" pos="0 0 0"><freejoint/>
    <geom type="sphere" size="0.01" mass="{M}" contype="0" conaffinity="0"/></body>
  </worldbody></mujoco>"""

# coupling, integrator, substeps per 2 ms macro step
ROWS = [("kinematic", "stable", 1), ("kinematic", "stable", 10),
        ("kinematic", "verlet", 400), ("kinematic", "verlet", 1000),
        ("inertial", "stable", 1), ("inertial", "stable", 10),
        ("inertial", "verlet", 1000)]


def wire(coupling: str, integrator: str, substeps: int):
    kwargs = dict(tolerance=1e-8) if integrator == "stable" else {}
    world = dx.World(dt=MACRO_DT / substeps, integrator=integrator, **kwargs)
    rod = world.add_rod(dx.Rod.straight(n_elements=N_EL, start=(0, 0, L), direction=(0, 0, -1),
                                        length=L, radius=R, density=RHO, youngs_modulus=E))
    rod.fix_start()
    backend = cosim.MujocoBackend(XML)
    backend.data.qvel[2] = -0.05  # a kick: 5 cm/s down
    sim = cosim.CoSimulation(world, backend, substeps=substeps)
    sim.attach(rod, "end", body="weight", frame=False, coupling=coupling)
    return sim, rod, backend


def run_row(coupling: str, integrator: str, substeps: int, duration: float) -> tuple[str, float]:
    sim, rod, backend = wire(coupling, integrator, substeps)
    static = (M + rod.mass / 2) * G * L / (E * math.pi * R * R)
    n = int(round(duration / MACRO_DT))
    lo = hi = 0.0
    t0 = time.perf_counter()
    try:
        for _ in range(n):
            sim.step()
            s = -float(rod.positions[-1, 2])
            if not math.isfinite(s):
                return f"NaN at {sim.time * 1e3:.0f} ms", time.perf_counter() - t0
            lo, hi = min(lo, s), max(hi, s)
    except dx.SimulationDiverged as err:
        return (f"diverges at {err.time * 1e3:.1f} ms ({err.reason.split(' (')[0]})",
                time.perf_counter() - t0)
    wall = time.perf_counter() - t0
    s = -float(rod.positions[-1, 2])
    v = float(np.linalg.norm(backend.data.qvel[:3]))
    return (f"stretch {s * 1e6:.3f} um ({(s / static - 1) * 100:+.2f} %), "
            f"body |v| {v:.1e} m/s, over the run {lo * 1e6:.2f} to {hi * 1e6:.2f} um "
            f"(centre {(lo + hi) / 2 * 1e6:.2f})"), wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="skip the explicit 1000-substep rows")
    parser.add_argument("--duration", type=float, default=1.0, help="simulated s per row")
    args = parser.parse_args()
    console = Console()
    rows = [r for r in ROWS if not (args.quick and r[1] == "verlet" and r[2] == 1000)]
    rod_mass = RHO * math.pi * R * R * L
    static = (M + rod_mass / 2) * G * L / (E * math.pi * R * R)
    console.print("compiling on the first run (numba: minutes)...")
    table = Table(title=f"{M * 1e3:.0f} g on {L:g} m of steel wire at MuJoCo's "
                        f"{MACRO_DT * 1e3:g} ms, kicked 5 cm/s, after {args.duration:g} s "
                        f"(static stretch {static * 1e6:.3f} um)")
    for col in ("coupling", "integrator", "substeps", "result", "wall s"):
        table.add_column(col, justify="left" if col == "result" else "right")
    for row in rows:  # compile (excluded from the wall times)
        try:
            wire(*row)[0].step()
        except dx.SimulationDiverged:
            pass
    for coupling, integrator, substeps in rows:
        result, wall = run_row(coupling, integrator, substeps, args.duration)
        name = "stable" if integrator == "stable" else "explicit"
        console.print(f"{coupling}, {name}, {substeps} substeps: {wall:.2f} s")
        table.add_row(coupling, name, str(substeps), result, f"{wall:.2f}")
    console.print(table)
    console.print(f"[dim]{time.strftime('%Y-%m-%d %H:%M')}, python {sys.version.split()[0]}, "
                  f"{os.cpu_count()} cores[/dim]")


if __name__ == "__main__":
    main()
