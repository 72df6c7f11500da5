"""Compile DeformX's numba kernels ahead of first use, into numba's cache next to the sources.

A kernel compiles once per distinct argument types. World's entry kernels come in eight kinds
(explicit or stable integrator, rods coupled by rod contact or not, with or without mesh/shape
colliders); :func:`precompile` runs one tiny world of each kind, touching the drivers, the
state round trip, energies and contact queries, then the co-simulation's and the renderers'
kernels. Each later call loads machine code from the cache instead of compiling it (a second
instead of minutes).

``pip install .`` runs this while it builds the wheel (``hatch_build.py``: two processes, one
per integrator, caches merged with :func:`merge_caches`) and ships the cache in the wheel, so
that a fresh install's first ``deformx demo`` starts at once; ``deformx precompile`` does the
same for an editable install. Kernels called with argument types not met here still compile
on first use.

    python -m deformx.precompile              # prints one line per world kind and the total
    python -m deformx.precompile --part 1/2   # half of the work (two processes at once)
"""

from __future__ import annotations

import pickle
import shutil
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import trimesh

from .engine import Rod, World


def _world(integrator: str, coupled: bool, colliders: bool) -> World:
    """A small world of one kernel kind: ropes over a plane, clamped and driven."""
    dt = 1e-5 if integrator == "verlet" else 2e-3
    world = World(dt=dt, integrator=integrator, rod_contact=coupled)
    for k in range(2):
        rod = world.add_rod(Rod.straight(n_elements=6, start=(-0.1, 0.03 * k, 0.1 + 0.02 * k),
                                         direction=(1.0, 0.0, 0.0), length=0.2, radius=0.005,
                                         youngs_modulus=1e6))
        if k == 0:
            clamp = rod.fix_start()
            clamp.set_velocity(velocity=(0.0, 0.0, 0.01), angular_velocity=(0.0, 0.0, 0.1))
            clamp.set_acceleration(linear=(0.0, 0.0, 0.1))
    world.add_plane(static_friction=0.5, kinetic_friction=0.4)
    if colliders:
        mesh = world.add_mesh(trimesh.creation.box(extents=(0.04, 0.04, 0.04)),
                              pose=(0.0, 0.0, 0.03))
        mesh.set_velocity(velocity=(0.0, 0.0, 0.01))
        world.add_sphere(0.02, center=(0.05, 0.0, 0.03))
        world.add_box((0.02, 0.02, 0.02), pose=np.eye(4))
        world.add_capsule(0.01, 0.05, pose=np.eye(4))
        world.add_cylinder(0.01, 0.05, pose=np.eye(4))
    return world


def _exercise(world: World) -> None:
    """The calls a user makes on a world: steps, state round trips, energies, contact."""
    world.step()
    state = world.get_state()
    world.step(2)
    world.set_state(state)
    rod = world.rods[0]
    rod.set_state(rod.get_state())
    world.step()
    world.energy()
    world.contact_forces(rod)
    world.contact_stats()
    for clamp in rod.clamps:
        clamp.impulse, clamp.force
        clamp.reset_impulse()


def _visual() -> None:
    """The renderers' kernels: a tube around a rod, a cable asset skinned onto one."""
    from .visual.assets import usb_c_cable
    from .visual.tube import Tube

    rod = Rod.straight(n_elements=4, length=0.1, radius=0.005)
    Tube(rod).update()
    usb_c_cable(length=0.1).skin(rod).update()


def _cosim() -> None:
    """The co-simulation kernels: a rod hung from a free MuJoCo body, both couplings."""
    from .cosim import CoSimulation, MujocoBackend

    xml = """<mujoco><option timestep="0.002"/><worldbody>
      <body name="hand" pos="0 0 0.5"><freejoint/><geom type="box" size=".02 .02 .02"
        mass="0.5"/></body></worldbody></mujoco>"""
    for coupling in ("kinematic", "inertial"):
        world = World(dt=2e-3, integrator="stable")
        rod = world.add_rod(Rod.straight(n_elements=6, start=(0.0, 0.0, 0.5),
                                         direction=(0.0, 0.0, -1.0), length=0.2))
        sim = CoSimulation(world, MujocoBackend(xml))
        sim.attach(rod, "start", "hand", coupling=coupling)
        sim.step()


