"""Kinematic drivers: the prescribed rigid motions of clamps and colliders (handles).

A driver is a row of the world's driver table (see ``kernels/bundles.py``): the pose of its
origin (position, rotation world-from-local), its velocity and angular velocity and their
rates, all in the world frame and at the world's current time. Inside ``step(n)`` every step
does ``v += a dt, p += v dt; w += alpha dt, R <- Exp(w dt) R`` (semi-implicit Euler, as MuJoCo
and PhysX integrate a free body). Setting a driver writes its row: it never rebuilds the world,
so a co-simulation or an RL environment can set every driver every control step.

Every driver reports the load the rods put on it: the last step's ``force`` (N) and ``torque``
(N m, about its origin), and the ``impulse`` (force and torque integrated over time, N s and
N m s) since :meth:`Driver.reset_impulse`; world frame.
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from . import validation as check
from .kernels.bundles import D_A, D_AL, D_COLS, D_P, D_R, D_V, D_W
from .kernels.drivers import clear_impulses, gather_impulses

_NO_IMPULSES = np.zeros((0, 0, 6))


def fresh_row() -> np.ndarray:
    row = np.zeros(D_COLS)
    row[D_R:D_R + 9] = np.eye(3).ravel()
    return row


def vec3(name: str, value: Any) -> tuple[float, float, float]:
    """A finite 3-vector as three floats; fast for tuples and arrays of three (called every
    control step: a numpy array here and a slice assignment would cost ~1 us more)."""
    try:
        x, y, z = value
        x, y, z = float(x), float(y), float(z)
    except (TypeError, ValueError):
        x, y, z = check.vector3(name, value)
        return float(x), float(y), float(z)
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
        check.vector3(name, value)  # raises, naming the parameter
    return x, y, z


def put3(row: np.ndarray, col: int, v: tuple[float, float, float]) -> None:
    """``row[col:col + 3] = v`` for three floats (element by element: faster than a slice)."""
    row[col] = v[0]
    row[col + 1] = v[1]
    row[col + 2] = v[2]


def rotation(name: str, R: Any) -> np.ndarray:
    """A proper 3x3 rotation matrix, else ``ValueError`` naming ``name``."""
    R = np.asarray(R, dtype=np.float64)
    if R.shape != (3, 3) or not np.all(np.isfinite(R)):
        raise ValueError(f"{name} must be a finite 3x3 rotation matrix")
    if np.abs(R @ R.T - np.eye(3)).max() > 1e-6 or np.linalg.det(R) < 0.0:
        raise ValueError(f"{name} must be a rotation matrix (orthonormal, det +1)")
    return R


class DriverTable:
    """A world's drivers: one row each, what the rods put on them, impulses, free rows.

    ``rows`` (D, D_COLS) is what the kernels integrate; ``env`` is the world's current ``env``
    buffer group, whose per-rod ``dreact`` / ``dimp`` the loads and impulses are summed from
    (``impulse_base`` keeps what was accumulated before the group was last rebuilt).
    """

    def __init__(self) -> None:
        self.rows = np.zeros((0, D_COLS))
        self.impulse_base = np.zeros((0, 6))
        self.env = None
        self._owner = np.zeros(0, dtype=np.int64)
        self._free: list[int] = []

    def add(self, handle: "Driver") -> None:
        """Give ``handle`` a row (a released one if there is one), starting from its own."""
        if self._free:
            index = self._free.pop()
            self.rows[index] = handle._own
        else:
            index = self.rows.shape[0]
            self.rows = np.vstack([self.rows, handle._own[None]])
            self.impulse_base = np.vstack([self.impulse_base, np.zeros((1, 6))])
        self.impulse_base[index] = 0.0
        handle._table, handle._driver = self, index

    def release(self, handle: "Driver") -> None:
        """Take ``handle``'s row back; the handle keeps a copy of its last state."""
        handle._own = self.rows[handle._driver].copy()
        self._free.append(handle._driver)
        handle._table, handle._driver = None, -1

    def load(self, d: int) -> np.ndarray:
        """Force and torque (6) the rods put on driver d in the last step."""
        if self.env is None or self.env["dreact"].shape[1] <= d:
            return np.zeros(6)
        return self.env["dreact"][:, d].sum(axis=0)

    def impulse(self, d: int) -> np.ndarray:
        out = self.impulse_base[d].copy()
        if self.env is not None and self.env["dimp"].shape[1] > d:
            out += self.env["dimp"][:, d].sum(axis=0)
        return out

    def reset_impulse(self, d: int) -> None:
        self.impulse_base[d] = 0.0
        if self.env is not None and self.env["dimp"].shape[1] > d:
            self.env["dimp"][:, d] = 0.0

    def impulses(self, index: np.ndarray) -> np.ndarray:
        """:meth:`impulse` of many drivers at once (n, 6); ``index`` from :meth:`index`."""
        out = np.empty((index.shape[0], 6))
        gather_impulses(self.impulse_base, self._dimp(), self._owner, index, out)
        return out

    def reset_impulses(self, index: np.ndarray) -> None:
        """:meth:`reset_impulse` of many drivers at once."""
        clear_impulses(self.impulse_base, self._dimp(), self._owner, index)

    def _dimp(self) -> np.ndarray:
        return _NO_IMPULSES if self.env is None else self.env["dimp"]

    def rebind(self, env) -> None:
        """Use a rebuilt ``env`` group, keeping the impulses accumulated in the old one."""
        if self.env is not None:
            dimp = self.env["dimp"]
            self.impulse_base[: dimp.shape[1]] += dimp.sum(axis=0)
        self.env = env
        # The rod whose clamp a driver is (the only one that loads it), -1 for the others.
        self._owner = np.full(env["dimp"].shape[1], -1, dtype=np.int64)
        for rows, drv in (("rod_pcon", "pcon_drv"), ("rod_fcon", "fcon_drv")):
            ptr = env[rows]
            self._owner[env[drv][ptr[0]:ptr[-1]]] = np.repeat(np.arange(ptr.size - 1),
                                                              np.diff(ptr))

    def index(self, handles: Sequence["Driver"]) -> np.ndarray:
        """The rows of ``handles`` (each must belong to this table)."""
        if any(h._table is not self for h in handles):
            raise ValueError("drivers: every driver must belong to this world")
        return np.array([h._driver for h in handles], dtype=np.int64)

    def set_many(self, handles: Sequence["Driver"], validate: bool = True,
                 **values: Any) -> None:
        """Array form of the setters: each value has one row per handle (see
        ``World.set_drivers``)."""
        index = self.index(handles)
        n = index.shape[0]
        for name, col0, width in (("position", D_P, 3), ("rotation", D_R, 9),
                                  ("velocity", D_V, 3), ("angular_velocity", D_W, 3),
                                  ("acceleration", D_A, 3), ("angular_acceleration", D_AL, 3)):
            value = values.get(name)
            if value is None:
                continue
            arr = np.asarray(value, dtype=np.float64).reshape(n, -1)
            if not validate:
                self.rows[index, col0:col0 + width] = arr
                continue
            if arr.shape != (n, width) or not np.all(np.isfinite(arr)):
                raise ValueError(f"{name} must be finite with shape ({n}, "
                                 f"{'3, 3' if width == 9 else 3}), got {np.shape(value)}")
            if name == "rotation":
                R = arr.reshape(n, 3, 3)
                err = np.abs(R @ R.transpose(0, 2, 1) - np.eye(3)).max(initial=0.0)
                if err > 1e-6 or np.any(np.linalg.det(R) < 0.0):
                    raise ValueError("rotation must hold rotation matrices (orthonormal, det +1)")
            self.rows[index, col0:col0 + width] = arr


