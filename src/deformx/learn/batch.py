"""``n`` copies of the hit-target task stepped together: one MuJoCo model holding ``n`` arms,
one DeformX world holding the ``n`` ropes (one kernel call steps them all) and one
co-simulation coupling them. The single environment is a batch of one; the vector
environment a batch of ``num_envs``.

By default (``spacing=0``) every copy stands at the same place, so each computes with the same
numbers as a lone environment and follows it bit for bit whatever the batch's size (a whip
amplifies a rounding difference of 1e-16 m to centimetres within a second): the ropes do not
collide with each other (``rod_contact=False``), and in MuJoCo no geom collides through the
broad phase; each copy's own candidate pairs (those MuJoCo's default filters would test in a
lone copy) are declared as explicit contact pairs, and MuJoCo solves each copy's constraints as
its own island, from a cold start (MuJoCo decides its solver's warm start for the whole model
at once: with it a capsule chain's copies agreed to ~1e-7 m only). ``spacing > 0`` places
copy ``i`` ``i * spacing`` m along x instead (out of the swing plane; more than twice the
reach so copies never meet): the same physics, rounded differently per copy.

Per-environment resets restore that copy's settled state: its arm's joints (and capsule
chain) in MuJoCo and its rope through the engine's per-rod state. A rope that diverges during
a step (NaN or runaway stretch; folds are stepped through, see ``docs/learning.md``) is reset while the others
finish the step (``World.step(on_diverged="report")``; where ropes may touch each other, the
whole step is rolled back and run again without it), and that copy's episode is cut short -
truncated, not terminated: the simulator could not go on, the task did not end, so a learner
bootstraps there - keeping its last valid observation in :attr:`HitTargetBatch.diverged_obs`.
"""

from __future__ import annotations

import math

import numpy as np

from .task import RANDOMISABLE, HitTargetConfig, initial_rope, rot_x


