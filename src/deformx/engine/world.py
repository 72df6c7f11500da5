"""World: the rods, the environment (gravity, planes, meshes, primitives), clamps, time, and
the integrator."""

from __future__ import annotations

import math
import os
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING, Sequence

import numpy as np

from ..errors import SimulationDiverged
from . import validation as check
from .contact import colliders as col
from .contact.segments import P_AUTO, P_C, P_K, P_MUK, P_MUS, query_cache
from .kernels import coupled, implicit, verlet
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

    ``rod_contact`` turns on contact between rods and of a rod with itself (capsule segments,
    neighbours along a rod excluded) with Coulomb coefficient ``rod_friction``; its penalty
    ``rod_contact_stiffness`` (N/m) and ``rod_contact_damping`` (N s/m) default to a stiff,
    critically damped contact chosen from the masses and ``dt``. Rods that touch each other
    advance together, one step at a time, on one thread.
    """

    def __init__(self, gravity: Sequence[float] = (0.0, 0.0, -9.81), dt: float = 1e-4,
                 integrator: str = "verlet", max_strain: float = 1.0,
                 threads: int | None = None, iterations: int = 4,
                 tolerance: float = 1e-4, rod_contact: bool = True, rod_friction: float = 0.2,
                 rod_contact_stiffness: float | None = None,
                 rod_contact_damping: float | None = None) -> None:
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
        if not isinstance(rod_contact, (bool, np.bool_)):
            raise ValueError(f"rod_contact must be True or False, got {rod_contact!r}")
        self.rod_contact = bool(rod_contact)
        self._rod_contact_params = np.array([
            -1.0 if rod_contact_stiffness is None else check.positive(
                "rod_contact_stiffness", rod_contact_stiffness, "N/m"),
            -1.0 if rod_contact_damping is None else check.non_negative(
                "rod_contact_damping", rod_contact_damping, "N s/m"),
            check.non_negative("rod_friction", rod_friction)])
        self._colliders: list[col.Collider] = []
        self._cols = None
        self._wrench = np.zeros((0, 0, 6))
        self._pairs = np.zeros((64, 2), dtype=np.int64)
        self._pair_state = np.zeros(4, dtype=np.int64)  # pairs, valid, builds, touching

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
        par = col.contact_params(stiffness, damping, friction, static_friction, kinetic_friction)
        self._planes.append(np.array([*p, *n, par[P_K], par[P_C], par[P_MUS], par[P_MUK],
                                      par[P_AUTO]]))
        self._planes_arr = np.array(self._planes)
        self._dirty = True
        return len(self._planes) - 1

    # ------------------------------------------------------------------ colliders
    def _add_collider(self, kind: str, pose: object, params: np.ndarray,
                      mesh: tuple[np.ndarray, np.ndarray] | None = None) -> col.Collider:
        c = col.Collider(self, len(self._colliders), kind, col.pose_matrix(pose), params, mesh)
        if mesh is not None:
            col.prepare_mesh(c)
        self._colliders.append(c)
        self._dirty = True
        return c

    def add_mesh(self, mesh: object, pose: object = None, stiffness: float | None = None,
                 damping: float | None = None, friction: float | None = None,
                 static_friction: float | None = None, kinetic_friction: float | None = None,
                 two_sided: bool | None = None,
                 repulsion_distance: float | None = None) -> col.Collider:
        """Add a triangle mesh collider; returns its handle (pose, velocity, reaction wrench).

        ``mesh``: a file path (OBJ/STL/PLY/GLB, loaded with trimesh), a ``trimesh.Trimesh`` or
        ``(vertices (V, 3) m, faces (F, 3))`` in the mesh's local frame. ``pose``: 4x4
        world-from-local matrix, ``(position, rotation)`` or a position (default identity).
        Contact parameters as for :meth:`add_plane`. A closed (watertight) mesh has an inside:
        a rod segment that ends up inside, less than ``repulsion_distance`` (m, default 10 %
        of the mesh's size) deep, is pushed out the nearest way; an open mesh (or
        ``two_sided=True``) pushes rods to whichever side they are on.
        """
        V, F, watertight = col.load_mesh(mesh)
        par = col.contact_params(stiffness, damping, friction, static_friction, kinetic_friction)
        size = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
        par = col.mesh_params(par, watertight, two_sided, repulsion_distance, size)
        return self._add_collider("mesh", pose, par, (V, F))

    def add_sphere(self, radius: float, center: Sequence[float] = (0.0, 0.0, 0.0),
                   **contact: float | None) -> col.Collider:
        """Add a sphere of ``radius`` (m) at ``center``; contact keywords as for add_plane."""
        par = col.contact_params(**_contact_keywords(contact))
        par = col.shape_params(par, [check.positive("radius", radius, "m")])
        return self._add_collider("sphere", check.vector3("center", center), par)

    def add_box(self, half_extents: Sequence[float], pose: object = None,
                **contact: float | None) -> col.Collider:
        """Add a box of ``half_extents`` (m, local x, y, z) at ``pose`` (see add_mesh)."""
        h = check.vector3("half_extents", half_extents)
        for i, v in enumerate(h):
            check.positive(f"half_extents[{i}]", v, "m")
        par = col.shape_params(col.contact_params(**_contact_keywords(contact)), list(h))
        return self._add_collider("box", pose, par)

    def add_capsule(self, radius: float, length: float, pose: object = None,
                    **contact: float | None) -> col.Collider:
        """Add a capsule: a segment of ``length`` (m) along local z with hemispherical caps of
        ``radius`` (m)."""
        par = col.shape_params(col.contact_params(**_contact_keywords(contact)), [
            check.positive("radius", radius, "m"),
            0.5 * check.non_negative("length", length, "m")])
        return self._add_collider("capsule", pose, par)

    def add_cylinder(self, radius: float, length: float, pose: object = None,
                     **contact: float | None) -> col.Collider:
        """Add a closed cylinder of ``radius`` and ``length`` (m) along local z."""
        par = col.shape_params(col.contact_params(**_contact_keywords(contact)), [
            check.positive("radius", radius, "m"), 0.5 * check.positive("length", length, "m")])
        return self._add_collider("cylinder", pose, par)

    @property
    def colliders(self) -> tuple[col.Collider, ...]:
        return tuple(self._colliders)

    def _collider_wrench(self, index: int) -> np.ndarray:
        if self._wrench.shape[1] <= index:
            return np.zeros(6)
        return self._wrench[:, index].sum(axis=0)

    def _prepare_contact(self) -> None:
        """Collider tables, per-element contact state and the rod-rod segment tables."""
        b = self._block
        E, N = b.Q.shape[0], b.pos.shape[0]
        # None without colliders: the kernels then compile without any mesh code.
        self._cols = (col.pack(self._colliders) + query_cache(N + E, len(self._rods))
                      if self._colliders else None)
        if getattr(self, "_col_anchor", None) is None or self._col_anchor.shape[0] != N + E:
            # Friction anchors of nodes, then elements (collider frame) and their colliders.
            self._col_anchor = np.zeros((N + E, 4))
            self._col_anchor_id = np.full(N + E, -1, dtype=np.int64)
            self._el_K = np.zeros((E, 3, 3, 3))
        self._col_pen = np.zeros((N, len(self._colliders)))
        self._wrench = np.zeros((len(self._rods), len(self._colliders), 6))
        seg_a = np.zeros(E, dtype=np.int64)
        seg_b = np.zeros(E, dtype=np.int64)
        seg_rod = np.full(E, -1, dtype=np.int64)
        seg_k = np.zeros(E, dtype=np.int64)
        seg_ne = np.zeros(E, dtype=np.int64)
        seg_closed = np.zeros(E, dtype=np.bool_)
        excluded = np.ones(E, dtype=np.int64)
        seg_radius = np.zeros(E)
        nodes = []
        for i, rod in enumerate(self._rods):
            n0, e0, ne = int(b.rod_node0[i]), int(b.rod_elem0[i]), rod.n_elements
            k = np.arange(ne)
            e = e0 + k
            seg_a[e] = n0 + k
            seg_b[e] = np.where(k + 1 < rod.n_nodes, n0 + k + 1, n0)
            seg_rod[e] = i
            seg_k[e] = k
            seg_ne[e] = ne
            seg_closed[e] = rod.closed
            radius = np.maximum(rod.node_radius[k], rod.node_radius[(k + 1) % rod.n_nodes])
            seg_radius[e] = radius
            # Pairs closer along the rod than a half turn of the tightest fold are left out:
            # they overlap in the straight rest shape when the radius exceeds the element.
            excluded[e] = 1 + int(math.floor(math.pi * radius.max() / rod.rest_lengths.min()))
            nodes.extend(range(n0, n0 + rod.n_nodes))
        self._segs = np.flatnonzero(seg_rod >= 0).astype(np.int64)
        self._nodes = np.array(nodes, dtype=np.int64)
        self._skin = 2.0 * float(seg_radius.max()) if E else 0.0
        self._ref = np.zeros((N, 3))
        self._xp = np.zeros((N, 3))
        self._vp = np.zeros((N, 3))
        self._extra = np.zeros((N, 3))
        self._pair_state[:] = 0
        self._seg_tables = (seg_a, seg_b, seg_rod, seg_k, seg_ne, seg_closed, excluded,
                            seg_radius)

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
        """Rebuild what the kernel needs after rods, clamps, colliders, dt or damping changed."""
        self._sync_constraints()
        self._prepare_contact()
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
            head = (
                b.rod_node0, b.rod_elem0, b.rod_vor0, b.rod_ne, b.rod_closed, decay, *common,
                b.Q, b.omega, b.J, b.inv_J, b.S, b.rest_len, b.rest_sigma, b.text, b.torque,
                b.dil, b.stress, b.B, b.rest_vor, b.rest_kappa, b.kappa, b.couple,
                b.scr_C, b.scr_X, b.scr_edot,
                self._pcon_node, self._pcon_data, self._fcon_elem, self._fcon_Q0, self._fcon_data,
                self._planes_arr)
            tail = self._contact_args()
        else:
            rates = np.array([r.damping for r in self._rods])
            retardation = np.array([r.internal_damping for r in self._rods])
            self._kernel = implicit.advance_rods_implicit
            head = (
                b.rod_node0, b.rod_elem0, b.rod_vor0, b.rod_ne, b.rod_closed, rates, retardation,
                *common,
                b.Q, b.omega, b.J, b.S, b.rest_len, b.rest_sigma, b.text, b.torque,
                b.dil, b.stress, b.B, b.rest_vor, b.rest_kappa, b.kappa, b.couple,
                b.scr_C, b.scr_X, b.scr_edot,
                self._pcon_node, self._pcon_data, self._fcon_elem, self._fcon_Q0, self._fcon_data,
                self._planes_arr)
            tail = (b.xn, b.vn, b.Qn, b.wn, b.fn_el, b.tn_el, b.anchor, b.anchor_on, b.c_plane,
                    b.c_stick, b.c_dir, b.stats, b.h_prev, b.rate, *self._contact_args())
        # The one-rod kernel's arguments after (r, n_steps, t, dt, gravity, max_strain[,
        # iterations, tolerance]) and before the rod-rod contact ones.
        self._rod_args = (*head, self._status, *tail)
        self._dirty = False

    def _contact_args(self) -> tuple:
        return (self._cols, self._col_anchor, self._col_anchor_id, self._col_pen, self._el_K,
                self._wrench)

    def _coupled(self) -> bool:
        """Rods step together (one step at a time) when they may touch each other or
        themselves."""
        return self.rod_contact and self._segs.shape[0] > 1

    def _advance(self, n_steps: int, args: tuple) -> None:
        """Run the kernel: rods in parallel groups, or all together with rod-rod contact."""
        b = self._block
        n_rods = len(self._rods)
        seg = self._seg_tables
        if self._coupled():
            last = self._extra if self.integrator == "verlet" else self._vp
            contact = (self._segs, *seg, self._nodes, self._pairs, self._pair_state, self._ref,
                       self._skin, self._rod_contact_params, last, self._xp)
            if self.integrator == "verlet":
                self._pairs = coupled.advance_world_verlet(
                    n_steps, self.time, self._dt, self.gravity, self.max_strain, n_rods,
                    self._rod_args, b.pos, b.vel, b.mass, b.node_kmin, self._status, self._times,
                    contact)
            else:
                self._pairs = coupled.advance_world_implicit(
                    n_steps, self.time, self._dt, self.gravity, self.max_strain,
                    self.iterations, self.tolerance, n_rods, self._rod_args, b.pos, b.vel,
                    self._status, self._times, contact)
            return
        if self.integrator == "verlet":
            extra = (self._extra, False)
        else:
            seg_a, seg_b, seg_rod, _, _, _, _, seg_radius = seg
            extra = (self._pairs, 0, seg_a, seg_b, seg_rod, seg_radius, self._xp, self._vp,
                     self._rod_contact_params)
        work = n_steps * int(b.rod_ne.sum())
        if len(self._groups) > 1 and work >= _MIN_THREADED_WORK:
            futures = [_pool(len(self._groups)).submit(self._kernel, r0, r1, *args, self._times,
                                                       self._rod_args, *extra)
                       for r0, r1 in self._groups]
            for f in futures:
                f.result()
        else:
            self._kernel(0, n_rods, *args, self._times, self._rod_args, *extra)

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
        for c in self._colliders:  # poses and velocities may have changed since the last step
            self._cols[1][c.index] = c._pose
            self._cols[2][c.index] = c._twist
        args = (n_steps, self.time, self._dt, self.gravity, self.max_strain)
        if self.integrator == "stable":
            args += (self.iterations, self.tolerance)
        self._advance(n_steps, args)
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
        """Contact forces (n_nodes, 3), N, on ``rod``'s nodes in the last step: planes,
        colliders and other rods (and itself)."""
        return self._block.contact_force[self._block.node_slice(rod._index, rod)].copy()

    def contact_stats(self) -> dict[str, int]:
        """Rod-rod contact: candidate pairs in the current Verlet list, pairs touching in the
        last explicit step, and how often the list was rebuilt."""
        st = self._pair_state
        return {"candidate_pairs": int(st[0]), "touching_pairs": int(st[3]),
                "pair_list_builds": int(st[2])}

    def __repr__(self) -> str:
        return (f"World(rods={len(self._rods)}, planes={len(self._planes)}, "
                f"colliders={len(self._colliders)}, dt={self._dt:g} s, "
                f"t={self.time:g} s, integrator={self.integrator!r})")


def _contact_keywords(contact: dict) -> dict:
    allowed = ("stiffness", "damping", "friction", "static_friction", "kinetic_friction")
    for key in contact:
        if key not in allowed:
            raise ValueError(f"unknown contact parameter {key!r}; valid: {', '.join(allowed)}")
    return {k: contact.get(k) for k in allowed}
