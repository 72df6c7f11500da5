"""Clamps: a rod node (and optionally an element's material frame) held by a kinematic driver.

The clamp's driver has its origin at the clamped node and, for a frame clamp, the rotation
``directors^T`` (world-from-material), so ``clamp.directors`` are the element's rows d1, d2, d3.
:meth:`Clamp.rebase` moves the driver's frame elsewhere (a robot body's origin holding the rod
end): the node then sits at a fixed ``offset`` in that frame and the element's frame at a fixed
rotation ``relative`` to it, so the body's own pose and twist drive the clamp exactly.
Between calls to :meth:`Clamp.set_pose` / :meth:`~Clamp.set_velocity` /
:meth:`~deformx.engine.drivers.Driver.set_acceleration` it moves as its driver is integrated
(see :mod:`deformx.engine.drivers`), so a robot gripper can drive a rod end by updating the
clamp once per control step.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

import numpy as np

from .drivers import Driver, put3, vec3
from .kernels.bundles import D_P, D_R, D_V, D_W

if TYPE_CHECKING:
    from .rod import Rod


class Clamp(Driver):
    """Holds rod node ``node`` at a position and (optionally) element ``element`` at a
    material frame; reports the rod's load on it (:attr:`force`, :attr:`torque`,
    :attr:`impulse`)."""

    def __init__(self, rod: "Rod", node: int, element: int | None,
                 position: bool = True) -> None:
        super().__init__()
        self.rod = rod
        self.node = int(node)
        self.element = None if element is None else int(element)
        self.holds_position = bool(position)  # False: the frame only (the node moves freely)
        self.offset = np.zeros(3)      # node in the driver's frame (m)
        self.relative = np.eye(3)      # material frame in the driver's frame (local-from-material)
        self.rebased = False           # a pin held at an offset turns with its driver
        self._own[D_P:D_P + 3] = rod.positions[self.node]
        if element is not None:
            self._set_rotation(rod.directors[self.element].T)

    def rebase(self, position: Sequence[float], rotation: np.ndarray | None = None) -> None:
        """Put the driver's origin at ``position`` (m) with ``rotation`` (world-from-local,
        default identity), keeping the node (and frame) where they are now: from here on the
        node sits at ``position + rotation @ offset`` and the frame at ``rotation @ relative``,
        and :meth:`set_pose` / :meth:`set_velocity` / ``set_acceleration`` move that frame (a
        body holding the rod end). Torques are reported about the new origin."""
        p = np.array(vec3("position", position))
        R = np.eye(3) if rotation is None else np.asarray(rotation, dtype=np.float64)
        if (R.shape != (3, 3) or not np.all(np.isfinite(R))
                or not np.allclose(R @ R.T, np.eye(3), atol=1e-8) or np.linalg.det(R) < 0):
            raise ValueError("rotation must be a 3x3 proper rotation matrix")
        self.offset = R.T @ (self.rod.positions[self.node] - p)
        if self.element is not None:
            self.relative = R.T @ self.rod.directors[self.element].T
        row = self._row
        row[D_P:D_P + 3] = p
        self._set_rotation(R)
        self.rebased = True
        if self.rod._world is not None:
            self.rod._world._stale_env = True

    @property
    def holds_frame(self) -> bool:
        """True if the clamp also fixes the material frame of its element."""
        return self.element is not None

    @property
    def directors(self) -> np.ndarray | None:
        """Clamped material frame now, rows d1, d2, d3 (None for a pin)."""
        if self.element is None:
            return None
        return (self._row[D_R:D_R + 9].reshape(3, 3) @ self.relative).T.copy()

    def set_pose(self, position: Sequence[float] | None = None,
                 directors: np.ndarray | None = None, rotation: np.ndarray | None = None) -> None:
        """Move the clamp now to ``position`` (m, its driver's origin) and, for a frame clamp,
        ``directors`` (3x3 rotation, rows d1, d2, d3 of the element) or ``rotation`` (the
        driver's world-from-local; world-from-material unless :meth:`rebase` was called)."""
        if position is not None:
            put3(self._row, D_P, vec3("position", position))
        for name, R in (("directors", directors), ("rotation", rotation)):
            if R is None:
                continue
            if self.element is None and not (self.rebased and name == "rotation"):
                raise ValueError(f"{name}: this clamp is a pin (position only); use "
                                 "fix_start/fix_end")
            Q = np.asarray(R, dtype=np.float64)
            if (Q.shape != (3, 3) or not np.all(np.isfinite(Q))
                    or not np.allclose(Q @ Q.T, np.eye(3), atol=1e-8) or np.linalg.det(Q) < 0):
                raise ValueError(f"{name} must be a 3x3 proper rotation matrix"
                                 + (" (rows d1, d2, d3)" if name == "directors" else ""))
            # the driver's rotation R makes the material frame R @ relative
            self._set_rotation(Q.T @ self.relative.T if name == "directors" else Q)

    def set_velocity(self, velocity: Sequence[float] | None = None,
                     angular_velocity: Sequence[float] | None = None, *,
                     linear: Sequence[float] | None = None,
                     angular: Sequence[float] | None = None) -> None:
        """Set the clamp's linear (m/s) and angular (rad/s, world frame) velocity from now on
        (``linear`` / ``angular`` are the same as for colliders); None keeps one as it is."""
        velocity = linear if velocity is None else velocity
        angular_velocity = angular if angular_velocity is None else angular_velocity
        row = self._row
        if velocity is not None:
            put3(row, D_V, vec3("velocity", velocity))
        if angular_velocity is not None:
            put3(row, D_W, self._check_spin("angular_velocity",
                                            vec3("angular_velocity", angular_velocity)))

    def _check_spin(self, name: str, w: tuple[float, float, float]) -> tuple[float, float, float]:
        if self.element is None and not self.rebased and w != (0.0, 0.0, 0.0):
            raise ValueError(f"{name}: this clamp is a pin (position only)")
        return w

    def release(self) -> None:
        """Remove the clamp from its rod."""
        self.rod._remove_clamp(self)

    def __repr__(self) -> str:
        kind = ("frame" if self.holds_position else "frame only") if self.element is not None \
            else "pin"
        return f"Clamp({kind}, node={self.node}, position={self.position.round(4).tolist()})"