class HitTargetBatch:
    """The task's physics and episode bookkeeping for ``n`` environments.

    ``params``: per environment, a dict of rope parameters overriding the config's
    (``youngs_modulus``, ``density``, ``damping``; the domain randomisation)."""

    def __init__(self, config: HitTargetConfig, n: int = 1, spacing: float = 0.0,
                 params: list | None = None) -> None:
        if not isinstance(n, (int, np.integer)) or n < 1:
            raise ValueError(f"num_envs must be an integer >= 1, got {n!r}")
        reach = 2.0 * (config.rope_length + config.stick_length)
        if not (spacing == 0.0 or spacing > reach):
            raise ValueError(f"spacing must be 0 (every copy in one place, bit-identical to a "
                             f"lone environment) or exceed twice the reach of a rope on its "
                             f"stick ({reach:g} m), got {spacing!r}")
        self.config = cfg = config
        self.n = int(n)
        self.origins = np.zeros((self.n, 3))
        self.origins[:, 0] = spacing * np.arange(self.n)  # all zero by default
        base = {k: getattr(cfg, k) for k in RANDOMISABLE}
        self.params = [dict(base, **(params[i] if params else {})) for i in range(self.n)]
        self._target = np.asarray(cfg.target, dtype=np.float64)
        self._active = np.asarray(cfg.active_joints, dtype=np.int64)
        self._q0 = np.asarray(cfg.q0, dtype=np.float64)
        self._upper = np.asarray(cfg.upper_limits, dtype=np.float64)
        self._build()
        n, k = self.n, len(cfg.bonus_thresholds)
        self.q_cmd = np.tile(self._q0, (n, 1))
        self.a_prev = np.zeros((n, len(self._active)))
        self.steps = np.zeros(n, dtype=np.int64)
        self.d = np.zeros(n)
        self.d_min = np.zeros(n)
        self.d_min_3d = np.zeros(n)
        self.bonus_taken = np.zeros((n, k), dtype=bool)
        self.touched = np.zeros(n, dtype=bool)
        for i in range(n):
            self.reset(i)

    # ------------------------------------------------------------------ building
    def _model_xml(self) -> str:
        spec = self._copies_spec(self.n)
        _per_copy_contacts(spec, self._copies_spec(1).compile())
        return spec.to_xml()

    def _copies_xml(self) -> str:
        """The copies' MJCF with MuJoCo's dynamic (broad-phase) collisions."""
        return self._copies_spec(self.n).to_xml()

    def _copies_spec(self, n: int):
        """The first ``n`` copies (prefixes ``e0_`` ...) in one ``mujoco.MjSpec``."""
        import mujoco

        from deformx import robots

        cfg = self.config
        root = mujoco.MjSpec.from_string(
            # no solver warm start: MuJoCo decides it for the whole model at once, and a
            # copy's contacts would then start from a guess that depends on the others'
            f'<mujoco><option timestep="{cfg.control_dt:.17g}" integrator="implicitfast">'
            '<flag warmstart="disable"/></option>'
            '<worldbody><geom name="floor" type="plane" size="0 0 0.05" '
            'rgba="0.55 0.55 0.5 1"/></worldbody></mujoco>')
        for i, p in enumerate(self.params[:n]):
            arm = robots.ur5e(
                tool_length=cfg.stick_length,
                base_position=tuple(np.asarray(cfg.base_position) + self.origins[i]),
                base_rotation=rot_x(cfg.base_rotation_x), ur_base_link=True, q0=cfg.q0,
                timestep=cfg.control_dt)
            if cfg.rope == "capsule":  # on its own arm: a whole-model round trip per copy
                arm = robots.capsule_rope(arm, parent="tool_tip", length=cfg.rope_length,
                                          n_segments=cfg.n_elements, radius=cfg.radius,
                                          density=p["density"],
                                          youngs_modulus=p["youngs_modulus"],
                                          damping=cfg.capsule_damping,
                                          armature=cfg.capsule_armature,
                                          timestep=cfg.control_dt, name="rope")
            arm = mujoco.MjSpec.from_string(arm)
            for key in list(arm.keys):  # the batch poses its copies itself
                arm.delete(key)
            arm.nkey = 0  # (a model written back to MJCF declares its keyframes' count)
            root.attach(arm, prefix=f"e{i}_", frame=root.worldbody.add_frame())
        return root

    def _build(self) -> None:
        import mujoco

        import deformx as dx
        from deformx import cosim, robots

        cfg = self.config
        self.backend = be = cosim.MujocoBackend(self._model_xml())
        m, d = be.model, be.data
        self._qadr = np.array([[m.jnt_qposadr[m.joint(f"e{i}_{j}").id] for j in robots.JOINTS]
                               for i in range(self.n)])
        self._vadr = np.array([[m.jnt_dofadr[m.joint(f"e{i}_{j}").id] for j in robots.JOINTS]
                               for i in range(self.n)])
        self._ctrl = np.array([[m.actuator(f"e{i}_{j.replace('_joint', '')}").id
                                for j in robots.JOINTS] for i in range(self.n)])
        self._tool = np.array([be.body_id(f"e{i}_tool_tip") for i in range(self.n)])
        # every joint of copy i (its arm and its capsule chain): what a reset restores
        qpos_i, dof_i = [], []
        for i in range(self.n):
            js = [j for j in range(m.njnt) if m.joint(j).name.startswith(f"e{i}_")]
            qpos_i.append(np.concatenate([np.arange(m.jnt_qposadr[j], m.jnt_qposadr[j] + (
                4 if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_BALL else 1)) for j in js]))
            dof_i.append(np.concatenate([np.arange(m.jnt_dofadr[j], m.jnt_dofadr[j] + (
                3 if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_BALL else 1)) for j in js]))
        self._qpos_i, self._dof_i = qpos_i, dof_i
        self._body_i = [np.array([b for b in range(m.nbody)
                                  if m.body(b).name.startswith(f"e{i}_")]) for i in range(self.n)]
        for i in range(self.n):
            d.qpos[self._qadr[i]] = self._q0
            d.ctrl[self._ctrl[i]] = self._q0
        mujoco.mj_forward(m, d)
        tops = d.xpos[self._tool].copy()
        shapes = [initial_rope(tops[i], cfg.rope_length, cfg.n_elements, cfg.radius)
                  for i in range(self.n)]
        self.diverged_obs: dict[int, np.ndarray] = {}  # copy -> its last valid observation
        self._obs: np.ndarray | None = None  # observations() since the last change of state
        self.sim, self.rods = None, []
        self._tip_index = None  # where the ropes' tips lie in the world's buffers
        self._tip_owner = None
        if cfg.rope == "capsule":
            self.ropes = [cosim.CapsuleRope(be, name=f"e{i}_rope") for i in range(self.n)]
            self._tip_sites = np.array([m.site(f"e{i}_rope_tip").id for i in range(self.n)])
            for rope, shape in zip(self.ropes, shapes):
                rope.set_shape(shape)
        else:
            world = dx.World(dt=cfg.rope_dt, integrator=cfg.integrator, rod_contact=False,
                             max_strain=cfg.max_strain,
                             order=cfg.order if cfg.integrator == "stable" else 1)
            for shape, p in zip(shapes, self.params):
                self.rods.append(world.add_rod(dx.Rod.from_points(
                    shape, radius=cfg.radius, density=p["density"],
                    youngs_modulus=p["youngs_modulus"], damping=p["damping"],
                    internal_damping=cfg.internal_damping,
                    stretch_modulus=cfg.stretch_modulus, shear_modulus=cfg.shear_modulus,
                    twist_modulus=cfg.twist_of(p["youngs_modulus"]))))
            world.add_plane(stiffness=cfg.ground_stiffness)
            self.sim = cosim.CoSimulation(world, be,
                                          continuous_drivers=cfg.continuous_drivers)
            for i, rod in enumerate(self.rods):
                self.sim.attach(rod, "start", body=f"e{i}_tool_tip", frame=cfg.clamp_frame)
            self.ropes = [cosim.RodRope(rod) for rod in self.rods]
        self._const_data = mujoco.MjData(m) if cfg.rope == "capsule" else None
        # each capsule chain's bodies and joints (what set_rope scales)
        self._capsules = ([self._find_capsule(i) for i in range(self.n)]
                          if cfg.rope == "capsule" else [])
        be.begin()
        for _ in range(int(round(cfg.settle_time / cfg.control_dt))):
            self._advance()
        self._settled = [self._save(i) for i in range(self.n)]

    # ------------------------------------------------------------------ state
    def _advance(self) -> None:
        if self.sim is not None:
            self.sim.step()
        else:
            self.backend.step()

    def _save(self, i: int) -> tuple:
        d = self.backend.data
        q, v = self._qpos_i[i], self._dof_i[i]
        rod = self.rods[i].get_state() if self.rods else None
        held = self.sim.held_wrench(f"e{i}_tool_tip") if self.sim is not None else None
        b = self._body_i[i]  # the co-simulation's wrench on the stick acts through these
        return (d.qpos[q].copy(), d.qvel[v].copy(), d.qacc_warmstart[v].copy(),
                d.qfrc_applied[v].copy(), d.xfrc_applied[b].copy(),
                d.ctrl[self._ctrl[i]].copy(), rod, held)

    def _load(self, i: int, saved: tuple) -> None:
        d = self.backend.data
        q, v, b = self._qpos_i[i], self._dof_i[i], self._body_i[i]
        (d.qpos[q], d.qvel[v], d.qacc_warmstart[v], d.qfrc_applied[v], d.xfrc_applied[b],
         d.ctrl[self._ctrl[i]], rod, held) = saved
        if rod is not None:
            self.rods[i].set_state(rod)
            self.sim.set_held_wrench(f"e{i}_tool_tip", held)

    def _full_state(self) -> tuple:
        import mujoco

        m, d = self.backend.model, self.backend.data
        spec = mujoco.mjtState.mjSTATE_INTEGRATION
        buf = np.empty(mujoco.mj_stateSize(m, spec))
        mujoco.mj_getState(m, d, buf, spec)
        held = self.sim.held_wrenches
        return buf, self.sim.world.get_state(), None if held is None else held.copy()

    def _restore_full(self, saved: tuple) -> None:
        import mujoco

        buf, world, held = saved
        mujoco.mj_setState(self.backend.model, self.backend.data, buf,
                           mujoco.mjtState.mjSTATE_INTEGRATION)
        self.sim.world.set_state(world)
        self.sim.held_wrenches = None if held is None else held.copy()

    def set_rope(self, i: int, params: dict) -> None:
        """Give copy ``i``'s rope new parameters (``youngs_modulus``, ``density``,
        ``damping``; the others keep theirs) in place, without a rebuild: the Cosserat rope
        through :meth:`~deformx.Rod.set_material`, the capsule chain through MuJoCo's model
        (body masses and inertias and joint stiffness, scaled; its joint damping is the
        config's ``capsule_damping``, not drawn). Takes effect from the
        copy's next reset, which restarts it from the settled hanging shape: a rope hangs
        straight whatever its material (its stretch modulus is not randomised)."""
        old = self.params[i]
        new = dict(old, **params)
        self.params[i] = new
        cfg = self.config
        if self.rods:
            rod = self.rods[i]
            rod.set_material(density=new["density"], youngs_modulus=new["youngs_modulus"],
                             shear_modulus=cfg.shear_modulus,
                             stretch_modulus=cfg.stretch_modulus,
                             twist_modulus=cfg.twist_of(new["youngs_modulus"]))
            rod.damping = new["damping"]
            return
        import mujoco

        m = self.backend.model
        bodies, joints = self._capsules[i]
        mass = new["density"] / old["density"]
        m.body_mass[bodies] *= mass
        m.body_inertia[bodies] *= mass
        m.jnt_stiffness[joints] *= new["youngs_modulus"] / old["youngs_modulus"]
        # derived constants (subtree masses, constraint weights) of the new masses
        mujoco.mj_setConst(m, self._const_data)

    def _find_capsule(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        m = self.backend.model
        prefix = f"e{i}_rope"
        bodies = np.array([b for b in self._body_i[i] if m.body(b).name.startswith(prefix)])
        return bodies, np.flatnonzero(np.isin(m.jnt_bodyid, bodies))

    # ------------------------------------------------------------------ episodes
    def reset(self, i: int) -> None:
        """Copy ``i`` back to its settled state and a new episode."""
        import mujoco

        self._load(i, self._settled[i])
        self._obs = None
        mujoco.mj_kinematics(self.backend.model, self.backend.data)  # its stick and chain
        self.q_cmd[i] = self._q0
        self.a_prev[i] = 0.0
        self.steps[i] = 0
        tip = self.tips()[0][i]
        self.d[i] = self.d_min[i] = float(self._distances(tip[None])[0])
        self.d_min_3d[i] = float(np.linalg.norm(tip - self._target))
        self.bonus_taken[i] = False
        self.touched[i] = False

    def step(self, actions: np.ndarray) -> tuple:
        """Apply ``actions`` (n, 3), advance one control step; returns rewards (n,),
        terminated (n,), truncated (n,), success (n,), diverged (n,)."""
        import deformx as dx

        cfg = self.config
        a = np.asarray(actions, dtype=np.float64).reshape(self.n, len(self._active))
        if not np.all(np.isfinite(a)):
            raise ValueError("actions must be finite")
        a = np.clip(a, -1.0, 1.0)
        q = self.q_cmd
        q[:, self._active] = np.clip(q[:, self._active] + np.clip(a, 0.0, 1.0) * cfg.step_limit,
                                     self._q0[self._active], self._upper)
        self.backend.data.ctrl[self._ctrl] = q
        diverged = np.zeros(self.n, dtype=bool)
        if self.sim is None:
            self._advance()
        elif not self.sim.world.rods_coupled:
            # Ropes that never touch: the others finish the step, a diverged one is reset.
            last = self.observations() if self._obs is None else self._obs
            failed = self.sim.step(on_diverged="report")
            for i in failed:
                diverged[i] = True
                self.diverged_obs[int(i)] = last[i].copy()
                self._load(int(i), self._settled[int(i)])
        else:
            before = self._full_state()
            while True:
                try:
                    self._advance()
                    break
                except dx.SimulationDiverged as err:
                    # roll the step back, take the diverged copy out (reset), step again
                    import mujoco

                    self._restore_full(before)
                    diverged[err.rod] = True
                    mujoco.mj_kinematics(self.backend.model, self.backend.data)
                    self.diverged_obs[err.rod] = self.observations()[err.rod]
                    self._load(err.rod, self._settled[err.rod])
                    before = self._full_state()
        self.steps += 1
        self._obs = None
        import mujoco

        mujoco.mj_kinematics(self.backend.model, self.backend.data)  # the sticks now, not
        tips, tip_v = self.tips()                                     # one step ago
        dist = self._distances(tips)
        ok = np.flatnonzero(~diverged)
        rewards = np.zeros(self.n)
        rewards[ok] = self._rewards(ok, dist[ok], tips[ok], tip_v[ok], a[ok])
        self.d_min_3d[ok] = np.minimum(self.d_min_3d[ok],
                                       np.linalg.norm(tips[ok] - self._target, axis=1))
        self.d[ok] = dist[ok]
        success = (self.d < cfg.success_distance) & ~diverged
        self.a_prev[:] = a
        terminated = success | (self.d > cfg.too_far)
        truncated = ((self.steps >= cfg.episode_steps) | diverged) & ~terminated
        return rewards, terminated, truncated, success, diverged

    def tips(self) -> tuple[np.ndarray, np.ndarray]:
        """Rope tip positions (n, 3) in each copy's frame and velocities (n, 3)."""
        if self.rods:
            if self._tip_index is None or self._tip_owner is not self.rods[0].positions.base:
                # (again whenever the world repacked its buffers)
                self._tip_owner = self.rods[0].positions.base
                self._tip_index = {k: _flat_rows([getattr(r, k)[-1] for r in self.rods])
                                   for k in ("positions", "velocities")}
            (pb, pi), (vb, vi) = self._tip_index["positions"], self._tip_index["velocities"]
            pos, vel = pb[pi], vb[vi]
        else:
            import mujoco

            m, d = self.backend.model, self.backend.data
            mujoco.mj_kinematics(m, d)
            mujoco.mj_comPos(m, d)
            pos = d.site_xpos[self._tip_sites].copy()
            vel = np.empty((self.n, 3))
            res = np.zeros(6)
            for i, site in enumerate(self._tip_sites):
                mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_SITE, site, res, 0)
                vel[i] = res[3:]
        return pos - self.origins, vel

    def _distances(self, tips: np.ndarray) -> np.ndarray:
        """Tip-to-target distances (n,): in the swing plane (y-z), or in 3D."""
        if self.config.distance == "3d":
            return np.linalg.norm(tips - self._target, axis=1)
        return np.hypot(tips[:, 1] - self._target[1], tips[:, 2] - self._target[2])

    def reward(self, i: int, d: float, tip: np.ndarray, tip_v: np.ndarray,
               a: np.ndarray) -> float:
        """Copy ``i``'s reward for a step that ends at tip-to-target distance ``d`` (m, in
        plane), tip position ``tip`` (env frame) and velocity ``tip_v``, after action ``a``;
        updates the episode's best distance and one-off bonuses."""
        return float(self._rewards(np.array([i]), np.array([d]), np.asarray(tip)[None],
                                   np.asarray(tip_v)[None], np.asarray(a)[None])[0])

    def _rewards(self, idx: np.ndarray, d: np.ndarray, tip: np.ndarray, tip_v: np.ndarray,
                 a: np.ndarray) -> np.ndarray:
        """Rewards of copies ``idx`` (the terms of ``docs/learning.md``), vectorised."""
        cfg = self.config
        r = cfg.w_proximity * np.exp(-d) + cfg.w_progress * (self.d[idx] - d)
        better = d < self.d_min[idx]
        r += np.where(better, cfg.w_new_best * (self.d_min[idx] - d), 0.0)
        self.d_min[idx] = np.where(better, d, self.d_min[idx])
        for k, (th, value) in enumerate(zip(cfg.bonus_thresholds, cfg.bonus_values)):
            first = (d < th) & ~self.bonus_taken[idx, k]
            self.bonus_taken[idx, k] |= first
            r += value * first
        touch = (d < cfg.touch_distance) & ~self.touched[idx]
        self.touched[idx] |= touch
        r += cfg.touch_bonus * touch
        r += cfg.success_bonus * (d < cfg.success_distance)
        axes = slice(0, 3) if cfg.distance == "3d" else slice(1, 3)  # the distance's space
        to = self._target[axes] - tip[:, axes]
        norm = np.linalg.norm(to, axis=1)
        towards = np.einsum("ij,ij->i", tip_v[:, axes], to) / np.maximum(norm, 1e-9)
        r += cfg.w_tip_velocity * np.where(norm > 1e-9, towards, 0.0)
        r += cfg.w_wrist_velocity * self.backend.data.qvel[self._vadr[idx, 3]]
        if cfg.w_strike:  # hit-apple: horizontal speed of the tip at the target
            near = np.linalg.norm(tip - self._target, axis=1) < cfg.strike_radius
            r += cfg.w_strike * near * np.hypot(tip_v[:, 0], tip_v[:, 1])
        r -= cfg.time_penalty
        r -= cfg.action_penalty * np.einsum("ij,ij->i", a, a)
        da = a - self.a_prev[idx]
        r -= cfg.smooth_penalty * np.einsum("ij,ij->i", da, da)
        return np.clip(r, *cfg.reward_range)

    def observations(self) -> np.ndarray:
        """(n, 18) float32: active joint positions and velocities, rope tip position and
        velocity, stick-tip position, target (each copy in its own frame)."""
        d = self.backend.data
        act = self._active
        tips, tip_v = self.tips()
        self._obs = np.concatenate([d.qpos[self._qadr[:, act]], d.qvel[self._vadr[:, act]],
                                    tips, tip_v, d.xpos[self._tool] - self.origins,
                                    np.broadcast_to(self._target, (self.n, 3))],
                                   axis=1).astype(np.float32)
        return self._obs.copy()  # kept: the last valid observation of a copy that diverges

    def info(self, i: int, success: bool = False, diverged: bool = False) -> dict:
        return {"d": float(self.d[i]), "d_min": float(self.d_min[i]),
                "d_min_3d": float(self.d_min_3d[i]), "success": bool(success),
                "diverged": bool(diverged), "joint_targets": self.q_cmd[i].copy()}


