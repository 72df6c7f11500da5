"""The coupling's per-step arithmetic over all coupled drivers at once (numba): rigid-body
kinematics from body frames to driver frames, and driver impulses to body wrenches.

numpy's small-array calls cost ~1-30 us each (``np.cross`` ~30 us), which would make the
coupling of one body cost more than the rod and MuJoCo steps together.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..engine.kernels.bundles import D_A, D_AL, D_P, D_R, D_V, D_W

# Columns of a body-motion row (see ``body_motions``).
M_P, M_R, M_V, M_W, M_A, M_AL, M_COM, M_COLS = 0, 3, 12, 15, 18, 21, 24, 27

# How far a driver's extrapolated pose may end from its body's frame and still be carried on
# continuously (drive_rows): well above an arm's per-step extrapolation miss (~10-100 um),
# well below a reset.
CONTINUOUS_POSITION = 2e-3  # m
CONTINUOUS_ANGLE = 0.05  # rad
# Macro steps over which a continuous driver makes up its miss. Over one, the correction
# closed a loop with the rods' wrench through the backend (the miss is mostly the body's answer
# to the last wrench): the hanging hit-target rope at BDF2 1e-4 s rang, from 0.05 to 11 N
# peak-to-peak at the tool within 0.8 s; over two it still grew, over four it settles as with
# jumps (0.005 N). The driver then trails its frame by a few misses (tens of um on an arm).
CONTINUOUS_STEPS = 4


@njit(cache=True)
def body_motions(ids, rootid, xpos, xmat, subtree_com, cvel, cacc, xipos, gravity, out) -> None:
    """Frame motion of MuJoCo bodies ``ids`` into rows of ``out`` (M_* columns): what
    ``mj_objectVelocity`` / ``mj_objectAcceleration`` (mjOBJ_XBODY, world frame) give, from
    the com-based ``cvel`` / ``cacc`` at the tree's subtree centre of mass, plus gravity
    (MuJoCo's accelerations carry -gravity)."""
    for k in range(ids.shape[0]):
        i = ids[k]
        c = rootid[i]
        d0, d1, d2 = xpos[i, 0] - subtree_com[c, 0], xpos[i, 1] - subtree_com[c, 1], \
            xpos[i, 2] - subtree_com[c, 2]
        w0, w1, w2 = cvel[i, 0], cvel[i, 1], cvel[i, 2]
        v0 = cvel[i, 3] - (d1 * w2 - d2 * w1)
        v1 = cvel[i, 4] - (d2 * w0 - d0 * w2)
        v2 = cvel[i, 5] - (d0 * w1 - d1 * w0)
        b0, b1, b2 = cacc[i, 0], cacc[i, 1], cacc[i, 2]
        out[k, M_A] = cacc[i, 3] - (d1 * b2 - d2 * b1) + (w1 * v2 - w2 * v1) + gravity[0]
        out[k, M_A + 1] = cacc[i, 4] - (d2 * b0 - d0 * b2) + (w2 * v0 - w0 * v2) + gravity[1]
        out[k, M_A + 2] = cacc[i, 5] - (d0 * b1 - d1 * b0) + (w0 * v1 - w1 * v0) + gravity[2]
        for j in range(3):
            out[k, M_P + j] = xpos[i, j]
            out[k, M_COM + j] = xipos[i, j]
            out[k, M_W + j] = cvel[i, j]
            out[k, M_AL + j] = cacc[i, j]
        out[k, M_V], out[k, M_V + 1], out[k, M_V + 2] = v0, v1, v2
        for j in range(9):
            out[k, M_R + j] = xmat[i, j]


@njit(cache=True)
def drive_rows(rows, index, body, off, rot, motion, origin, inv_T, reach) -> None:
    """Driver ``index[k]`` (a row of the world's driver table) takes the motion of the frame
    at ``off[k]`` / ``rot[k]`` in body ``body[k]`` (a row of ``motion``, M_* columns): pose,
    velocity and acceleration of its origin (rigid-body kinematics), the body's angular
    velocity and acceleration; ``origin[k]`` keeps the driver's position.

    With ``reach`` >= 0 (``CONTINUOUS_POSITION``) the pose stays continuous: where the
    driver's own extrapolation ended within ``reach`` (m) and ``CONTINUOUS_ANGLE`` of the
    frame, the driver keeps its pose and makes up the difference over the time ``1 / inv_T``
    (``CONTINUOUS_STEPS`` macro steps: velocity + miss inv_T); only a farther frame (a reset,
    a teleport) is jumped to. A jump of the held node at each macro step, however
    small (the extrapolation misses the backend's own integration by ~a T^2 / 2: tens of um
    on an arm), is one rod substep's worth of velocity, so it kicks a rod the harder the
    finer its substeps, and the rod then does not converge as its step shrinks
    (docs/learning.md)."""
    Rb = np.empty(9)
    E = np.empty(9)
    for k in range(body.shape[0]):
        b, d = body[k], index[k]
        o0, o1, o2 = off[k, 0], off[k, 1], off[k, 2]
        r0 = motion[b, M_R] * o0 + motion[b, M_R + 1] * o1 + motion[b, M_R + 2] * o2
        r1 = motion[b, M_R + 3] * o0 + motion[b, M_R + 4] * o1 + motion[b, M_R + 5] * o2
        r2 = motion[b, M_R + 6] * o0 + motion[b, M_R + 7] * o1 + motion[b, M_R + 8] * o2
        p0, p1, p2 = motion[b, M_P] + r0, motion[b, M_P + 1] + r1, motion[b, M_P + 2] + r2
        for i in range(3):
            for j in range(3):
                Rb[3 * i + j] = (motion[b, M_R + 3 * i] * rot[k, 0, j]
                                 + motion[b, M_R + 3 * i + 1] * rot[k, 1, j]
                                 + motion[b, M_R + 3 * i + 2] * rot[k, 2, j])
        e0 = e1 = e2 = f0 = f1 = f2 = 0.0
        near = False
        if reach >= 0.0:
            # the misses: position, and the rotation Rb Rd^T from the driver's frame to the body's
            e0, e1, e2 = p0 - rows[d, D_P], p1 - rows[d, D_P + 1], p2 - rows[d, D_P + 2]
            for i in range(3):
                for j in range(3):
                    E[3 * i + j] = (Rb[3 * i] * rows[d, D_R + 3 * j]
                                    + Rb[3 * i + 1] * rows[d, D_R + 3 * j + 1]
                                    + Rb[3 * i + 2] * rows[d, D_R + 3 * j + 2])
            # its skew part: sin(angle) times the axis, the angle itself to 4e-4 within reach
            f0, f1, f2 = 0.5 * (E[7] - E[5]), 0.5 * (E[2] - E[6]), 0.5 * (E[3] - E[1])
            near = (e0 * e0 + e1 * e1 + e2 * e2 <= reach * reach
                    and f0 * f0 + f1 * f1 + f2 * f2 <= CONTINUOUS_ANGLE ** 2
                    and E[0] + E[4] + E[8] > 2.0)  # (not a half turn, where sin is small too)
        if not near:
            rows[d, D_P], rows[d, D_P + 1], rows[d, D_P + 2] = p0, p1, p2
            for j in range(9):
                rows[d, D_R + j] = Rb[j]
            e0 = e1 = e2 = f0 = f1 = f2 = 0.0
        for j in range(3):
            origin[k, j] = rows[d, D_P + j]
        w0, w1, w2 = motion[b, M_W], motion[b, M_W + 1], motion[b, M_W + 2]
        a0, a1, a2 = motion[b, M_AL], motion[b, M_AL + 1], motion[b, M_AL + 2]
        x0, x1, x2 = w1 * r2 - w2 * r1, w2 * r0 - w0 * r2, w0 * r1 - w1 * r0  # w x r
        rows[d, D_V] = motion[b, M_V] + x0 + inv_T * e0
        rows[d, D_V + 1] = motion[b, M_V + 1] + x1 + inv_T * e1
        rows[d, D_V + 2] = motion[b, M_V + 2] + x2 + inv_T * e2
        rows[d, D_A] = motion[b, M_A] + a1 * r2 - a2 * r1 + w1 * x2 - w2 * x1
        rows[d, D_A + 1] = motion[b, M_A + 1] + a2 * r0 - a0 * r2 + w2 * x0 - w0 * x2
        rows[d, D_A + 2] = motion[b, M_A + 2] + a0 * r1 - a1 * r0 + w0 * x1 - w1 * x0
        rows[d, D_W] = motion[b, M_W] + inv_T * f0
        rows[d, D_W + 1] = motion[b, M_W + 1] + inv_T * f1
        rows[d, D_W + 2] = motion[b, M_W + 2] + inv_T * f2
        for j in range(3):
            rows[d, D_AL + j] = motion[b, M_AL + j]


@njit(cache=True)
def wrenches_from_impulses(imp, body, origin, com, inv_dt, out) -> None:
    """Sum driver impulses (force, torque about the driver's ``origin``) into each body's
    mean wrench over the step, torque moved to the body's ``com`` (``out`` (B, 6) zeroed)."""
    for k in range(body.shape[0]):
        b = body[k]
        f0, f1, f2 = imp[k, 0], imp[k, 1], imp[k, 2]
        d0, d1, d2 = origin[k, 0] - com[b, 0], origin[k, 1] - com[b, 1], origin[k, 2] - com[b, 2]
        out[b, 0] += inv_dt * f0
        out[b, 1] += inv_dt * f1
        out[b, 2] += inv_dt * f2
        out[b, 3] += inv_dt * (imp[k, 3] + d1 * f2 - d2 * f1)
        out[b, 4] += inv_dt * (imp[k, 4] + d2 * f0 - d0 * f2)
        out[b, 5] += inv_dt * (imp[k, 5] + d0 * f1 - d1 * f0)
