"""Micro benchmarks: seconds per step of DeformX, and of PyElastica when it is installed.

The cases are plain data (:class:`BenchCase`) so that the repository's ``benchmarks/``
scripts and ``deformx bench`` time exactly the same setups. Each case is a set of identical
cantilevers (clamped at the start, under gravity, uniformly damped), advanced with the
explicit position-Verlet integrator at the same ``dt`` in both engines.

    >>> from deformx.apps import bench
    >>> r = bench.time_deformx(bench.CASES["1x100"], n_steps=2000)
    >>> r.seconds_per_step
"""

from __future__ import annotations

import importlib.util
import math
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


def build_deformx(case: BenchCase, integrator: str = "verlet", **world_options):
    """Return ``(world, rods)`` for a case (``world_options`` go to :class:`World`)."""
    import deformx as dx

    # The peer simulates these cantilevers without any contact, so compare like with like.
    world_options.setdefault("rod_contact", False)
    world = dx.World(gravity=case.gravity, dt=case.dt, integrator=integrator, **world_options)
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


# ---------------------------------------------------------------------------------------------
# Large steps: the stable (implicit) integrator against explicit steps at their stability limit.
#
# Speed is compared in wall-clock seconds per simulated second, so that an engine taking bigger
# steps gets credit for them: ``seconds per step / dt``. Explicit engines are timed at their
# largest stable ``dt``, found by :func:`largest_stable_dt` (geometric bisection on short runs).

STABLE_CASES: dict[str, BenchCase] = {
    "soft": BenchCase("soft", n_rods=1, n_elements=100, dt=1.0e-2,
                      description="one clamped cantilever, 1 m, 100 elements, r=1 cm, E=1e6 Pa"),
    "steel": BenchCase("steel", n_rods=1, n_elements=100, radius=1.0e-3, density=7850.0,
                       youngs_modulus=2.0e11, dt=1.0e-2,
                       description="steel wire, 1 m, 100 elements, r=1 mm, E=2e11 Pa"),
    "256x20": BenchCase("256x20", n_rods=256, n_elements=20, dt=1.0e-2,
                        description="256 clamped cantilevers in one world, 20 elements each, E=1e6 Pa"),
}

__all__ += ["STABLE_CASES", "StabilityResult", "explicit_dt_estimate", "stays_bounded_deformx",
            "stays_bounded_elastica", "largest_stable_dt", "time_deformx_stable", "seconds_per_sim_second"]


@dataclass
class StabilityResult:
    """Outcome of :func:`largest_stable_dt`: ``dt_max`` ran stably, ``dt_fail`` did not."""

    dt_max: float
    dt_fail: float
    trials: int
    seconds: float  # wall time spent searching


def explicit_dt_estimate(case: BenchCase) -> float:
    """DeformX's conservative explicit step for the case's rods (a start for the search)."""
    from ..engine.rod import explicit_time_step

    shear = case.youngs_modulus / (2.0 * (1.0 + case.poisson_ratio))
    return explicit_time_step(case.length / case.n_elements, case.radius, case.density,
                              case.youngs_modulus, shear)


def _trial_steps(dt: float, duration: float, max_steps: int) -> int:
    return max(1, min(int(math.ceil(duration / dt)), max_steps))


def _bounded(positions: np.ndarray, case: BenchCase) -> bool:
    """Finite, and every node within ``2 L`` of where the rod starts (its clamp)."""
    if not np.all(np.isfinite(positions)):
        return False
    return bool(np.max(np.linalg.norm(positions - _start(case, 0)[:, None], axis=0)) < 2.0 * case.length)


