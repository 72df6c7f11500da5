"""PPO on the hit-target task (stable-baselines3, extra ``[learn]``), resumable, and what a
trained policy is judged by: the joint-command trajectories it generates in simulation (its
deterministic rollout and ``rollouts - 1`` more with its own exploration noise, as the paper
"first uses the trained policy to generate successful joint-command trajectories"), the best
one's ``d_min``, that trajectory as a CSV a real UR5e replays open loop (control rate), and
that replay.

The authors' PPO (their own implementation) and SB3's nearest settings:

| authors (RL_Demo/RL/algos/ppo.py) | here (SB3 PPO) |
| --- | --- |
| actor and critic 18-256-128, tanh (actor mean squashed by a last tanh) | ``net_arch=dict(pi=[256, 128], vf=[256, 128])``, ``Tanh`` (mean not squashed; actions are clipped) |
| Gaussian policy, fixed covariance diag(0.5) ("action_std" 0.5 as a variance) | std sqrt(0.5) = 0.707, ``log_std`` frozen |
| lr 3e-4, gamma 0.99, clip 0.2, 4 epochs | the same |
| rollout 64 steps per environment | ``n_steps=64`` |
| gradient clip 0.5 | ``max_grad_norm=0.5`` |
| 4 environments | ``num_envs`` (one batch: one world, one MuJoCo model) |
| each epoch one full-batch gradient step | ``minibatches=1`` (``batch_size = num_envs * 64``) |
| Monte Carlo returns, normalised; advantage = return - value | ``gae_lambda=1`` (SB3 bootstraps at the rollout's end and normalises advantages) |

A run directory holds ``checkpoints/latest.zip`` (written every ``checkpoint_every`` steps by
a rename, so a kill loses at most that much; with ``normalize``, ``vecnormalize.pkl`` beside
it and beside ``policy.zip``), ``episodes.csv`` (one row per finished episode,
appended), ``tb/`` (TensorBoard), and at the end ``policy.zip``, ``learning_curve.png``,
``best_rollout.csv`` (time, six joint targets), ``best_rollout.mp4`` and ``summary.json``.
``TrainSettings.deploy`` generates and chooses the trajectories on a finer rope than training
can afford (its step, elements, order); the policy is closed loop and steers that rope too.
"""

from __future__ import annotations

import csv
import json
import math
import os
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
import numpy as np

from .task import HitTargetConfig


@dataclass
class TrainSettings:
    """What ``deformx train hit-target`` runs (SI units where they apply)."""

    total_steps: int = 200_000               # environment steps, all environments together
    num_envs: int = 16
    rollout: int = 64                        # steps per environment per PPO update
    epochs: int = 4
    learning_rate: float = 3e-4
    gamma: float = 0.99
    clip: float = 0.2
    std: float = math.sqrt(0.5)              # fixed policy std (the authors' variance 0.5)
    minibatches: int = 1                     # per epoch (the authors: the whole batch)
    gae_lambda: float = 1.0
    grad_clip: float = 0.5
    seed: int = 0
    checkpoint_every: int = 20_000           # environment steps
    video: bool = True
    normalize: bool = False                  # observations and rewards by SB3's VecNormalize
    rollouts: int = 64                       # policy rollouts drawn after training (1: the
                                             # deterministic one only); the best is exported
    select: str = "best"                     # "best": least d_min on the training rope (the
                                             # paper); "robust": least worst d_min over it and
                                             # ROBUST_MODELS (Cosserat rope only; with deploy:
                                             # over the deployment rope and
                                             # ``robust_draws`` perturbed draws of it)
    robust_draws: int = 2                    # perturbed draws of the deployment rope a
                                             # robust choice with deploy replays on
    robust_pool: int = 0                     # a robust choice among the robust_pool
                                             # trajectories best on the rope they were drawn
                                             # on (0: all): more rollouts for as many replays
    robust_within: float = 0.0               # m: a robust choice among the trajectories
                                             # within this d_min on the rope they were drawn
                                             # on (0: no bound; none within: among all)
    task: dict = field(default_factory=dict)  # HitTargetConfig overrides (target, rope, ...)
    deploy: dict = field(default_factory=dict)  # HitTargetConfig changes of the training rope
                                                # for the rope the trajectories are generated
                                                # and chosen on (default: the training rope)

    def __post_init__(self) -> None:
        for name in ("total_steps", "num_envs", "rollout", "epochs", "checkpoint_every",
                     "minibatches", "rollouts", "robust_draws"):
            v = getattr(self, name)
            if not isinstance(v, (int, np.integer)) or v < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {v!r}")
        if not isinstance(self.robust_pool, (int, np.integer)) or self.robust_pool < 0:
            raise ValueError(f"robust_pool must be an integer >= 0 (0: every rollout), got "
                             f"{self.robust_pool!r}")
        if not (isinstance(self.robust_within, (int, float, np.floating))
                and 0.0 <= self.robust_within < math.inf):
            raise ValueError(f"robust_within must be a distance >= 0 m (0: no bound), got "
                             f"{self.robust_within!r}")
        if self.select not in ("best", "robust"):
            raise ValueError(f"select must be 'best' or 'robust', got {self.select!r}")
        if self.deploy:
            if self.task.get("rope", "cosserat") != "cosserat":
                raise ValueError("deploy changes the Cosserat rope: it needs rope='cosserat'")
            unknown = sorted(set(self.deploy) - DEPLOYABLE)
            if unknown:
                raise ValueError(f"deploy: {', '.join(unknown)} cannot be changed for "
                                 f"deployment; valid: {', '.join(sorted(DEPLOYABLE))}")
        if self.select == "robust" and self.task.get("rope", "cosserat") != "cosserat":
            raise ValueError("select='robust' replays on other Cosserat ropes: it needs "
                             "rope='cosserat'")