KINDS: tuple[tuple[str, Callable[[], None]], ...] = tuple(
    (f"{integrator}, {'rod contact' if coupled else 'no rod contact'}, "
     f"{'colliders' if colliders else 'plane only'}",
     lambda i=integrator, c=coupled, m=colliders: _exercise(_world(i, c, m)))
    for integrator in ("stable", "verlet") for coupled in (True, False)
    for colliders in (True, False)
) + (("co-simulation", _cosim), ("renderers", _visual))


def parts(n: int) -> list[list[int]]:
    """Indices into KINDS for ``n`` processes. The kinds of one integrator share most of their
    callees, compiled once per process: two processes take one integrator each (stable, with
    the co-simulation, which steps it: ~220 s on two cores; explicit: ~150 s)."""
    if n == 2:
        return [[0, 1, 2, 3, 8], [4, 5, 6, 7, 9]]
    return [list(range(k, len(KINDS), n)) for k in range(n)]


def precompile(echo: Callable[[str], None] | None = print, part: int = 0,
               n_parts: int = 1) -> float:
    """Compile (or load from the cache) every kernel kind, or part ``part`` of ``n_parts``
    (0-based; for that many processes at once); returns the seconds it took."""
    if not 0 <= part < n_parts:
        raise ValueError(f"part must be in [0, {n_parts - 1}] for n_parts={n_parts}, got {part}")
    start = time.perf_counter()
    if echo is not None:
        from importlib.metadata import version  # not numba's: this module defines no kernel

        echo(f"part {part + 1}/{n_parts} with numba {version('numba')}, numpy {np.__version__}")
    for k in sorted(parts(n_parts)[part]):
        name, run = KINDS[k]
        t = time.perf_counter()
        run()
        if echo is not None:
            echo(f"  {name}: {time.perf_counter() - t:.1f} s")
    total = time.perf_counter() - start
    if echo is not None:
        echo(f"kernels compiled in {total:.1f} s")
    return total


def _read_index(path: Path) -> tuple[object, object, dict]:
    """numba's cache index file: (numba version, source stamp, {key: data file name})."""
    with open(path, "rb") as f:
        version = pickle.load(f)
        stamp, overloads = pickle.loads(f.read())
    return version, stamp, overloads


def merge_caches(into: Path, other: Path) -> int:
    """Add the kernels cached under ``other`` (a copy of the package compiled by another
    process) to those cached under ``into`` (same sources); returns how many were added.
    Keys ``into`` lacks are copied, their data files renumbered after ``into``'s."""
    added = 0
    for index in Path(other).rglob("__pycache__/*.nbi"):
        target = Path(into) / index.relative_to(other)
        if not target.exists():
            target.parent.mkdir(parents=True, exist_ok=True)
            for data in index.parent.glob(index.stem + ".*.nbc"):
                shutil.copy2(data, target.parent / data.name)
            shutil.copy2(index, target)
            added += len(_read_index(index)[2])
            continue
        version, stamp, ours = _read_index(target)
        v2, s2, theirs = _read_index(index)
        if (v2, s2) != (version, stamp):
            continue  # another numba or other sources: not ours to mix in
        used = set(ours.values())
        number = 1
        for key, name in theirs.items():
            if key in ours:
                continue
            while f"{index.stem}.{number}.nbc" in used:
                number += 1
            new = f"{index.stem}.{number}.nbc"
            shutil.copy2(index.parent / name, target.parent / new)
            ours[key] = new
            used.add(new)
            added += 1
        with open(target, "wb") as f:  # numba's layout: the version, then (stamp, overloads)
            pickle.dump(version, f, protocol=-1)
            f.write(pickle.dumps((stamp, ours), protocol=-1))
    return added


def main(argv: list[str] | None = None) -> None:
    """``python -m deformx.precompile [--part K/N]`` (K in 1..N: one of N processes)."""
    import argparse

    parser = argparse.ArgumentParser(prog="python -m deformx.precompile", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--part", default="1/1", help="K/N: the K-th of N equal parts (1-based)")
    parser.add_argument("--merge", nargs=2, metavar=("INTO", "FROM"), type=Path,
                        help="add the kernels cached in package copy FROM to those in INTO")
    args = parser.parse_args(argv)
    if args.merge:
        added = merge_caches(*args.merge)
        print(f"merged {added} compiled kernels into {args.merge[0]}", file=sys.stderr)
        return
    try:
        k, n = (int(x) for x in args.part.split("/"))
    except ValueError:
        parser.error(f"--part must look like K/N, e.g. 1/2; got {args.part!r}")
    precompile(lambda line: print(line, file=sys.stderr, flush=True), part=k - 1, n_parts=n)


if __name__ == "__main__":
    main()
