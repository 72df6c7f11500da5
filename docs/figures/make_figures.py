"""Figures for docs/integrators.md (measured, not drawn): run from the repository root.

    python docs/figures/make_figures.py

numerical_damping.png: amplitude kept per period of a vibrating cantilever with the stable
    integrator at several dt, against backward Euler's prediction.
cost_vs_stiffness.png: wall seconds per simulated second of a clamped 1 m, 100-element rod
    (r = 1 mm) against Young's modulus: verlet at its stable step vs stable at dt = 1e-2.
"""

from __future__ import annotations

import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import deformx as dx

OUT = Path(__file__).parent


def cantilever(dt: float, integrator: str, E: float, r: float, L: float, n: int, rho: float = 1100.0):
    rod = dx.Rod.straight(n_elements=n, start=(0, 0, 0), direction=(1, 0, 0), normal=(0, 0, 1),
                          length=L, radius=r, density=rho, youngs_modulus=E)
    world = dx.World(gravity=(0, 0, 0), dt=dt, integrator=integrator)
    world.add_rod(rod)
    rod.fix_start()
    return world, rod


def amplitude_per_period(dt: float) -> tuple[float, float]:
    """(steps per period, measured amplitude ratio per period) for the first bending mode."""
    E, r, L, n, rho = 2e6, 0.01, 0.35, 20, 1100.0
    world, rod = cantilever(dt, "stable", E, r, L, n, rho)
    # Release from a small static tip deflection.
    rod.external_forces[-1] = (0.0, 0.0, -2e-4)
    rod.damping = 20.0
    world.run(2.0)
    rod.external_forces[-1] = 0.0
    rod.damping = 0.0
    rod.velocities[:] = 0.0
    rod.angular_velocities[:] = 0.0
    z, t = [], []
    for _ in range(int(round(6.0 / dt))):
        world.step(1)
        z.append(rod.positions[-1, 2])
        t.append(world.time)
    z, t = np.array(z), np.array(t)
    peaks = [i for i in range(1, len(z) - 1) if z[i] > z[i - 1] and z[i] >= z[i + 1] and z[i] > 0]
    period = float(np.mean(np.diff(t[peaks])))
    ratio = float((z[peaks[-1]] / z[peaks[0]]) ** (1.0 / (len(peaks) - 1)))
    return period / dt, ratio


def figure_damping() -> None:
    N = np.logspace(0.8, 3.2, 200)
    kept = (1 + (2 * np.pi / N) ** 2) ** (-N / 2)
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.semilogx(N, kept, "k-", label="backward Euler: (1 + (2π/N)²)^(-N/2)")
    pts = [amplitude_per_period(dt) for dt in (1e-3, 3e-3, 1e-2, 3e-2)]
    ax.semilogx([p[0] for p in pts], [p[1] for p in pts], "o", ms=8,
                label="measured: cantilever, dt = 1e-3 ... 3e-2 s")
    ax.set_xlabel("steps per period N")
    ax.set_ylabel("amplitude kept per period")
    ax.set_title("Numerical damping of the stable integrator")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(OUT / "numerical_damping.png", dpi=110)
    print("numerical_damping.png:", [(round(a, 1), round(b, 4)) for a, b in pts])


def seconds_per_step(world, n: int) -> float:
    world.step(2)
    t0 = time.perf_counter()
    world.step(n)
    return (time.perf_counter() - t0) / n


def figure_cost() -> None:
    Es = np.logspace(6, np.log10(2e11), 6)
    explicit, stable = [], []
    for E in Es:
        rod = dx.Rod.straight(n_elements=100, length=1.0, radius=1e-3, density=7850.0, youngs_modulus=E)
        dt_e = rod.stable_dt()
        w, _ = cantilever(dt_e, "verlet", E, 1e-3, 1.0, 100, 7850.0)
        w.gravity = np.array([0.0, 0.0, -9.81])
        explicit.append(seconds_per_step(w, 2000) / dt_e)
        w, _ = cantilever(1e-2, "stable", E, 1e-3, 1.0, 100, 7850.0)
        w.gravity = np.array([0.0, 0.0, -9.81])
        stable.append(seconds_per_step(w, 100) / 1e-2)
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.loglog(Es, explicit, "o-", label="verlet at rod.stable_dt()")
    ax.loglog(Es, stable, "s-", label="stable at dt = 1e-2 s")
    ax.axhline(1.0, color="k", lw=0.8, ls="--")
    ax.text(Es[0], 1.15, "real time", fontsize=8)
    ax.set_xlabel("Young's modulus E (Pa)")
    ax.set_ylabel("wall seconds per simulated second")
    ax.set_title("Clamped 1 m wire, r = 1 mm, 100 elements, gravity")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(OUT / "cost_vs_stiffness.png", dpi=110)
    print("cost_vs_stiffness.png:", [(f"{E:.0e}", f"{a:.3g}", f"{b:.3g}") for E, a, b in zip(Es, explicit, stable)])


if __name__ == "__main__":
    import sys
    if "--cost-only" not in sys.argv:
        figure_damping()
    figure_cost()
