"""The batched hit-target environment: ``num_envs`` copies in one MuJoCo model and one DeformX
world (:class:`~deformx.learn.batch.HitTargetBatch`), as a Gymnasium ``VectorEnv``::

    envs = gym.make_vec("deformx/HitTarget-v0", num_envs=64,
                        vectorization_mode="vector_entry_point")

Autoreset in the same step (Gymnasium's ``AutoresetMode.SAME_STEP``): a copy whose episode
ended is reset at once, the observation returned is its new episode's first, and
``infos["final_obs"]`` / ``infos["final_info"]`` (masked by ``_final_obs`` / ``_final_info``)
hold how it ended, as stable-baselines3 expects (see :mod:`deformx.learn.sb3`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from .batch import HitTargetBatch, with_params
from .hit_target import make_config, task_spaces
from .task import HitTargetConfig


class HitTargetVecEnv(VectorEnv):
    """``num_envs`` hit-target environments stepped together (see the module docstring).

    ``spacing`` (m): 0 (default) puts every copy in one place, each following a lone
    environment bit for bit; > 0 stands them this far apart along x (out of the swing plane);
    observations are in each copy's own frame. With ``config.randomise`` each copy draws new
    rope parameters at every reset of its episode (``seed``, or the seed given to
    :meth:`reset`), changed in place (:meth:`HitTargetBatch.set_rope`)."""

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}

    def __init__(self, num_envs: int = 8, target: Any = None, rope: str | None = None,
                 config: HitTargetConfig | None = None, spacing: float = 0.0, seed: int = 0,
                 **overrides: Any) -> None:
        overrides.pop("render_mode", None)  # gymnasium passes it along; frames: single env
        self.config = cfg = make_config(config, target, rope, overrides)
        self._rng = np.random.default_rng(seed)  # rope parameters (config.randomise)
        params = ([with_params(cfg, self._rng) for _ in range(num_envs)] if cfg.randomise
                  else None)
        self.batch = HitTargetBatch(cfg, num_envs, spacing=spacing, params=params)
        self.num_envs = self.batch.n
        self.single_observation_space, self.single_action_space = task_spaces(cfg)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._np_random = None

    def reset(self, *, seed: int | list | None = None, options: dict | None = None):
        """Reset every copy (``options={"reset_mask": mask}``: only those)."""
        if seed is not None:
            self._np_random_seed = seed if isinstance(seed, int) else seed[0]
            self._np_random = np.random.default_rng(self._np_random_seed)
            self._rng = np.random.default_rng(self._np_random_seed)
        mask = np.ones(self.num_envs, dtype=bool)
        if options and "reset_mask" in options:
            mask = np.asarray(options["reset_mask"], dtype=bool)
        for i in np.flatnonzero(mask):
            self._reset_one(int(i))
        return self.batch.observations(), self._infos(np.zeros(self.num_envs, bool),
                                                      np.zeros(self.num_envs, bool))

    def step(self, actions):
        b = self.batch
        rewards, terminated, truncated, success, diverged = b.step(actions)
        obs = b.observations()
        infos = self._infos(success, diverged)
        done = np.flatnonzero(terminated | truncated)
        if len(done):
            final_obs = np.full(self.num_envs, None, dtype=object)
            final_info: dict[str, Any] = {}
            for i in done:
                final_obs[i] = b.diverged_obs.pop(int(i)) if diverged[i] else obs[i].copy()
                final_info = self._add_info(final_info, b.info(int(i), success[i], diverged[i]),
                                            int(i))
                self._reset_one(int(i))
            obs = b.observations()
            infos["final_obs"] = final_obs
            infos["_final_obs"] = terminated | truncated
            infos["final_info"] = final_info
            infos["_final_info"] = terminated | truncated
        return obs, rewards, terminated, truncated, infos

    def _reset_one(self, i: int) -> None:
        if self.config.randomise:
            self.batch.set_rope(i, with_params(self.config, self._rng))
        self.batch.reset(i)

    def _infos(self, success: np.ndarray, diverged: np.ndarray) -> dict:
        b = self.batch
        every = np.ones(self.num_envs, dtype=bool)
        return {"d": b.d.copy(), "_d": every, "d_min": b.d_min.copy(), "_d_min": every,
                "d_min_3d": b.d_min_3d.copy(), "_d_min_3d": every,
                "success": success.copy(), "_success": every,
                "diverged": diverged.copy(), "_diverged": every,
                "joint_targets": b.q_cmd.copy(), "_joint_targets": every}

    def close_extras(self, **kwargs: Any) -> None:
        pass
