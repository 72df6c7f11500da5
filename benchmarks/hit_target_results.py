"""The hit-target results tables: PPO trained on each target with each rope model, then

1. in-sim d_min of the best of the trajectories the trained policy generates (its
   deterministic rollout and 63 more with its exploration noise: the paper's "Sim" column,
   "the trained policy is first used to generate successful joint-command trajectories"), and
   the deterministic rollout's alone,
2. the open-loop replay of its joint-command trajectory, n times, on the rope it was trained
   on with its parameters perturbed per replay (mean +- std of d_min; the stand-in for the
   paper's n = 10 real repeats),
3. cross-model transfer - the offline stand-in for the paper's sim-to-real table: both
   policies' trajectories replayed on a reference rope (the default rope's moduli,
   ``--ref-elements`` elements, perturbed parameters; by default the stable integrator
   (backward Euler) at ``--ref-dt`` = 1.25e-5 s, 160 steps per control step, its clamp carried
   on continuously (``continuous_drivers``; with it jumped to the arm at each control step the
   reference does not converge in its step); the explicit integrator stops on these whips - a
   100-element rope passing a fold at its step limit runs away in stretch, at 5e-6 s it turns
   NaN - see docs/learning.md; ``--ref-integrator verlet`` runs it at its limit).
   A replay whose rope diverged counts as "diverged", not as a distance.

    python benchmarks/hit_target_results.py --steps 200000 --envs 16 --out runs
    python benchmarks/hit_target_results.py --normalize --seeds 3 --out runs   # the table
    python benchmarks/hit_target_results.py --steps 20000 --targets high --ropes cosserat
    python benchmarks/hit_target_results.py --normalize --seeds 2 --select robust --out runs
    python benchmarks/hit_target_results.py --normalize --seeds 2 --select robust --ref-check \
        --ropes cosserat --out runs    # + the reference's own step and element convergence
    python benchmarks/hit_target_results.py --normalize --seeds 4 --ropes cosserat --ref-check \
        --train-elements 40 --train-dt 1e-4 --train-order 1 --out runs   # a finer training rope
    python benchmarks/hit_target_results.py --normalize --seeds 2 --ropes cosserat \
        --train-elements 40 --train-dt 1e-4 --train-order 1 --train-randomise 0.2 --out runs
    (a sub-stepped training rope's clamp is carried on continuously by default since
    2026-12-06; ``--train-jumps`` trains as the tables before that date)
    python benchmarks/hit_target_results.py --steps 400000 --normalize --seeds 4 --targets mid \
        --ropes cosserat --train-elements 100 --train-dt 1e-4 --train-order 1 \
        --train-continuous --out runs   # the reference's elements and clamp, 8x its step
    ... --deploy-dt 1.25e-5 --out runs   # the same runs, their trajectories generated on the
                                         # reference's step (TrainSettings.deploy)
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

TARGETS = {"high": (0.0, 2.0, 2.3), "mid": (0.0, 2.0, 1.5), "low": (0.0, 1.7, 0.5)}
PAPER = {"high": (4.2, 4.9), "mid": (1.4, 4.4), "low": (3.3, 4.3)}  # cm: Cosserat, capsule
REF_CHECK_DTS = (1e-4, 5e-5, 2.5e-5, 1.25e-5, 6.25e-6)  # s: the reference's step check
REF_CHECK_ELEMENTS, REF_CHECK_ELEMENTS_DT = (150, 200), 1.25e-5  # its element check


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=200_000)
    parser.add_argument("--envs", type=int, default=16)
    parser.add_argument("--replays", type=int, default=10)
    parser.add_argument("--seeds", type=int, default=1,
                        help="PPO runs per cell (seeds 0..n-1); the best one's trajectory is "
                             "replayed")
    parser.add_argument("--seed-ids", type=int, nargs="+", default=None,
                        help="these PPO seeds instead of 0..--seeds-1 (run directories "
                             "always suffixed _s<seed>)")
    parser.add_argument("--targets", nargs="+", default=list(TARGETS), choices=list(TARGETS))
    parser.add_argument("--ropes", nargs="+", default=["cosserat", "capsule"])
    parser.add_argument("--out", type=Path, default=Path("runs"))
    parser.add_argument("--normalize", action="store_true", help="VecNormalize in training")
    parser.add_argument("--rollouts", type=int, default=64,
                        help="trajectories each trained policy generates to choose from")
    parser.add_argument("--select", default="best", choices=["best", "robust"],
                        help="which sampled trajectory is exported (TrainSettings.select; "
                             "robust: Cosserat rows only)")
    parser.add_argument("--robust-pool", type=int, default=0,
                        help="a robust choice replays only the best this many in sim "
                             "(TrainSettings.robust_pool; 0: all)")
    parser.add_argument("--robust-within", type=float, default=0.0,
                        help="m: a robust choice only among the trajectories within this "
                             "d_min in sim (TrainSettings.robust_within; 0: no bound)")
    parser.add_argument("--robust-draws", type=int, default=2,
                        help="perturbed draws of the deployment rope a robust choice replays "
                             "on (TrainSettings.robust_draws; with --deploy-*)")
    parser.add_argument("--ref-elements", type=int, default=100,
                        help="elements of the reference rope")
    parser.add_argument("--ref-integrator", default="stable", choices=["stable", "verlet"])
    parser.add_argument("--ref-dt", type=float, default=1.25e-5,
                        help="reference rope step (s) with the stable integrator (5e-5 in "
                             "the tables before 2026-12-05 17:00)")
    parser.add_argument("--ref-check", action="store_true",
                        help="also replay each trajectory once on the reference rope with its "
                             "nominal parameters at backward-Euler steps of 1e-4 down to "
                             "6.25e-6 s, and with 150 and 200 elements at 1.25e-5 s (how well "
                             "the reference itself is converged)")
    parser.add_argument("--ref-jumps", action="store_true",
                        help="the reference rope's clamp jumped to the arm's frame at each "
                             "control step (the tables before 2026-12-05 17:00) instead of "
                             "carried on continuously")
    parser.add_argument("--train-elements", type=int, default=None,
                        help="elements of the Cosserat training rope (default: the task's 20)")
    parser.add_argument("--train-dt", type=float, default=None,
                        help="step (s) of the Cosserat training rope (default: the task's 2 ms)")
    parser.add_argument("--train-order", type=int, default=None, choices=[1, 2],
                        help="stable integrator order of the Cosserat training rope (default: "
                             "the task's BDF2)")
    parser.add_argument("--train-randomise", type=float, default=None,
                        help="train on Cosserat ropes whose E, density and damping are drawn "
                             "+- this fraction at every reset (as `deformx train hit-target "
                             "--randomise`); trajectories are still sampled on the nominal rope")
    clamp = parser.add_mutually_exclusive_group()
    clamp.add_argument("--train-continuous", action="store_true",
                       help="carry the Cosserat training rope's clamp on continuously between "
                            "control steps, as the reference's (HitTargetConfig."
                            "continuous_drivers; the task's default where --train-dt sub-steps "
                            "the control step)")
    clamp.add_argument("--train-jumps", action="store_true",
                       help="jump the Cosserat training rope's clamp to the arm's frame at each "
                            "control step (the task's default with one rope step per control "
                            "step; how sub-stepped training ropes ran before 2026-12-06)")
    parser.add_argument("--deploy-elements", type=int, default=None,
                        help="generate and choose the Cosserat policy's trajectories on a rope "
                             "of this many elements (TrainSettings.deploy; default: the "
                             "training rope's)")
    parser.add_argument("--deploy-dt", type=float, default=None,
                        help="... of this step (s), e.g. 1.25e-5")
    parser.add_argument("--deploy-order", type=int, default=None, choices=[1, 2],
                        help="... of this order")
    args = parser.parse_args()
    from deformx.cosim.coupling import continuous_by_default
    from deformx.engine.rod import explicit_time_step
    from deformx.learn.task import RANDOMISABLE, HitTargetConfig
    from deformx.learn.train import (REPLAY_PERTURBATION, TrainSettings, deployed,
                                     load_trajectory, replay, train)

    rows = []
    for name in args.targets:
        for rope in args.ropes:
            task = dict(target=TARGETS[name], rope=rope)
            deploy = {}
            tag = ""
            if rope == "cosserat":  # the training rope's own numbers, where not the task's
                for key, arg, short in (("n_elements", args.train_elements, "e"),
                                        ("rope_dt", args.train_dt, "dt"),
                                        ("order", args.train_order, "o")):
                    if arg is not None:
                        task[key] = arg
                        tag += f"_{short}{arg:g}"
                if args.train_randomise:
                    task["randomise"] = dict.fromkeys(RANDOMISABLE, args.train_randomise)
                    tag += f"_r{args.train_randomise:g}"
                # the clamp as run: continuous ("_c") where asked or, by default, where the
                # rope is sub-stepped; untagged run directories hold jumped clamps
                if args.train_continuous or args.train_jumps:
                    task["continuous_drivers"] = bool(args.train_continuous)
                trained = HitTargetConfig(**task)
                continuous = trained.continuous_drivers
                if continuous is None:  # the co-simulation's own rule
                    continuous = continuous_by_default(round(trained.control_dt / trained.rope_dt))
                tag += "_c" if continuous else ""
                deploy = {key: arg for key, arg in (("n_elements", args.deploy_elements),
                                                    ("rope_dt", args.deploy_dt),
                                                    ("order", args.deploy_order))
                          if arg is not None}
            runs = []
            seeds = args.seed_ids if args.seed_ids else range(args.seeds)
            suffix = args.seed_ids is not None or args.seeds > 1
            for seed in seeds:  # resumable: a finished run only re-evaluates
                out = args.out / (f"{name}_{rope}{tag}" + (f"_s{seed}" if suffix else ""))
                t0 = time.perf_counter()
                select = args.select if rope == "cosserat" else "best"
                summary = train(out, TrainSettings(total_steps=args.steps, num_envs=args.envs,
                                                   normalize=args.normalize, seed=seed,
                                                   video=False, select=select,
                                                   rollouts=args.rollouts, task=task,
                                                   deploy=deploy,
                                                   robust_draws=args.robust_draws,
                                                   robust_pool=args.robust_pool,
                                                   robust_within=args.robust_within),
                                progress=False)
                rank = summary["worst_d_min"] if select == "robust" else summary["d_min"]
                runs.append((rank, seed, out, summary, time.perf_counter() - t0))
                print(f"{name} {rope} seed {seed}: {100 * summary['d_min']:.1f} cm", flush=True)
            _, seed, out, summary, wall = min(runs, key=lambda r: r[0])
            _, q = load_trajectory(out / "best_rollout.csv")
            # (the rope the trajectory was chosen on; replays draw their own parameters)
            cfg = deployed(HitTargetConfig(**task), deploy)
            same = replay(q, cfg, n=args.replays, perturb=REPLAY_PERTURBATION, seed=1)
            limit = explicit_time_step(cfg.rope_length / args.ref_elements, cfg.radius,
                                       cfg.density, max(cfg.youngs_modulus,
                                                        cfg.stretch_modulus or 0.0),
                                       cfg.shear_modulus or cfg.youngs_modulus / 3.0)
            ref_dt = 2e-3 / math.ceil(2e-3 / limit)  # the rope's explicit limit, or under
            if args.ref_integrator == "stable":
                ref_dt = args.ref_dt
            # backward Euler: the reference of every table so far (docs/learning.md)
            # the clamp carried on continuously: with it jumped to the arm at each control step
            # the sub-stepped reference does not converge in its step (docs/learning.md)
            ref_cfg = replace(cfg, rope="cosserat", integrator=args.ref_integrator,
                              n_elements=args.ref_elements, rope_dt=ref_dt, order=1,
                              continuous_drivers=not args.ref_jumps)
            ref = replay(q, ref_cfg, n=args.replays, perturb=REPLAY_PERTURBATION, seed=2)
            # The reference rope's own step convergence on this trajectory (nominal
            # parameters): a whip's d_min is only as certain as these agree.
            checks = [(args.ref_elements, dt) for dt in REF_CHECK_DTS] + [
                (n, REF_CHECK_ELEMENTS_DT) for n in REF_CHECK_ELEMENTS]
            ref_steps = {f"{n}@{dt:g}": float(replay(q, replace(ref_cfg, integrator="stable",
                                                                n_elements=n, rope_dt=dt),
                                                     n=1)[0])
                         for n, dt in checks} if args.ref_check else {}
            row = dict(target=name, rope=rope, sim=summary["d_min"], wall=wall, seed=seed,
                       training_rope={k: v for k, v in task.items() if k != "target"},
                       deploy=deploy,
                       seeds=[r[3]["d_min"] for r in runs], select=summary.get("select"),
                       worst=summary.get("worst_d_min"),
                       deterministic=summary["d_min_deterministic"],
                       sampled_successes=summary["successes_sampled"],
                       rollouts=summary["rollouts"],
                       replay=same.tolist(), reference=ref.tolist(), reference_steps=ref_steps,
                       paper=PAPER[name][0 if rope == "cosserat" else 1])
            rows.append(row)
            (out / "results.json").write_text(json.dumps(row, indent=1))
            print(json.dumps(row), flush=True)

    def stat(v):
        v = np.asarray(v)
        ok = np.isfinite(v)
        s = f"{100 * v[ok].mean():.1f} +- {100 * v[ok].std():.1f}" if ok.any() else "-"
        return s + ("" if ok.all() else f" ({(~ok).sum()} diverged)")

    print(f"\n| target | rope | sim d_min (cm) | paper sim (cm) | deterministic (cm) | "
          f"successful rollouts | open-loop replay, own rope (n={args.replays}) | replay on "
          f"the reference rope | reference, nominal, at 1e-4 / 5e-5 / 2.5e-5 / 1.25e-5 / "
          f"6.25e-6 s, then 150 / 200 elements at 1.25e-5 s (cm) | "
          f"every seed (cm) | train wall (s) |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in rows:
        print(f"| {r['target']} {TARGETS[r['target']]} | {r['rope']} | {100 * r['sim']:.1f} | "
              f"{r['paper']} | {100 * r['deterministic']:.1f} | "
              f"{r['sampled_successes']} / {r['rollouts']} | {stat(r['replay'])} | "
              f"{stat(r['reference'])} | "
              f"{' / '.join(f'{100 * v:.1f}' for v in r['reference_steps'].values()) or '-'} | "
              f"{' / '.join(f'{100 * v:.1f}' for v in r['seeds'])} | {r['wall']:.0f} |")
    print(f"\n{time.strftime('%Y-%m-%d %H:%M')}, python {sys.version.split()[0]}, "
          f"{os.cpu_count()} cores, {args.steps} steps x {args.envs} envs per run")


if __name__ == "__main__":
    main()
