"""Cold start: seconds from ``import deformx`` to the end of the first ``world.step()`` with an
empty numba cache, for a source tree against a reference commit, side by side in one run.

Each measurement is a fresh interpreter with ``PYTHONPATH=<tree>/src`` and ``NUMBA_CACHE_DIR``
set to a new empty folder (numba then caches there, not next to the sources; cache files next to
the sources are deleted before each cold run anyway). Each cold run is checked to have compiled
(no numba cache hits, cache files written to the new folder); a second run in the same folder is
the warm start (kernels loaded from the cache). Trees alternate run by run (tree, reference, tree,
reference, ...) so that both see the same machine load; the table gives min-max over rounds.

Scenes (public API only, so that they run on both trees):
  a. the world of ``deformx demo``: four 40-element ropes (E = 1e5 ... 1e7 Pa) clamped 0.4 m
     above a ground plane, explicit steps of 2e-5 s, rod contact on;
  b. one clamped 50-element rod and a ground plane, ``integrator="stable"``, dt = 1e-2 s;
  c. two 40-element ropes crossing over a box mesh ((V, F) arrays from trimesh),
     ``integrator="stable"``, dt = 1e-2 s, rod contact on.

Installed: what a user of ``pip install .`` sees. The wheel's build compiles the kernels
(``hatch_build.py``: ``build_cache``, two processes, caches merged; timed once per round as the
install's extra cost), then each scene's import + first step runs on that package copy with
numba's cache next to its sources, as in site-packages. The reference commit has no such build
step: its installed first step is its cold one.

    python benchmarks/bench_coldstart.py                       # 3 rounds, scenes a, b, c
    python benchmarks/bench_coldstart.py --quick               # 1 round, scene a
    python benchmarks/bench_coldstart.py --tree ../other --reference f69ee60 --rounds 5
"""

from __future__ import annotations

import shutil
import sys
import tempfile
import time
from pathlib import Path

from rich.console import Console
from rich.table import Table

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _subproc import (check_tree, clear_in_tree_caches,  # noqa: E402
                      header, now_and_load, numba_cache_files, prime,
                      reference_tree, run_in_tree, span, tree_parser)

# Scene code: PREP runs before the clock starts (the user's own inputs), BUILD after the import.
# Scene a is cli.demo_scene() as build_world() builds it; its dt, 2e-5 s, is what the demo
# computes (estimate_stable_dt of the stiffest rope, rounded down).
SCENES: dict[str, tuple[str, str, str]] = {
    "a": ("demo, 4 ropes, verlet", "", """
world = dx.World(gravity=(0.0, 0.0, -9.81), dt=2e-5, integrator="verlet")
for k, E in enumerate((1e5, 5e5, 2e6, 1e7)):
    rod = world.add_rod(dx.Rod.straight(
        n_elements=40, start=(0.0, 0.12 * k, 0.4), direction=(1.0, 0.0, 0.0),
        normal=(0.0, 0.0, 1.0), length=0.8, radius=0.005, density=1200.0, youngs_modulus=E,
        damping=1.0))
    rod.fix_start()
world.add_plane(point=(0.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0), static_friction=0.6,
                kinetic_friction=0.5)
"""),
    "b": ("1 rod + plane, stable", "", """
world = dx.World(dt=1e-2, integrator="stable")
rod = world.add_rod(dx.Rod.straight(n_elements=50, start=(0.0, 0.0, 0.5), length=1.0))
rod.fix_start()
world.add_plane()
"""),
    "c": ("2 ropes + mesh, stable", """
import numpy as np, trimesh
box = trimesh.creation.box(extents=(0.4, 0.4, 0.2))
V, F = np.asarray(box.vertices) + (0.0, 0.0, 0.1), np.asarray(box.faces)
""", """
world = dx.World(dt=1e-2, integrator="stable", rod_contact=True)
world.add_mesh((V, F))
r = 0.005
world.add_rod(dx.Rod.straight(n_elements=40, start=(-0.5, 0.0, 0.2 + r), direction=(1, 0, 0),
                              length=1.0, radius=r))
world.add_rod(dx.Rod.straight(n_elements=40, start=(0.0, -0.5, 0.2 + 3 * r),
                              direction=(0, 1, 0), length=1.0, radius=r))
"""),
}
# Seconds from import to the end of the first step (tree, cold), and the speed-up over the
# reference (reference cold / tree cold) that every round pair should reach.
TARGET_SECONDS = {"a": 15.0, "b": 25.0, "c": 35.0}
TARGET_SPEEDUP = 2.0


