"""Python call overhead of ``world.step()``, warm numba cache, for a source tree against a
reference commit, side by side in one run.

Per-call cost of ``world.step()`` called N times against ``world.step(N) / N``; their difference
is what one call costs on top of the kernel (argument checks, bookkeeping, the kernel dispatch).
Each tree runs in its own fresh interpreter (``PYTHONPATH=<tree>/src``, its own numba cache
folder, kept over the rounds), steps untimed once to load or compile its kernels, then times the
cases with ``time.perf_counter``: the median of several repeats, loop and batch alternating.
Trees alternate round by round (tree, reference, tree, ...); the table gives min-max over rounds.

Cases:
  a. one clamped 100-element cantilever (r = 1 cm, E = 1e6 Pa, damping 1/s) in
     ``dx.World(dt=1e-4)``: explicit steps, the world's defaults otherwise (rod contact on);
  b. the same with ``integrator="stable"``, dt = 1e-3 s;
  c. a control loop on the RL rope (1 m, 20 elements, r = 6.35 mm, 700 kg/m^3, E = 2e5 Pa,
     damping 0.1, hanging from a clamp at (0, 0, 1.7)), stable integrator, dt = 2e-3 s:
     ``clamp.set_velocity(velocity=(vx, 0, 0))`` with a varying vx, then ``world.step()``.
     Overhead here is one iteration minus ``step(N) / N`` (both timed while the clamp moves:
     step() alone and step(N) keep the last velocity set).

    python benchmarks/bench_overhead.py              # 3 rounds
    python benchmarks/bench_overhead.py --quick      # 1 round, fewer repeats
    python benchmarks/bench_overhead.py --tree ../other --reference f69ee60 --rounds 5
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from rich.console import Console
from rich.table import Table

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _subproc import (check_tree, header, now_and_load,  # noqa: E402
                      reference_tree, run_in_tree, span, tree_parser)

PROBE = """
import itertools, math
from statistics import median
import deformx as dx
_check_tree(dx)


def cantilever(**world):
    w = dx.World(**world)
    rod = w.add_rod(dx.Rod.straight(n_elements=100, start=(0, 0, 0), direction=(1, 0, 0),
                                    normal=(0, 0, 1), length=1.0, radius=0.01, density=1000.0,
                                    youngs_modulus=1e6, poisson_ratio=0.5, damping=1.0))
    rod.fix_start()
    return w


def rl_rope():
    w = dx.World(dt=2e-3, integrator="stable")
    rod = w.add_rod(dx.Rod.straight(n_elements=20, start=(0, 0, 1.7), direction=(0, 0, -1),
                                    length=1.0, radius=6.35e-3, density=700.0,
                                    youngs_modulus=2e5, damping=0.1))
    return w, rod.fix_start()


def loop(w, n):
    t = time.perf_counter()
    for _ in range(n):
        w.step()
    return (time.perf_counter() - t) / n


def batch(w, n):
    t = time.perf_counter()
    w.step(n)
    return (time.perf_counter() - t) / n


def drive(w, clamp, n, phase=itertools.count()):
    t = time.perf_counter()
    for _ in range(n):
        clamp.set_velocity(velocity=(0.1 * math.sin(next(phase) * 0.01), 0.0, 0.0))
        w.step()
    return (time.perf_counter() - t) / n


def case(**timings):
    # One untimed round (loads or compiles the kernels), then REPEATS alternating rounds:
    # median microseconds per step of each timing, and of its excess over 'batched'.
    for f in timings.values():
        f()
    rows = [{{name: f() * 1e6 for name, f in timings.items()}} for _ in range({repeats})]
    out = {{name: median(r[name] for r in rows) for name in timings}}
    out.update({{name + "_overhead": median(r[name] - r["batched"] for r in rows)
                for name in timings if name != "batched"}})
    return out


