"""World: the rods, the environment (gravity, planes), clamps, time, and the integrator."""

from __future__ import annotations

import math
import os
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING, Sequence

import numpy as np

from ..errors import SimulationDiverged
from . import validation as check
from .kernels import implicit, verlet
from .layout import Block
from .rod import Rod

if TYPE_CHECKING:
    from .recorder import Recorder

INTEGRATORS = ("verlet", "stable")
# Element-steps below which one call is too short to be worth handing to threads.
_MIN_THREADED_WORK = 20_000
_POOL: ThreadPoolExecutor | None = None


def default_threads() -> int:
    """Worker threads for multi-rod worlds: ``DEFORMX_NUM_THREADS`` or the usable cores."""
    env = os.environ.get("DEFORMX_NUM_THREADS")
    if env:
        return check.integer_at_least("DEFORMX_NUM_THREADS", int(env), 1)
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _pool(n: int) -> ThreadPoolExecutor:
    global _POOL
    if _POOL is None or _POOL._max_workers < n:
        _POOL = ThreadPoolExecutor(max_workers=n, thread_name_prefix="deformx")
    return _POOL


def _balanced_groups(rod_ne: np.ndarray, n_groups: int) -> list[tuple[int, int]]:
    """Split rods into at most ``n_groups`` contiguous ranges of similar element count."""
    n_rods = rod_ne.shape[0]
    n_groups = max(1, min(n_groups, n_rods))
    cuts = np.searchsorted(np.cumsum(rod_ne), np.arange(1, n_groups) * rod_ne.sum() / n_groups)
    bounds = [0, *sorted(set(int(c) + 1 for c in cuts)), n_rods]
    return [(a, b) for a, b in zip(bounds[:-1], bounds[1:]) if b > a]
_REASONS = {
    verlet.NOT_FINITE: "a position, frame or load became NaN/inf",
    verlet.RUNAWAY_STRETCH: "runaway stretch (element strain beyond max_strain)",
    verlet.RUNAWAY_BEND: "runaway bending/twist (neighbouring frames turned by > 170 degrees)",
    implicit.NOT_CONVERGED: "Newton's method did not converge even on dt/64 sub-steps",
}


