"""Co-simulation of rods with a rigid-body simulator: the paper's Algorithm 1, two-way.

Per macro step (the backend's ``dt``): read every coupled body's frame motion (pose, twist,
acceleration); hand it to the engine's kinematic drivers (attachment clamps and the body's
colliders), which extrapolate it inside the rod substeps by semi-implicit Euler on SE(3)
(equations 1-2); advance the rods; take each driver's impulse over the macro step, move its
torque to the body's centre of mass and apply the mean wrench (impulse / dt) to the body for
the backend's step; step the backend. The rods own every wire contact; the backend owns the
bodies and their own contacts.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from time import perf_counter
from typing import Any, Sequence

import numpy as np

from ..engine import validation as check
from ..engine.constraints import Clamp
from ..engine.contact.colliders import Collider
from ..engine.rod import Rod
from ..engine.running import callback_periods, progress_bar
from ..engine.world import World
from .backend import Backend, BodyMotion, Geom
from .kernels import (CONTINUOUS_POSITION, CONTINUOUS_STEPS, M_A, M_AL, M_COLS, M_COM, M_P,
                      M_R, M_V, M_W, drive_rows, wrenches_from_impulses)


@dataclass
class Attachment:
    """A rod node (and frame) held by a body.

    ``coupling`` "kinematic": ``clamp`` holds the node (and frame) where the body's predicted
    motion puts it and the clamp's reaction goes back to the body. "inertial": the body's
    ``mass`` rides on the node inside the rod's solve (the node is free; ``clamp``, if any,
    holds the frame only) and the body is given the wrench that makes it follow the node.
    """

    rod: Rod
    node: int
    body: str
    clamp: Clamp | None
    offset: np.ndarray
    coupling: str = "kinematic"
    mass: float = 0.0
    _force: np.ndarray = field(default_factory=lambda: np.zeros(3))  # added to fext (N)
    _v0: np.ndarray = field(default_factory=lambda: np.zeros(3))     # node velocity at start
    _a0: np.ndarray = field(default_factory=lambda: np.zeros(3))     # body point's free acc.
    _r: np.ndarray = field(default_factory=lambda: np.zeros(3))      # node from body origin
    _p0: np.ndarray = field(default_factory=lambda: np.zeros(3))     # body point at start
    _slack: float = 0.0  # m: node-body drift that puts the node back on the body


@dataclass
class BodyColliders:
    """The colliders standing for one body's geoms."""

    body: str
    static: bool
    colliders: list[Collider] = field(default_factory=list)
    geoms: list[Geom] = field(default_factory=list)
    planes: list[int] = field(default_factory=list)  # indices of the world's planes