# What may differ between the rope a policy is trained on and the one its trajectories are
# generated on (the discretisation, not the task or the rope's material).
DEPLOYABLE = {"n_elements", "rope_dt", "order", "continuous_drivers"}
# Relative spread (uniform +-) of the rope parameters for replays on a perturbed rope: the
# stand-in for the paper's repeats on the real rope, and one of the robust choice's models.
REPLAY_PERTURBATION = {"youngs_modulus": 0.1, "density": 0.05, "damping": 0.2}
# The ropes a "robust" choice replays every sampled trajectory on, as HitTargetConfig changes
# of the training rope: its parameters perturbed, finer steps (BDF2 0.5 ms, backward Euler
# 0.1 ms) and twice the elements at 0.25 ms. A whip that passes the target in one model only
# is chaos the sampling happened to catch (docs/learning.md, Results).
ROBUST_MODELS = ({"randomise": REPLAY_PERTURBATION},
                 {"rope_dt": 5e-4}, {"order": 1, "rope_dt": 1e-4},
                 {"n_elements": 40, "rope_dt": 2.5e-4})
# With ``deploy`` the trajectories are generated on a rope as fine as a reference, so a
# "robust" choice replays them on perturbed draws of it instead, seeded from here on (apart
# from the replays' 1 and 2, whose draws the tables report).
DEPLOY_ROBUST_FIRST_SEED = 11


def deployed(config: HitTargetConfig, deploy: dict) -> HitTargetConfig:
    """The rope ``TrainSettings.deploy`` describes: ``config`` with those changes, nominal
    (not randomised); a new step without its own clamp setting takes the task's default rule
    (the clamp carried on continuously where the step sub-steps the control step)."""
    changes = dict(deploy)
    if "rope_dt" in changes:
        changes.setdefault("continuous_drivers", None)
    return replace(config, randomise={}, **changes)


def _ppo():
    try:
        from stable_baselines3 import PPO
    except ImportError as err:  # pragma: no cover - the [learn] extra
        raise ImportError("training needs stable-baselines3 and torch: python -m pip install "
                          "'deformx[learn]'") from err
    return PPO