class World:
    """A simulation: rods, gravity, contact planes, clamps; advances them together.

    ``gravity`` in m/s^2, ``dt`` in s. ``integrator="verlet"`` is PyElastica's position
    Verlet (explicit; needs dt below roughly ``min(dl, 2r) sqrt(rho/E) / 4``).
    ``max_strain`` is the element strain beyond which the run is declared diverged;
    ``threads`` (default: usable cores) advance groups of rods in parallel.

    ``integrator="stable"`` is backward Euler solved by Newton's method with a banded direct
    solve per rod: stable for any stiffness at large steps (1e-2 s for steel wire), with the
    numerical damping of backward Euler. ``iterations`` caps the Newton iterations per step
    and ``tolerance`` is the converged update size relative to the element length; see
    :meth:`solver_stats`.
    """

    def __init__(self, gravity: Sequence[float] = (0.0, 0.0, -9.81), dt: float = 1e-4,
                 integrator: str = "verlet", max_strain: float = 1.0,
                 threads: int | None = None, iterations: int = 4,
                 tolerance: float = 1e-4) -> None:
        if integrator not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {INTEGRATORS}, got {integrator!r}")
        self.integrator = integrator
        self.gravity = check.vector3("gravity", gravity)
        self._dt = check.positive("dt", dt, "s")
        self.max_strain = check.positive("max_strain", max_strain)
        self.iterations = check.integer_at_least("iterations", iterations, 1)
        self.tolerance = check.positive("tolerance", tolerance)
        self.threads = default_threads() if threads is None else check.integer_at_least(
            "threads", threads, 1)
        self.time = 0.0
        self._rods: list[Rod] = []
        self._planes: list[np.ndarray] = []
        self._block: Block | None = None
        self._dirty = True
        self._planes_arr = np.zeros((0, 11))

    # ------------------------------------------------------------------ building
    @property
    def dt(self) -> float:
        """Time step (s)."""
        return self._dt

    @dt.setter
    def dt(self, value: float) -> None:
        self._dt = check.positive("dt", value, "s")
        self._dirty = True

    @property
    def rods(self) -> tuple[Rod, ...]:
        return tuple(self._rods)

    def add_rod(self, rod: Rod) -> Rod:
        """Add ``rod`` (its arrays become views into the world's packed state); returns it."""
        if not isinstance(rod, Rod):
            raise ValueError(f"rod must be a deformx.Rod, got {type(rod).__name__}")
        if rod._world is not None:
            raise ValueError("rod already belongs to a world")
        rod._world = self
        rod._index = len(self._rods)
        self._rods.append(rod)
        self._block = Block(self._rods)
        self._dirty = True
        return rod

    def add_plane(self, point: Sequence[float] = (0.0, 0.0, 0.0),
                  normal: Sequence[float] = (0.0, 0.0, 1.0), stiffness: float | None = None,
                  damping: float | None = None, friction: float | None = None,
                  static_friction: float | None = None,
                  kinetic_friction: float | None = None) -> int:
        """Add an infinite ground plane; returns its index.

        ``stiffness`` (N/m per node) and ``damping`` (N s/m per node): None picks a stiff,
        critically damped penalty from each node's mass and ``dt``. ``friction`` sets both
        Coulomb coefficients; ``static_friction`` / ``kinetic_friction`` set them apart
        (defaults 0.5 and equal to the static one).
        """
        p = check.vector3("point", point)
        n = check.vector3("normal", normal, unit=True)
        auto = stiffness is None
        k = 0.0 if auto else check.positive("stiffness", stiffness, "N/m")
        c = -1.0 if damping is None else check.non_negative("damping", damping, "N s/m")
        if friction is not None:
            mu = check.non_negative("friction", friction)
            mu_s = mu if static_friction is None else static_friction
            mu_k = mu if kinetic_friction is None else kinetic_friction
        else:
            mu_s = 0.5 if static_friction is None else static_friction
            mu_k = mu_s if kinetic_friction is None else kinetic_friction
        mu_s = check.non_negative("static_friction", mu_s)
        mu_k = check.non_negative("kinetic_friction", mu_k)
        if mu_k > mu_s:
            raise ValueError(f"kinetic_friction ({mu_k}) must be <= static_friction ({mu_s})")
        self._planes.append(np.array([*p, *n, k, c, mu_s, mu_k, 1.0 if auto else 0.0]))
        self._planes_arr = np.array(self._planes)
        self._dirty = True
        return len(self._planes) - 1

    # ------------------------------------------------------------------ stepping
    def _sync_constraints(self) -> None:
        pn, pd, fe, fq, fd = [], [], [], [], []
        rod_pcon, rod_fcon = [0], [0]
        for i, rod in enumerate(self._rods):
            n0 = self._block.rod_node0[i]
            e0 = self._block.rod_elem0[i]
            for c in rod._clamps:
                pn.append(n0 + c.node)
                pd.append([*c._pos0, *c._vel, c._t0])
                if c._Q0 is not None:
                    fe.append(e0 + c.element)
                    fq.append(c._Q0)
                    fd.append([*c._omega, c._t0])
            rod_pcon.append(len(pn))
            rod_fcon.append(len(fe))
        self._rod_pcon = np.array(rod_pcon, dtype=np.int64)
        self._rod_fcon = np.array(rod_fcon, dtype=np.int64)
        self._pcon_node = np.array(pn, dtype=np.int64)
        self._pcon_data = np.array(pd, dtype=np.float64).reshape(-1, 7)
        self._fcon_elem = np.array(fe, dtype=np.int64)
        self._fcon_Q0 = np.array(fq, dtype=np.float64).reshape(-1, 3, 3)
        self._fcon_data = np.array(fd, dtype=np.float64).reshape(-1, 4)

    def _prepare(self) -> None:
        """Rebuild what the kernel needs after rods, clamps, planes, dt or damping changed."""
        self._sync_constraints()
        b = self._block
        n_rods = len(self._rods)
        decay = np.array([math.exp(-r.damping * self._dt) for r in self._rods])
        self._status = np.zeros((n_rods, 3), dtype=np.int64)
        self._times = np.empty(n_rods)
        self._groups = _balanced_groups(b.rod_ne, self.threads)
        common = (
            self._rod_pcon, self._rod_fcon,
            b.pos, b.vel, b.mass, b.node_radius, b.node_kmin, b.fext, b.force, b.contact_force)
        if self.integrator == "verlet":
            viscous = [i for i, r in enumerate(self._rods) if r.internal_damping > 0.0]
            if viscous:
                raise ValueError(f"internal_damping: rod {viscous[0]} sets it, but it needs "
                                 "integrator='stable' (explicit steps cannot afford it)")
            decay = np.array([math.exp(-r.damping * self._dt) for r in self._rods])
            self._kernel = verlet.advance_rods
            self._args = (
                b.rod_node0, b.rod_elem0, b.rod_vor0, b.rod_ne, b.rod_closed, decay, *common,
                b.Q, b.omega, b.J, b.inv_J, b.S, b.rest_len, b.rest_sigma, b.text, b.torque,
                b.dil, b.stress, b.B, b.rest_vor, b.rest_kappa, b.kappa, b.couple,
                b.scr_lab, b.scr_C, b.scr_X, b.scr_edot,
                self._pcon_node, self._pcon_data, self._fcon_elem, self._fcon_Q0, self._fcon_data,
                self._planes_arr, self._status, self._times)
        else:
            rates = np.array([r.damping for r in self._rods])
            retardation = np.array([r.internal_damping for r in self._rods])
            self._kernel = implicit.advance_rods_implicit
            self._args = (
                self.iterations, self.tolerance,
                b.rod_node0, b.rod_elem0, b.rod_vor0, b.rod_ne, b.rod_closed, rates, retardation,
                *common,
                b.Q, b.omega, b.J, b.S, b.rest_len, b.rest_sigma, b.text, b.torque,
                b.dil, b.stress, b.B, b.rest_vor, b.rest_kappa, b.kappa, b.couple,
                b.scr_lab, b.scr_C, b.scr_X, b.scr_edot,
                self._pcon_node, self._pcon_data, self._fcon_elem, self._fcon_Q0, self._fcon_data,
                self._planes_arr, self._status, self._times,
                b.xn, b.vn, b.Qn, b.wn, b.fn_el, b.tn_el, b.anchor, b.anchor_on, b.c_plane,
                b.c_stick, b.c_dir, b.stats, b.h_prev, b.rate)
        self._dirty = False

    def step(self, n_steps: int = 1) -> None:
        """Advance ``n_steps`` time steps (one kernel call for all rods and steps)."""
        n_steps = check.integer_at_least("n_steps", n_steps, 0)
        if n_steps == 0:
            return
        if self._block is None:
            self.time += n_steps * self._dt
            return
        if self._dirty:
            self._prepare()
        status, times = self._status, self._times
        status[:] = 0
        args = (n_steps, self.time, self._dt, self.gravity, self.max_strain, *self._args)
        work = n_steps * int(self._block.rod_ne.sum())
        if len(self._groups) > 1 and work >= _MIN_THREADED_WORK:
            futures = [_pool(len(self._groups)).submit(self._kernel, r0, r1, *args)
                       for r0, r1 in self._groups]
            for f in futures:
                f.result()
        else:
            self._kernel(0, len(self._rods), *args)
        failed = np.flatnonzero(status[:, 0] != verlet.OK)
        if failed.size:
            # Report the rod that failed first; the world's state is not usable afterwards.
            r = int(failed[np.argmin(status[failed, 2])])
            self.time = float(self.time + (int(status[r, 2]) + 0.5) * self._dt)
            self._raise_diverged(int(status[r, 0]), r, int(status[r, 1]))
        self.time = float(times[0])

    def _raise_diverged(self, code: int, r: int, k: int) -> None:
        # The explicit limit means nothing to the stable integrator, which has already tried
        # dt/64 sub-steps: suggest a smaller step of the same kind.
        suggested = min(rod.stable_dt() for rod in self._rods)
        if self.integrator == "stable" or suggested >= self._dt:
            suggested = 0.25 * self._dt
        raise SimulationDiverged(rod=r, element=k, time=self.time, suggested_dt=suggested,
                                 reason=_REASONS.get(code, "unknown"), dt=self._dt)

    def run(self, duration: float, progress: bool = False,
            recorder: "Recorder | None" = None) -> None:
        """Advance by ``duration`` s (rounded to whole steps), sampling ``recorder`` on the way.

        ``progress=True`` shows a progress bar (useful for long runs).
        """
        duration = check.non_negative("duration", duration, "s")
        n_total = int(round(duration / self._dt))
        # Chunks bound the Python overhead; recorder samples fall on chunk ends.
        chunk = max(1, min(n_total, 2000))
        if recorder is not None:
            chunk = max(1, min(chunk, int(round(recorder.every / self._dt))))
            if not recorder.times:
                recorder.sample()
        bar = None
        if progress:
            from rich.progress import Progress
            bar = Progress(transient=True)
            bar.start()
            task = bar.add_task(f"simulating {duration:g} s", total=n_total)
        try:
            done = 0
            while done < n_total:
                n = min(chunk, n_total - done)
                self.step(n)
                done += n
                if recorder is not None and recorder.due():
                    recorder.sample()
                if bar is not None:
                    bar.update(task, completed=done)
        finally:
            if bar is not None:
                bar.stop()

    # ------------------------------------------------------------------ diagnostics
    def energy(self) -> dict[str, float]:
        """Total energies (J): kinetic, stretch, shear, bend, twist, gravity and their total."""
        out = dict(kinetic=0.0, stretch=0.0, shear=0.0, bend=0.0, twist=0.0, gravity=0.0)
        for rod in self._rods:
            out["kinetic"] += rod.kinetic_energy()
            for k, v in rod.elastic_energy().items():
                out[k] += v
            out["gravity"] += rod.gravitational_energy(self.gravity)
        out["total"] = sum(out.values())
        return out

    def solver_stats(self) -> dict[str, float]:
        """Newton statistics of the stable integrator since the world was built: steps,
        mean iterations per step, (sub-)steps that hit the iteration cap, the last relative
        update (update size / element length, compare with ``tolerance``) and how often a
        step had to be halved because Newton did not converge (``halvings``)."""
        if self.integrator != "stable" or self._block is None:
            return {"steps": 0, "mean_iterations": 0.0, "capped_steps": 0, "last_update": 0.0,
                    "halvings": 0}
        st = self._block.stats
        return {"steps": int(st[:, 0].max()),
                "mean_iterations": float(st[:, 1].sum() / max(st[:, 0].sum(), 1)),
                "capped_steps": int(st[:, 2].sum()),
                "last_update": float(st[:, 3].max()),
                "halvings": int(st[:, 4].sum())}

    def contact_forces(self, rod: Rod) -> np.ndarray:
        """Plane contact forces (n_nodes, 3), N, on ``rod`` during the last step."""
        return self._block.contact_force[self._block.node_slice(rod._index, rod)].copy()

    def __repr__(self) -> str:
        return (f"World(rods={len(self._rods)}, planes={len(self._planes)}, dt={self._dt:g} s, "
                f"t={self.time:g} s, integrator={self.integrator!r})")
