"""The hit-target task's numbers (:class:`HitTargetConfig`: the authors' task by default) and
its starting shape."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

ROPES = ("cosserat", "capsule")
# The rope parameters a task may randomise (HitTargetConfig.randomise keys).
RANDOMISABLE = ("youngs_modulus", "density", "damping")


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
    youngs_modulus: float = 2e5              # Pa, bending (the authors' calibrated value)
    damping: float = 0.1                     # 1/s
    internal_damping: float = 0.0            # s, Kelvin-Voigt (stable integrator only)
    # Pa: a rope stretches and shears like its fibres, not like its bending; None gives the
    # authors' (E and E / 3), whose rope stretches ~100 % at the clamp at 8 m/s (docs/learning.md)
    stretch_modulus: float | None = 2e7
    shear_modulus: float | None = 6.7e6
    # Pa: the rope twists as the authors' does (None: E / 3, following a randomised E); the
    # shear modulus above would make it 67x stiffer in twist than in bending, which kinks and
    # stalls Newton when the rope folds (docs/learning.md)
    twist_modulus: float | None = None
    max_strain: float = 1.0                  # element strain the engine calls a divergence
    rope_dt: float = 2e-3                    # s, Cosserat rope's step (one per control step)
    integrator: str = "stable"               # Cosserat rope: "stable" or "verlet" (explicit)
    order: int = 2                           # stable integrator: 2 BDF2, 1 backward Euler
    ground_stiffness: float = 100.0          # N/m per node
    # the clamp carried on continuously across control steps (CoSimulation's
    # continuous_drivers): what a sub-stepped rope needs to converge in its step; None: on
    # when rope_dt sub-steps the control step, off with one rope step per control step
    continuous_drivers: bool | None = None
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
    # the hit-apple variant: distance in 3D instead of the swing plane, and a reward for the
    # tip's horizontal speed (m/s) while within strike_radius of the target
    distance: str = "plane"                  # "plane" (y-z) or "3d"
    w_strike: float = 0.0
    strike_radius: float = 0.1
    # randomisation of the rope (fractions, uniform +-), redrawn at every reset of an
    # episode and changed in place (HitTargetBatch.set_rope)
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
        for name in ("stretch_modulus", "shear_modulus", "twist_modulus"):
            if getattr(self, name) is not None and not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0 Pa or None, got {getattr(self, name)!r}")
        if self.distance not in ("plane", "3d"):
            raise ValueError(f"distance must be 'plane' or '3d', got {self.distance!r}")
        unknown = set(self.randomise) - set(RANDOMISABLE)
        if unknown:
            raise ValueError(f"randomise: only {', '.join(RANDOMISABLE[:-1])} and "
                             f"{RANDOMISABLE[-1]}, got {sorted(unknown)}")

    def twist_of(self, youngs_modulus: float) -> float:
        """The rope's twist modulus (Pa) for a bending modulus ``youngs_modulus`` (Pa)."""
        return self.twist_modulus if self.twist_modulus is not None else youngs_modulus / 3.0

    @property
    def step_limit(self) -> float:
        """Largest joint increment per control step (rad)."""
        return self.vel_limit * self.control_dt * self.action_scale


def rot_x(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def initial_rope(top: np.ndarray, length: float, n: int, radius: float,
                 along: np.ndarray = np.array([0.0, 1.0, 0.0])) -> np.ndarray:
    """``n + 1`` nodes exactly ``length / n`` apart (so a capsule chain fits them too) from
    ``top`` straight down to the ground (z = radius), the rest lying on it along ``along``."""
    from ..apps.calibration import resample

    corner = np.array([top[0], top[1], max(float(top[2]), radius)])
    corner[2] = radius
    poly = np.array([top, corner, corner + 2.0 * length * along])
    return resample(poly, n, exact=length / n)
