"""One small rope interface over a DeformX rod and the linked-capsule baseline, so an
experiment (calibration, the hit-target task) can swap the two rope models."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from ..engine.rod import Rod


def _quat_matrix(mj, q: np.ndarray) -> np.ndarray:
    R = np.zeros(9)
    mj.mju_quat2Mat(R, np.asarray(q, dtype=np.float64))
    return R.reshape(3, 3)


def _align(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation taking unit vector a onto unit vector b."""
    v = np.cross(a, b)
    c = float(np.dot(a, b))
    if c < -1.0 + 1e-12:  # opposite: half a turn about any axis normal to a
        n = np.cross(a, [1.0, 0.0, 0.0])
        if np.linalg.norm(n) < 1e-6:
            n = np.cross(a, [0.0, 1.0, 0.0])
        n /= np.linalg.norm(n)
        return 2.0 * np.outer(n, n) - np.eye(3)
    K = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + K + K @ K / (1.0 + c)


class Rope(Protocol):
    """Node positions (n+1, 3) m, tip position (3) m and tip velocity (3) m/s, world frame;
    the tip is the rope's free (last) end."""

    @property
    def positions(self) -> np.ndarray: ...

    @property
    def tip_position(self) -> np.ndarray: ...

    @property
    def tip_velocity(self) -> np.ndarray: ...


class RodRope:
    """A DeformX rod as a :class:`Rope`."""

    def __init__(self, rod: Rod) -> None:
        self.rod = rod

    @property
    def positions(self) -> np.ndarray:
        return self.rod.positions.copy()

    @property
    def tip_position(self) -> np.ndarray:
        return self.rod.positions[-1].copy()

    @property
    def tip_velocity(self) -> np.ndarray:
        return self.rod.velocities[-1].copy()


class CapsuleRope:
    """A :func:`deformx.robots.capsule_rope` chain in a MuJoCo backend as a :class:`Rope`
    (positions read after the backend's last step: call after ``CoSimulation.step``)."""

    def __init__(self, backend, name: str = "rope") -> None:
        import mujoco

        self._mj = mujoco
        self.backend = backend
        m = backend.model
        ids = []
        while True:
            i = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, f"{name}_{len(ids)}")
            if i < 0:
                break
            ids.append(i)
        if not ids:
            raise ValueError(f"name: no capsule rope {name!r} (bodies {name}_0, {name}_1, ...) "
                             "in the model")
        self._ids = np.array(ids)
        self._tip = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, f"{name}_tip")
        self._res = np.zeros(6)
        self._qadr = np.array([m.jnt_qposadr[m.body_jntadr[i]] for i in ids])
        self._vadr = np.array([m.jnt_dofadr[m.body_jntadr[i]] for i in ids])
        self.segment_length = float(np.linalg.norm(m.body_pos[ids[1]])) if len(ids) > 1 else \
            float(np.linalg.norm(m.site_pos[self._tip]))

    def set_shape(self, points: np.ndarray) -> None:
        """Bend the chain at rest through ``points`` ((n+1, 3) m, world; spaced by the segment
        length, the first where the rope hangs from its parent): sets the ball joints, zeroes
        their velocities and updates MuJoCo's kinematics."""
        mj, m, d = self._mj, self.backend.model, self.backend.data
        pts = np.asarray(points, dtype=np.float64)
        if pts.shape != (len(self._ids) + 1, 3):
            raise ValueError(f"points must have shape ({len(self._ids) + 1}, 3), got {pts.shape}")
        seg = np.diff(pts, axis=0)
        lengths = np.linalg.norm(seg, axis=1)
        if np.abs(lengths - self.segment_length).max() > 1e-6 * self.segment_length + 1e-9:
            raise ValueError(f"points must be {self.segment_length:g} m apart (the segment "
                             f"length); got {lengths.min():g} to {lengths.max():g} m")
        mj.mj_kinematics(m, d)
        parent = int(m.body_parentid[self._ids[0]])
        R_parent = d.xmat[parent].reshape(3, 3).copy()
        q = np.zeros(4)
        for k, i in enumerate(self._ids):
            R_rest = R_parent @ _quat_matrix(mj, m.body_quat[i])  # joint at identity
            R_j = R_rest.T @ _align(R_rest[:, 2], seg[k] / lengths[k]) @ R_rest
            mj.mju_mat2Quat(q, R_j.ravel())
            d.qpos[self._qadr[k]:self._qadr[k] + 4] = q
            d.qvel[self._vadr[k]:self._vadr[k] + 3] = 0.0
            R_parent = R_rest @ R_j
        mj.mj_kinematics(m, d)

    def _sync(self) -> None:
        d = self.backend.data
        self._mj.mj_kinematics(self.backend.model, d)  # after mj_step the poses are stale

    @property
    def positions(self) -> np.ndarray:
        self._sync()
        d = self.backend.data
        return np.vstack([d.xpos[self._ids], d.site_xpos[self._tip][None]])

    @property
    def tip_position(self) -> np.ndarray:
        self._sync()
        return self.backend.data.site_xpos[self._tip].copy()

    @property
    def tip_velocity(self) -> np.ndarray:
        m, d = self.backend.model, self.backend.data
        self._mj.mj_kinematics(m, d)
        self._mj.mj_comPos(m, d)
        self._mj.mj_comVel(m, d)
        self._mj.mj_objectVelocity(m, d, self._mj.mjtObj.mjOBJ_SITE, self._tip, self._res, 0)
        return self._res[3:].copy()
