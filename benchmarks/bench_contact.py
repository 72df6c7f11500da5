"""Contact speed: rod-rod contact against PyElastica's RodRodContact, and mesh contact cost.

Two tables, each measured in one run on the same machine (ratios, not absolute times, are what
carries over between machines):

1. Two 100-element rods in contact (clamped cantilevers, the second lying across the first),
   explicit steps at the same dt: seconds per step of PyElastica 1.0 with ``RodRodContact`` and
   of DeformX with its default rod-rod contact; both also without contact, to show what contact
   costs in each. Target: DeformX >= 10x faster.
2. Scaling: n rods of 50 elements in a heap (rods crossing every few cm), explicit steps on one
   thread, with and without rod-rod contact: contact cost per segment and step should stay
   roughly flat as n grows (sort-and-sweep Verlet list).
3. A 100-element rope lying on a ~100,000-triangle mesh (a grid floor; and a rope draped over a
   blob), explicit steps: the contact's cost per step (the step with the mesh minus the step
   without it) against the cost of the rod's internal forces (``rod_internal_loads`` timed
   alone). Target: contact <= 2x internal forces.
4. Contact at large steps (the stable integrator at dt = 1e-2 against 1e-3, step halvings,
   Newton iterations, against the code before large-step contact): the table of
   ``bench_large_steps.py``, which runs each tree in its own interpreter.

    python benchmarks/bench_contact.py                  # full (3 rounds of table 4)
    python benchmarks/bench_contact.py --quick          # fewer steps and repeats, 1 round
    python benchmarks/bench_contact.py --no-large-steps # tables 1-3 only
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np
from rich.console import Console
from rich.table import Table

import deformx as dx
from deformx.apps import bench

DT = 5e-5
N_EL = 100
R = 0.01


def best_of(fn, repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        best = min(best, fn())
    return best


def deformx_pair(contact: bool):
    world = dx.World(dt=DT, rod_contact=contact)
    a = world.add_rod(dx.Rod.straight(n_elements=N_EL, start=(0, 0, 0), direction=(1, 0, 0),
                                      length=1.0, radius=R, youngs_modulus=1e6, density=1000.0,
                                      damping=1.0))
    b = world.add_rod(dx.Rod.straight(n_elements=N_EL, start=(0.5, -0.5, 2.05 * R),
                                      direction=(0, 1, 0), length=1.0, radius=R,
                                      youngs_modulus=1e6, density=1000.0, damping=1.0))
    a.fix_start()
    b.fix_start()
    return world


def elastica_pair(contact: bool):
    import elastica as ea

    class Sim(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.Damping, ea.Contact):
        pass

    sim = Sim()
    rods = []
    for start, direction in (((0.0, 0.0, 0.0), (1.0, 0.0, 0.0)),
                             ((0.5, -0.5, 2.05 * R), (0.0, 1.0, 0.0))):
        rod = ea.CosseratRod.straight_rod(N_EL, np.array(start), np.array(direction),
                                          np.array([0.0, 0.0, 1.0]), 1.0, R, 1000.0,
                                          youngs_modulus=1e6, shear_modulus=1e6 / 3.0)
        sim.append(rod)
        sim.constrain(rod).using(ea.OneEndFixedBC, constrained_position_idx=(0,),
                                 constrained_director_idx=(0,))
        sim.add_forcing_to(rod).using(ea.GravityForces, acc_gravity=np.array([0, 0, -9.81]))
        sim.dampen(rod).using(ea.AnalyticalLinearDamper, uniform_damping_constant=1.0,
                              time_step=DT)
        rods.append(rod)
    if contact:
        sim.detect_contact_between(rods[0], rods[1]).using(ea.RodRodContact, k=1e4, nu=10.0)
    sim.finalize()
    stepper = ea.PositionVerlet()

    def run(n: int) -> None:
        t = np.float64(0.0)
        for _ in range(n):
            t = stepper.step(sim, t, np.float64(DT))
    return run


def time_deformx_pair(contact: bool, steps: int, repeats: int) -> float:
    world = deformx_pair(contact)
    world.step(2000)  # compile, and let b settle onto a

    def once():
        t0 = time.perf_counter()
        world.step(steps)
        return (time.perf_counter() - t0) / steps
    return best_of(once, repeats)


def time_elastica_pair(contact: bool, steps: int, repeats: int) -> float:
    run = elastica_pair(contact)
    run(200)

    def once():
        t0 = time.perf_counter()
        run(steps)
        return (time.perf_counter() - t0) / steps
    return best_of(once, repeats)


def internal_forces_seconds(world: dx.World, repeats: int, calls: int = 20000) -> float:
    """Seconds per call of the internal-force kernel on the world's first rod."""
    from numba import njit

    from deformx.engine.kernels.bundles import carve_rods
    from deformx.engine.kernels.cosserat import rod_internal_loads

    @njit(cache=False)
    def loop(n, RF, RI):
        rd = carve_rods(RF, RI)
        for _ in range(n):
            rod_internal_loads(0, rd)

    args = world._bufs[:2]  # the rods' buffers
    loop(10, *args)

    def once():
        t0 = time.perf_counter()
        loop(calls, *args)
        return (time.perf_counter() - t0) / calls
    return best_of(once, repeats)