def _per_copy_contacts(spec, lone) -> None:
    """Make each copy's geoms (prefixes ``e0_``, ``e1_``, ... in ``spec``, a ``mujoco.MjSpec``)
    collide only with their own copy's and the world's: the geom pairs MuJoCo's default
    filters pass in ``lone`` (the compiled model of copy 0 alone: contype/conaffinity, same or
    parent body after welds, excluded body pairs) become explicit pairs of every copy, with the
    contact parameters MuJoCo mixes for a dynamic contact, and no copy geom collides through
    the broad phase."""
    import itertools
    import re

    import mujoco

    m = lone
    ct, ca = m.geom_contype, m.geom_conaffinity
    weld, parent = m.body_weldid, m.body_parentid
    excluded = {(min(s >> 16, s & 0xFFFF), max(s >> 16, s & 0xFFFF))
                for s in np.asarray(m.exclude_signature, dtype=np.int64)}
    filter_parent = not m.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_FILTERPARENT
    names = [m.geom(g).name for g in range(m.ngeom)]
    if any(not nm for nm in names):
        raise ValueError("every geom of the hit-target model needs a name for its contact pairs")
    pairs = []
    for a, b in itertools.combinations(range(m.ngeom), 2):
        if not (ct[a] & ca[b] or ct[b] & ca[a]):
            continue
        b1, b2 = int(m.geom_bodyid[a]), int(m.geom_bodyid[b])
        w1, w2 = int(weld[b1]), int(weld[b2])
        if w1 == w2 or (min(b1, b2), max(b1, b2)) in excluded:
            continue
        if filter_parent and w1 and w2 and (w1 == weld[parent[w2]] or w2 == weld[parent[w1]]):
            continue
        if not (names[a].startswith("e0_") or names[b].startswith("e0_")):
            continue  # world-world: no copy's business
        pairs.append((names[a], names[b], _mixed_contact(m, a, b)))
    copy_geom = re.compile(r"e(\d+)_")
    copies = set()
    for g in spec.geoms:
        match = copy_geom.match(g.name)
        if match:
            g.contype = g.conaffinity = 0
            copies.add(int(match.group(1)))
    for i in sorted(copies):
        for a, b, kw in pairs:
            spec.add_pair(geomname1=a.replace("e0_", f"e{i}_", 1),
                          geomname2=b.replace("e0_", f"e{i}_", 1), **kw)


