"""Inverse kinematics for a point of a MuJoCo body (damped least squares), e.g. to make a
robot's tool trace a path through position servos."""

from __future__ import annotations

from typing import Sequence

import numpy as np


def solve_position(model, body: str, target: Sequence[float], q: Sequence[float],
                   joints: Sequence[str] | None = None, rest: Sequence[float] | None = None,
                   iterations: int = 20, damping: float = 1e-2, rest_gain: float = 0.05,
                   tolerance: float = 1e-8) -> np.ndarray:
    """Joint angles (rad) that put body ``body``'s origin at ``target`` (m, world), starting
    from ``q`` (the model's whole ``qpos``) and moving only ``joints`` (names; default all
    hinge/slide joints). Damped least squares (``damping``, m) with a pull of ``rest_gain``
    towards ``rest`` in the null space; returns the whole ``qpos``."""
    import mujoco

    data = mujoco.MjData(model)
    data.qpos[:] = np.asarray(q, dtype=np.float64)
    bid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body)
    if bid < 0:
        raise ValueError(f"body: no body named {body!r}")
    if joints is None:
        kinds = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
        jids = [j for j in range(model.njnt) if int(model.jnt_type[j]) in kinds]
    else:
        jids = []
        for name in joints:
            j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
            if j < 0:
                raise ValueError(f"joints: no joint named {name!r}")
            jids.append(j)
    dofs = np.array([model.jnt_dofadr[j] for j in jids])
    qadr = np.array([model.jnt_qposadr[j] for j in jids])
    rest_q = data.qpos[qadr].copy() if rest is None else np.asarray(rest, dtype=np.float64)
    target = np.asarray(target, dtype=np.float64)
    jacp = np.zeros((3, model.nv))
    for _ in range(iterations):
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        err = target - data.xpos[bid]
        if float(err @ err) < tolerance ** 2:
            break
        mujoco.mj_jacBody(model, data, jacp, None, bid)
        J = jacp[:, dofs]
        JJt = J @ J.T + damping ** 2 * np.eye(3)
        dq = J.T @ np.linalg.solve(JJt, err)
        null = np.eye(len(jids)) - J.T @ np.linalg.solve(JJt, J)
        dq += null @ (rest_gain * (rest_q - data.qpos[qadr]))
        data.qpos[qadr] += dq
        lo, hi = model.jnt_range[jids, 0], model.jnt_range[jids, 1]
        limited = model.jnt_limited[jids].astype(bool)
        data.qpos[qadr] = np.where(limited, np.clip(data.qpos[qadr], lo, hi), data.qpos[qadr])
    return data.qpos.copy()