def probe(scene: str) -> str:
    """Subprocess code: PREP, then import deformx, build the scene, one step, report."""
    _, prep, build = SCENES[scene]
    return f"""{prep}
t0 = time.perf_counter()
import deformx as dx
t_import = time.perf_counter()
_check_tree(dx)
{build}
world.step()
t_step = time.perf_counter()
_report(import_s=t_import - t0, first_step_s=t_step - t0, **_numba_cache_stats())
"""


def cold_then_warm(tree: Path, scene: str) -> tuple[dict, dict]:
    """A cold run in a new empty numba cache folder, then a warm run in the same folder."""
    with tempfile.TemporaryDirectory(prefix="deformx-numba-") as tmp:
        cache = Path(tmp)
        clear_in_tree_caches(tree)
        cold, wall = run_in_tree(tree, probe(scene), cache)
        cold["wall_s"] = wall
        written, in_tree = len(numba_cache_files(cache)), clear_in_tree_caches(tree)
        if cold["cache_hits"] or not cold["cache_misses"] or not written or in_tree:
            raise RuntimeError(f"{tree}, scene {scene}: the cold run did not compile from scratch "
                               f"into NUMBA_CACHE_DIR ({cold['cache_hits']} cache hits, "
                               f"{cold['cache_misses']} compilations, {written} files written "
                               f"there, {in_tree} next to the sources)")
        warm, wall = run_in_tree(tree, probe(scene), cache)
        warm["wall_s"] = wall
        if not warm["cache_hits"]:
            raise RuntimeError(f"{tree}, scene {scene}: the warm run loaded nothing from the cache")
    return cold, warm


def installed(tree: Path, scenes: str) -> tuple[float, dict[str, dict]]:
    """The tree's wheel-build compile (seconds), then each scene's first step on its output."""
    sys.path.insert(0, str(tree))
    try:
        from hatch_build import build_cache
    finally:
        sys.path.pop(0)
    with tempfile.TemporaryDirectory(prefix="deformx-wheel-") as tmp:
        t0 = time.perf_counter()
        root, _ = build_cache(tree / "src" / "deformx", Path(tmp), 2)
        build_s = time.perf_counter() - t0
        fake = Path(tmp) / "site"  # run_in_tree wants <tree>/src/deformx
        (fake / "src").mkdir(parents=True)
        shutil.move(str(root), fake / "src" / "deformx")
        runs = {}
        for scene in scenes:
            first, wall = run_in_tree(fake, probe(scene), None)
            first["wall_s"] = wall
            if first["cache_misses"]:
                raise RuntimeError(f"installed, scene {scene}: {first['cache_misses']} kernels "
                                   "compiled despite the wheel's cache")
            runs[scene] = first
    return build_s, runs


