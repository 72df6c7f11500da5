"""World: the rods, the environment (gravity, planes, meshes, primitives), drivers, time and the
integrator. It builds the packed buffers (``model.py``, ``packing.py``), hands them to one entry
kernel per integrator (``kernels/step.py``) and keeps handles (rods, clamps, colliders) as
views with an index into them."""

from __future__ import annotations

import logging
import warnings
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from ..errors import SimulationDiverged
from . import assemble, running
from . import validation as check
from .contact import colliders as col
from .contact.segments import P_AUTO, P_C, P_K, P_MUK, P_MUS
from .contact.speculative import V_OUT
from .drivers import Driver, DriverTable
from .kernels import implicit, step, verlet
from .kernels.bundles import (OPT_FLAG, SIM_DT, SIM_G, SIM_LEN, SIM_MAX_STRAIN, SIM_RR, SIM_SKIN,
                              SIM_ORDER, SIM_T, SIM_TOL)
from .kernels.step import advance_drivers, compiled_entry
from .model import bind_rod, pack_rods, set_damping, write_damping, write_material
from .packing import Packed
from .rod import Rod
from .state import WorldState, put_rod, rod_slices, take_rod
from .threads import MIN_THREADED_WORK, balanced_groups, default_threads, pool

_log = logging.getLogger("deformx")

if TYPE_CHECKING:
    from .recorder import Recorder

INTEGRATORS = ("verlet", "stable")
_REASONS = {
    verlet.NOT_FINITE: "a position, frame or load became NaN/inf",
    verlet.RUNAWAY_STRETCH: "runaway stretch (element strain beyond max_strain)",
    verlet.RUNAWAY_BEND: "runaway bending/twist (neighbouring frames turned by > 170 degrees)",
    implicit.NOT_CONVERGED: "Newton's method did not converge even on dt/64 sub-steps",
}


