"""Clamps: prescribed position (and material frame) of a node/element, drivable between steps."""

from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

import numpy as np

from .kernels.so3 import axis_angle_matrix
from .validation import vector3

if TYPE_CHECKING:
    from .rod import Rod


class Clamp:
    """Holds a rod node at a position and (optionally) an element at a material frame.

    Between calls to :meth:`set_pose` / :meth:`set_velocity` the pose moves at the set linear
    (m/s) and angular (rad/s, lab frame) velocity, so a robot gripper can drive a rod end along
    a trajectory by updating the clamp once per control step.
    """

    def __init__(self, rod: "Rod", node: int, element: int | None) -> None:
        self.rod = rod
        self.node = int(node)
        self.element = None if element is None else int(element)
        self._t0 = self._now()
        self._pos0 = rod.positions[self.node].copy()
        self._Q0 = None if element is None else rod.directors[self.element].copy()
        self._vel = np.zeros(3)
        self._omega = np.zeros(3)

    def _now(self) -> float:
        world = self.rod._world
        return 0.0 if world is None else world.time

    def _changed(self) -> None:
        if self.rod._world is not None:
            self.rod._world._dirty = True

    @property
    def holds_frame(self) -> bool:
        """True if the clamp also fixes the material frame of its element."""
        return self._Q0 is not None

    @property
    def position(self) -> np.ndarray:
        """Clamp position now (m)."""
        return self._pos0 + (self._now() - self._t0) * self._vel

    @property
    def directors(self) -> np.ndarray | None:
        """Clamped material frame now, rows d1, d2, d3 (None for a pin)."""
        if self._Q0 is None:
            return None
        tau = self._now() - self._t0
        speed = float(np.linalg.norm(self._omega))
        R = axis_angle_matrix(self._omega, speed * tau)
        return self._Q0 @ R.T

    @property
    def velocity(self) -> np.ndarray:
        """Linear velocity (m/s)."""
        return self._vel.copy()

    @property
    def angular_velocity(self) -> np.ndarray:
        """Angular velocity (rad/s, lab frame)."""
        return self._omega.copy()

    def _rebase(self) -> None:
        pos, Q = self.position, self.directors
        self._t0 = self._now()
        self._pos0 = pos
        if Q is not None:
            self._Q0 = Q

    def set_pose(self, position: Sequence[float] | None = None,
                 directors: np.ndarray | None = None) -> None:
        """Move the clamp now to ``position`` (m) and, for a frame clamp, ``directors``
        (3x3 rotation, rows d1, d2, d3)."""
        self._rebase()
        if position is not None:
            self._pos0 = vector3("position", position)
        if directors is not None:
            if self._Q0 is None:
                raise ValueError("directors: this clamp is a pin (position only); use fix_start/fix_end")
            Q = np.asarray(directors, dtype=np.float64)
            if Q.shape != (3, 3) or not np.allclose(Q @ Q.T, np.eye(3), atol=1e-8) or np.linalg.det(Q) < 0:
                raise ValueError("directors must be a 3x3 proper rotation matrix (rows d1, d2, d3)")
            self._Q0 = Q.copy()
        self._changed()

    def set_velocity(self, velocity: Sequence[float] | None = None,
                     angular_velocity: Sequence[float] | None = None) -> None:
        """Set the clamp's linear (m/s) and angular (rad/s, lab frame) velocity from now on."""
        self._rebase()
        if velocity is not None:
            self._vel = vector3("velocity", velocity)
        if angular_velocity is not None:
            if self._Q0 is None:
                raise ValueError("angular_velocity: this clamp is a pin (position only)")
            self._omega = vector3("angular_velocity", angular_velocity)
        self._changed()

    def release(self) -> None:
        """Remove the clamp from its rod."""
        self.rod._clamps.remove(self)
        self._changed()