def main() -> None:
    parser = tree_parser(__doc__)
    parser.add_argument("--scenes", default="abc", help="scenes to run (default: abc)")
    parser.add_argument("--quick", action="store_true", help="1 round, scene a only")
    parser.add_argument("--no-installed", action="store_true",
                        help="skip the installed-wheel measurement (its build takes minutes)")
    args = parser.parse_args()
    rounds, scenes = (1, "a") if args.quick else (args.rounds, args.scenes)
    if rounds < 1 or not scenes or set(scenes) - set(SCENES):
        parser.error(f"--rounds must be >= 1 and --scenes a subset of {''.join(SCENES)}")
    tree = check_tree(args.tree)
    console = Console(width=None if sys.stdout.isatty() else 150)
    console.print(header(tree, args.reference))

    runs: dict[tuple[str, str], list[tuple[dict, dict]]] = {}
    wheel: list[tuple[float, dict[str, dict]]] = []
    with reference_tree(args.reference) as ref:
        prime(tree)  # untimed: OS file cache and .pyc files for both trees
        prime(ref)
        for k in range(rounds):
            for scene in scenes:
                for who, path in (("tree", tree), ("reference", ref)):
                    cold, warm = cold_then_warm(path, scene)
                    runs.setdefault((scene, who), []).append((cold, warm))
                    console.print(
                        f"round {k + 1}/{rounds} scene {scene} {who:9s}: cold "
                        f"{cold['first_step_s']:.1f} s (import {cold['import_s']:.1f} s, "
                        f"subprocess {cold['wall_s']:.1f} s, {cold['cache_misses']} compiled), "
                        f"warm {warm['first_step_s']:.2f} s (subprocess {warm['wall_s']:.1f} s)")
            if not args.no_installed:
                wheel.append(installed(tree, scenes))
                console.print(f"round {k + 1}/{rounds} installed: wheel-build compile "
                              f"{wheel[-1][0]:.0f} s, first step "
                              + ", ".join(f"{s} {r['first_step_s']:.2f} s"
                                          for s, r in wheel[-1][1].items()))

    table = Table(title="Cold start: seconds from import deformx to the end of the first step, "
                        f"empty numba cache (min-max over {rounds} round{'s' * (rounds > 1)})")
    for col in ("scene", "tree cold", "reference cold", "ratio ref/tree", "tree warm",
                "reference warm", "subprocess cold\ntree / reference", "target (tree)", "met"):
        table.add_column(col, justify="left" if col == "scene" else "right")
    def seconds(scene: str, who: str, run: int, key: str = "first_step_s") -> list[float]:
        """One number per round: ``run`` 0 is the cold run, 1 the warm one."""
        return [pair[run][key] for pair in runs[scene, who]]

    for scene in scenes:
        tree_cold, ref_cold = seconds(scene, "tree", 0), seconds(scene, "reference", 0)
        ratios = [r / t for t, r in zip(tree_cold, ref_cold)]
        table.add_row(
            f"{scene}. {SCENES[scene][0]}", span(tree_cold), span(ref_cold),
            span(ratios, "{:.2f}x"), span(seconds(scene, "tree", 1), "{:.2f}"),
            span(seconds(scene, "reference", 1), "{:.2f}"),
            f"{span(seconds(scene, 'tree', 0, 'wall_s'))} / "
            f"{span(seconds(scene, 'reference', 0, 'wall_s'))}",
            f"<= {TARGET_SECONDS[scene]:g} s, >= {TARGET_SPEEDUP:g}x",
            f"{'yes' if max(tree_cold) <= TARGET_SECONDS[scene] else 'no'}, "
            f"{'yes' if min(ratios) >= TARGET_SPEEDUP else 'no'}")
    console.print(table)
    console.print("ratio: reference cold / tree cold, per round pair; met: every tree round within "
                  "the time target, every round pair at the speed-up.")
    if wheel:
        table = Table(title="Installed with pip (kernels compiled while the wheel builds): "
                            f"import + first step (min-max over {len(wheel)} round"
                            f"{'s' * (len(wheel) > 1)})")
        for col in ("scene", "tree installed", "reference (= its cold)", "ratio ref/tree",
                    "target (tree)", "met"):
            table.add_column(col, justify="left" if col == "scene" else "right")
        for scene in scenes:
            first = [w[1][scene]["first_step_s"] for w in wheel]
            ref_cold = seconds(scene, "reference", 0)
            ratios = [r / t for t, r in zip(first, ref_cold)]
            table.add_row(f"{scene}. {SCENES[scene][0]}", span(first, "{:.2f}"), span(ref_cold),
                          span(ratios, "{:.0f}x"), f"<= {TARGET_SECONDS[scene]:g} s, "
                          f">= {TARGET_SPEEDUP:g}x",
                          f"{'yes' if max(first) <= TARGET_SECONDS[scene] else 'no'}, "
                          f"{'yes' if min(ratios) >= TARGET_SPEEDUP else 'no'}")
        console.print(table)
        console.print(f"the install's extra cost, compiling every kind of kernel in two processes: "
                      f"{span([w[0] for w in wheel], '{:.0f}')} s")
    console.print(f"finished {now_and_load()}")


if __name__ == "__main__":
    main()
