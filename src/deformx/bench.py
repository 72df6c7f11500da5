"""Micro benchmarks: seconds per step of DeformX, and of PyElastica when it is installed.

The cases are plain data (:class:`BenchCase`) so that the repository's ``benchmarks/``
scripts and ``deformx bench`` time exactly the same setups. Each case is a set of identical
cantilevers (clamped at the start, under gravity, uniformly damped), advanced with the
explicit position-Verlet integrator at the same ``dt`` in both engines.

    >>> from deformx import bench
    >>> r = bench.time_deformx(bench.CASES["1x100"], n_steps=2000)
    >>> r.seconds_per_step
"""

from __future__ import annotations

import importlib.util
import time
from dataclasses import dataclass, field, replace

import numpy as np

__all__ = [
    "BenchCase",
    "BenchResult",
    "CASES",
    "elastica_available",
    "build_deformx",
    "build_elastica",
    "time_deformx",
    "time_elastica",
    "run_cases",
]


@dataclass(frozen=True)
class BenchCase:
    """``n_rods`` identical clamped cantilevers of ``n_elements`` elements, side by side in y."""

    name: str
    n_rods: int = 1
    n_elements: int = 100
    length: float = 1.0
    radius: float = 0.01
    density: float = 1000.0
    youngs_modulus: float = 1.0e6
    poisson_ratio: float = 0.5
    damping: float = 1.0
    dt: float = 1.0e-4
    spacing: float = 0.05
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)
    description: str = field(default="", compare=False)

    @property
    def n_dofs(self) -> int:
        return self.n_rods * (self.n_elements + 1)

    def label(self) -> str:
        return f"{self.n_rods} rod{'s' if self.n_rods != 1 else ''} x {self.n_elements} el"


CASES: dict[str, BenchCase] = {
    "1x100": BenchCase("1x100", n_rods=1, n_elements=100,
                       description="one clamped cantilever, 100 elements, E=1e6, dt=1e-4"),
    "64x50": BenchCase("64x50", n_rods=64, n_elements=50,
                       description="64 clamped cantilevers, 50 elements each, E=1e6, dt=1e-4"),
}


@dataclass
class BenchResult:
    case: BenchCase
    engine: str
    n_steps: int
    seconds: float
    setup_seconds: float = 0.0
    final_tip: np.ndarray | None = None

    @property
    def seconds_per_step(self) -> float:
        return self.seconds / max(self.n_steps, 1)

    @property
    def realtime_factor(self) -> float:
        """Simulated seconds per wall-clock second."""
        return self.case.dt / self.seconds_per_step if self.seconds > 0 else float("inf")


def elastica_available() -> bool:
    return importlib.util.find_spec("elastica") is not None


def _start(case: BenchCase, k: int) -> np.ndarray:
    return np.array([0.0, k * case.spacing, 0.0])


# ---------------------------------------------------------------------------------------------
# DeformX


def build_deformx(case: BenchCase):
    """Return ``(world, rods)`` for a case."""
    import deformx as dx

    world = dx.World(gravity=case.gravity, dt=case.dt, integrator="verlet")
    rods = []
    for k in range(case.n_rods):
        rod = dx.Rod.straight(n_elements=case.n_elements, start=tuple(_start(case, k)),
                              direction=(1.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0), length=case.length,
                              radius=case.radius, density=case.density,
                              youngs_modulus=case.youngs_modulus, poisson_ratio=case.poisson_ratio,
                              damping=case.damping)
        world.add_rod(rod)
        rod.fix_start()
        rods.append(rod)
    return world, rods


def time_deformx(case: BenchCase, n_steps: int = 2000, warmup_steps: int = 10) -> BenchResult:
    """Seconds for ``n_steps`` steps after a warm-up (which includes any numba compile)."""
    t0 = time.perf_counter()
    world, rods = build_deformx(case)
    world.step(warmup_steps)
    setup = time.perf_counter() - t0
    t0 = time.perf_counter()
    world.step(n_steps)
    seconds = time.perf_counter() - t0
    return BenchResult(case, "deformx", n_steps, seconds, setup, rods[0].positions[-1].copy())


# ---------------------------------------------------------------------------------------------
# PyElastica (optional)


def build_elastica(case: BenchCase):
    """Return ``(simulator, stepper, rods)`` for a case in PyElastica 1.0 (same discretization)."""
    import elastica as ea

    class _Sim(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.Damping):
        pass

    sim = _Sim()
    shear = case.youngs_modulus / (2.0 * (1.0 + case.poisson_ratio))
    rods = []
    for k in range(case.n_rods):
        rod = ea.CosseratRod.straight_rod(
            case.n_elements, _start(case, k), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]),
            case.length, case.radius, case.density, youngs_modulus=case.youngs_modulus,
            shear_modulus=shear)
        sim.append(rod)
        sim.constrain(rod).using(ea.OneEndFixedBC, constrained_position_idx=(0,),
                                 constrained_director_idx=(0,))
        sim.add_forcing_to(rod).using(ea.GravityForces, acc_gravity=np.array(case.gravity))
        if case.damping > 0.0:
            sim.dampen(rod).using(ea.AnalyticalLinearDamper, uniform_damping_constant=case.damping,
                                  time_step=case.dt)
        rods.append(rod)
    sim.finalize()
    return sim, ea.PositionVerlet(), rods


def time_elastica(case: BenchCase, n_steps: int = 2000, warmup_steps: int = 10) -> BenchResult:
    """Seconds for ``n_steps`` PyElastica steps after a warm-up (which includes its numba compile)."""
    t0 = time.perf_counter()
    sim, stepper, rods = build_elastica(case)
    t = np.float64(0.0)
    dt = np.float64(case.dt)
    for _ in range(warmup_steps):
        t = stepper.step(sim, t, dt)
    setup = time.perf_counter() - t0
    t0 = time.perf_counter()
    for _ in range(n_steps):
        t = stepper.step(sim, t, dt)
    seconds = time.perf_counter() - t0
    return BenchResult(case, "pyelastica", n_steps, seconds, setup,
                       np.asarray(rods[0].position_collection[:, -1]).copy())


# ---------------------------------------------------------------------------------------------


def run_cases(cases=None, n_steps: int | dict[str, int] = 2000, with_elastica: bool | None = None,
              on_result=None) -> list[tuple[BenchResult, BenchResult | None]]:
    """Time every case in DeformX and (if available and wanted) PyElastica.

    ``n_steps`` may be a dict per case name. ``on_result(case, deformx_result, elastica_result)``
    is called after each case (for progress output).
    """
    if cases is None:
        cases = list(CASES.values())
    if with_elastica is None:
        with_elastica = elastica_available()
    out = []
    for case in cases:
        n = n_steps[case.name] if isinstance(n_steps, dict) else n_steps
        ours = time_deformx(case, n)
        theirs = time_elastica(case, n) if with_elastica else None
        out.append((ours, theirs))
        if on_result is not None:
            on_result(case, ours, theirs)
    return out


def quick(case: BenchCase, **changes) -> BenchCase:
    """A copy of a case with some fields changed (e.g. ``quick(CASES['64x50'], n_rods=8)``)."""
    return replace(case, **changes)