def stays_bounded_deformx(case: BenchCase, dt: float, duration: float = 1.0, max_steps: int = 20000,
                          check_every: int = 500, integrator: str = "verlet") -> bool:
    """Run one rod of ``case`` for ``min(duration / dt, max_steps)`` steps of ``dt``: True if the
    nodes stay finite and within ``2 L`` of the clamp and no :class:`SimulationDiverged` is raised.

    The rods of a case are identical and do not interact, so one rod has the same limit as all.
    The duration matters: a soft cantilever near its limit runs stably while straight and blows
    up only once it bends (after 0.04 to 0.2 s for E = 1e6 Pa), so 1 s is the default.
    """
    from ..errors import SimulationDiverged

    one = replace(case, n_rods=1, dt=dt)
    world, rods = build_deformx(one, integrator=integrator)
    n = _trial_steps(dt, duration, max_steps)
    done = 0
    try:
        while done < n:
            k = min(check_every, n - done)
            world.step(k)
            done += k
            if not _bounded(rods[0].positions.T, one):
                return False
    except SimulationDiverged:
        return False
    return True


def stays_bounded_elastica(case: BenchCase, dt: float, duration: float = 1.0, max_steps: int = 20000,
                           check_every: int = 500) -> bool:
    """As :func:`stays_bounded_deformx`, for PyElastica's position Verlet (damper built for ``dt``)."""
    import warnings

    one = replace(case, n_rods=1, dt=dt)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim, stepper, rods = build_elastica(one)
        n = _trial_steps(dt, duration, max_steps)
        t = np.float64(0.0)
        h = np.float64(dt)
        done = 0
        with np.errstate(all="ignore"):
            while done < n:
                k = min(check_every, n - done)
                for _ in range(k):
                    t = stepper.step(sim, t, h)
                done += k
                if not _bounded(np.asarray(rods[0].position_collection), one):
                    return False
    return True


def largest_stable_dt(is_stable, dt0: float, rel_tol: float = 0.05, max_trials: int = 40) -> StabilityResult:
    """Largest ``dt`` with ``is_stable(dt)`` True, by geometric bisection.

    From ``dt0`` the step is doubled (or halved) until the outcome changes, then the bracket
    ``[stable, unstable]`` is split at its geometric mean until ``unstable / stable <= 1 + rel_tol``.
    """
    t0 = time.perf_counter()
    trials = 1
    if is_stable(dt0):
        lo, hi = dt0, None
        while hi is None:
            if trials >= max_trials:
                raise RuntimeError(f"still stable at dt = {lo:g} after {trials} trials")
            trials += 1
            if is_stable(2.0 * lo):
                lo = 2.0 * lo
            else:
                hi = 2.0 * lo
    else:
        lo, hi = None, dt0
        while lo is None:
            if trials >= max_trials:
                raise RuntimeError(f"still unstable at dt = {hi:g} after {trials} trials")
            trials += 1
            if is_stable(0.5 * hi):
                lo = 0.5 * hi
            else:
                hi = 0.5 * hi
    while hi / lo > 1.0 + rel_tol and trials < max_trials:
        mid = math.sqrt(lo * hi)
        if is_stable(mid):
            lo = mid
        else:
            hi = mid
        trials += 1
    return StabilityResult(lo, hi, trials, time.perf_counter() - t0)


def seconds_per_sim_second(result: BenchResult) -> float:
    """Wall-clock seconds per simulated second of a timing: ``seconds per step / dt``."""
    return result.seconds_per_step / result.case.dt


def time_deformx_stable(case: BenchCase, n_steps: int = 100, warmup_steps: int = 1,
                        **world_options) -> tuple[BenchResult, dict]:
    """Seconds for ``n_steps`` steps of ``integrator="stable"`` at ``case.dt``, from rest after a
    warm-up (which includes any numba compile), and the world's :meth:`~World.solver_stats`
    (warm-up included). ``world_options`` (``iterations``, ``tolerance``, ...) go to
    :class:`World`; left out, its defaults apply."""
    t0 = time.perf_counter()
    world, rods = build_deformx(case, integrator="stable", **world_options)
    world.step(warmup_steps)
    setup = time.perf_counter() - t0
    t0 = time.perf_counter()
    world.step(n_steps)
    seconds = time.perf_counter() - t0
    result = BenchResult(case, "deformx-stable", n_steps, seconds, setup, rods[0].positions[-1].copy())
    return result, world.solver_stats()
