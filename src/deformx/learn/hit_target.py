"""The paper's hit-target task: a UR5e with a stick swings a rope so that its tip passes as
close as possible to a target (``d_min``), as a Gymnasium environment.

Every number of the authors' task (their public code and the paper's appendix) is a field of
:class:`~deformx.learn.task.HitTargetConfig`; ``docs/learning.md`` lists them. The robot steps
in MuJoCo at the 2 ms control rate, the rope in DeformX through
:class:`deformx.cosim.CoSimulation` (``rope="cosserat"``: the stable integrator at second
order, BDF2, one 2 ms step per control step; see ``docs/learning.md`` for the choice) or as
a chain of capsules inside MuJoCo (``rope="capsule"``, the baseline). The physics is a
:class:`~deformx.learn.batch.HitTargetBatch` of one.

Frames: the environment's frame is the world frame; the robot's ``base_link`` stands at
(0, 0, 1.7) m turned -90 deg about x, so the arm swings in the y-z plane.
"""

from __future__ import annotations

from dataclasses import asdict, fields, replace
from typing import Any

import numpy as np

try:
    import gymnasium as gym
    from gymnasium import spaces
except ImportError as err:  # pragma: no cover - the [learn] extra
    raise ImportError("deformx.learn needs gymnasium: python -m pip install 'deformx[learn]'"
                      ) from err

from .batch import HitTargetBatch, with_params
from .task import HitTargetConfig


def make_config(config: HitTargetConfig | None, target: Any, rope: str | None,
                overrides: dict) -> HitTargetConfig:
    """The config with keyword overrides (unknown names refused)."""
    changes = dict(overrides)
    if target is not None:
        changes["target"] = tuple(float(v) for v in target)
    if rope is not None:
        changes["rope"] = rope
    bad = set(changes) - {f.name for f in fields(HitTargetConfig)}
    if bad:
        raise ValueError(f"unknown HitTarget parameter(s) {sorted(bad)}; see "
                         "deformx.learn.HitTargetConfig")
    return replace(config or HitTargetConfig(), **changes)


def task_spaces(cfg: HitTargetConfig) -> tuple[spaces.Box, spaces.Box]:
    n_act = len(cfg.active_joints)
    return (spaces.Box(-np.inf, np.inf, shape=(4 * 3 + 2 * n_act,), dtype=np.float32),
            spaces.Box(-1.0, 1.0, shape=(n_act,), dtype=np.float32))


class HitTargetEnv(gym.Env):
    """Gymnasium environment of the hit-target task (see the module docstring).

    Observation (18, float32): active joint positions (3) and velocities (3), rope tip
    position (3) and velocity (3), stick-tip position (3), target (3). Action (3) in
    [-1, 1]: clipped to [0, 1], times ``config.step_limit``, added to the commanded joint
    targets, which stay in [q0, upper_limits]. ``info``: ``d`` and ``d_min`` (in the swing
    plane, y-z), ``d_min_3d``, ``success``, ``diverged``, ``joint_targets``. An episode ends
    on success or d > 4 m (``terminated``), on the time limit or a diverged rope
    (``truncated``; the observation is then the last valid one).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 50}

    def __init__(self, target: Any = None, rope: str | None = None,
                 render_mode: str | None = None, config: HitTargetConfig | None = None,
                 width: int = 480, height: int = 360, **overrides: Any) -> None:
        self.config = cfg = make_config(config, target, rope, overrides)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.render_mode = render_mode
        self._size = (int(width), int(height))
        self.observation_space, self.action_space = task_spaces(cfg)
        self.batch = HitTargetBatch(cfg, 1)
        self._renderer = None
        self._camera = None

    # the physics, for users and tests
    @property
    def backend(self):
        return self.batch.backend

    @property
    def sim(self):
        return self.batch.sim

    @property
    def rod(self):
        return self.batch.rods[0] if self.batch.rods else None

    @property
    def rope(self):
        return self.batch.ropes[0]

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        if self.config.randomise:  # a new rope, changed in place
            self.batch.set_rope(0, with_params(self.config, self.np_random))
        self.batch.reset(0)
        return self.batch.observations()[0], self.batch.info(0)

    def step(self, action):
        a = np.asarray(action, dtype=np.float64).reshape(-1)
        if a.shape != self.action_space.shape:
            raise ValueError(f"action must hold {self.action_space.shape[0]} numbers, got "
                             f"{a.shape}")
        rewards, terminated, truncated, success, diverged = self.batch.step(a[None])
        # a diverged rope: the episode is cut short at its last valid state
        obs = self.batch.diverged_obs.pop(0) if diverged[0] else self.batch.observations()[0]
        return (obs, float(rewards[0]), bool(terminated[0]), bool(truncated[0]),
                self.batch.info(0, success[0], diverged[0]))

    def _reward(self, d: float, tip: np.ndarray, tip_v: np.ndarray, a: np.ndarray) -> float:
        return self.batch.reward(0, d, tip, tip_v, a)

    # ------------------------------------------------------------------ rendering
    def render(self):
        if self.render_mode != "rgb_array":
            return None
        from deformx.visual.camera import Camera
        from deformx.visual.fast import FastRenderer

        if self._renderer is None:
            if self.sim is None:
                raise NotImplementedError("rgb_array rendering draws the Cosserat rope; the "
                                          "capsule rope is drawn by MuJoCo's own renderer")
            self._renderer = FastRenderer(self.sim)
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