class World:
    """A simulation: rods, gravity, contact planes, colliders, clamps; advances them together.

    ``gravity`` in m/s^2, ``dt`` in s. ``integrator="verlet"`` is PyElastica's position
    Verlet (explicit; needs dt below roughly ``min(dl, 2r) sqrt(rho/E) / 4``).
    ``max_strain`` is the element strain beyond which the run is declared diverged;
    ``threads`` (default: usable cores) advance groups of rods in parallel.

    ``integrator="stable"`` is backward Euler solved by Newton's method with a banded direct
    solve per rod: stable for any stiffness at large steps (1e-2 s for steel wire), with the
    numerical damping of backward Euler. ``order=2`` makes it BDF2 (second-order
    backward differentiation: same stability, far less numerical damping of slow motion, same
    cost per step; a step after a change of step size or a write to the state is backward
    Euler). ``iterations`` caps the Newton iterations per step
    and ``tolerance`` is the converged update size relative to the element length; see
    :meth:`solver_stats`.

    ``rod_contact`` turns on contact between rods and of a rod with itself (capsule segments,
    neighbours along a rod excluded) with Coulomb coefficient ``rod_friction``; its penalty
    ``rod_contact_stiffness`` (N/m) and ``rod_contact_damping`` (N s/m) default to a stiff,
    critically damped contact chosen from the masses and ``dt``. Rods that touch each other
    advance together, one step at a time, on one thread; rods of different
    ``Rod.contact_group`` never touch.

    Clamps and colliders are kinematic drivers (see :mod:`deformx.engine.drivers`): set their
    pose, velocity and acceleration between steps (or many at once with :meth:`set_drivers`)
    without rebuilding anything; they move on inside ``step(n)``.
    """

    def __init__(self, gravity: Sequence[float] = (0.0, 0.0, -9.81), dt: float = 1e-4,
                 integrator: str = "verlet", max_strain: float = 1.0,
                 threads: int | None = None, iterations: int = 4,
                 tolerance: float = 1e-4, rod_contact: bool = True, rod_friction: float = 0.2,
                 rod_contact_stiffness: float | None = None,
                 rod_contact_damping: float | None = None, order: int = 1) -> None:
        if integrator not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {INTEGRATORS}, got {integrator!r}")
        self.integrator = integrator
        self._sim = np.zeros(SIM_LEN)
        self._dt = check.positive("dt", dt, "s")
        self.gravity = gravity
        self.max_strain = max_strain
        self.iterations = iterations
        self.tolerance = tolerance
        self.order = order
        self.threads = default_threads() if threads is None else check.integer_at_least(
            "threads", threads, 1)
        self._stale_env = True
        self.time = 0.0
        self._rods: list[Rod] = []
        self._planes: list[np.ndarray] = []
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
        self._ignored: set[tuple[int, int]] = set()
        # Buffers (rebuilt when stale), the driver table and the rod-rod pair list.
        self._rods_p: Packed | None = None
        self._env: Packed | None = None
        self._cols_p: Packed | None = None
        self._stale_rods = True
        self._stale_env = True
        self._drivers = DriverTable()
        self._pairs = np.zeros((64, 2), dtype=np.int64)
        self._args: tuple | None = None  # the kernel's arguments but the last two, one group
        self._deep_warned: set[tuple[int, int]] = set()  # (stats column, rod)

    # ------------------------------------------------------------------ building
    @property
    def dt(self) -> float:
        """Time step (s)."""
        return self._dt

    @dt.setter
    def dt(self, value: float) -> None:
        self._dt = check.positive("dt", value, "s")
        self._stale_env = True

    @property
    def gravity(self) -> np.ndarray:
        """Gravity (m/s^2, world frame); may be changed between steps."""
        return self._sim[SIM_G:SIM_G + 3].copy()

    @gravity.setter
    def gravity(self, value: Sequence[float]) -> None:
        self._sim[SIM_G:SIM_G + 3] = check.vector3("gravity", value)

    @property
    def max_strain(self) -> float:
        """Element strain beyond which a run is declared diverged."""
        return float(self._sim[SIM_MAX_STRAIN])

    @max_strain.setter
    def max_strain(self, value: float) -> None:
        self._sim[SIM_MAX_STRAIN] = check.positive("max_strain", value)

    @property
    def tolerance(self) -> float:
        """Newton tolerance of the stable integrator (update size / element length)."""
        return float(self._sim[SIM_TOL])

    @tolerance.setter
    def tolerance(self, value: float) -> None:
        self._sim[SIM_TOL] = check.positive("tolerance", value)

    @property
    def order(self) -> int:
        """Order of the stable integrator: 1 (backward Euler) or 2 (BDF2); may be changed
        between steps."""
        return int(self._sim[SIM_ORDER])

    @order.setter
    def order(self, value: int) -> None:
        if isinstance(value, bool) or value not in (1, 2):
            raise ValueError(f"order must be 1 (backward Euler) or 2 (BDF2), got {value!r}")
        if value == 2 and self.integrator != "stable":
            raise ValueError("order=2 (BDF2) needs integrator='stable'")
        self._sim[SIM_ORDER] = float(value)

    @property
    def iterations(self) -> int:
        """Newton iterations per step of the stable integrator (at most)."""
        return self._iterations

    @iterations.setter
    def iterations(self, value: int) -> None:
        self._iterations = check.integer_at_least("iterations", value, 1)
        self._stale_env = True

    @property
    def rods(self) -> tuple[Rod, ...]:
        return tuple(self._rods)

    def add_rod(self, rod: Rod) -> Rod:
        """Add ``rod`` (its arrays become views into the world's packed state); returns it."""
        if not isinstance(rod, Rod):
            raise ValueError(f"rod must be a deformx.Rod, got {type(rod).__name__}")
        if rod._world is not None:
            raise ValueError("rod already belongs to a world")
        short = rod.rest_lengths < 0.1 * np.maximum(rod.node_radius[:-1], rod.node_radius[1:]) \
            if not rod.closed else rod.rest_lengths < 0.1 * rod.node_radius
        if short.any():
            k = int(np.argmax(short))
            warnings.warn(f"rod: element {k} is {rod.rest_lengths[k]:.3g} m long, less than a "
                          f"tenth of the rod's radius: contact and bending are not meaningful "
                          f"there (use fewer elements)", stacklevel=2)
        rod._world = self
        rod._index = len(self._rods)
        self._rods.append(rod)
        for c in rod._clamps:
            self._drivers.add(c)
        # Pack now so the rod's arrays are views from here on (as documented).
        self._rods_p = pack_rods(self._rods, self._dt, self.integrator == "stable")
        self._stale_rods = False
        self._stale_env = True
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
        self._stale_env = True
        return len(self._planes) - 1

    @property
    def planes(self) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
        """The contact planes as (point, unit normal) pairs (m)."""
        return tuple((p[:3].copy(), p[3:6].copy()) for p in self._planes)

    # ------------------------------------------------------------------ colliders
    def _add_collider(self, kind: str, pose: object, params: np.ndarray,
                      mesh: tuple[np.ndarray, np.ndarray] | None = None) -> col.Collider:
        c = col.Collider(len(self._colliders), kind, col.pose_matrix(pose), params, mesh)
        if mesh is not None:
            col.prepare_mesh(c)
        self._colliders.append(c)
        self._drivers.add(c)
        self._stale_env = True
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

    def _ignore(self, rod: Rod, colliders: Sequence[col.Collider], ignore: bool = True) -> None:
        for c in colliders:
            if not isinstance(c, col.Collider) or c._table is not self._drivers:
                raise ValueError(f"ignore: {c!r} is not a collider of this world")
            if ignore:
                self._ignored.add((rod._index, c.index))
            else:
                self._ignored.discard((rod._index, c.index))
        self._stale_env = True

    # ------------------------------------------------------------------ drivers
    def _register_clamp(self, clamp) -> None:
        self._drivers.add(clamp)
        self._stale_env = True

    def _release_clamp(self, clamp) -> None:
        self._drivers.release(clamp)
        self._stale_env = True

    def set_drivers(self, drivers: Sequence[Driver], position: np.ndarray | None = None,
                    rotation: np.ndarray | None = None, velocity: np.ndarray | None = None,
                    angular_velocity: np.ndarray | None = None,
                    acceleration: np.ndarray | None = None,
                    angular_acceleration: np.ndarray | None = None,
                    validate: bool = True) -> None:
        """Set many drivers at once (array form of their setters): each given array has one
        row per driver, (n, 3) or (n, 3, 3) for ``rotation`` (world from local), world frame.
        ``validate=False`` skips the shape, finiteness and rotation checks (values from
        another simulator's state, set every control step)."""
        self._drivers.set_many(drivers, validate=validate, position=position, rotation=rotation,
                               velocity=velocity, angular_velocity=angular_velocity,
                               acceleration=acceleration,
                               angular_acceleration=angular_acceleration)

    @property
    def driver_table(self) -> DriverTable:
        """Every driver of the world as one table (rows ``D_*`` columns of
        ``kernels/bundles.py``; ``index(handles)``, ``impulses(index)``,
        ``reset_impulses(index)``): the array form a co-simulation writes once per step."""
        return self._drivers

    def driver_impulses(self, drivers: Sequence[Driver]) -> np.ndarray:
        """Impulses (n, 6) of many drivers since their last reset (see ``Driver.impulse``)."""
        return self._drivers.impulses(self._drivers.index(drivers))

    def reset_driver_impulses(self, drivers: Sequence[Driver]) -> None:
        """``reset_impulse()`` of many drivers at once."""
        self._drivers.reset_impulses(self._drivers.index(drivers))

    # ------------------------------------------------------------------ preparing
    def _rod_parameters_changed(self, rod: Rod) -> None:
        """A rod's damping or contact group changed: rewrite its entries in place (O(1): a
        batch of environments redraws one rope's damping at each of its resets)."""
        if self._rods_p is not None and not self._stale_rods:
            self._check_damping([rod])
            write_damping(self._rods_p, rod, rod._index, self._dt)
            self._rods_p["group"][rod._index] = rod.contact_group
            self._forget_factors(rod._index)

    def _rod_material_changed(self, rod: Rod) -> None:
        """A rod's masses, inertia or stiffness changed: rewrite its slices in place."""
        if self._rods_p is not None and not self._stale_rods:
            write_material(self._rods_p, rod, rod._index)
            self._forget_factors(rod._index)

    def _check_damping(self, rods: Sequence[Rod] | None = None) -> None:
        if self.integrator == "verlet":
            viscous = [r for r in (self._rods if rods is None else rods)
                       if r.internal_damping > 0.0]
            if viscous:
                raise ValueError(f"internal_damping: rod {viscous[0]._index} sets it, but it "
                                 "needs integrator='stable' (explicit steps cannot afford it)")

    def _prepare(self) -> None:
        """Rebuild the buffers after rods, clamps, planes, colliders or dt changed."""
        if self._stale_rods:
            self._rods_p = pack_rods(self._rods, self._dt, self.integrator == "stable")
            self._stale_rods = False
        self._check_damping()
        set_damping(self._rods_p, self._rods, self._dt)
        rp = self._rods_p
        self._env = assemble.env_group(self._rods, rp, self._planes, self._drivers.rows.shape[0])
        self._drivers.rebind(self._env)  # impulses accumulated so far survive the rebuild
        # Stable kernels always get collider tables (empty without colliders): one compiled
        # variant instead of two, ~60 s less to compile; explicit ones get None without
        # colliders, which prunes the collider code from plain worlds' per-step loop.
        self._cols_p = assemble.cols_group(self._colliders, self._ignored, rp, self._cols_p,
                                           empty=self.integrator == "stable")
        self._sim[SIM_DT] = self._dt
        self._sim[SIM_RR:SIM_RR + 3] = self._rod_contact_params
        self._sim[SIM_SKIN] = 2.0 * float(rp["seg_radius"].max()) if rp["Q"].shape[0] else 0.0
        self._groups = ([(0, len(self._rods))] if self.rods_coupled
                        else balanced_groups(rp["ne"], self.threads))
        self._opts = assemble.run_options(self._groups, self.iterations)
        self._bind_kernel()
        self._stale_env = False
        self._forget_factors()

    def _forget_factors(self, index: int | None = None) -> None:
        """The stable integrator starts calm steps from the Newton factor an earlier step left
        (see kernels/implicit.py): after a change from outside the step (parameters, state,
        clamps), that rod's (``index``; all by default) must be made afresh."""
        if self._rods_p is not None:
            fact = self._rods_p["fact_h"]
            fact[slice(None) if index is None else index] = 0.0

    def _bind_kernel(self) -> None:
        """The kernel for this world and the tuple of buffers it is called with."""
        rp, cp = self._rods_p, self._cols_p
        self._bufs = (rp.F, rp.I, self._env.F, self._env.I, None if cp is None else cp.F,
                      None if cp is None else cp.I)
        self._kernel = step.KERNELS[self.integrator, self.rods_coupled]
        self._call = self._first_call
        self._dispatched = 0
        self._args = (self._sim, self._opts[0], *self._bufs) if len(self._groups) == 1 else None

    # A copy or pickle (RL branching, multiprocessing) holds the buffers and handles; the
    # compiled entry point is looked up again, and the rods' arrays become views again.
    _UNPICKLED = ("_call", "_args", "_kernel", "_bufs", "_dispatched")

    def __getstate__(self) -> dict:
        return {k: v for k, v in self.__dict__.items() if k not in self._UNPICKLED}

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._args = None
        if self._rods_p is not None:
            for i, rod in enumerate(self._rods):
                bind_rod(self._rods_p, rod, i)
        if not (self._stale_env or self._stale_rods):
            self._bind_kernel()

    # ------------------------------------------------------------------ stepping
    @property
    def time(self) -> float:
        """Simulated time (s)."""
        return float(self._sim[SIM_T])  # where the kernels read it and leave the new time

    @time.setter
    def time(self, value: float) -> None:
        self._sim[SIM_T] = float(value)

    def step(self, n_steps: int = 1, on_diverged: str = "raise") -> np.ndarray | None:
        """Advance ``n_steps`` time steps (one kernel call for all rods and steps).

        A rod that diverges raises :class:`SimulationDiverged` (``on_diverged="raise"``). In a
        world whose rods never touch each other (see :attr:`rods_coupled`), ``"report"``
        finishes the step for every other rod instead and returns the indices of the rods
        that diverged (an empty array when none did): they are left where they failed, their
        loads on their drivers (reactions, impulses) zeroed, to be restored with
        ``rod.set_state`` before the next step (a batch of environments resets that one).
        Worlds whose rods touch raise either way.
        """
        if on_diverged != "raise":
            return self._step_reporting(n_steps, on_diverged)
        if type(n_steps) is not int or n_steps < 1:
            n_steps = check.integer_at_least("n_steps", n_steps, 0)
            if n_steps == 0:
                return None
        if self._stale_env or self._stale_rods:
            if not self._rods:
                advance_drivers(self._drivers.rows, n_steps, self._dt)
                self.time += n_steps * self._dt
                return
            self._prepare()
        if self._args is not None:  # one group of rods: the kernel, called directly
            out = self._call(n_steps, *self._args, self._drivers.rows, self._pairs)
            if out is None:  # no divergence, no deep start, the pair list did not grow
                return None
            self._pairs = out
            flag = int(self._opts[0][OPT_FLAG])
        else:
            flag = self._advance_threaded(n_steps)
        if flag >= 0:
            self._raise_diverged(flag)
        if flag == -2:
            self._warn_deep()
        return None

    @property
    def rods_coupled(self) -> bool:
        """Whether rods may touch each other (rod contact on and more than one segment):
        such rods advance together, and a divergence stops them all."""
        return self.rod_contact and self._rods_p is not None and self._rods_p["segs"].shape[0] > 1

    def _step_reporting(self, n_steps: int, on_diverged: str) -> np.ndarray:
        if on_diverged != "report":
            raise ValueError(f"on_diverged must be 'raise' or 'report', got {on_diverged!r}")
        start = self.time
        try:
            self.step(n_steps)
            return _NO_RODS
        except SimulationDiverged:
            status = self._rods_p["status"]
            failed = np.flatnonzero(status[:, 0] != verlet.OK)
            firsts = {g[0] for g in self._groups}
            if self.rods_coupled or (self._colliders and firsts.intersection(failed.tolist())):
                # Rods stepped together, or the colliders' motion came from a failed rod's copy.
                raise
        ok = np.flatnonzero(status[:, 0] == verlet.OK)
        # Every rod failed (a batch of one): the time the step would have reached.
        self.time = (float(self._rods_p["times"][ok[0]]) if ok.size
                     else start + n_steps * self._dt)
        env = self._env
        env["dreact"][failed] = 0.0
        env["dimp"][failed] = 0.0
        self._warn_deep()
        return failed

    def _first_call(self, n_steps: int, *args: Any) -> tuple:
        """The kernel through numba's dispatcher (compiling or loading it); from the third
        call on its compiled entry point for these argument types (~1 us less per step(), in
        a control loop), which costs ~0.2 ms to look up: a world stepped once by run() skips
        that."""
        out = self._kernel(n_steps, *args)
        self._dispatched += 1
        if self._dispatched >= 3:
            self._call = compiled_entry(self._kernel, (n_steps, *args))
        return out

    def _warn_deep(self) -> None:
        """One warning per rod found deeper inside a collider or plane, and one per rod
        found deeper inside another rod, than a step resolves (it is pushed out at no more
        than 0.1 m/s; see contact/speculative.py)."""
        for column, what in ((5, "a collider or plane"), (9, "another rod or itself")):
            deep = self._rods_p["stats"][:, column]
            for r in np.flatnonzero(deep > 0.0):
                if (column, int(r)) not in self._deep_warned:
                    self._deep_warned.add((column, int(r)))
                    _log.warning("rod %d is %.3g m inside %s at t = %.4g s (more than a step "
                                 "resolves): pushing it out at <= %g m/s", r, deep[r], what,
                                 self.time, V_OUT)
            deep[:] = 0.0

    def _advance_threaded(self, n_steps: int) -> int:
        """Groups of rods on threads (each with its own copy of the drivers); returns the
        kernels' flag (see :mod:`.kernels.step`) and leaves the new time unless a rod failed."""
        work = n_steps * int(self._rods_p["ne"].sum())
        args = (*self._bufs, self._drivers.rows, self._pairs)
        if work >= MIN_THREADED_WORK[self.integrator]:
            futures = [pool(len(self._groups)).submit(self._kernel, n_steps, self._sim, opts,
                                                      *args)
                       for opts in self._opts]
            for f in futures:
                f.result()
        else:
            for opts in self._opts:
                self._kernel(n_steps, self._sim, opts, *args)
        step.collect_drivers(*self._bufs[2:], self._drivers.rows, len(self._rods))
        status = self._rods_p["status"]
        flags = [int(opts[OPT_FLAG]) for opts in self._opts]
        failed = [f for f in flags if f >= 0]
        if failed:
            return min(failed, key=lambda r: status[r, 2])
        self.time = float(self._rods_p["times"][self._groups[0][0]])
        return -2 if -2 in flags else -1

    def _raise_diverged(self, r: int) -> None:
        status = self._rods_p["status"]
        code, k, steps = (int(x) for x in status[r])
        # Report the rod that failed first; the world's state is not usable afterwards.
        self.time = float(self.time + (steps + 0.5) * self._dt)
        # The explicit limit means nothing to the stable integrator, which has already tried
        # dt/64 sub-steps: suggest a smaller step of the same kind.
        suggested = 0.25 * self._dt
        if self.integrator == "verlet":
            limit = min(rod.stable_dt() for rod in self._rods)
            suggested = limit if limit < self._dt else suggested
        raise SimulationDiverged(rod=r, element=k, time=self.time, suggested_dt=suggested,
                                 reason=_REASONS.get(code, "unknown"), dt=self._dt)

    def run(self, duration: float, progress: bool = False,
            recorder: "Recorder | None" = None, callbacks: Sequence[Any] = ()) -> None:
        """Advance by ``duration`` s (rounded to whole steps).

        ``callbacks``: callables with an ``every`` attribute (s), called with the world at the
        start and every ``every`` s of simulated time (a :class:`~deformx.Recorder` is one, and
        so is ``recorder``). ``progress=True`` shows a progress bar (useful for long runs).
        """
        running.run(self, duration, progress=progress, recorder=recorder, callbacks=callbacks)

    @property
    def arrays(self) -> dict[str, np.ndarray]:
        """Named views of every packed array (rods, then environment and colliders; a
        collider field clashing with a rod field is prefixed ``cols_``): for diagnostics and
        tests. Writing into them changes the simulation."""
        self._ready()
        out = dict(self._rods_p.fields)
        for packed in (self._env, self._cols_p):
            if packed is not None:
                for k, v in packed.fields.items():
                    out[k if k not in out else f"cols_{k}"] = v
        out["pairs"] = self._pairs
        out["drivers"] = self._drivers.rows
        return out

    # ------------------------------------------------------------------ state
    def _ready(self) -> None:
        if not self._rods:
            raise ValueError("the world has no rods yet")
        if self._stale_env or self._stale_rods:
            self._prepare()

    def get_state(self) -> WorldState:
        """A copy of everything the next step depends on: time, the rods' state and solver
        memory, friction anchors and contact sets, mesh query caches, rod-rod pairs and the
        drivers (numpy arrays; picklable). :meth:`set_state` restores it bit for bit."""
        self._ready()
        cp = self._cols_p
        return WorldState(time=self.time, rods=self._rods_p.state(),
                          cols=None if cp is None else cp.state(), drivers=self._drivers.rows.copy(),
                          pairs=self._pairs.copy())

    def set_state(self, state: WorldState) -> None:
        """Restore a :meth:`get_state` snapshot of this world (same rods, clamps, colliders)."""
        if not isinstance(state, WorldState):
            raise ValueError(f"state must be a WorldState from get_state(), got {type(state).__name__}")
        self._ready()
        if state.drivers.shape != self._drivers.rows.shape or (state.cols is None) != (self._cols_p is None):
            raise ValueError("state: it was taken from a world with other drivers or colliders")
        self._rods_p.set_state(state.rods)
        if self._cols_p is not None:
            self._cols_p.set_state(state.cols)
        self._drivers.rows[:] = state.drivers
        # The compiled kernel is called without numba's type checks: exact dtype and layout.
        self._pairs = np.array(state.pairs, dtype=np.int64, order="C", ndmin=2)
        self.time = float(state.time)
        self._rods_p["status"][:, 0] = 0  # a diverged world is usable again once restored
        self._forget_factors()

    def _rod_state(self, rod: Rod) -> dict:
        self._ready()
        sl = rod_slices(self._rods_p, rod._index, rod)
        out = {"rods": take_rod(self._rods_p, sl),
               "drivers": {c.node: c._row.copy() for c in rod._clamps}}
        if self._cols_p is not None:
            out["cols"] = take_rod(self._cols_p, sl)
        return out

    def _set_rod_state(self, rod: Rod, state: dict) -> None:
        self._ready()
        sl = rod_slices(self._rods_p, rod._index, rod)
        try:
            put_rod(self._rods_p, sl, state["rods"])
            if self._cols_p is not None and "cols" in state:
                put_rod(self._cols_p, sl, state["cols"])
        except (KeyError, ValueError, TypeError) as err:
            raise ValueError(f"state: not a get_state() of this rod ({err})") from None
        for c in rod._clamps:
            if c.node in state.get("drivers", {}):
                c._row[:] = state["drivers"][c.node]
        self._rods_p["status"][rod._index, 0] = 0  # usable again after a divergence
        self._rods_p["pair_state"][1] = 0  # positions jumped: rebuild the rod-rod pair list
        self._forget_factors(rod._index)

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
        update (update size / element length, compare with ``tolerance``), how often a
        step had to be halved because Newton did not converge (``halvings``) and how often a
        second-order step that did not converge was retried whole by backward Euler
        (``first_order_retries``; ``order=2`` only), and how many rod steps started from the
        Newton factor of an earlier step (``reused_factors``: calm steps, see
        docs/integrators.md), and how many steps that did not converge were retried without
        the solver's shortcuts before any halving (``careful_retries``, docs/contact.md)."""
        if self.integrator != "stable" or self._rods_p is None:
            return {"steps": 0, "mean_iterations": 0.0, "capped_steps": 0, "last_update": 0.0,
                    "halvings": 0, "first_order_retries": 0, "reused_factors": 0,
                    "careful_retries": 0}
        st = self._rods_p["stats"]
        return {"steps": int(st[:, 0].max()),
                "mean_iterations": float(st[:, 1].sum() / max(st[:, 0].sum(), 1)),
                "capped_steps": int(st[:, 2].sum()),
                "last_update": float(st[:, 3].max()),
                "halvings": int(st[:, 4].sum()),
                "first_order_retries": int(st[:, 6].sum()),
                "reused_factors": int(st[:, 7].sum()),
                "careful_retries": int(st[:, 8].sum())}

    def contact_forces(self, rod: Rod) -> np.ndarray:
        """Contact forces (n_nodes, 3), N, on ``rod``'s nodes in the last step: planes,
        colliders and other rods (and itself)."""
        n0 = int(self._rods_p["node0"][rod._index])
        return self._rods_p["contact_force"][n0:n0 + rod.n_nodes].copy()

    def contact_stats(self) -> dict[str, int]:
        """Rod-rod contact: candidate pairs in the current Verlet list, pairs touching in the
        last explicit step, and how often the list was rebuilt."""
        if self._rods_p is None:
            return {"candidate_pairs": 0, "touching_pairs": 0, "pair_list_builds": 0}
        st = self._rods_p["pair_state"]
        return {"candidate_pairs": int(st[0]), "touching_pairs": int(st[3]),
                "pair_list_builds": int(st[2])}

    def __repr__(self) -> str:
        return (f"World(rods={len(self._rods)}, planes={len(self._planes)}, "
                f"colliders={len(self._colliders)}, dt={self._dt:g} s, "
                f"t={self.time:g} s, integrator={self.integrator!r})")


_NO_RODS = np.zeros(0, dtype=np.int64)
_NO_RODS.flags.writeable = False


def _contact_keywords(contact: dict) -> dict:
    allowed = ("stiffness", "damping", "friction", "static_friction", "kinetic_friction")
    for key in contact:
        if key not in allowed:
            raise ValueError(f"unknown contact parameter {key!r}; valid: {', '.join(allowed)}")
    return {k: contact.get(k) for k in allowed}