def heap(n_rods: int, contact: bool) -> dx.World:
    """``n_rods`` rods of 50 elements, 0.5 m, radius 5 mm, in four crossing layers (parallel
    rods within a layer, 45 degrees between layers) falling onto each other and the ground;
    the area grows with ``n_rods`` so that the density of crossings stays the same."""
    world = dx.World(dt=2e-5, rod_contact=contact, threads=1)
    per_layer = max(1, n_rods // 4)
    spacing = 1.0 / np.sqrt(n_rods)
    for k in range(n_rods):
        layer, i = k % 4, k // 4
        angle = layer * np.pi / 4
        d = np.array([np.cos(angle), np.sin(angle), 0.0])
        across = np.array([-d[1], d[0], 0.0])
        centre = (i - (per_layer - 1) / 2) * spacing * across + (0, 0, 0.006 + 0.011 * layer)
        world.add_rod(dx.Rod.straight(n_elements=50, start=centre - 0.25 * d, direction=d,
                                      length=0.5, radius=0.005, youngs_modulus=1e6,
                                      density=1000.0, damping=5.0))
    world.add_plane(friction=0.5)
    world.run(0.02)
    return world


def rope_on_mesh(scene: str, with_mesh: bool):
    """A 100-element rope (r = 5 mm) at rest on a mesh, or the same rope alone."""
    from deformx.engine.geometry.shapes import blob_mesh, grid_mesh

    world = dx.World(dt=2e-5, rod_contact=False)
    if scene == "floor":
        V, F = grid_mesh(1.2, 224)  # 100,352 triangles, 5.4 mm apart
        rod = dx.Rod.straight(n_elements=N_EL, start=(-0.4, 0.013, 0.005), direction=(1, 0, 0),
                              length=0.8, radius=0.005, youngs_modulus=1e6, density=1000.0,
                              damping=5.0)
        mesh = (V, F)
    else:
        mesh = blob_mesh(radius=0.1, subdivisions=7)  # 327,680 triangles, ~1 mm apart
        top = float(mesh.vertices[:, 2].max())
        rod = dx.Rod.straight(n_elements=N_EL, start=(-0.3, 0.004, top + 0.006),
                              direction=(1, 0, 0), length=0.6, radius=0.005,
                              youngs_modulus=1e6, density=1000.0, damping=5.0)
    world.add_rod(rod)
    n_tri = len(mesh[1]) if isinstance(mesh, tuple) else len(mesh.faces)
    if with_mesh:
        world.add_mesh(mesh, friction=0.5)
        world.run(0.1 if scene == "floor" else 0.6)  # come to rest on it (the blob: draped)
    else:
        world.gravity = np.zeros(3)
    return world, n_tri


def time_steps(world: dx.World, steps: int, repeats: int) -> float:
    world.step(10)

    def once():
        t0 = time.perf_counter()
        world.step(steps)
        return (time.perf_counter() - t0) / steps
    return best_of(once, repeats)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer steps and repeats")
    parser.add_argument("--no-large-steps", action="store_true",
                        help="skip table 4 (contact at dt = 1e-2 vs 1e-3, ~3 min per round)")
    args = parser.parse_args()
    steps, repeats = (500, 2) if args.quick else (3000, 3)
    console = Console(width=max(Console().width, 150))
    have_pe = bench.elastica_available()

    # 1. rod-rod
    rows = []
    for contact in (True, False):
        ours = time_deformx_pair(contact, steps, repeats)
        theirs = time_elastica_pair(contact, steps // 5, repeats) if have_pe else float("nan")
        rows.append((contact, ours, theirs))
    t = Table(title=f"Two 100-element rods in contact, explicit dt = {DT:g} s: seconds per step "
                    f"(best of {repeats})")
    for col in ("contact", "PyElastica", "DeformX", "speed-up", "target"):
        t.add_column(col, justify="right")
    for contact, ours, theirs in rows:
        ratio = theirs / ours
        target = ""
        if contact:
            target = ">= 10x " + ("met" if ratio >= 10 else "missed")
        t.add_row("RodRodContact / rod_contact=True" if contact else "none",
                  f"{theirs * 1e6:.0f} us", f"{ours * 1e6:.1f} us", f"{ratio:.0f}x", target)
    console.print(t)
    (_, c_ours, c_pe), (_, n_ours, n_pe) = rows
    console.print(f"contact's share of a step: PyElastica {(c_pe - n_pe) / n_pe:.1f}x the rest "
                  f"of the step, DeformX {(c_ours - n_ours) / n_ours:.2f}x")

    # 2. scaling of rod-rod contact
    t = Table(title="Rod-rod contact cost vs size: n rods x 50 elements in a heap, explicit, "
                    "one thread")
    for col in ("rods", "segments", "step without", "step with rod contact",
                "contact per segment-step", "candidate pairs"):
        t.add_column(col, justify="right")
    for n_rods in ((16, 64) if args.quick else (16, 64, 256)):
        n_steps = max(20, steps * 4 // n_rods)
        t_off = time_steps(heap(n_rods, False), n_steps, repeats)
        w_on = heap(n_rods, True)
        t_on = time_steps(w_on, n_steps, repeats)
        t.add_row(str(n_rods), str(50 * n_rods), f"{t_off * 1e6:.0f} us", f"{t_on * 1e6:.0f} us",
                  f"{(t_on - t_off) / (50 * n_rods) * 1e9:.0f} ns",
                  str(w_on.contact_stats()["candidate_pairs"]))
    console.print(t)

    # 3. mesh contact cost
    t = Table(title="A 100-element rope at rest on a large mesh, explicit dt = 2e-5 s: contact "
                    "cost per step vs internal forces")
    for col in ("scene", "triangles", "step without mesh", "step with mesh",
                "contact per step", "internal forces", "contact / internal", "target"):
        t.add_column(col, justify="right")
    for scene in ("floor", "blob"):
        bare, _ = rope_on_mesh(scene, False)
        full, n_tri = rope_on_mesh(scene, True)
        t_bare = time_steps(bare, steps, repeats)
        t_full = time_steps(full, steps, repeats)
        t_int = internal_forces_seconds(bare, repeats)
        contact = t_full - t_bare
        ratio = contact / t_int
        t.add_row(scene, f"{n_tri:,}", f"{t_bare * 1e6:.1f} us", f"{t_full * 1e6:.1f} us",
                  f"{contact * 1e6:.1f} us", f"{t_int * 1e6:.1f} us", f"{ratio:.2f}x",
                  "<= 2x " + ("met" if ratio <= 2 else "missed"))
    console.print(t)
    console.print(f"[dim]{time.strftime('%Y-%m-%d %H:%M')}, python {sys.version.split()[0]}, "
                  f"{os.cpu_count()} cores; mesh scenes: the rope lies on the floor / hangs "
                  "over the blob; without the mesh the same rope floats (no gravity)[/dim]")

    # 4. contact at large steps
    if not args.no_large_steps:
        import bench_large_steps
        bench_large_steps.main(["--rounds", "1" if args.quick else "3"])


if __name__ == "__main__":
    main()
