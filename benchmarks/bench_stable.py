"""Large steps: DeformX's stable integrator at dt = 1e-2 vs explicit steps at their stability limit.

Speed is wall-clock seconds per simulated second (seconds per step / dt), so that an engine
taking bigger steps gets credit for them. For each case, in one run on the same machine:

* PyElastica 1.0 (position Verlet) at its largest stable dt,
* DeformX's explicit integrator (the same position Verlet) at its largest stable dt,
* DeformX's ``integrator="stable"`` at dt = 1e-2 s, with its Newton statistics.

The largest stable dt is found by geometric bisection on one rod of the case (the rods of a case
are identical and do not interact, so one rod has the limit of all): a trial runs
min(duration / dt, max_steps) steps from rest and is stable if every node stays finite and within
2 L of the clamp (and, for DeformX, no SimulationDiverged is raised). Explicit engines are then
timed for a fixed number of steps at that dt (best of several repeats, interleaved so all engines
see the same machine load); the stable integrator is timed over whole simulated seconds from rest.

    python benchmarks/bench_stable.py            # full
    python benchmarks/bench_stable.py --quick    # shorter searches, fewer steps and repeats
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import replace

import numpy as np
from rich.console import Console
from rich.table import Table

import deformx
from deformx.apps import bench

# Issue targets: PyElastica wall s / sim s divided by ours (stable, dt = 1e-2).
TARGETS = {"soft": 30.0, "steel": 500.0, "256x20": None}
LABELS = {"soft": "1 x 100, E=1e6 Pa, r=1 cm", "steel": "1 x 100 steel wire, E=2e11 Pa, r=1 mm",
          "256x20": "256 x 20, E=1e6 Pa, r=1 cm"}


def fmt_time(seconds: float) -> str:
    """Wall seconds per simulated second, readable across six decades."""
    if not np.isfinite(seconds):
        return "n/a"
    if seconds >= 100:
        return f"{seconds:.0f} s"
    if seconds >= 1:
        return f"{seconds:.2f} s"
    if seconds >= 1e-3:
        return f"{seconds * 1e3:.1f} ms"
    return f"{seconds * 1e6:.0f} us"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="shorter stability searches, fewer steps and repeats")
    parser.add_argument("--cases", default=",".join(bench.STABLE_CASES),
                        help="comma-separated subset of: " + ", ".join(bench.STABLE_CASES))
    args = parser.parse_args()
    names = [n.strip() for n in args.cases.split(",") if n.strip()]
    for n in names:
        if n not in bench.STABLE_CASES:
            parser.error(f"unknown case {n!r}")

    if args.quick:
        search = dict(duration=0.5, max_steps=20000)
        rel_tol = 0.10
        explicit_steps = {"soft": 1000, "steel": 1000, "256x20": 20}
        stable_sim_seconds = {"soft": 1.0, "steel": 1.0, "256x20": 0.5}
        repeats = 1
    else:
        search = dict(duration=1.0, max_steps=20000)
        rel_tol = 0.03
        explicit_steps = {"soft": 5000, "steel": 5000, "256x20": 200}
        stable_sim_seconds = {"soft": 2.0, "steel": 2.0, "256x20": 1.0}
        repeats = 3
    have_pe = bench.elastica_available()
    # Wide enough for the table when the output is not a terminal (a log file, CI).
    console = Console() if sys.stdout.isatty() else Console(width=170)
    if not have_pe:
        console.print("PyElastica is not installed: DeformX columns only.")

    table = Table(title="Wall seconds per simulated second: explicit at its largest stable dt "
                        "vs DeformX stable at dt = 1e-2 s (best of %d)" % repeats)
    for col in ("case", "PyElastica\ndt_max", "PyElastica\nwall s / sim s", "DeformX explicit\ndt_max",
                "DeformX explicit\nwall s / sim s", "DeformX stable\ndt=1e-2\nwall s / sim s",
                "Newton it/step\n(capped / halved\n/ steps)", "speed-up\nPE / stable", "target"):
        table.add_column(col, justify="right")
    notes = []
    t_start = time.perf_counter()

    for name in names:
        case = bench.STABLE_CASES[name]
        dt0 = bench.explicit_dt_estimate(case)
        console.log(f"[bold]{name}[/bold]: {case.description}")

        pe = None
        if have_pe:
            pe = bench.largest_stable_dt(lambda dt: bench.stays_bounded_elastica(case, dt, **search),
                                         dt0, rel_tol=rel_tol)
            console.log(f"  PyElastica dt_max = {pe.dt_max:.3g} s (unstable at {pe.dt_fail:.3g} s; "
                        f"{pe.trials} trials, {pe.seconds:.1f} s)")
        dx = bench.largest_stable_dt(lambda dt: bench.stays_bounded_deformx(case, dt, **search),
                                     dt0, rel_tol=rel_tol)
        console.log(f"  DeformX explicit dt_max = {dx.dt_max:.3g} s (unstable at {dx.dt_fail:.3g} s; "
                    f"{dx.trials} trials, {dx.seconds:.1f} s)")

        n_exp = explicit_steps[name]
        n_stable = max(1, int(round(stable_sim_seconds[name] / case.dt)))
        pe_t, dx_t, st_t, stats = [], [], [], None
        for _ in range(repeats):
            if pe is not None:
                r = bench.time_elastica(replace(case, dt=pe.dt_max), n_exp)
                if not np.all(np.isfinite(r.final_tip)):
                    notes.append(f"{name}: PyElastica went non-finite while timed at dt={pe.dt_max:.3g}")
                pe_t.append(bench.seconds_per_sim_second(r))
            r = bench.time_deformx(replace(case, dt=dx.dt_max), n_exp)
            if not np.all(np.isfinite(r.final_tip)):
                notes.append(f"{name}: DeformX explicit went non-finite while timed at dt={dx.dt_max:.3g}")
            dx_t.append(bench.seconds_per_sim_second(r))
            r, s = bench.time_deformx_stable(case, n_stable)
            st_t.append(bench.seconds_per_sim_second(r))
            stats = s
        pe_best = min(pe_t) if pe_t else float("nan")
        dx_best, st_best = min(dx_t), min(st_t)
        speedup = pe_best / st_best
        console.log(f"  wall s / sim s: PyElastica {fmt_time(pe_best)}, DeformX explicit {fmt_time(dx_best)}, "
                    f"DeformX stable {fmt_time(st_best)}; Newton {stats}")
        if stats.get("halvings", 0):
            notes.append(f"{name}: Newton did not converge and the step was halved {stats['halvings']} times "
                         f"in {stats['steps']} steps")
        if stats["capped_steps"]:
            notes.append(f"{name}: {stats['capped_steps']} of {stats['steps']} stable (sub-)steps were accepted "
                         f"at the Newton iteration cap (last relative update {stats['last_update']:.1e})")
        target = TARGETS[name]
        if target is None or not have_pe:
            target_txt = "report"
        else:
            mark = "[green]met[/green]" if speedup >= target else "[red]missed[/red]"
            target_txt = f">= {target:g}x {mark}"
        table.add_row(
            LABELS[name],
            f"{pe.dt_max:.2g} s" if pe else "n/a",
            fmt_time(pe_best),
            f"{dx.dt_max:.2g} s",
            fmt_time(dx_best),
            fmt_time(st_best),
            f"{stats['mean_iterations']:.2f} ({stats['capped_steps']} / {stats.get('halvings', 0)} "
            f"/ {stats['steps']})",
            f"{speedup:.0f}x" if np.isfinite(speedup) else "n/a",
            target_txt,
        )

    console.print(table)
    defaults = deformx.World(integrator="stable")
    console.print(
        f"[dim]dt_max: geometric bisection to {rel_tol:.0%} on one rod; a trial is "
        f"min({search['duration']:g} s / dt, {search['max_steps']}) steps from rest, stable if all nodes stay "
        f"finite and within 2 L of the clamp (DeformX: and no SimulationDiverged). Explicit timings: "
        f"{explicit_steps} steps at dt_max; stable timings: {stable_sim_seconds} simulated s from rest, "
        f"World defaults iterations={defaults.iterations}, tolerance={defaults.tolerance:g}. Damping 1 /s in both engines; DeformX threads: "
        f"{os.environ.get('DEFORMX_NUM_THREADS', 'all cores')}, PyElastica: one thread.[/dim]")
    for note in notes:
        console.print(f"[yellow]note:[/yellow] {note}")
    console.print(f"[dim]{time.strftime('%Y-%m-%d %H:%M')}, python {sys.version.split()[0]}, "
                  f"{os.cpu_count()} cores, total {time.perf_counter() - t_start:.0f} s[/dim]")


if __name__ == "__main__":
    main()
