"""DeformX vs PyElastica 1.0, explicit integrator, same discretisation, same machine, one run.

Prints seconds per step for the issue's cases (best of several repeats, interleaved so both
engines see the same machine load), their ratio, and the numba compile/import costs measured in
fresh subprocesses with an empty cache (cold) and again with the cache filled (warm).

    python benchmarks/bench_engine.py            # full
    python benchmarks/bench_engine.py --quick    # fewer steps and repeats
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

from rich.console import Console
from rich.table import Table

from deformx.apps import bench

PROBE = r"""
import time
t0 = time.perf_counter()
import deformx as dx
t1 = time.perf_counter()
w = dx.World(dt=1e-4)
n_rods = {n_rods}
for k in range(n_rods):
    r = w.add_rod(dx.Rod.straight(n_elements=20, start=(0, 0.1 * k, 0)))
    r.fix_start()
w.step(1)
t2 = time.perf_counter()
print(t1 - t0, t2 - t1)
"""


def compile_times(n_rods: int, cache_dir: str) -> tuple[float, float]:
    """(import seconds, first-step seconds) in a fresh interpreter using ``cache_dir``."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    out = subprocess.run([sys.executable, "-c", PROBE.format(n_rods=n_rods)], env=env,
                         capture_output=True, text=True, check=True).stdout.split()
    return float(out[0]), float(out[1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer steps and repeats")
    args = parser.parse_args()
    steps = {"1x100": 2000, "64x50": 100} if args.quick else {"1x100": 10000, "64x50": 500}
    repeats = 2 if args.quick else 5
    console = Console()

    table = Table(title="Explicit integrator, seconds per step (best of %d)" % repeats)
    for col in ("case", "DeformX", "PyElastica", "speed-up", "target"):
        table.add_column(col, justify="right")
    targets = {"1x100": 3.0, "64x50": 6.0}
    have_pe = bench.elastica_available()
    for name, n in steps.items():
        case = bench.CASES[name]
        ours, theirs = [], []
        for _ in range(repeats):
            ours.append(bench.time_deformx(case, n).seconds_per_step)
            if have_pe:
                theirs.append(bench.time_elastica(case, max(n // 4, 50)).seconds_per_step)
        o = min(ours)
        t = min(theirs) if theirs else float("nan")
        table.add_row(f"{case.label()} (dt={case.dt:g})", f"{o * 1e6:.1f} us",
                      f"{t * 1e6:.1f} us" if theirs else "n/a", f"{t / o:.1f}x" if theirs else "n/a",
                      f">= {targets[name]:g}x")
    console.print(table)

    ctable = Table(title="numba compile and import (fresh interpreter)")
    for col in ("numba cache", "import deformx", "build + first step", "total", "target"):
        ctable.add_column(col, justify="right")
    with tempfile.TemporaryDirectory() as cache:
        for state, target in (("cold (empty cache)", "<= 15 s"), ("warm", "<= 1 s in all")):
            imp, first = compile_times(2, cache)
            ctable.add_row(state, f"{imp:.2f} s", f"{first:.2f} s", f"{imp + first:.2f} s", target)
    console.print(ctable)
    console.print(f"[dim]{time.strftime('%Y-%m-%d %H:%M')}, python {sys.version.split()[0]}, "
                  f"{os.cpu_count()} cores[/dim]")


if __name__ == "__main__":
    main()
