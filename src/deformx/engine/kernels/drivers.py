"""Kinematic drivers inside the kernels: clamps and moving colliders follow a prescribed
rigid motion, extrapolated step by step as MuJoCo and PhysX integrate a body (the predictor of
the paper's Algorithm 1, equations 1-2).

A driver row (see :mod:`.bundles`) holds the pose, velocity and acceleration of its origin,
world frame. Each step of ``dt`` first updates the rates, ``v += a dt``, ``w += alpha dt``;
during the step the driver moves with those rates, ``p(tau) = p + tau v``,
``R(tau) = Exp(tau w) R``; at the step's end ``p += dt v``, ``R <- Exp(dt w) R``
(semi-implicit Euler; position and orientation updated separately).

Clamps: node ``i`` sits at ``p + R off`` and moves with ``v + w x (R off)``; element ``e``
has directors ``(R rel)^T`` (rows d1, d2, d3) and the material angular velocity
``Q w``. The reaction of a clamp is the force and torque the rod puts on the driver (about
its origin, world frame) while the clamp holds it.
"""

from __future__ import annotations

from numba import njit

from .bundles import D_A, D_AL, D_P, D_R, D_V, D_W
from .so3 import rodrigues_coefficients
from .refcount import NO_REFCOUNT


@njit(cache=True, error_model="numpy")
def exp_times(w0, w1, w2, tau, R):
    """Exp(tau [w]) R for a row-major 3x3 tuple ``R`` (Rodrigues' formula)."""
    p0 = tau * w0
    p1 = tau * w1
    p2 = tau * w2
    t2 = p0 * p0 + p1 * p1 + p2 * p2
    if t2 == 0.0:
        return R
    s, c = rodrigues_coefficients(t2)
    # E = I + s K + c K^2, K = [p]x
    e00 = 1.0 - c * (p1 * p1 + p2 * p2)
    e11 = 1.0 - c * (p0 * p0 + p2 * p2)
    e22 = 1.0 - c * (p0 * p0 + p1 * p1)
    e01 = -s * p2 + c * p0 * p1
    e10 = s * p2 + c * p0 * p1
    e02 = s * p1 + c * p0 * p2
    e20 = -s * p1 + c * p0 * p2
    e12 = -s * p0 + c * p1 * p2
    e21 = s * p0 + c * p1 * p2
    return (e00 * R[0] + e01 * R[3] + e02 * R[6], e00 * R[1] + e01 * R[4] + e02 * R[7],
            e00 * R[2] + e01 * R[5] + e02 * R[8],
            e10 * R[0] + e11 * R[3] + e12 * R[6], e10 * R[1] + e11 * R[4] + e12 * R[7],
            e10 * R[2] + e11 * R[5] + e12 * R[8],
            e20 * R[0] + e21 * R[3] + e22 * R[6], e20 * R[1] + e21 * R[4] + e22 * R[7],
            e20 * R[2] + e21 * R[5] + e22 * R[8])


@njit(cache=True, error_model="numpy")
def load_drivers(dl, drv, r, env, cols) -> None:
    """Rod ``r``'s copy of the drivers it uses (its clamps', the colliders') from the table:
    copying every row for every rod cost O(rods x drivers) per call in a batch of
    environments, each with its own clamp."""
    for c in range(env.rod_pcon[r], env.rod_pcon[r + 1]):
        _copy_row(dl, drv, env.pcon_drv[c])
    for c in range(env.rod_fcon[r], env.rod_fcon[r + 1]):
        _copy_row(dl, drv, env.fcon_drv[c])
    if cols is not None:
        for c in range(cols.kind.shape[0]):
            _copy_row(dl, drv, cols.drv[c])


@njit(cache=True, inline="always", error_model="numpy")
def _begin(dl, d, dt) -> None:
    for j in range(3):
        dl[d, D_V + j] += dt * dl[d, D_A + j]
        dl[d, D_W + j] += dt * dl[d, D_AL + j]


