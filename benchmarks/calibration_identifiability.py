"""How well the calibration experiment identifies a rope's parameters: how far the markers
move when E or the damping change (0.8 s of the 1.2 Hz, 0.2 m motion), and a CMA-ES fit to
markers of a simulation (E 2e5 Pa, damping 0.1 1/s) plus 2 mm noise, started at E 1.2e5,
damping 0.3 - the setup of tests/test_cosim.py's calibration test.

    python benchmarks/calibration_identifiability.py
"""

from __future__ import annotations

import os
import sys
import time
from dataclasses import replace

import numpy as np

from deformx.apps import calibration as cal
from deformx.apps import rope_fit as rf


def main() -> None:
    setup = cal.Setup()
    motion = rf.tool_motion(setup, 0.8, 0.01)
    truth = cal.run("cosserat", duration=0.8, setup=setup, every=0.02, motion=motion)
    for name, values in (("youngs_modulus", (1.9e5, 2.1e5, 1.0e5, 3.0e5)),
                         ("damping", (0.05, 0.2, 0.5))):
        for v in values:
            sim = cal.run("cosserat", duration=0.8, every=0.02, motion=motion,
                          setup=replace(setup, **{name: v}))
            print(f"{name} {v:g}: markers move {1e3 * cal.marker_error(sim, truth).mean():.1f} "
                  "mm on average", flush=True)
    noisy = truth.copy()
    noisy[:, 2:5] += np.random.default_rng(1).normal(scale=0.002, size=noisy[:, 2:5].shape)
    t0 = time.perf_counter()
    res = rf.calibrate(noisy, motion, "cosserat", setup=setup,
                       start={"youngs_modulus": 1.2e5, "damping": 0.3}, max_evals=36)
    print(f"fit: E {res.parameters['youngs_modulus']:.4g} Pa (truth 2e5), damping "
          f"{res.parameters['damping']:.3g} 1/s (truth 0.1), error {1e3 * res.error:.2f} mm, "
          f"{len(res.evaluations)} simulations in {time.perf_counter() - t0:.0f} s")
    print(f"{time.strftime('%Y-%m-%d %H:%M')}, python {sys.version.split()[0]}, "
          f"{os.cpu_count()} cores")


if __name__ == "__main__":
    main()
