"""Batched hit-target environments: environment steps per second of ``gym.make_vec``'s batch
(one MuJoCo model with N UR5e arms, one DeformX world with N ropes) against PyElastica stepping
the same rope at the authors' 1e-5 s (200 substeps per 2 ms control step), in the same run.

Random actions; episodes that end are reset in the same step (counted in). The split says
where a batch step goes: ropes (the world's kernel), MuJoCo (all arms), coupling (reading
bodies, drivers, wrenches) and Python (the task: actions, rewards, observations, resets).
Rounds interleave every case; the table gives min-max over rounds.

    python benchmarks/bench_learn.py                      # N = 16, 64; 3 rounds
    python benchmarks/bench_learn.py --envs 64 256 --rounds 1
    python benchmarks/bench_learn.py --tree ../copy --reference cecd6a9 --envs 64

With ``--reference COMMIT`` the batches of a source tree (``--tree``, default this repository)
and of that commit run side by side instead of PyElastica: each round builds and times them in
a fresh interpreter per tree (``PYTHONPATH=<tree>/src``, one numba cache folder per tree kept
over the rounds), trees alternating; the table gives each tree's rates and the ratio per round.
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
ROPES = {
    "default (BDF2 1 x 2 ms; before 3529659: backward Euler 4 x 0.5 ms)": dict(),
    "default, twist-stiff (G_t = G = 6.7e6 Pa, before 71227bd)": dict(twist_modulus=6.7e6),
    "backward Euler 4 x 0.5 ms": dict(order=1, rope_dt=5e-4),
    "backward Euler 1 x 2 ms": dict(order=1, rope_dt=2e-3),
    "authors' soft rope, explicit 4 x 0.5 ms": dict(SOFT, integrator="verlet", rope_dt=5e-4),
}


def batch_rate(venv, steps: int, rng: np.random.Generator) -> tuple[float, dict]:
    """Environment steps per second and the split (s per batch step)."""
    sim = venv.batch.sim
    sim.profile = True
    sim.reset_timings()
    n = venv.num_envs
    actions = rng.uniform(-1, 1, (steps, n, 3)).astype(np.float32)
    t0 = time.perf_counter()
    for a in actions:
        venv.step(a)
    wall = (time.perf_counter() - t0) / steps
    tm = {k: v / steps for k, v in sim.timings.items() if k != "steps"}
    sim.profile = False
    tm["python"] = wall - sum(tm.values())
    return n / wall, tm


# What one tree's round runs in its own interpreter (see _subproc.py): the same batches and
# the same random actions as the in-process run.
PROBE = """
import numpy as np
import deformx
_check_tree(deformx)
from deformx.learn.vector import HitTargetVecEnv
from deformx.learn.task import HitTargetConfig
{batch_rate}
rng = np.random.default_rng({seed})
rates = {{}}
for n in {envs!r}:
    for name, kw in {ropes!r}.items():
        # a tree without BDF2 has no "order": its stable rope is backward Euler
        kw = {{k: v for k, v in kw.items() if k in HitTargetConfig.__dataclass_fields__}}
        v = HitTargetVecEnv(n, settle_time=0.2, **kw)
        v.reset(seed=0)
        batch_rate(v, 3, rng)
        rates[f"{{n}}|{{name}}"] = batch_rate(v, {steps}, rng)[0]
        v.close()
