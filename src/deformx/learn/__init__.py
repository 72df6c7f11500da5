"""Robot learning on DeformX (extra ``[learn]``): the paper's hit-target rope-swinging task as
Gymnasium environments.

``import deformx.learn`` registers ``deformx/HitTarget-v0``::

    import gymnasium as gym
    import deformx.learn  # noqa: F401  (or gym.register_envs(deformx.learn))

    env = gym.make("deformx/HitTarget-v0", target=(0.0, 2.0, 1.5), rope="cosserat")

See ``docs/learning.md``.
"""

from __future__ import annotations

import gymnasium as _gym

from .hit_target import HitTargetConfig, HitTargetEnv

__all__ = ["HitTargetConfig", "HitTargetEnv"]

if "deformx/HitTarget-v0" not in _gym.registry:
    _gym.register(id="deformx/HitTarget-v0", entry_point="deformx.learn.hit_target:HitTargetEnv",
                  disable_env_checker=False)
