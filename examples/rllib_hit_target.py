"""Train the hit-target task with Ray RLlib's PPO (new API stack, torch), query the policy and
save a checkpoint: the single environment through the Gymnasium API, so RLlib's env runners
(on this machine or a cluster) each make their own copy.

    pip install ".[rllib]"
    python examples/rllib_hit_target.py                  # 5 iterations, in this process
    python examples/rllib_hit_target.py --runners 2 --iterations 50 --out runs/rllib

The environment id is given as ``"deformx:deformx/HitTarget-v0"``: the ``module:`` prefix makes
Gymnasium import deformx (which registers the id) inside every remote env runner, where the
plain id is unknown. stable-baselines3 with the batched vector environment (``deformx train
hit-target``) is the faster route on one machine: one kernel call steps every rope.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

ENV_ID = "deformx:deformx/HitTarget-v0"


def build(target: tuple, runners: int, episode_steps: int, settle_time: float, batch: int,
          seed: int):
    """An RLlib PPO algorithm on the hit-target task (the authors' PPO numbers: lr 3e-4,
    gamma 0.99, clip 0.2, 4 epochs, 256-128 tanh networks)."""
    from ray.rllib.algorithms.ppo import PPOConfig

    config = (
        PPOConfig()
        .framework("torch")
        .environment(ENV_ID, env_config=dict(target=target, episode_steps=episode_steps,
                                             settle_time=settle_time))
        .env_runners(num_env_runners=runners, num_envs_per_env_runner=1)
        .learners(num_learners=0)
        .training(train_batch_size_per_learner=batch, minibatch_size=min(64, batch),
                  num_epochs=4, lr=3e-4, gamma=0.99, clip_param=0.2, grad_clip=0.5)
        .rl_module(model_config={"fcnet_hiddens": [256, 128], "fcnet_activation": "tanh"})
        .debugging(seed=seed)
    )
    return config.build_algo()


def act(algo, obs):
    """The policy's deterministic action for one observation (18,)."""
    import numpy as np
    import torch
    from ray.rllib.core.columns import Columns

    module = algo.get_module()
    with torch.no_grad():
        out = module.forward_inference({Columns.OBS: torch.as_tensor(obs[None])})
    dist = module.get_inference_action_dist_cls().from_logits(out[Columns.ACTION_DIST_INPUTS])
    return np.clip(dist.to_deterministic().sample()[0].numpy(), -1.0, 1.0).astype(np.float32)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--target", type=float, nargs=3, default=(0.0, 2.0, 1.5), metavar="M")
    p.add_argument("--iterations", type=int, default=5)
    p.add_argument("--runners", type=int, default=0, help="remote env runners (0: in process)")
    p.add_argument("--batch", type=int, default=1024, help="environment steps per iteration")
    p.add_argument("--episode-steps", type=int, default=700)
    p.add_argument("--settle-time", type=float, default=1.0, help="s, at every reset")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", type=Path, default=Path("runs/rllib"), help="checkpoint folder")
    args = p.parse_args()

    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")  # nothing leaves this machine
    import ray

    import deformx.learn

    ray.init(num_cpus=max(2, args.runners + 1), include_dashboard=False)
    algo = build(tuple(args.target), args.runners, args.episode_steps, args.settle_time,
                 args.batch, args.seed)
    for i in range(args.iterations):
        t = time.perf_counter()
        res = algo.train()
        runners = res.get("env_runners", {})
        print(f"iteration {i + 1}: {time.perf_counter() - t:.1f} s, return "
              f"{runners.get('episode_return_mean', float('nan')):.2f}, "
              f"{res.get('num_env_steps_sampled_lifetime')} steps")
    path = algo.save_to_path(str(args.out.resolve()))
    env = deformx.learn.HitTargetEnv(target=tuple(args.target),
                                     episode_steps=args.episode_steps,
                                     settle_time=args.settle_time)
    obs, info = env.reset(seed=args.seed)
    d_min, done = info["d_min"], False
    while not done:
        obs, _, terminated, truncated, info = env.step(act(algo, obs))
        d_min, done = info["d_min"], terminated or truncated
    print(f"checkpoint: {path}; deterministic rollout d_min = {100 * d_min:.1f} cm")
    algo.stop()
    ray.shutdown()


if __name__ == "__main__":
    main()
