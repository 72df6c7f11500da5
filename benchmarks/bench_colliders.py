"""Collider cost: microseconds per explicit step of five 24-element cables lying on each kind of
collider (none, plane, box, plane + box, sphere, triangle mesh), and the ratio to the plane.

Scene: 5 rods side by side 5 cm apart along x (0.6 m, 24 elements, r 4 mm, E 2e6 Pa,
1200 kg/m^3, damping 1.5: the demo's cable), starting 1 cm above the surface under them,
explicit steps of 4e-5 s, gravity, no rod-rod contact. Colliders: a plane at z = 0; a box
0.8 x 0.4 x 0.1 m with its top at z = 0; plane + box: a 2 cm slab (0.8 x 0.15 m) on the plane
under the three middle rods, the outer two on the plane; plane + far box: the plane and the box
5 m away (never within reach: what a collider costs that nothing touches); a sphere of radius 0.5 m with its top
at z = 0; the box as a 12-triangle mesh (trimesh). Each world first runs 0.1 s (the first call
compiles; its time is reported), then rounds interleave the cases (``world.step(n)`` timed);
the table gives min-max over rounds.

    python benchmarks/bench_colliders.py            # 3 rounds of 2000 steps
    python benchmarks/bench_colliders.py --quick    # 1 round of 500 steps
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import trimesh
from rich.console import Console
from rich.table import Table

import deformx as dx

DT = 4e-5
N_RODS, N_EL, LENGTH, RADIUS = 5, 24, 0.6, 0.004
CABLE = dict(radius=RADIUS, density=1200.0, youngs_modulus=2e6, damping=1.5)
BOX_HALF, BOX_POSE = (0.4, 0.2, 0.05), (0.0, 0.0, -0.05)  # top at z = 0
SLAB_HALF = (0.4, 0.075, 0.01)  # on the plane, under the rods at y = 0 and +-5 cm
SPHERE_R = 0.5


def rods_y():
    return [0.05 * (k - (N_RODS - 1) / 2) for k in range(N_RODS)]


def scene(case: str, threads: int | None) -> dx.World:
    world = dx.World(dt=DT, integrator="verlet", rod_contact=False, threads=threads)
    surface = {y: 0.0 for y in rods_y()}  # z of the surface under each rod
    if case in ("plane", "plane + box"):
        world.add_plane()
    if case == "box":
        world.add_box(BOX_HALF, pose=BOX_POSE)
    if case == "plane + box":
        world.add_box(SLAB_HALF, pose=(0.0, 0.0, SLAB_HALF[2]))
        surface = {y: 2 * SLAB_HALF[2] if abs(y) < SLAB_HALF[1] else 0.0 for y in surface}
    if case == "plane + far box":  # the box is never within reach: its query should cost ~0
        world.add_plane()
        world.add_box(BOX_HALF, pose=(5.0, 0.0, 0.0))
    if case == "sphere":
        world.add_sphere(SPHERE_R, center=(0.0, 0.0, -SPHERE_R))
    if case == "mesh":
        world.add_mesh(trimesh.creation.box(extents=[2 * h for h in BOX_HALF]), pose=BOX_POSE)
    for y, z in surface.items():
        world.add_rod(dx.Rod.straight(n_elements=N_EL, start=(-LENGTH / 2, y, z + 0.01 + RADIUS),
                                      direction=(1, 0, 0), length=LENGTH, **CABLE))
    return world


CASES = ("none", "plane", "box", "plane + box", "plane + far box", "sphere", "mesh")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="1 round of 500 steps")
    parser.add_argument("--rounds", type=int, default=None)
    parser.add_argument("--steps", type=int, default=None, help="steps per timed call")
    parser.add_argument("--threads", type=int, default=None,
                        help="world threads (default: deformx's default)")
    args = parser.parse_args()
    rounds = args.rounds or (1 if args.quick else 3)
    steps = args.steps or (500 if args.quick else 2000)
    console = Console()
    console.print("building and compiling (first run: numba compiles the explicit kernels)...")
    worlds, first = {}, {}
    for case in CASES:
        world = scene(case, args.threads)
        t0 = time.perf_counter()
        world.step(1)
        first[case] = time.perf_counter() - t0
        world.step(int(round(0.1 / DT)))  # warm up, and the rods reach the surface
        worlds[case] = world
    per_step = {case: [] for case in CASES}
    for r in range(rounds):
        for case in CASES:
            t0 = time.perf_counter()
            worlds[case].step(steps)
            per_step[case].append((time.perf_counter() - t0) / steps)
        console.print(f"round {r + 1}: " + ", ".join(
            f"{c} {per_step[c][-1] * 1e6:.1f}" for c in CASES) + " us/step")

    def span(values, scale, fmt):
        lo, hi = f"{min(values) * scale:{fmt}}", f"{max(values) * scale:{fmt}}"
        return lo if lo == hi else f"{lo}-{hi}"

    nodes = N_RODS * (N_EL + 1)
    plane = per_step["plane"]
    table = Table(title=f"{N_RODS} rods x {N_EL} elements on colliders, explicit dt {DT:g} s, "
                        f"{steps} steps per call (min-max of {rounds} rounds)")
    for col in ("colliders", "us / step", "us / node / step", "vs plane only", "first call s"):
        table.add_column(col, justify="right")
    for case in CASES:
        t = per_step[case]
        ratio = [a / b for a, b in zip(t, plane)]
        label = {"none": "no colliders", "plane": "plane only", "box": "box only",
                 "sphere": "sphere only", "mesh": "mesh (box, 12 triangles) only"}.get(case, case)
        table.add_row(label, span(t, 1e6, ".1f"), span(t, 1e6 / nodes, ".3f"),
                      span(ratio, 1, ".2f") + "x", f"{first[case]:.1f}")
    console.print(table)
    console.print(f"[dim]{time.strftime('%Y-%m-%d %H:%M')}, python {sys.version.split()[0]}, "
                  f"{os.cpu_count()} cores, world threads {worlds['plane'].threads}[/dim]")


if __name__ == "__main__":
    main()