def continuous_by_default(substeps: int) -> bool:
    """Whether ``CoSimulation(continuous_drivers=None)`` carries its drivers on continuously:
    with several rod substeps per macro step (see :class:`CoSimulation`)."""
    return substeps > 1


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b over the last axis (numpy's cross costs ~30 us a call on small arrays)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a1 * b2 - a2 * b1
    out[..., 1] = a2 * b0 - a0 * b2
    out[..., 2] = a0 * b1 - a1 * b0
    return out


def point_motion(m: BodyMotion, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Velocity and acceleration of the body-fixed point at world offset ``r`` from the
    frame's origin (rigid-body kinematics)."""
    w = m.angular_velocity
    v = m.velocity + _cross(w, r)
    a = m.acceleration + _cross(m.angular_acceleration, r) + _cross(w, _cross(w, r))
    return v, a


class CoSimulation:
    """Rods in ``world`` coupled two-way with the bodies of ``backend``.

    ``substeps``: rod steps per macro step; None takes ``backend.dt / world.dt``, which must be
    a whole number (with ``integrator="stable"`` one substep at the backend's step is the
    normal case); given, it sets ``world.dt = backend.dt / substeps``.

    ``smooth_feedback``: apply to each body the mean of this and the last macro step's driver
    wrenches instead of this step's alone (the same impulse, half a step later). The exchange
    is staggered - the rods step with the body's predicted motion, the body with the rods'
    wrench - and rods resolved in several substeps answer a body's motion as a stiff spring:
    a UR5e holding the hit-target rope at 2 ms macro steps then rings at the macro step's
    Nyquist frequency, growing ~5 % a step (backward Euler at 2.5e-5 s, BDF2 at 1e-4 s), where
    the mean is exactly zero; with one backward-Euler step per macro step it rang at a quarter
    of the macro rate, growing ~2 % a step. With the mean the hanging rope's load settles to
    its weight's share in every case.

    ``continuous_drivers``: a driver whose extrapolation over the last macro step ended near
    its body's frame keeps its pose and makes up the miss over the coming macro steps
    (velocity + miss / (``kernels.CONTINUOUS_STEPS`` T)) instead of jumping to the frame
    (``kernels.drive_rows``). The miss (~a T^2 / 2, the substeps' extrapolation against the
    backend's own integration, and the body's answer to the last wrench) jumped in one substep
    kicks the held rod harder the finer its substeps: with the jumps, a whipped rope's d_min
    moved by 5-25 cm per halving of its step down to 3e-6 s; with continuous drivers it settles
    (docs/learning.md). ``None`` (default): on where the rods take several substeps per macro
    step, off with one (the miss then moves the held node within its only step, a nudge of
    tens of micrometres rather than a kick, and the tables of docs/learning.md were made so).
    """

    def __init__(self, world: World, backend: Backend, substeps: int | None = None,
                 smooth_feedback: bool = True,
                 continuous_drivers: bool | None = None) -> None:
        if not isinstance(world, World):
            raise ValueError(f"world must be a deformx.World, got {type(world).__name__}")
        self.world = world
        self.backend = backend
        T = float(backend.dt)
        if substeps is None:
            ratio = T / world.dt
            n = int(round(ratio))
            if n < 1 or abs(ratio - n) > 1e-9 * ratio:
                raise ValueError(f"substeps: the backend's dt ({T:g} s) is not a whole number "
                                 f"of world.dt ({world.dt:g} s); give substeps or set world.dt "
                                 f"to {T:g} / n")
        else:
            if not isinstance(substeps, (int, np.integer)) or substeps < 1:
                raise ValueError(f"substeps must be an integer >= 1, got {substeps!r}")
            n = int(substeps)
            world.dt = T / n
        self.substeps = n
        self.smooth_feedback = bool(smooth_feedback)
        self.continuous_drivers = (continuous_by_default(n) if continuous_drivers is None
                                   else bool(continuous_drivers))
        # the drivers' wrench of the last macro step, per body of _coupled (smooth_feedback)
        self.held_wrenches: np.ndarray | None = None
        self.attachments: list[Attachment] = []
        self.bodies: dict[str, BodyColliders] = {}
        self._wrenches = np.zeros((0, 6))  # last step's, one row per body of _coupled
        self._coupled: list[str] = []  # moving bodies with attachments or colliders
        self._index: dict[str, int] = {}
        self._drivers: list = []
        self._ignores: dict = {}  # (rod, collider) pairs this co-simulation made ignore
        self._inertial: list[str] = []  # bodies riding on rod nodes
        self._steps = 0
        self.profile = False  # when True, step() adds its phases' seconds to `timings`
        self.reset_timings()

    # ------------------------------------------------------------------ building
    @property
    def time(self) -> float:
        """Simulated time (s) of the backend (the rods' time equals it after each step)."""
        return self.backend.time

    @property
    def dt(self) -> float:
        """The macro step (s): the backend's step."""
        return float(self.backend.dt)

    def _check_body(self, body: str) -> str:
        if not isinstance(body, str) or not self.backend.has_body(body):
            # the backend's own error names the bodies it has
            getattr(self.backend, "body_id", lambda b: None)(body)
            raise ValueError(f"body: no body named {body!r} in the backend")
        return body

    def _static(self, body: str) -> bool:
        is_static = getattr(self.backend, "is_static", None)
        return bool(is_static(body)) if is_static is not None else body == "world"

    def _refresh_coupled(self) -> None:
        names = {a.body for a in self.attachments}
        names |= {b for b, bc in self.bodies.items() if not bc.static}
        coupled = sorted(n for n in names if not self._static(n))
        for gone in set(self._coupled) - set(coupled):  # its last wrench must not stay applied
            self.backend.apply_wrench(gone, np.zeros(3), np.zeros(3))
        self._coupled = coupled
        self._wrenches = np.zeros((len(coupled), 6))
        self.held_wrenches = None
        self._index = {name: k for k, name in enumerate(self._coupled)}
        self._inertial = sorted({a.body for a in self.attachments if a.coupling == "inertial"})
        self._kinematic_drivers()
        self._update_ignores()

    def _update_ignores(self) -> None:
        """A held rod ignores the colliders of the body holding it and of the bodies welded
        to that body (a gripper's fingers, the stick whose tip holds the rope)."""
        want = {}
        for a in self.attachments:
            welded = getattr(self.backend, "welded", None)
            group = [a.body] if welded is None or self._static(a.body) else welded(a.body)
            for b in group:
                for c in self.bodies.get(b, BodyColliders(b, True)).colliders:
                    want[(id(a.rod), id(c))] = (a.rod, c)
        for key, (rod, c) in self._ignores.items():
            if key not in want:
                rod.unignore(c)
        for key, (rod, c) in want.items():
            if key not in self._ignores:
                rod.ignore(c)
        self._ignores = want

    def attach(self, rod: Rod, end: str | int = "start", body: str = "world",
               offset: Sequence[float] = (0.0, 0.0, 0.0), frame: bool = True,
               coupling: str = "auto") -> Attachment:
        """Hold ``rod``'s ``end`` ("start", "end" or a node index) with ``body``.

        The node sits at ``offset`` (m, body frame) from the body's origin - the rod's node
        must already be there (within half an element) - and with ``frame`` the element's
        material frame keeps the rotation relative to the body that it has now. The rod's
        reaction goes back to the body; the rod ignores contact with that body's colliders.

        ``coupling``: "kinematic" (the body's predicted motion drives the node; the rod's
        reaction is applied to the body after the rods' step: right for robots and heavy or
        jointed bodies), "inertial" (the body's mass rides on the node inside the rod's
        solve and the body follows the node: stable for a light free body on a stiff wire,
        where the explicit feedback of "kinematic" diverges), or "auto" ("inertial" for a free
        body with no children, else "kinematic"). See ``docs/cosim.md``.
        """
        if not isinstance(rod, Rod) or rod._world is not self.world:
            raise ValueError("rod must be a rod of this co-simulation's world")
        if end == "start":
            node = 0
        elif end == "end":
            node = rod.n_nodes - 1
        elif isinstance(end, (int, np.integer)) and -rod.n_nodes <= end < rod.n_nodes:
            node = int(end) % rod.n_nodes
        else:
            raise ValueError(f"end must be 'start', 'end' or a node index in "
                             f"[{-rod.n_nodes}, {rod.n_nodes - 1}], got {end!r}")
        self._check_body(body)
        self.backend.begin()
        m = self.backend.motion(body)
        off = np.array(check.vector3("offset", offset), dtype=np.float64)
        target = m.position + m.rotation @ off
        gap = float(np.linalg.norm(rod.positions[node] - target))
        if gap > 0.5 * float(rod.rest_lengths.min()):
            raise ValueError(f"attach: node {node} of the rod is {gap:.4g} m from the attachment "
                             f"point {np.round(target, 5).tolist()} (body {body!r} + offset); "
                             "build the rod with that node there")
        if coupling not in ("auto", "kinematic", "inertial"):
            raise ValueError(f"coupling must be 'auto', 'kinematic' or 'inertial', got "
                             f"{coupling!r}")
        free = getattr(self.backend, "free_mass", lambda b: None)(body)
        if coupling == "inertial" and free is None:
            raise ValueError(f"coupling='inertial' needs a free body (one free joint, no child "
                             f"bodies); {body!r} is not one: use 'kinematic'")
        if coupling == "auto":
            coupling = "inertial" if free is not None else "kinematic"
        if self._static(body):
            coupling = "kinematic"
        if any(a.rod is rod and a.node == node for a in self.attachments):
            raise ValueError(f"attach: node {node} of this rod is attached already")
        rod.positions[node] = target
        clamp = None
        if coupling == "kinematic" or frame:
            clamp = rod.hold(node, frame=frame, position=coupling == "kinematic")
            clamp.rebase(m.position, m.rotation)
        att = Attachment(rod=rod, node=node, body=body, clamp=clamp, offset=off,
                         coupling=coupling, mass=0.0 if free is None else free)
        if coupling == "inertial":
            att._slack = 0.25 * float(rod.rest_lengths.min())
            rod.set_point_mass(node, att.mass)
            rod.velocities[node] = point_motion(m, m.rotation @ off)[0]
        self.attachments.append(att)
        self._refresh_coupled()
        return att

    def detach(self, what: Rod | Attachment, end: str | int | None = None) -> None:
        """Release an attachment (or every attachment of a rod, or of its ``end``): the
        rod end is free from the next step on and touches that body's colliders again; a
        body that holds and touches no rod any more gets no wrench from the next step on."""
        if isinstance(what, Attachment):
            chosen = [what]
        else:
            chosen = [a for a in self.attachments if a.rod is what]
            if end is not None:
                node = {"start": 0, "end": what.n_nodes - 1}.get(end, end)
                chosen = [a for a in chosen if a.node == int(node) % what.n_nodes]
        if not chosen or any(a not in self.attachments for a in chosen):
            raise ValueError("detach: no such attachment")
        for a in chosen:
            self.attachments.remove(a)
            if a.clamp is not None:
                a.clamp.release()
            if a.coupling == "inertial":
                a.rod.set_point_mass(a.node, 0.0)
        self._refresh_coupled()

    def add_colliders(self, body: str, stiffness: float | None = None,
                      damping: float | None = None, friction: float | None = None
                      ) -> list[Collider]:
        """Every collision geom of ``body`` becomes a rod collider moving with it (a static
        body's once, fixed); the rods' contact reactions go back to the body. Contact
        ``stiffness`` / ``damping`` as for :meth:`deformx.World.add_mesh`; ``friction``
        defaults to each geom's own. Rods attached to the body ignore them."""
        self._check_body(body)
        if body in self.bodies:
            raise ValueError(f"add_colliders: body {body!r} already has its colliders")
        static = self._static(body)
        self.backend.begin()
        m = self.backend.motion(body)
        bc = BodyColliders(body=body, static=static)
        w = self.world
        for g in self.backend.geoms(body):
            mu = g.friction if friction is None else friction
            kw = dict(stiffness=stiffness, damping=damping, friction=mu)
            R = m.rotation @ g.rotation
            p = m.position + m.rotation @ g.position
            if g.kind == "plane":
                if not static:
                    raise ValueError(f"add_colliders: plane geom {g.name!r} on the moving body "
                                     f"{body!r}; rods only collide with static planes")
                bc.planes.append(w.add_plane(point=p, normal=R[:, 2], **kw))
                continue
            pose = (p, R)
            if g.kind == "sphere":
                c = w.add_sphere(float(g.size[0]), center=p, **kw)
            elif g.kind == "box":
                c = w.add_box(g.size[:3], pose=pose, **kw)
            elif g.kind == "capsule":
                c = w.add_capsule(float(g.size[0]), 2.0 * float(g.size[1]), pose=pose, **kw)
            elif g.kind == "cylinder":
                c = w.add_cylinder(float(g.size[0]), 2.0 * float(g.size[1]), pose=pose, **kw)
            else:
                c = w.add_mesh((g.vertices, g.faces), pose=pose, **kw)
            if g.kind == "sphere":
                c.set_pose(rotation=R)
            bc.colliders.append(c)
            bc.geoms.append(g)
        self.bodies[body] = bc
        self._refresh_coupled()
        return list(bc.colliders)

    # ------------------------------------------------------------------ stepping
    def _kinematic_drivers(self) -> None:
        """The drivers that follow moving bodies (kinematic clamps, colliders), as arrays:
        each one's body (index into ``_coupled``) and its frame in the body's frame."""
        where = {name: k for k, name in enumerate(self._coupled)}
        drivers, body, off, rot = [], [], [], []
        for a in self.attachments:
            if a.clamp is not None and a.body in where:
                drivers.append(a.clamp)  # rebased: its frame is the body's
                body.append(where[a.body])
                off.append(np.zeros(3))
                rot.append(np.eye(3))
        for name, bc in self.bodies.items():
            if name in where:
                for c, g in zip(bc.colliders, bc.geoms):
                    drivers.append(c)
                    body.append(where[name])
                    off.append(g.position)
                    rot.append(g.rotation)
        self._drivers = drivers
        self._drv_index = self.world.driver_table.index(drivers)
        self._origin = np.zeros((len(drivers), 3))
        self._drv_body = np.array(body, dtype=np.int64)
        self._drv_off = np.array(off, dtype=np.float64).reshape(-1, 3)
        self._drv_rot = np.array(rot, dtype=np.float64).reshape(-1, 3, 3)

    def _drive(self, m: np.ndarray) -> None:
        """Every kinematic driver takes its body's motion (rigid-body kinematics of its frame)."""
        for a in self.attachments:
            if a.coupling == "inertial" and a.body in self._index:
                self._ride(a, m[self._index[a.body]])
        if not self._drivers:
            return
        table = self.world.driver_table
        drive_rows(table.rows, self._drv_index, self._drv_body, self._drv_off, self._drv_rot, m,
                   self._origin, 1.0 / (CONTINUOUS_STEPS * self.world.dt * self.substeps),
                   CONTINUOUS_POSITION if self.continuous_drivers else -1.0)
        table.reset_impulses(self._drv_index)

    def _ride(self, a: Attachment, m: np.ndarray) -> None:
        """An inertial attachment before the rods' step: the node carries the body's mass and
        the body's other loads (its free acceleration, read from the backend with no rod
        wrench, less gravity, which the node's mass already feels). The node's own state is
        the truth (the body follows it); it is put back on the body's point only when the two
        drifted apart by more than a quarter element (the body blocked by its own contacts)."""
        R = m[M_R:M_R + 9].reshape(3, 3)
        w, al = m[M_W:M_W + 3], m[M_AL:M_AL + 3]
        r = R @ a.offset
        wr = _cross(w, r)
        p = m[M_P:M_P + 3] + r
        v = m[M_V:M_V + 3] + wr
        acc = m[M_A:M_A + 3] + _cross(al, r) + _cross(w, wr)
        if np.linalg.norm(a.rod.positions[a.node] - p) > a._slack:
            a.rod.positions[a.node] = p
            a.rod.velocities[a.node] = v
        a._p0, a._v0, a._a0, a._r = p, v, acc, r
        a._force = a.mass * (acc - self.world.gravity)
        a.rod.external_forces[a.node] += a._force

    def _feed_back(self, m: np.ndarray) -> None:
        """Mean wrench of the macro step on every coupled body, torque about its COM."""
        T = self.dt
        n = len(self._coupled)
        if n == 0:
            return
        wrench = np.zeros((n, 6))
        com = m[:, M_COM:M_COM + 3]
        if self._drivers:
            table = self.world.driver_table
            wrenches_from_impulses(table.impulses(self._drv_index), self._drv_body,
                                   self._origin, com, 1.0 / T, wrench)
            if self.smooth_feedback:
                this = wrench.copy()
                if self.held_wrenches is not None:
                    wrench += self.held_wrenches
                    wrench *= 0.5
                self.held_wrenches = this
        for a in self.attachments:
            k = self._index.get(a.body)
            if a.coupling != "inertial" or k is None:
                continue
            a.rod.external_forces[a.node] -= a._force
            # the force that brings the body's point to the node in the body's Euler step
            # (p1 = p0 + T v1): with one implicit rod step, the node's velocity as well
            f = a.mass * (((a.rod.positions[a.node] - a._p0) / T - a._v0) / T - a._a0)
            wrench[k, :3] += f
            wrench[k, 3:] += _cross(m[k, M_P:M_P + 3] + a._r - com[k], f)
        self._wrenches = wrench
        batch = getattr(self.backend, "apply_wrenches", None)
        if batch is not None:
            batch(self._coupled, wrench)
        else:
            for k, name in enumerate(self._coupled):
                self.backend.apply_wrench(name, wrench[k, :3], wrench[k, 3:])

    def _motions(self) -> np.ndarray:
        """The coupled bodies' motions, one row each (``kernels.M_*`` columns)."""
        rows = getattr(self.backend, "motion_rows", None)
        if rows is not None:
            return rows(self._coupled)
        out = np.empty((len(self._coupled), M_COLS))
        for k, name in enumerate(self._coupled):
            x = self.backend.motion(name)
            out[k, M_P:M_P + 3], out[k, M_R:M_R + 9] = x.position, np.ravel(x.rotation)
            out[k, M_V:M_V + 3], out[k, M_W:M_W + 3] = x.velocity, x.angular_velocity
            out[k, M_A:M_A + 3] = x.acceleration
            out[k, M_AL:M_AL + 3], out[k, M_COM:M_COM + 3] = x.angular_acceleration, x.com
        return out

    def step(self, on_diverged: str = "raise") -> np.ndarray | None:
        """One macro step of Algorithm 1 (see the module docstring). ``on_diverged`` as for
        :meth:`World.step`: ``"report"`` returns the rods that diverged (their loads on the
        bodies zeroed for this step; restore them before the next)."""
        be = self.backend
        clock = perf_counter if self.profile else None
        if clock:
            t0 = clock()
        for name in self._inertial:
            be.apply_wrench(name, np.zeros(3), np.zeros(3))  # its free acceleration is read
        be.begin()
        if clock:
            t1 = clock()
        motions = self._motions()
        self._drive(motions)
        if clock:
            t2 = clock()
        diverged = self.world.step(self.substeps, on_diverged=on_diverged)
        if clock:
            t3 = clock()
        self._feed_back(motions)
        if clock:
            t4 = clock()
        be.step()
        self._steps += 1
        if clock:
            t5 = clock()
            tm = self.timings
            tm["backend"] += (t1 - t0) + (t5 - t4)
            tm["coupling"] += (t2 - t1) + (t4 - t3)
            tm["rods"] += t3 - t2
            tm["steps"] += 1
        return diverged

    def reset_timings(self) -> None:
        """Zero :attr:`timings` (seconds spent per phase, summed over steps while
        :attr:`profile` is True: "backend" (its forward pass and step), "rods" (the world's
        step), "coupling" (reading motions, setting drivers, wrenches), "steps")."""
        self.timings = dict(backend=0.0, rods=0.0, coupling=0.0, steps=0)

    def run(self, duration: float, callbacks: Sequence[Any] = (), progress: bool = False
            ) -> None:
        """Advance by ``duration`` s (whole macro steps); each callback (a callable with an
        ``every`` attribute, s) is called with this co-simulation at the start and every
        ``every`` s of simulated time."""
        duration = check.non_negative("duration", duration, "s")
        T = self.dt
        n_total = int(round(duration / T))
        periods = callback_periods(callbacks, T)
        with progress_bar(f"co-simulating {duration:g} s", n_total, progress) as update:
            for k in range(n_total + 1):
                for cb, p in zip(callbacks, periods):
                    if k % p == 0:
                        cb(self)
                if k == n_total:
                    break
                self.step()
                if k % 50 == 0:
                    update(k + 1)

    def held_wrench(self, body: str) -> np.ndarray | None:
        """The drivers' wrench on ``body`` (6) that ``smooth_feedback`` carries into the next
        macro step; None before the first step (a per-body state: restore it with
        :meth:`set_held_wrench` when restoring that body)."""
        k = self._index.get(self._check_body(body))
        if self.held_wrenches is None or k is None:
            return None
        return self.held_wrenches[k].copy()

    def set_held_wrench(self, body: str, wrench: np.ndarray | None) -> None:
        """Restore what :meth:`held_wrench` returned (None, or before the first step: no
        change)."""
        k = self._index.get(self._check_body(body))
        if self.held_wrenches is not None and k is not None and wrench is not None:
            self.held_wrenches[k] = wrench

    def wrench(self, body: str) -> np.ndarray:
        """The last macro step's mean force (N) and torque (N m, about the body's centre of
        mass) the rods put on ``body``, world frame (6)."""
        self._check_body(body)
        k = self._index.get(body)
        if k is None or k >= self._wrenches.shape[0]:
            return np.zeros(6)
        return self._wrenches[k].copy()

    def __repr__(self) -> str:
        return (f"CoSimulation(rods={len(self.world.rods)}, attachments={len(self.attachments)}, "
                f"bodies={self._coupled}, dt={self.dt:g}, substeps={self.substeps})")


__all__ = ["Attachment", "CoSimulation", "point_motion"]
