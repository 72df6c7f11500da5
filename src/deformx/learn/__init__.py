"""Robot learning on DeformX (extra ``[learn]``): the paper's hit-target rope-swinging task as
Gymnasium environments.

``import deformx`` (with Gymnasium installed) registers ``deformx/HitTarget-v0``::

    import gymnasium as gym
    import deformx  # noqa: F401

    env = gym.make("deformx/HitTarget-v0", target=(0.0, 2.0, 1.5), rope="cosserat")
    envs = gym.make_vec("deformx/HitTarget-v0", num_envs=64,
                        vectorization_mode="vector_entry_point")  # one world, one model

See ``docs/learning.md``.
"""

from __future__ import annotations

from .hit_target import HitTargetEnv
from .task import HitTargetConfig

__all__ = ["HitTargetConfig", "HitTargetEnv"]