@njit(cache=True, inline="always", error_model="numpy")
def _end(dl, d, dt) -> None:
    R = exp_times(dl[d, D_W], dl[d, D_W + 1], dl[d, D_W + 2], dt, _rot(dl, d))
    for j in range(3):
        dl[d, D_P + j] += dt * dl[d, D_V + j]
    for j in range(9):
        dl[d, D_R + j] = R[j]


@njit(cache=True, error_model="numpy")
def begin_step(dl, dt) -> None:
    """Rates of every driver for the coming step: v += a dt, w += alpha dt."""
    for d in range(dl.shape[0]):
        _begin(dl, d, dt)


@njit(cache=True, error_model="numpy")
def end_step(dl, dt) -> None:
    """Pose of every driver at the step's end: p += dt v, R <- Exp(dt w) R."""
    for d in range(dl.shape[0]):
        _end(dl, d, dt)


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def step_rod_drivers(dl, dt, r, env, cols, end) -> None:
    """``begin_step`` (or with ``end`` ``end_step``) of only the drivers rod ``r`` uses: its
    clamps' (each once) and the colliders' (a batch of rods then does not integrate every
    rod's clamp for every rod)."""
    c0, c1 = env.rod_pcon[r], env.rod_pcon[r + 1]
    f0, f1 = env.rod_fcon[r], env.rod_fcon[r + 1]
    for c in range(c0, c1):
        if not _seen(env, c0, c, f0, f0, env.pcon_drv[c]):
            if end:
                _end(dl, env.pcon_drv[c], dt)
            else:
                _begin(dl, env.pcon_drv[c], dt)
    for c in range(f0, f1):
        if not _seen(env, c0, c1, f0, c, env.fcon_drv[c]):
            if end:
                _end(dl, env.fcon_drv[c], dt)
            else:
                _begin(dl, env.fcon_drv[c], dt)
    if cols is not None:
        for c in range(cols.kind.shape[0]):
            if end:
                _end(dl, cols.drv[c], dt)
            else:
                _begin(dl, cols.drv[c], dt)


@njit(cache=True, error_model="numpy")
def store_drivers(drv, env, cols, r0, r1) -> None:
    """The drivers advanced by rods r0 .. r1 - 1 back into the table: each clamp's from its
    rod's copy, the colliders' from the first rod's."""
    for r in range(r0, r1):
        for c in range(env.rod_pcon[r], env.rod_pcon[r + 1]):
            _copy_row(drv, env.dloc[r], env.pcon_drv[c])
        for c in range(env.rod_fcon[r], env.rod_fcon[r + 1]):
            _copy_row(drv, env.dloc[r], env.fcon_drv[c])
    if cols is not None and r1 > r0:
        for c in range(cols.kind.shape[0]):
            _copy_row(drv, env.dloc[r0], cols.drv[c])


@njit(cache=True, inline="always", error_model="numpy")
def _copy_row(dst, src, d) -> None:
    for j in range(src.shape[1]):
        dst[d, j] = src[d, j]


@njit(cache=True, inline="always", error_model="numpy")
def _rot(dl, d):
    b = D_R
    return (dl[d, b], dl[d, b + 1], dl[d, b + 2], dl[d, b + 3], dl[d, b + 4], dl[d, b + 5],
            dl[d, b + 6], dl[d, b + 7], dl[d, b + 8])


@njit(cache=True, inline="always", error_model="numpy")
def origin_at(dl, d, tau):
    """Position of driver ``d``'s origin ``tau`` s into the step (no rotation needed)."""
    return (dl[d, D_P] + tau * dl[d, D_V], dl[d, D_P + 1] + tau * dl[d, D_V + 1],
            dl[d, D_P + 2] + tau * dl[d, D_V + 2])


