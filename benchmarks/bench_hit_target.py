"""Hit-target environment (deformx.learn): environment steps per second of one environment,
per rope model, with the same random actions; and how many random-action episodes end in a
divergence of the rope (NaN or runaway stretch; the stable integrator steps through folds).

    python benchmarks/bench_hit_target.py                 # 3 interleaved rounds of 300 steps
    python benchmarks/bench_hit_target.py --steps 700 --rounds 1
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np
from rich.console import Console
from rich.table import Table

SOFT = dict(stretch_modulus=None, shear_modulus=None)  # the authors' rope: E everywhere
CASES = {
    "cosserat, stable 4 x 0.5 ms (default)": dict(),
    "cosserat, stable 1 x 2 ms": dict(integrator="stable", rope_dt=2e-3),
    "authors' soft rope, stable 4 x 0.5 ms": dict(SOFT),
    "authors' soft rope, explicit 4 x 0.5 ms": dict(SOFT, integrator="verlet", rope_dt=5e-4),
    "capsule chain (MuJoCo)": dict(rope="capsule"),
}


def episode(env, seed: int, steps: int) -> tuple[float, int, bool]:
    """Seconds per step, steps run, whether the rope diverged."""
    env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    actions = rng.uniform(-1, 1, (steps, 3)).astype(np.float32)
    t0 = time.perf_counter()
    n = 0
    info = {"diverged": False}
    for a in actions:
        _, _, term, trunc, info = env.step(a)
        n += 1
        if term or trunc:
            break
    return (time.perf_counter() - t0) / n, n, info["diverged"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    from deformx.learn import HitTargetEnv

    envs = {name: HitTargetEnv(**kw) for name, kw in CASES.items()}
    for env in envs.values():
        episode(env, 0, 5)  # compile / load the kernel caches outside the timing
    times = {name: [] for name in envs}
    diverged = {name: 0 for name in envs}
    for r in range(args.rounds):
        for name, env in envs.items():
            dt, n, div = episode(env, r, args.steps)
            times[name].append(dt)
            diverged[name] += int(div)
    table = Table(title=f"HitTarget-v0, one environment, random actions, {args.steps} steps x "
                        f"{args.rounds} interleaved rounds (range)")
    for col in ("rope", "us / step", "steps / s", "episodes diverged"):
        table.add_column(col, justify="right")
    for name, ts in times.items():
        lo, hi = min(ts), max(ts)
        table.add_row(name, f"{1e6 * lo:.0f}-{1e6 * hi:.0f}", f"{1 / hi:.0f}-{1 / lo:.0f}",
                      f"{diverged[name]} / {args.rounds}")
    Console().print(table)
    Console().print(f"[dim]{time.strftime('%Y-%m-%d %H:%M')}, python {sys.version.split()[0]}, "
                    f"{os.cpu_count()} cores[/dim]")


if __name__ == "__main__":
    main()
