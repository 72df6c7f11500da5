"""Ray RLlib trains on the hit-target environment through the Gymnasium API
(examples/rllib_hit_target.py). Needs the [rllib] extra; CI installs it in its numpy 1.x
environment (ray pins gymnasium 1.2.2, the main environment keeps the newest)."""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path

import numpy as np
import pytest

ray = pytest.importorskip("ray")
pytest.importorskip("ray.rllib")


@pytest.fixture(scope="module")
def example():
    spec = importlib.util.spec_from_file_location(
        "rllib_hit_target", Path(__file__).resolve().parents[1] / "examples" / "rllib_hit_target.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    ray.init(num_cpus=2, include_dashboard=False)
    yield mod
    ray.shutdown()


def test_rllib_ppo_trains_acts_and_restores_its_checkpoint(example, tmp_path):
    from ray.rllib.algorithms.algorithm import Algorithm

    import deformx.learn

    algo = example.build((0.0, 2.0, 1.5), runners=0, episode_steps=40, settle_time=0.2,
                         batch=128, seed=0)
    steps = []
    for _ in range(2):
        res = algo.train()
        steps.append(res["num_env_steps_sampled_lifetime"])
        assert np.isfinite(res["env_runners"]["episode_return_mean"])
    assert steps[0] >= 128 and steps[1] >= steps[0] + 128
    env = deformx.learn.HitTargetEnv(target=(0.0, 2.0, 1.5), episode_steps=40, settle_time=0.2)
    obs, _ = env.reset(seed=1)
    a = example.act(algo, obs)
    assert a.shape == (3,) and env.action_space.contains(a)
    _, reward, *_ = env.step(a)
    assert np.isfinite(reward)
    algo.save_to_path(str(tmp_path))
    algo.stop()
    restored = Algorithm.from_checkpoint(str(tmp_path))
    np.testing.assert_array_equal(example.act(restored, obs), a)
    restored.stop()
    env.close()