class Driver:
    """A handle on one driver row: its own row until a world's table takes it in, then a view
    with an index into that table."""

    def __init__(self) -> None:
        self._own = fresh_row()
        self._table: DriverTable | None = None
        self._driver = -1

    @property
    def _row(self) -> np.ndarray:
        if self._table is None:
            return self._own
        return self._table.rows[self._driver]

    # -------------------------------------------------------------- reading
    @property
    def position(self) -> np.ndarray:
        """Position (m) of the driver's origin now."""
        return self._row[D_P:D_P + 3].copy()

    @property
    def rotation(self) -> np.ndarray:
        """Rotation world-from-local (3x3) now."""
        return self._row[D_R:D_R + 9].reshape(3, 3).copy()

    @property
    def velocity(self) -> np.ndarray:
        """Linear velocity (m/s) of the origin."""
        return self._row[D_V:D_V + 3].copy()

    @property
    def angular_velocity(self) -> np.ndarray:
        """Angular velocity (rad/s, world frame)."""
        return self._row[D_W:D_W + 3].copy()

    @property
    def acceleration(self) -> np.ndarray:
        """Linear acceleration (m/s^2) of the origin."""
        return self._row[D_A:D_A + 3].copy()

    @property
    def angular_acceleration(self) -> np.ndarray:
        """Angular acceleration (rad/s^2, world frame)."""
        return self._row[D_AL:D_AL + 3].copy()

    @property
    def force(self) -> np.ndarray:
        """Force (N, world) the rods put on the driver in the last step."""
        return self._load()[:3]

    @property
    def torque(self) -> np.ndarray:
        """Torque (N m, world) the rods put on the driver about its origin in the last step."""
        return self._load()[3:]

    @property
    def impulse(self) -> np.ndarray:
        """Force and torque integrated over time since :meth:`reset_impulse` (6: N s, N m s;
        world frame, torque about the driver's origin)."""
        if self._table is None:
            return np.zeros(6)
        return self._table.impulse(self._driver)

    def reset_impulse(self) -> None:
        """Start accumulating :attr:`impulse` afresh."""
        if self._table is not None:
            self._table.reset_impulse(self._driver)

    def _load(self) -> np.ndarray:
        if self._table is None:
            return np.zeros(6)
        return self._table.load(self._driver)

    # -------------------------------------------------------------- setting
    def _set_rotation(self, R: np.ndarray) -> None:
        self._row[D_R:D_R + 9] = R.ravel()

    def set_acceleration(self, linear: Sequence[float] | None = (0.0, 0.0, 0.0),
                         angular: Sequence[float] | None = (0.0, 0.0, 0.0)) -> None:
        """Linear (m/s^2) and angular (rad/s^2) acceleration from now on, world frame; None
        leaves one as it is."""
        row = self._row
        if linear is not None:
            put3(row, D_A, vec3("linear", linear))
        if angular is not None:
            put3(row, D_AL, self._check_spin("angular", vec3("angular", angular)))

    def _check_spin(self, name: str, w: tuple[float, float, float]) -> tuple[float, float, float]:
        return w


def pose_from(position: Any, rotation_: Any) -> tuple[tuple | None, np.ndarray | None]:
    """Validated position and rotation (either may be None)."""
    p = None if position is None else vec3("position", position)
    R = None if rotation_ is None else rotation("rotation", rotation_)
    return p, R
