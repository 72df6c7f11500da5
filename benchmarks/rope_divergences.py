"""Why and how often the hit-target rope stops (``SimulationDiverged``), per rope model.

1. A frame clamp driven round a 0.5 m circle, spun up to 10 m/s over 0.5 s (no robot): the
   first element's length (ratio to rest) at 8 m/s and the time the run stops, if it does.
2. A batch of 32 hit-target copies under aggressive random actions (half the copies at full
   speed each step) for 400 steps: divergences by reason and by element.

    python benchmarks/rope_divergences.py
"""

from __future__ import annotations

import collections
import math
import os
import sys
import time

import numpy as np

import deformx as dx

SOFT = dict(stretch_modulus=None, shear_modulus=None)  # the authors' rope: E everywhere
STIFF = dict(stretch_modulus=2e7, shear_modulus=6.7e6)  # the task's default
ROPES = {"authors' (E everywhere)": SOFT, "stiff shear, soft stretch":
         dict(stretch_modulus=None, shear_modulus=6.7e6), "default (stiff stretch, shear)": STIFF}


def circle(moduli: dict, speed: float = 10.0, radius: float = 0.5) -> str:
    world = dx.World(dt=5e-4, integrator="stable", rod_contact=False)
    rod = world.add_rod(dx.Rod.straight(n_elements=20, start=(radius, 0, 1.0),
                                        direction=(0, 0, -1), length=1.0, radius=0.00635,
                                        density=700.0, youngs_modulus=2e5, damping=0.1,
                                        **{k: v for k, v in moduli.items() if v is not None}))
    clamp = rod.fix_start()
    w_max, ramp = speed / radius, 0.5
    at8 = None
    for k in range(1000):
        t = 2e-3 * k
        w = w_max * min(1.0, t / ramp)
        th = 0.5 * w_max * t * t / ramp if t < ramp else 0.5 * w_max * ramp + w_max * (t - ramp)
        alpha = w_max / ramp if t < ramp else 0.0
        c, s = math.cos(th), math.sin(th)
        clamp.set_pose((radius * c, radius * s, 1.0))
        clamp.set_velocity((-w * radius * s, w * radius * c, 0.0))
        clamp.set_acceleration((-w * w * radius * c - alpha * radius * s,
                                -w * w * radius * s + alpha * radius * c, 0.0))
        try:
            world.step(4)
        except dx.SimulationDiverged as err:
            return f"first element x{at8 or float('nan'):.2f} at 8 m/s; stops at " \
                   f"{w * radius:.1f} m/s ({err.reason.split(' (')[0]})"
        if at8 is None and w * radius >= 8.0:
            at8 = float(np.linalg.norm(rod.positions[1] - rod.positions[0])) / 0.05
    return f"first element x{at8:.2f} at 8 m/s; runs 2 s (10 m/s for 1.5 s)"


def batch(moduli: dict, n: int = 32, steps: int = 400) -> str:
    from deformx.learn.batch import HitTargetBatch
    from deformx.learn.task import HitTargetConfig

    b = HitTargetBatch(HitTargetConfig(settle_time=0.3, **moduli), n)
    reasons, elements = collections.Counter(), collections.Counter()
    advance = b._advance

    def counted():
        try:
            advance()
        except dx.SimulationDiverged as err:
            reasons[err.reason.split(" (")[0]] += 1
            elements[err.element] += 1
            raise

    b._advance = counted
    rng = np.random.default_rng(0)
    for _ in range(steps):
        a = rng.uniform(-1, 1, (n, 3))
        a[rng.uniform(size=n) < 0.5] = 1.0
        _, term, trunc, _, _ = b.step(a)
        for i in np.flatnonzero(term | trunc):
            b.reset(int(i))
    return (f"{sum(reasons.values())} of {n * steps} steps: {dict(reasons)}; elements "
            f"{dict(sorted(elements.items()))}")


def main() -> None:
    t0 = time.perf_counter()
    for name, moduli in ROPES.items():
        print(f"{name}\n  circle: {circle(moduli)}\n  batch:  {batch(moduli)}", flush=True)
    print(f"{time.strftime('%Y-%m-%d %H:%M')}, python {sys.version.split()[0]}, "
          f"{os.cpu_count()} cores, {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