_report(**rates)
"""


def compare_trees(args) -> None:
    """--reference: the tree's batches against the reference commit's, same run."""
    import inspect
    import tempfile
    from pathlib import Path

    from _subproc import check_tree, header, reference_tree, run_in_tree, span

    console = Console(width=None if sys.stdout.isatty() else 150)
    tree = check_tree(args.tree)
    console.print(header(tree, args.reference))
    runs: dict[str, list[dict]] = {"tree": [], "reference": []}
    with reference_tree(args.reference) as ref, \
            tempfile.TemporaryDirectory(prefix="deformx-numba-") as cache:
        for k in range(args.rounds):
            for who, path in (("tree", tree), ("reference", ref)):
                folder = Path(cache) / who  # one cache per tree: only round 1 compiles
                folder.mkdir(exist_ok=True)
                code = PROBE.format(batch_rate=inspect.getsource(batch_rate), seed=k,
                                    envs=args.envs, ropes=ROPES, steps=args.steps)
                result, wall = run_in_tree(path, code, folder)
                runs[who].append(result)
                console.print(f"round {k + 1}/{args.rounds} {who:9s} ({wall:.0f} s)")
    table = Table(title=f"HitTarget-v0 batches, env steps / s, random actions, {args.steps} "
                        f"batch steps x {args.rounds} rounds (min-max), tree vs {args.reference}")
    for col in ("envs", "rope", "tree", "reference", "ratio tree/ref per round"):
        table.add_column(col, justify="right")
    for key in runs["tree"][0]:
        n, name = key.split("|", 1)
        t = [r[key] for r in runs["tree"]]
        f = [r[key] for r in runs["reference"]]
        table.add_row(n, name, span(t, "{:,.0f}"), span(f, "{:,.0f}"),
                      span([a / b for a, b in zip(t, f)], "{:.2f}x"))
    console.print(table)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--envs", type=int, nargs="+", default=[16, 64])
    parser.add_argument("--steps", type=int, default=100, help="batch steps per round")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--tree", type=str, default=os.path.dirname(os.path.dirname(
        os.path.abspath(__file__))), help="source tree to measure (with --reference)")
    parser.add_argument("--reference", default=None,
                        help="commit to compare with, side by side (instead of PyElastica)")
    args = parser.parse_args()
    sys.path.insert(0, os.path.dirname(__file__))
    if args.reference:
        from pathlib import Path

        args.tree = Path(args.tree)
        compare_trees(args)
        return
    from bench_cosim import elastica_rope  # the same rope, PyElastica at 1e-5 s

    from deformx.learn.vector import HitTargetVecEnv

    console = Console()
    rng = np.random.default_rng(0)
    envs = {}
    for n in args.envs:
        for name, kw in ROPES.items():
            t0 = time.perf_counter()
            envs[(n, name)] = v = HitTargetVecEnv(n, settle_time=0.2, **kw)
            v.reset(seed=0)
            batch_rate(v, 3, rng)  # warm
            console.print(f"built {n} x {name} in {time.perf_counter() - t0:.1f} s")
    _, pe_step = elastica_rope()
    pe_step()
    rates = {key: [] for key in envs}
    splits = {key: [] for key in envs}
    pe = []
    for _ in range(args.rounds):
        for key, v in envs.items():
            r, tm = batch_rate(v, args.steps, rng)
            rates[key].append(r)
            splits[key].append(tm)
        t0 = time.perf_counter()
        for _ in range(20):
            pe_step()
        pe.append(20 / (time.perf_counter() - t0))
    pe_lo, pe_hi = min(pe), max(pe)
    table = Table(title=f"HitTarget-v0 batches, random actions, {args.steps} batch steps x "
                        f"{args.rounds} rounds (min-max)")
    for col in ("envs", "rope", "env steps / s", "x PyElastica 1e-5 s",
                "split per env step (us): rope / MuJoCo / coupling / Python"):
        table.add_column(col, justify="right")
    for (n, name), rs in rates.items():
        med = {k: float(np.median([s[k] for s in splits[(n, name)]])) * 1e6 / n
               for k in ("rods", "backend", "coupling", "python")}
        table.add_row(str(n), name, f"{min(rs):,.0f}-{max(rs):,.0f}",
                      f"{min(rs) / pe_hi:.0f}-{max(rs) / pe_lo:.0f}x",
                      " / ".join(f"{med[k]:.1f}" for k in ("rods", "backend", "coupling",
                                                           "python")))
    console.print(table)
    console.print(f"PyElastica, one rope, 200 x 1e-5 s per control step: {pe_lo:,.0f}-"
                  f"{pe_hi:,.0f} control steps / s (no robot, no Python task code)")
    console.print(f"[dim]{time.strftime('%Y-%m-%d %H:%M')}, python {sys.version.split()[0]}, "
                  f"{os.cpu_count()} cores[/dim]")


if __name__ == "__main__":
    main()