@njit(cache=True, error_model="numpy")
def pose_at(dl, d, tau):
    """Position and rotation (row-major tuple) of driver ``d`` ``tau`` s into the step."""
    R = exp_times(dl[d, D_W], dl[d, D_W + 1], dl[d, D_W + 2], tau, _rot(dl, d))
    return (dl[d, D_P] + tau * dl[d, D_V], dl[d, D_P + 1] + tau * dl[d, D_V + 1],
            dl[d, D_P + 2] + tau * dl[d, D_V + 2]), R


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def clamp_values(tau, c0, c1, f0, f1, pos, Q, env, dl) -> None:
    """Clamped nodes and frames of one rod at ``tau`` s into the step."""
    for c in range(c0, c1):
        i = env.pcon_node[c]
        p, R = pose_at(dl, env.pcon_drv[c], tau)
        o0, o1, o2 = env.pcon_off[c, 0], env.pcon_off[c, 1], env.pcon_off[c, 2]
        pos[i, 0] = p[0] + R[0] * o0 + R[1] * o1 + R[2] * o2
        pos[i, 1] = p[1] + R[3] * o0 + R[4] * o1 + R[5] * o2
        pos[i, 2] = p[2] + R[6] * o0 + R[7] * o1 + R[8] * o2
    for c in range(f0, f1):
        e = env.fcon_elem[c]
        _, R = pose_at(dl, env.fcon_drv[c], tau)
        rel = env.fcon_rel[c]
        for a in range(3):
            for b in range(3):
                Q[e, a, b] = R[3 * b] * rel[0, a] + R[3 * b + 1] * rel[1, a] + R[3 * b + 2] * rel[2, a]


@njit(cache=True, inline="always", error_model="numpy")
def clamp_rate(dl, d, r0, r1, r2):
    """Velocity (m/s) of the point at world offset r from driver d's origin."""
    w0, w1, w2 = dl[d, D_W], dl[d, D_W + 1], dl[d, D_W + 2]
    return (dl[d, D_V] + w1 * r2 - w2 * r1, dl[d, D_V + 1] + w2 * r0 - w0 * r2,
            dl[d, D_V + 2] + w0 * r1 - w1 * r0)


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def clamp_rates(tau, c0, c1, f0, f1, pos, vel, Q, omega, env, dl) -> None:
    """Clamped nodes and frames of one rod take their driver's rates (angular: world ->
    material frame)."""
    for c in range(c0, c1):
        i = env.pcon_node[c]
        d = env.pcon_drv[c]
        p = origin_at(dl, d, tau)
        v = clamp_rate(dl, d, pos[i, 0] - p[0], pos[i, 1] - p[1], pos[i, 2] - p[2])
        for j in range(3):
            vel[i, j] = v[j]
    for c in range(f0, f1):
        e = env.fcon_elem[c]
        d = env.fcon_drv[c]
        for j in range(3):
            omega[e, j] = (Q[e, j, 0] * dl[d, D_W] + Q[e, j, 1] * dl[d, D_W + 1]
                           + Q[e, j, 2] * dl[d, D_W + 2])


@njit(cache=True, inline="always", error_model="numpy")
def clear_reactions(r, c0, c1, f0, f1, env) -> None:
    for c in range(c0, c1):
        for j in range(6):
            env.dreact[r, env.pcon_drv[c], j] = 0.0
    for c in range(f0, f1):
        for j in range(6):
            env.dreact[r, env.fcon_drv[c], j] = 0.0


@njit(cache=True, inline="always", error_model="numpy")
def add_node_reaction(r, d, tau, x0, x1, x2, f0, f1, f2, env, dl) -> None:
    """Force f (N, world) of the rod on driver d at point x, and its moment about the
    driver's origin at ``tau`` s into the step."""
    p = origin_at(dl, d, tau)
    r0, r1, r2 = x0 - p[0], x1 - p[1], x2 - p[2]
    env.dreact[r, d, 0] += f0
    env.dreact[r, d, 1] += f1
    env.dreact[r, d, 2] += f2
    env.dreact[r, d, 3] += r1 * f2 - r2 * f1
    env.dreact[r, d, 4] += r2 * f0 - r0 * f2
    env.dreact[r, d, 5] += r0 * f1 - r1 * f0