def make_model(settings: TrainSettings, env, tensorboard: str | None = None):
    """A PPO model with the authors' settings mapped to SB3 (module docstring)."""
    import torch

    PPO = _ppo()
    n = settings.num_envs * settings.rollout
    model = PPO("MlpPolicy", env, learning_rate=settings.learning_rate,
                n_steps=settings.rollout, batch_size=max(2, n // settings.minibatches),
                n_epochs=settings.epochs, gamma=settings.gamma, gae_lambda=settings.gae_lambda,
                clip_range=settings.clip, max_grad_norm=settings.grad_clip,
                policy_kwargs=dict(net_arch=dict(pi=[256, 128], vf=[256, 128]),
                                   activation_fn=torch.nn.Tanh,
                                   log_std_init=math.log(settings.std)),
                tensorboard_log=tensorboard, seed=settings.seed, device="cpu", verbose=0)
    model.policy.log_std.requires_grad_(False)  # fixed exploration noise, as the authors'
    return model


def _callback(out: Path, settings: TrainSettings, progress: bool):
    from stable_baselines3.common.callbacks import BaseCallback

    from ..engine.running import progress_bar

    class Track(BaseCallback):
        """Episode rows to episodes.csv, d_min to TensorBoard, checkpoints, progress."""

        def _on_training_start(self) -> None:
            self.returns = np.zeros(settings.num_envs)
            self.lengths = np.zeros(settings.num_envs, dtype=np.int64)
            self.next_checkpoint = (self.num_timesteps // settings.checkpoint_every + 1) * \
                settings.checkpoint_every
            self.csv = open(out / "episodes.csv", "a", newline="")
            self.writer = csv.writer(self.csv)
            if self.csv.tell() == 0:
                self.writer.writerow(["timesteps", "return", "length", "d_min", "d_min_3d",
                                      "success"])
            self.bar_cm = progress_bar("PPO (environment steps)", settings.total_steps,
                                       progress)
            self.bar = self.bar_cm.__enter__()
            self.bar(self.num_timesteps)  # a resumed run starts where it stopped

        def _on_step(self) -> bool:
            norm = self.model.get_vec_normalize_env()
            self.returns += norm.get_original_reward() if norm is not None else \
                self.locals["rewards"]
            self.lengths += 1
            for i in np.flatnonzero(self.locals["dones"]):
                info = self.locals["infos"][i]
                self.writer.writerow([self.num_timesteps, f"{self.returns[i]:.6g}",
                                      int(self.lengths[i]), f"{info['episode_d_min']:.6g}",
                                      f"{info['episode_d_min_3d']:.6g}",
                                      int(info["episode_success"])])
                self.logger.record_mean("hit/return", float(self.returns[i]))
                self.logger.record_mean("hit/d_min", info["episode_d_min"])
                self.returns[i] = 0.0
                self.lengths[i] = 0
            if self.num_timesteps >= self.next_checkpoint:
                save_checkpoint(self.model, out)
                self.csv.flush()
                self.next_checkpoint += settings.checkpoint_every
            self.bar(self.num_timesteps)
            return True

        def _on_training_end(self) -> None:
            self.csv.close()
            self.bar_cm.__exit__(None, None, None)

    return Track()


def save_checkpoint(model, out: Path) -> Path:
    """``checkpoints/latest.zip`` by a rename: never a half-written checkpoint."""
    ckpt = out / "checkpoints"
    ckpt.mkdir(parents=True, exist_ok=True)
    norm = model.get_vec_normalize_env()
    if norm is not None:  # the statistics first: a checkpoint never lacks its own
        norm.save(ckpt / "vecnormalize.tmp.pkl")
        os.replace(ckpt / "vecnormalize.tmp.pkl", ckpt / "vecnormalize.pkl")
    tmp = ckpt / "latest.tmp.zip"
    model.save(tmp)
    os.replace(tmp, ckpt / "latest.zip")
    return ckpt / "latest.zip"


def train(out: str | Path, settings: TrainSettings | None = None, resume: bool = True,
          progress: bool = True) -> dict:
    """Train PPO on the hit-target task into ``out`` (see the module docstring); with
    ``resume`` an existing ``checkpoints/latest.zip`` there is continued. Returns the
    summary (also in ``summary.json``)."""
    from .sb3 import SB3VecEnv
    from .vector import HitTargetVecEnv

    settings = settings or TrainSettings()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    config = HitTargetConfig(**settings.task)
    (out / "settings.json").write_text(json.dumps(
        {"train": {k: v for k, v in asdict(settings).items() if k != "task"},
         "task": asdict(config)}, indent=1, default=str))
    venv = SB3VecEnv(HitTargetVecEnv(settings.num_envs, config=config, seed=settings.seed))
    latest = out / "checkpoints" / "latest.zip"
    if settings.normalize:
        from stable_baselines3.common.vec_env import VecNormalize

        stats = out / "checkpoints" / "vecnormalize.pkl"
        venv = VecNormalize.load(stats, venv) if resume and stats.is_file() else \
            VecNormalize(venv, gamma=settings.gamma)
    if resume and latest.is_file():
        model = _ppo().load(latest, env=venv, device="cpu")
        model.policy.log_std.requires_grad_(False)
    else:
        model = make_model(settings, venv, tensorboard=str(out / "tb"))
    remaining = settings.total_steps - model.num_timesteps
    if remaining > 0:
        model.learn(remaining, callback=_callback(out, settings, progress),
                    reset_num_timesteps=False, tb_log_name="ppo")
        save_checkpoint(model, out)
    model.save(out / "policy.zip")
    norm = model.get_vec_normalize_env()
    if norm is not None:
        norm.save(out / "vecnormalize.pkl")
    venv.close()

    def mean_action(obs: np.ndarray) -> np.ndarray:
        return model.predict(norm.normalize_obs(obs) if norm is not None else obs,
                             deterministic=True)[0]

    # As the paper deploys it: the trained policy generates joint-command trajectories in
    # simulation (its own exploration noise), and the best one is replayed open loop - on the
    # nominal rope, also where training randomised it (and the robust choice's other models);
    # with ``deploy``, on a finer rope than training could afford (the policy is closed loop:
    # it steers that rope as it steered the training one).
    config = deployed(config, settings.deploy)
    samples = sample_rollouts(mean_action, config, n=settings.rollouts, std=settings.std,
                              seed=settings.seed)
    scores = {"d_min": np.where(samples["diverged"], np.inf, samples["d_min"])}
    n = len(samples["actions"])
    # the trajectories a robust choice replays: the pool best where they were drawn
    pool = (np.argsort(scores["d_min"], kind="stable")[:settings.robust_pool]
            if settings.robust_pool else np.arange(n))

    def on(rope: HitTargetConfig, seed: int) -> np.ndarray:  # NaN: not in the pool
        d = np.full(n, np.nan)
        d[pool] = replay_actions([samples["actions"][i] for i in pool], rope, seed=seed)
        return d

    if settings.select == "robust" and settings.deploy:
        perturbed = replace(config, randomise=REPLAY_PERTURBATION)
        for k in range(DEPLOY_ROBUST_FIRST_SEED,
                       DEPLOY_ROBUST_FIRST_SEED + settings.robust_draws):
            scores[f"perturbed_seed{k}"] = on(perturbed, k)
    elif settings.select == "robust":
        for k, m in enumerate(ROBUST_MODELS):
            scores[";".join(f"{a}={b}" for a, b in m.items() if a != "randomise")
                   or f"perturbed_seed{k + 1}"] = on(replace(config, **m), k + 1)
    score = np.nan_to_num(np.max(list(scores.values()), axis=0), nan=np.inf)
    if settings.select == "robust" and settings.robust_within > 0.0:
        # the least worst among those as close as asked where they were drawn, if any is
        within = (scores["d_min"] <= settings.robust_within) & np.isfinite(score)
        if within.any():
            score = np.where(within, score, np.inf)
    # every sampled trajectory's d_min (m) on each rope the choice looked at (nan: not
    # replayed there)
    np.savetxt(out / "rollout_scores.csv", np.column_stack(list(scores.values())),
               delimiter=",", header=",".join(scores), comments="", fmt="%.6g")
    best = int(np.argmin(score))
    result = rollout(_playback(samples["actions"][best]), config,
                     video=out / "best_rollout.mp4" if settings.video else None)
    export_trajectory(out / "best_rollout.csv", result["times"], result["joint_targets"])
    curve = plot_learning_curve(out / "episodes.csv", out / "learning_curve.png")
    summary = {"timesteps": int(model.num_timesteps), "d_min": result["d_min"],
               "d_min_3d": result["d_min_3d"], "success": result["success"],
               "rollouts": settings.rollouts, "best_rollout": best, "select": settings.select,
               "robust_within": settings.robust_within,
               "deploy": dict(settings.deploy),
               "worst_d_min": max(float(score[best]), result["d_min"]),
               "d_min_deterministic": float(samples["d_min"][0]),
               "d_min_sampled_median": float(np.median(samples["d_min"])),
               "successes_sampled": int(samples["success"].sum()),
               "learning_curve": str(curve) if curve else None}
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    return summary


def rollout(policy, config: HitTargetConfig, video: str | Path | None = None,
            seed: int = 0) -> dict:
    """The deterministic rollout of ``policy`` (an SB3 model, or a callable obs -> action)
    on one environment: ``d_min``, ``d_min_3d``, ``success``, ``times`` and the commanded
    ``joint_targets`` (steps, 6) - the open-loop trajectory."""
    from .hit_target import HitTargetEnv

    render = video is not None and config.rope == "cosserat"
    env = HitTargetEnv(config=config, render_mode="rgb_array" if render else None)
    obs, info = env.reset(seed=seed)
    act = policy if callable(policy) else (lambda o: policy.predict(o, deterministic=True)[0])
    targets, frames = [], []
    every = max(1, int(round(1.0 / (30 * config.control_dt))))  # ~30 frames per second
    for k in range(config.episode_steps):
        obs, _, terminated, truncated, info = env.step(act(obs))
        targets.append(info["joint_targets"])
        if render and k % every == 0:
            frames.append(env.render())
        if terminated or truncated:
            break
    if render and frames:
        import imageio.v2 as imageio

        imageio.mimwrite(str(video), frames, fps=30, macro_block_size=1)
    env.close()
    times = config.control_dt * np.arange(1, len(targets) + 1)
    return {"d_min": info["d_min"], "d_min_3d": info["d_min_3d"], "success": info["success"],
            "times": times, "joint_targets": np.array(targets)}


def sample_rollouts(policy, config: HitTargetConfig, n: int = 64, std: float = 0.0,
                    seed: int = 0) -> dict:
    """``n`` episodes of ``policy`` (a callable: observations (n, 18) -> mean actions) stepped
    together in one batch: rollout 0 takes the mean actions, the others the mean plus
    Gaussian noise of ``std`` (the policy's exploration; seeded by ``seed``), clipped to
    [-1, 1]. Returns per rollout ``d_min``, ``d_min_3d`` (m), ``success``, ``diverged``
    (the rope stopped: the episode was cut short there), ``steps`` and
    ``actions`` (a list of (steps, 3) arrays, each up to its episode's end)."""
    from .batch import HitTargetBatch

    if not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n must be an integer >= 1, got {n!r}")
    if not std >= 0.0:
        raise ValueError(f"std must be >= 0, got {std!r}")
    rng = np.random.default_rng(seed)
    batch = HitTargetBatch(config, n)  # every copy starts reset
    live = np.ones(n, dtype=bool)
    d_min, d_min_3d = batch.d_min.copy(), batch.d_min_3d.copy()
    success = np.zeros(n, dtype=bool)
    failed = np.zeros(n, dtype=bool)
    steps = np.zeros(n, dtype=np.int64)
    taken = []  # (n, 3) per step; copy i's episode is its first steps[i] rows
    for _ in range(config.episode_steps):
        a = np.asarray(policy(batch.observations()), dtype=np.float64).reshape(n, -1)
        noise = rng.standard_normal(a.shape)
        noise[0] = 0.0
        a = np.clip(a + std * noise, -1.0, 1.0)
        _, terminated, truncated, won, diverged = batch.step(a)
        taken.append(a)
        steps += live
        ok = live & ~diverged  # a diverged copy was put back: its last values stand
        d_min = np.where(ok, batch.d_min, d_min)
        d_min_3d = np.where(ok, batch.d_min_3d, d_min_3d)
        success |= live & won
        failed |= live & diverged
        live &= ~(terminated | truncated)
        if not live.any():
            break
    taken = np.array(taken)
    return {"d_min": d_min, "d_min_3d": d_min_3d, "success": success, "diverged": failed,
            "steps": steps, "actions": [taken[:k, i] for i, k in enumerate(steps)]}


def replay_actions(actions: list, config: HitTargetConfig, seed: int = 0) -> np.ndarray:
    """In-plane d_min (m) of each action sequence (as ``sample_rollouts`` returns them) replayed
    open loop on ``config``'s rope, all in one batch (``config.randomise``: each copy's rope
    drawn by ``seed``); each counts its own episode's steps only; inf where the rope diverged.
    The joint commands depend on the actions alone, so this replays the same trajectories."""
    from .batch import HitTargetBatch, with_params

    n = len(actions)
    steps = np.array([len(a) for a in actions])
    if n == 0 or steps.max() == 0:
        raise ValueError("actions: no action sequence to replay")
    rng = np.random.default_rng(seed)
    cfg = replace(config, episode_steps=max(config.episode_steps, int(steps.max())))
    batch = HitTargetBatch(cfg, n, params=[with_params(cfg, rng) for _ in range(n)])
    d_min = np.full(n, np.inf)
    failed = np.zeros(n, dtype=bool)
    padded = np.zeros((int(steps.max()), n, len(cfg.active_joints)))  # zeros: commands hold
    for i, a in enumerate(actions):
        padded[:len(a), i] = a
    for k, a in enumerate(padded):
        live = steps > k
        _, _, _, _, diverged = batch.step(a)
        failed |= live & diverged
        d_min = np.where(live, np.minimum(d_min, batch.d), d_min)
    return np.where(failed, np.inf, d_min)


def _playback(actions: np.ndarray):
    """A policy that plays ``actions`` back in order (then zeros: the commands hold)."""
    actions = np.asarray(actions)
    it = iter(actions)
    hold = np.zeros(actions.shape[1])
    return lambda obs: next(it, hold)


def export_trajectory(path: str | Path, times: np.ndarray, joint_targets: np.ndarray) -> Path:
    """CSV a UR5e can replay: ``time`` (s) and the six joint targets (rad) at the control
    rate (the paper's open-loop deployment)."""
    from deformx.robots import JOINTS

    path = Path(path)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time"] + list(JOINTS))
        for t, q in zip(times, joint_targets):
            w.writerow([f"{t:.6f}"] + [f"{v:.9f}" for v in q])
    return path


def load_trajectory(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """(times, joint_targets (steps, 6)) from :func:`export_trajectory`'s CSV."""
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    if data.shape[1] != 7:
        raise ValueError(f"{path}: expected 7 columns (time and six joints), got "
                         f"{data.shape[1]}")
    return data[:, 0], data[:, 1:]


def replay(joint_targets: np.ndarray, config: HitTargetConfig, n: int = 1,
           perturb: dict | None = None, seed: int = 0) -> np.ndarray:
    """Replay a joint-command trajectory open loop ``n`` times (``perturb``: rope parameter
    fractions drawn per replay, e.g. ``{"youngs_modulus": 0.1}``); returns each replay's
    in-plane ``d_min`` (m), inf for a replay whose rope diverged (the simulator stopped:
    no distance to report)."""
    from dataclasses import replace

    from .batch import HitTargetBatch, with_params

    rng = np.random.default_rng(seed)
    cfg = replace(config, randomise=dict(perturb or {}),
                  episode_steps=max(config.episode_steps, len(joint_targets)))
    params = [with_params(cfg, rng) for _ in range(n)]
    batch = HitTargetBatch(cfg, n, params=params)
    d_min = np.full(n, np.inf)
    failed = np.zeros(n, dtype=bool)
    for q in np.asarray(joint_targets, dtype=np.float64):
        batch.q_cmd[:] = q  # the trajectory itself; actions of zero leave it as it is
        _, terminated, _, _, diverged = batch.step(np.zeros((n, len(cfg.active_joints))))
        failed |= diverged
        d_min = np.minimum(d_min, batch.d)
    return np.where(failed, np.inf, d_min)


def plot_learning_curve(episodes_csv: str | Path, png: str | Path) -> Path | None:
    """Return and d_min per episode against environment steps (a moving mean over 50)."""
    path = Path(episodes_csv)
    if not path.is_file():
        return None
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if len(rows) < 2:
        return None
    data = {key: np.array([float(r[key]) for r in rows]) for key in rows[0]}
    size = len(rows)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    k = max(1, min(50, size // 5))
    smooth = np.ones(k) / k
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.6))
    for ax, key, label in ((a, "return", "episode return"), (b, "d_min", "d_min (m)")):
        ax.plot(data["timesteps"], data[key], ".", ms=2, alpha=0.3)
        if size >= k:
            ax.plot(data["timesteps"][k - 1:], np.convolve(data[key], smooth, "valid"))
        ax.set_xlabel("environment steps")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return Path(png)


__all__ = ["TrainSettings", "train", "rollout", "replay", "export_trajectory",
           "load_trajectory", "plot_learning_curve", "make_model"]