w = cantilever(dt=1e-4)
explicit = case(per_call=lambda: loop(w, {n_explicit}), batched=lambda: batch(w, {n_explicit}))
w = cantilever(dt=1e-3, integrator="stable")
stable = case(per_call=lambda: loop(w, {n_stable}), batched=lambda: batch(w, {n_stable}))
w, clamp = rl_rope()
rope = case(drive=lambda: drive(w, clamp, {n_rope}), per_call=lambda: loop(w, {n_rope}),
            batched=lambda: batch(w, {n_rope}))
_report(explicit=explicit, stable=stable, rope=rope)
"""
# Steps per timing: each timing takes some 10-70 ms on a laptop core; the stable cantilever
# takes more steps, as its step times vary by more than the overhead measured.
STEPS = {"explicit": 2000, "stable": 1000, "rope": 500}
# Rows of the table: (key, label, case, timing, target overhead in us per call or iteration).
ROWS = (
    ("a", "a. 1x100 explicit: step()", "explicit", "per_call", 5.0),
    ("b", "b. 1x100 stable: step()", "stable", "per_call", 5.0),
    ("c", "c. rope: set_velocity, step()", "rope", "drive", 10.0),
    ("c step()", "c. rope: step() alone", "rope", "per_call", None),
)


def main() -> None:
    parser = tree_parser(__doc__)
    parser.add_argument("--repeats", type=int, default=21,
                        help="timings per case within a run, median taken (default: 21)")
    parser.add_argument("--quick", action="store_true", help="1 round of 5 repeats")
    args = parser.parse_args()
    rounds, repeats = (1, 5) if args.quick else (args.rounds, args.repeats)
    if rounds < 1 or repeats < 1:
        parser.error("--rounds and --repeats must be >= 1")
    tree = check_tree(args.tree)
    console = Console(width=None if sys.stdout.isatty() else 150)
    console.print(header(tree, args.reference))
    code = PROBE.format(repeats=repeats, **{f"n_{c}": n for c, n in STEPS.items()})

    runs: dict[str, list[dict]] = {"tree": [], "reference": []}
    with reference_tree(args.reference) as ref, \
            tempfile.TemporaryDirectory(prefix="deformx-numba-") as cache:
        for k in range(rounds):
            for who, path in (("tree", tree), ("reference", ref)):
                folder = Path(cache) / who  # one cache per tree: only round 1 compiles
                folder.mkdir(exist_ok=True)
                result, wall = run_in_tree(path, code, folder)
                runs[who].append(result)
                console.print(f"round {k + 1}/{rounds} {who:9s} ({wall:.0f} s), overhead: "
                              + ", ".join(f"{key} {result[c][t + '_overhead']:.1f} us"
                                          for key, _, c, t, _ in ROWS))

    table = Table(title=f"Python call overhead, microseconds per step, warm cache, median of "
                        f"{repeats} repeats per run, min-max over {rounds} "
                        f"round{'s' * (rounds > 1)}")
    for col in ("case", "tree\nper call", "tree\nstep(N)/N", "tree\noverhead",
                "reference\nper call", "reference\nstep(N)/N", "reference\noverhead",
                "overhead ratio\nref/tree", "target\noverhead", "met"):
        table.add_column(col, justify="left" if col == "case" else "right")
    for _, label, c, t, target in ROWS:
        cells, over = [], {}
        for who, r in runs.items():
            over[who] = [x[c][t + "_overhead"] for x in r]
            cells += [span([x[c][t] for x in r]), span([x[c]["batched"] for x in r]),
                      span(over[who])]
        ratios = [b / a for a, b in zip(over["tree"], over["reference"]) if a > 0]
        table.add_row(label, *cells, span(ratios, "{:.2f}x") if ratios else "n/a",
                      "" if target is None else f"<= {target:g} us",
                      "" if target is None else ("yes" if max(over["tree"]) <= target else "no"))
    console.print(table)
    console.print("overhead: per call (or per iteration) minus step(N)/N, median of the "
                  "repeats' differences; ratio per round pair; met: every tree round within the "
                  f"target. Steps per timing: {STEPS}.")
    console.print(f"finished {now_and_load()}")


if __name__ == "__main__":
    main()