def _mixed_contact(m, a: int, b: int) -> dict:
    """Contact parameters of geoms ``a`` and ``b`` as MuJoCo mixes them for a dynamic
    contact (an explicit pair does not mix; its own defaults would apply)."""
    if m.geom_priority[a] != m.geom_priority[b]:
        g = a if m.geom_priority[a] > m.geom_priority[b] else b
        condim, f = int(m.geom_condim[g]), m.geom_friction[g]
        solref, solimp = m.geom_solref[g].copy(), m.geom_solimp[g].copy()
    else:
        condim = int(max(m.geom_condim[a], m.geom_condim[b]))
        f = np.maximum(m.geom_friction[a], m.geom_friction[b])
        s1, s2 = m.geom_solmix[a], m.geom_solmix[b]
        if s1 < 1e-15 and s2 < 1e-15:
            mix = 0.5
        elif s1 < 1e-15:
            mix = 0.0
        elif s2 < 1e-15:
            mix = 1.0
        else:
            mix = s1 / (s1 + s2)
        r1, r2 = m.geom_solref[a], m.geom_solref[b]
        solref = (mix * r1 + (1 - mix) * r2 if r1[0] > 0 and r2[0] > 0
                  else np.minimum(r1, r2))
        solimp = mix * m.geom_solimp[a] + (1 - mix) * m.geom_solimp[b]
    return dict(condim=condim, friction=[f[0], f[0], f[1], f[2], f[2]],
                solref=list(solref), solimp=list(solimp),
                margin=float(max(m.geom_margin[a], m.geom_margin[b])),
                gap=float(max(m.geom_gap[a], m.geom_gap[b])))


def _flat_rows(views: list) -> tuple[np.ndarray, np.ndarray]:
    """(flat buffer, (k, 3) indices) such that ``buffer[indices]`` gathers the 3-vectors
    ``views`` (rows of one packed engine buffer) in one step, not a Python loop."""
    base = views[0]
    while base.base is not None:
        base = base.base
    start = base.__array_interface__["data"][0]
    item = base.itemsize
    off = np.array([(v.__array_interface__["data"][0] - start) // item for v in views])
    if any(v.strides != (item,) for v in views) or off.min() < 0 or off.max() + 3 > base.size:
        raise RuntimeError("rope tips are not rows of one engine buffer")
    return base.reshape(-1), off[:, None] + np.arange(3)


def with_params(config: HitTargetConfig, rng: np.random.Generator) -> dict:
    """Rope parameters drawn for one copy by ``config.randomise`` (uniform, +- fractions)."""
    out = {}
    for name, frac in config.randomise.items():
        out[name] = getattr(config, name) * (1.0 + frac * rng.uniform(-1.0, 1.0))
    return out


__all__ = ["HitTargetBatch", "with_params"]
