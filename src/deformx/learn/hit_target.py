"""The paper's hit-target task: a UR5e with a stick swings a rope so that its tip passes as
close as possible to a target (``d_min``), as a Gymnasium environment.

Every number of the authors' task (their public code and the paper's appendix) is a field of
:class:`HitTargetConfig`; ``docs/learning.md`` lists them. The robot steps in MuJoCo at the
2 ms control rate, the rope in DeformX through :class:`deformx.cosim.CoSimulation`
(``rope="cosserat"``: the explicit integrator at 0.5 ms, four substeps per control step, which
follows a converged 1e-5 s run to 0.04 cm mean tip error, ``benchmarks/bench_rope_accuracy.py``)
or as a chain of capsules inside MuJoCo (``rope="capsule"``, the baseline).

Frames: the environment's frame is the world frame; the robot's ``base_link`` stands at
(0, 0, 1.7) m turned -90 deg about x, so the arm swings in the y-z plane.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields, replace
from typing import Any

import numpy as np

try:
    import gymnasium as gym
    from gymnasium import spaces
except ImportError as err:  # pragma: no cover - the [learn] extra
    raise ImportError("deformx.learn needs gymnasium: python -m pip install 'deformx[learn]'"
                      ) from err

ROPES = ("cosserat", "capsule")


@dataclass
class HitTargetConfig:
    """Every number of the task (SI units, radians). Defaults: the authors' task."""

    target: tuple = (0.0, 2.0, 2.3)          # m, environment frame
    rope: str = "cosserat"
    # robot
    base_position: tuple = (0.0, 0.0, 1.7)
    base_rotation_x: float = -math.pi / 2    # about the world x axis
    q0: tuple = (-1.5935, -2.2756, -1.1913, -0.3241, 1.5707, 3.1415)
    active_joints: tuple = (1, 2, 3)         # shoulder_lift, elbow, wrist_1
    upper_limits: tuple = (-1.92, -0.44, 2 * math.pi)  # task limits of the active joints
    stick_length: float = 0.65
    vel_limit: float = math.pi / 2           # rad/s; one step may add vel_limit dt scale
    action_scale: float = 3.0
    # rope
    rope_length: float = 1.0
    n_elements: int = 20
    radius: float = 0.00635
    density: float = 700.0
    youngs_modulus: float = 2e5
    damping: float = 0.1                     # 1/s
    rope_dt: float = 5e-4                    # s, Cosserat rope's step (4 per control step)
    integrator: str = "stable"               # Cosserat rope: "stable" or "verlet" (explicit)
    ground_stiffness: float = 100.0          # N/m per node
    clamp_frame: bool = True                 # the rope's first element turns with the stick
    capsule_damping: float = 1e-2            # N m s/rad per joint of the capsule rope
    capsule_armature: float = 1e-3
    # episode
    control_dt: float = 2e-3
    episode_steps: int = 700
    settle_time: float = 1.0                 # s the hanging rope settles before an episode
    # reward
    w_proximity: float = 1.0
    w_progress: float = 10.0
    w_new_best: float = 30.0
    bonus_thresholds: tuple = (0.5, 0.2, 0.1, 0.05)
    bonus_values: tuple = (1.0, 3.0, 5.0, 10.0)
    touch_distance: float = 0.03
    touch_bonus: float = 50.0
    success_distance: float = 0.05
    success_bonus: float = 50.0
    w_tip_velocity: float = 1.0
    w_wrist_velocity: float = 0.5
    time_penalty: float = 0.05
    action_penalty: float = 0.05
    smooth_penalty: float = 0.02
    reward_range: tuple = (-10.0, 200.0)
    too_far: float = 4.0
    # randomisation of the rope (fractions, uniform +-; 0: off), drawn at each reset
    randomise: dict = field(default_factory=dict)  # e.g. {"youngs_modulus": 0.3}

    def __post_init__(self) -> None:
        if self.rope not in ROPES:
            raise ValueError(f"rope must be one of {ROPES}, got {self.rope!r}")
        t = np.asarray(self.target, dtype=float)
        if t.shape != (3,) or not np.all(np.isfinite(t)):
            raise ValueError(f"target must be three finite numbers (m), got {self.target!r}")
        if len(self.q0) != 6:
            raise ValueError(f"q0 must hold 6 joint angles (rad), got {len(self.q0)}")
        if len(self.upper_limits) != len(self.active_joints):
            raise ValueError("upper_limits: one per active joint")
        ratio = self.control_dt / self.rope_dt
        if abs(ratio - round(ratio)) > 1e-9 * ratio or round(ratio) < 1:
            raise ValueError(f"rope_dt must divide control_dt ({self.control_dt:g} s), got "
                             f"{self.rope_dt:g}")
        for name in ("rope_length", "radius", "density", "youngs_modulus", "control_dt",
                     "stick_length"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")
        unknown = set(self.randomise) - {"youngs_modulus", "density", "damping"}
        if unknown:
            raise ValueError(f"randomise: only youngs_modulus, density and damping, got "
                             f"{sorted(unknown)}")

    @property
    def step_limit(self) -> float:
        """Largest joint increment per control step (rad)."""
        return self.vel_limit * self.control_dt * self.action_scale


def _rot_x(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def initial_rope(top: np.ndarray, length: float, n: int, radius: float,
                 along: np.ndarray = np.array([0.0, 1.0, 0.0])) -> np.ndarray:
    """``n + 1`` nodes exactly ``length / n`` apart (so a capsule chain fits them too) from
    ``top`` straight down to the ground (z = radius), the rest lying on it along ``along``."""
    from ..apps.calibration import _resample

    corner = np.array([top[0], top[1], max(float(top[2]), radius)])
    corner[2] = radius
    poly = np.array([top, corner, corner + 2.0 * length * along])
    return _resample(poly, n, exact=length / n)


class HitTargetEnv(gym.Env):
    """Gymnasium environment of the hit-target task (see the module docstring).

    Observation (18, float32): active joint positions (3) and velocities (3), rope tip
    position (3) and velocity (3), stick-tip position (3), target (3). Action (3) in
    [-1, 1]: clipped to [0, 1], times ``config.step_limit``, added to the commanded joint
    targets, which stay in [q0, upper_limits]. ``info``: ``d`` and ``d_min`` (in the swing
    plane, y-z), ``d_min_3d``, ``success``, ``diverged``.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 50}

    def __init__(self, target: Any = None, rope: str | None = None,
                 render_mode: str | None = None, config: HitTargetConfig | None = None,
                 width: int = 480, height: int = 360, **overrides: Any) -> None:
        cfg = config or HitTargetConfig()
        changes = dict(overrides)
        if target is not None:
            changes["target"] = tuple(float(v) for v in target)
        if rope is not None:
            changes["rope"] = rope
        known = {f.name for f in fields(HitTargetConfig)}
        bad = set(changes) - known
        if bad:
            raise ValueError(f"unknown HitTarget parameter(s) {sorted(bad)}; see "
                             "deformx.learn.HitTargetConfig")
        self.config = cfg = replace(cfg, **changes)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.render_mode = render_mode
        self._size = (int(width), int(height))
        n_act = len(cfg.active_joints)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(n_act,), dtype=np.float32)
        self.observation_space = spaces.Box(-np.inf, np.inf, shape=(4 * 3 + 2 * n_act,),
                                            dtype=np.float32)
        self._target = np.asarray(cfg.target, dtype=np.float64)
        self._active = np.asarray(cfg.active_joints, dtype=np.int64)
        self._q0 = np.asarray(cfg.q0, dtype=np.float64)
        self._upper = np.asarray(cfg.upper_limits, dtype=np.float64)
        self._params = {k: getattr(cfg, k) for k in ("youngs_modulus", "density", "damping")}
        self._build(self._params)
        self._renderer = None
        self._camera = None

    # ------------------------------------------------------------------ building
    def _build(self, params: dict) -> None:
        """MuJoCo model, rope and co-simulation for rope parameters ``params``; then let the
        rope settle and keep that state for resets."""
        import mujoco

        import deformx as dx
        from deformx import cosim, robots

        cfg = self.config
        xml = robots.ur5e(tool_length=cfg.stick_length, base_position=cfg.base_position,
                          base_rotation=_rot_x(cfg.base_rotation_x), ur_base_link=True,
                          q0=cfg.q0, timestep=cfg.control_dt, floor=True)
        m = mujoco.MjModel.from_xml_string(xml)
        d = mujoco.MjData(m)
        mujoco.mj_resetDataKeyframe(m, d, 0)
        mujoco.mj_kinematics(m, d)
        top = d.xpos[m.body("tool_tip").id].copy()
        shape = initial_rope(top, cfg.rope_length, cfg.n_elements, cfg.radius)
        self.sim = None
        self.rod = None
        if cfg.rope == "capsule":
            xml = robots.capsule_rope(xml, parent="tool_tip", length=cfg.rope_length,
                                      n_segments=cfg.n_elements, radius=cfg.radius,
                                      density=params["density"],
                                      youngs_modulus=params["youngs_modulus"],
                                      damping=cfg.capsule_damping,
                                      armature=cfg.capsule_armature, timestep=cfg.control_dt)
            self.backend = cosim.MujocoBackend(xml, keyframe=None)
            self.rope = cosim.CapsuleRope(self.backend)
            self._set_arm(self.backend, self._q0)
            self.rope.set_shape(shape)
        else:
            self.backend = cosim.MujocoBackend(xml)
            self._set_arm(self.backend, self._q0)
            world = dx.World(dt=cfg.rope_dt, gravity=(0.0, 0.0, -9.81),
                             integrator=cfg.integrator)
            self.rod = world.add_rod(dx.Rod.from_points(
                shape, radius=cfg.radius, density=params["density"],
                youngs_modulus=params["youngs_modulus"], damping=params["damping"]))
            world.add_plane(stiffness=cfg.ground_stiffness)
            self.sim = cosim.CoSimulation(world, self.backend)
            self.sim.attach(self.rod, "start", body="tool_tip", frame=cfg.clamp_frame)
            self.rope = cosim.RodRope(self.rod)
        mm = self.backend.model
        self._qadr = np.array([mm.jnt_qposadr[mm.joint(j).id] for j in robots.JOINTS])
        self._vadr = np.array([mm.jnt_dofadr[mm.joint(j).id] for j in robots.JOINTS])
        self._tool = self.backend.body_id("tool_tip")
        self.backend.begin()
        for _ in range(int(round(cfg.settle_time / cfg.control_dt))):
            self._advance()
        self._settled = self._save()
        self._built_params = dict(params)

    def _set_arm(self, backend, q: np.ndarray) -> None:
        import mujoco

        from deformx import robots

        m, d = backend.model, backend.data
        for j, name in enumerate(robots.JOINTS):
            d.qpos[m.jnt_qposadr[m.joint(name).id]] = q[j]
        d.ctrl[:6] = q
        mujoco.mj_forward(m, d)

    def _advance(self) -> None:
        if self.sim is not None:
            self.sim.step()
        else:
            self.backend.step()

    def _save(self) -> tuple:
        import mujoco

        m, d = self.backend.model, self.backend.data
        spec = mujoco.mjtState.mjSTATE_INTEGRATION
        buf = np.empty(mujoco.mj_stateSize(m, spec))
        mujoco.mj_getState(m, d, buf, spec)
        world = self.sim.world.get_state() if self.sim is not None else None
        return buf, world

    def _load(self, saved: tuple) -> None:
        import mujoco

        buf, world = saved
        m, d = self.backend.model, self.backend.data
        mujoco.mj_setState(m, d, buf, mujoco.mjtState.mjSTATE_INTEGRATION)
        mujoco.mj_forward(m, d)
        if world is not None:
            self.sim.world.set_state(world)

    # ------------------------------------------------------------------ gymnasium API
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        cfg = self.config
        params = dict(self._params)
        for name, frac in cfg.randomise.items():
            params[name] = self._params[name] * (1.0 + frac * self.np_random.uniform(-1, 1))
        if params != self._built_params:
            self._build(params)
        self._load(self._settled)
        self._q_cmd = self._q0.copy()
        self._a_prev = np.zeros(len(self._active))
        self._steps = 0
        tip = self.rope.tip_position
        self._d = self._plane_distance(tip)
        self._d_min = self._d
        self._d_min_3d = float(np.linalg.norm(tip - self._target))
        self._bonus_taken = np.zeros(len(cfg.bonus_thresholds), dtype=bool)
        self._touched = False
        return self._observation(), self._info(False, False)

    def step(self, action):
        import deformx as dx

        cfg = self.config
        a = np.asarray(action, dtype=np.float64).reshape(-1)
        if a.shape != (len(self._active),):
            raise ValueError(f"action must hold {len(self._active)} numbers, got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError("action must be finite")
        a = np.clip(a, -1.0, 1.0)
        delta = np.clip(a, 0.0, 1.0) * cfg.step_limit
        q = self._q_cmd
        q[self._active] = np.clip(q[self._active] + delta, self._q0[self._active], self._upper)
        self.backend.data.ctrl[:6] = q
        diverged = False
        try:
            self._advance()
        except dx.SimulationDiverged:
            diverged = True
        self._steps += 1
        tip = self.rope.tip_position
        tip_v = self.rope.tip_velocity
        d = self._plane_distance(tip)
        reward = self._reward(d, tip, tip_v, a)
        self._d = d
        self._d_min_3d = min(self._d_min_3d, float(np.linalg.norm(tip - self._target)))
        success = d < cfg.success_distance
        terminated = bool(success or d > cfg.too_far or diverged)
        truncated = bool(self._steps >= cfg.episode_steps and not terminated)
        self._a_prev = a
        return self._observation(), reward, terminated, truncated, self._info(success,
                                                                              diverged)

    def _plane_distance(self, tip: np.ndarray) -> float:
        return float(math.hypot(tip[1] - self._target[1], tip[2] - self._target[2]))

    def _reward(self, d: float, tip: np.ndarray, tip_v: np.ndarray, a: np.ndarray) -> float:
        cfg = self.config
        r = cfg.w_proximity * math.exp(-d) + cfg.w_progress * (self._d - d)
        if d < self._d_min:
            r += cfg.w_new_best * (self._d_min - d)
            self._d_min = d
        for k, (th, value) in enumerate(zip(cfg.bonus_thresholds, cfg.bonus_values)):
            if d < th and not self._bonus_taken[k]:
                self._bonus_taken[k] = True
                r += value
        if d < cfg.touch_distance and not self._touched:
            self._touched = True
            r += cfg.touch_bonus
        if d < cfg.success_distance:
            r += cfg.success_bonus
        to_target = self._target[1:] - tip[1:]
        norm = math.hypot(*to_target)
        if norm > 1e-9:
            r += cfg.w_tip_velocity * float(tip_v[1:] @ to_target) / norm
        wrist = self._vadr[3]
        r += cfg.w_wrist_velocity * float(self.backend.data.qvel[wrist])
        r -= cfg.time_penalty
        r -= cfg.action_penalty * float(a @ a)
        r -= cfg.smooth_penalty * float((a - self._a_prev) @ (a - self._a_prev))
        return float(np.clip(r, *cfg.reward_range))

    def _observation(self) -> np.ndarray:
        d = self.backend.data
        act = self._active
        return np.concatenate([d.qpos[self._qadr[act]], d.qvel[self._vadr[act]],
                               self.rope.tip_position, self.rope.tip_velocity,
                               d.xpos[self._tool], self._target]).astype(np.float32)

    def _info(self, success: bool, diverged: bool) -> dict:
        return {"d": self._d, "d_min": self._d_min, "d_min_3d": self._d_min_3d,
                "success": bool(success), "diverged": bool(diverged),
                "joint_targets": self._q_cmd.copy()}

    # ------------------------------------------------------------------ rendering
    def render(self):
        if self.render_mode != "rgb_array":
            return None
        from deformx.visual.camera import Camera
        from deformx.visual.fast import FastRenderer

        if self._renderer is None:
            source = self.sim if self.sim is not None else None
            if source is None:
                raise NotImplementedError("rgb_array rendering draws the Cosserat rope; the "
                                          "capsule rope is drawn by MuJoCo's own renderer")
            self._renderer = FastRenderer(source)
            w, h = self._size
            self._camera = Camera(position=(3.2, 1.0, 1.6), look_at=(0.0, 1.0, 1.2), fov_y=55,
                                  width=w, height=h)
        return self._renderer.render(self._camera).rgb

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def config_dict(self) -> dict:
        """The task's numbers, as a plain dict (for logs)."""
        return asdict(self.config)