@njit(cache=True, inline="always", error_model="numpy")
def add_frame_reaction(r, d, Q, e, t0, t1, t2, env) -> None:
    """Torque t (N m, material frame of element e) of the rod on driver d."""
    for j in range(3):
        env.dreact[r, d, 3 + j] += Q[e, 0, j] * t0 + Q[e, 1, j] * t1 + Q[e, 2, j] * t2


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def add_impulse(r, h, c0, c1, f0, f1, env) -> None:
    """Accumulate ``h`` s of the last reactions of the rod's clamp drivers (each once)."""
    for c in range(c0, c1):
        d = env.pcon_drv[c]
        if not _seen(env, c0, c, f0, f0, d):
            for j in range(6):
                env.dimp[r, d, j] += h * env.dreact[r, d, j]
    for c in range(f0, f1):
        d = env.fcon_drv[c]
        if not _seen(env, c0, c1, f0, c, d):
            for j in range(6):
                env.dimp[r, d, j] += h * env.dreact[r, d, j]


@njit(cache=True, inline="always", error_model="numpy")
def _seen(env, c0, c1, f0, f1, d) -> bool:
    """Whether driver d holds one of the node clamps c0..c1 or frame clamps f0..f1."""
    for c in range(c0, c1):
        if env.pcon_drv[c] == d:
            return True
    for c in range(f0, f1):
        if env.fcon_drv[c] == d:
            return True
    return False


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def collider_poses(r, tau, cols, dl) -> None:
    """Poses and twists of every collider as rod ``r`` sees them ``tau`` s into the step."""
    for c in range(cols.kind.shape[0]):
        d = cols.drv[c]
        p, R = pose_at(dl, d, tau)
        for a in range(3):
            for b in range(3):
                cols.pose[r, c, a, b] = R[3 * a + b]
            cols.pose[r, c, a, 3] = p[a]
            cols.twist[r, c, a] = dl[d, D_V + a]
            cols.twist[r, c, 3 + a] = dl[d, D_W + a]


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def collider_impulses(r, h, cols, env) -> None:
    """Copy rod ``r``'s last contact wrench on each collider to its driver's reaction and
    accumulate ``h`` s of it into the impulse."""
    for c in range(cols.kind.shape[0]):
        d = cols.drv[c]
        for j in range(6):
            env.dreact[r, d, j] = cols.wrench[r, c, j]
            env.dimp[r, d, j] += h * cols.wrench[r, c, j]


@njit(cache=True, error_model="numpy")
def gather_impulses(base, dimp, owner, index, out) -> None:
    """``out[k] = base[d] + sum over rods of dimp[:, d]`` for ``d = index[k]`` (the array form
    of ``Driver.impulse``; numpy's fancy indexing costs ~10 us a call here). ``owner[d]``: the
    one rod that loads a clamp's driver (-1: any rod may, a collider), so a batch of rods each
    with its own clamp costs O(drivers), not O(rods x drivers)."""
    for k in range(index.shape[0]):
        d = index[k]
        for j in range(6):
            v = base[d, j]
            if d < dimp.shape[1]:
                if owner[d] >= 0:
                    v += dimp[owner[d], d, j]
                else:
                    for r in range(dimp.shape[0]):
                        v += dimp[r, d, j]
            out[k, j] = v


@njit(cache=True, error_model="numpy")
def clear_impulses(base, dimp, owner, index) -> None:
    """Zero the impulses of drivers ``index`` (the array form of ``reset_impulse``)."""
    for k in range(index.shape[0]):
        d = index[k]
        for j in range(6):
            base[d, j] = 0.0
            if d < dimp.shape[1]:
                if owner[d] >= 0:
                    dimp[owner[d], d, j] = 0.0
                else:
                    for r in range(dimp.shape[0]):
                        dimp[r, d, j] = 0.0
