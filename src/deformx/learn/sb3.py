"""A stable-baselines3 ``VecEnv`` over :class:`~deformx.learn.vector.HitTargetVecEnv`: SB3's
conventions on top of the Gymnasium vector environment's same-step autoreset - ``dones``
(terminated or truncated), ``infos[i]["terminal_observation"]`` and, for a time limit,
``infos[i]["TimeLimit.truncated"] = True`` so that PPO bootstraps the value there."""

from __future__ import annotations

from typing import Any

import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv

from .vector import HitTargetVecEnv


class SB3VecEnv(VecEnv):
    """``SB3VecEnv(HitTargetVecEnv(...))``: the batch as SB3 steps it."""

    def __init__(self, venv: HitTargetVecEnv) -> None:
        self.venv = venv
        super().__init__(venv.num_envs, venv.single_observation_space,
                         venv.single_action_space)
        self._actions: np.ndarray | None = None
        self._seed: int | None = None

    def reset(self) -> np.ndarray:
        obs, _ = self.venv.reset(seed=self._seed)
        self._seed = None
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions)

    def step_wait(self):
        obs, rewards, terminated, truncated, infos = self.venv.step(self._actions)
        dones = terminated | truncated
        out = [self._info(infos, i) for i in range(self.num_envs)]
        for i in np.flatnonzero(dones):
            out[i]["terminal_observation"] = infos["final_obs"][i]
            out[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
            out[i]["episode_d_min"] = float(infos["final_info"]["d_min"][i])
            out[i]["episode_d_min_3d"] = float(infos["final_info"]["d_min_3d"][i])
            out[i]["episode_success"] = bool(infos["final_info"]["success"][i])
        return obs, rewards.astype(np.float32), dones, out

    @staticmethod
    def _info(infos: dict, i: int) -> dict:
        return {"d": float(infos["d"][i]), "diverged": bool(infos["diverged"][i])}

    def close(self) -> None:
        self.venv.close()

    def seed(self, seed: int | None = None):
        self._seed = seed
        return [seed] * self.num_envs

    def get_attr(self, attr_name: str, indices: Any = None) -> list:
        return [getattr(self.venv, attr_name)] * len(self._indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        setattr(self.venv, attr_name, value)

    def env_method(self, method_name: str, *args: Any, indices: Any = None, **kwargs: Any):
        return [getattr(self.venv, method_name)(*args, **kwargs)
                for _ in self._indices(indices)]

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list:
        return [False] * len(self._indices(indices))

    def _indices(self, indices: Any) -> list:
        if indices is None:
            return list(range(self.num_envs))
        return [indices] if isinstance(indices, int) else list(indices)
