"""Explicit position-Verlet stepping (PyElastica's PositionVerlet), one rod per task.

Each step: half kinematic step, clamp values, internal loads, gravity + external loads + plane
contact, velocity update, clamp rates, uniform damping, half kinematic step, clamp values; the
order is PyElastica's, so trajectories agree to round-off. Inside one call the closing half step
of a step and the opening half step of the next are fused into one full step (same result to
round-off, half the rotation work). Without rod-rod contact each rod advances all its steps
independently; ``advance_rods`` releases the GIL so the World can run groups of rods on threads.
With rod-rod contact, :mod:`.coupled` calls ``advance_rod`` one step at a time for every rod.
"""

from __future__ import annotations

from numba import njit

from ..contact.plane import plane_contact_node, plane_penalty
from ..contact.segments import rod_collider_contacts
from .cosserat import rod_extent, rod_internal_loads
from .refcount import NO_REFCOUNT
from .so3 import rotate_directors

# Divergence codes returned in status[r, 0].
OK, NOT_FINITE, RUNAWAY_STRETCH, RUNAWAY_BEND = 0, 1, 2, 3


@njit(cache=True, error_model="numpy")
def _kinematic(n0, nn, e0, ne, pos, vel, Q, omega, h):
    """Positions += h v; directors rotated by h * omega (material frame)."""
    for i in range(n0, n0 + nn):
        for j in range(3):
            pos[i, j] += h * vel[i, j]
    for e in range(e0, e0 + ne):
        rotate_directors(Q, e, h, omega[e, 0], omega[e, 1], omega[e, 2])


@njit(cache=True, error_model="numpy")
def _constrain_values(t, c0, c1, f0, f1, pos, Q, pcon_node, pcon_data, fcon_elem, fcon_Q0, fcon_data):
    """Clamped nodes/frames follow their pose, extrapolated at constant velocity from t0."""
    for c in range(c0, c1):
        tau = t - pcon_data[c, 6]
        i = pcon_node[c]
        for j in range(3):
            pos[i, j] = pcon_data[c, j] + tau * pcon_data[c, 3 + j]
    for c in range(f0, f1):
        e = fcon_elem[c]
        tau = t - fcon_data[c, 3]
        for a in range(3):
            for b in range(3):
                Q[e, a, b] = fcon_Q0[c, a, b]
        # Lab angular velocity -> material frame of Q0, then rotate by tau.
        w0 = fcon_data[c, 0]
        w1 = fcon_data[c, 1]
        w2 = fcon_data[c, 2]
        rotate_directors(Q, e, tau, Q[e, 0, 0] * w0 + Q[e, 0, 1] * w1 + Q[e, 0, 2] * w2,
                         Q[e, 1, 0] * w0 + Q[e, 1, 1] * w1 + Q[e, 1, 2] * w2,
                         Q[e, 2, 0] * w0 + Q[e, 2, 1] * w1 + Q[e, 2, 2] * w2)


@njit(cache=True, error_model="numpy")
def _constrain_rates(c0, c1, f0, f1, vel, Q, omega, pcon_node, pcon_data, fcon_elem, fcon_data):
    """Clamped nodes/frames take their prescribed velocity (angular: lab -> material)."""
    for c in range(c0, c1):
        i = pcon_node[c]
        for j in range(3):
            vel[i, j] = pcon_data[c, 3 + j]
    for c in range(f0, f1):
        e = fcon_elem[c]
        for j in range(3):
            omega[e, j] = (Q[e, j, 0] * fcon_data[c, 0] + Q[e, j, 1] * fcon_data[c, 1]
                           + Q[e, j, 2] * fcon_data[c, 2])


@njit(cache=True, error_model="numpy")
def _check(e0, ne, v0, nv, dil, kappa, rest_vor, torque, max_strain):
    """(code, element) of the first NaN or runaway strain in a rod; (OK, -1) if fine."""
    for k in range(ne):
        d = dil[e0 + k]
        t = torque[e0 + k, 0] + torque[e0 + k, 1] + torque[e0 + k, 2]
        if not (d == d and t == t and abs(t) < 1e300):
            return NOT_FINITE, k
        if not (abs(d - 1.0) <= max_strain):
            return RUNAWAY_STRETCH, k
    for j in range(nv):
        vj = v0 + j
        ang2 = (kappa[vj, 0] ** 2 + kappa[vj, 1] ** 2 + kappa[vj, 2] ** 2) * rest_vor[vj] ** 2
        if not (ang2 < 9.0):  # neighbouring frames turned by > ~170 degrees (or NaN)
            return (RUNAWAY_BEND if ang2 == ang2 else NOT_FINITE), j
    return OK, -1


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def advance_rod(
    r, n_steps, t, dt, gravity, max_strain,
    rod_node0, rod_elem0, rod_vor0, rod_ne, rod_closed, rod_decay, rod_pcon, rod_fcon,
    pos, vel, mass, node_radius, node_kmin, fext, force, contact_force,
    Q, omega, J, inv_J, S, rest_len, rest_sigma, text, torque, dil, stress,
    B, rest_vor, rest_kappa, kappa, couple,
    scr_C, scr_X, scr_edot,
    pcon_node, pcon_data, fcon_elem, fcon_Q0, fcon_data,
    planes, status, cols, col_anchor, col_anchor_id, col_pen, el_K, wrench, extra, use_extra,
    start_mid, end_mid,
):
    """Advance rod ``r`` by ``n_steps`` steps from time ``t``; returns the new time.

    Contact: ``planes``, the colliders ``cols`` (meshes, primitives; friction anchors in
    ``col_anchor*``, reactions into ``wrench[r]``) and, with ``use_extra``, the node forces
    ``extra`` (rod-rod contact, computed by the caller at this step's mid-point).
    On divergence stops with ``status[r]`` = (code, element, steps done).

    A caller stepping one step at a time (rod-rod contact) may leave the rod at the next
    step's mid-point (``end_mid``: positions and frames at ``t + h``) and start from there
    (``start_mid``): the two half drifts between steps become one, as within a call.
    """
    h = 0.5 * dt
    n0, e0, v0, ne, nn, nv, closed = rod_extent(r, rod_node0, rod_elem0, rod_vor0, rod_ne, rod_closed)
    c0, c1 = rod_pcon[r], rod_pcon[r + 1]
    f0, f1 = rod_fcon[r], rod_fcon[r + 1]
    decay = rod_decay[r]
    g0, g1, g2 = gravity[0], gravity[1], gravity[2]
    n_planes = planes.shape[0]
    # ``cols`` is None without colliders: numba then prunes the collider branch at compile
    # time, which keeps the mesh code (and its compile time) out of plain worlds.
    n_cols = 0
    if cols is not None:
        n_cols = cols[0].shape[0]
    touching = n_planes > 0 or n_cols > 0 or use_extra

    if not start_mid:
        _kinematic(n0, nn, e0, ne, pos, vel, Q, omega, h)
    for step in range(n_steps):
        t += h
        _constrain_values(t, c0, c1, f0, f1, pos, Q, pcon_node, pcon_data, fcon_elem, fcon_Q0, fcon_data)

        rod_internal_loads(r, rod_node0, rod_elem0, rod_vor0, rod_ne, rod_closed,
                           pos, vel, Q, omega, J, S, rest_len, rest_sigma, B, rest_vor,
                           rest_kappa, force, torque, dil, kappa, stress, couple,
                           scr_C, scr_X, scr_edot)
        for i in range(n0, n0 + nn):
            force[i, 0] += mass[i] * g0 + fext[i, 0]
            force[i, 1] += mass[i] * g1 + fext[i, 1]
            force[i, 2] += mass[i] * g2 + fext[i, 2]
        for e in range(e0, e0 + ne):
            for j in range(3):
                torque[e, j] += text[e, j]
        if touching:
            for i in range(n0, n0 + nn):
                for j in range(3):
                    contact_force[i, j] = 0.0
            if n_planes > 0:
                _plane_contacts(n0, nn, planes, pos, vel, mass, node_radius, node_kmin, force, dt,
                                contact_force)
            if cols is not None:
                rod_collider_contacts(r, n0, nn, e0, ne, dt, dt, pos, vel, pos, mass, node_radius,
                                      node_kmin, cols, col_anchor, col_anchor_id, col_pen, el_K, wrench,
                                      force, contact_force, True, False)
            if use_extra:
                for i in range(n0, n0 + nn):
                    for j in range(3):
                        force[i, j] += extra[i, j]
                        contact_force[i, j] += extra[i, j]

        code, k = _check(e0, ne, v0, nv, dil, kappa, rest_vor, torque, max_strain)
        if code != OK:
            status[r, 0] = code
            status[r, 1] = k
            status[r, 2] = step
            return t

        for i in range(n0, n0 + nn):
            inv_m = 1.0 / mass[i]
            for j in range(3):
                vel[i, j] += dt * (force[i, j] * inv_m)
        for e in range(e0, e0 + ne):
            for j in range(3):
                omega[e, j] += dt * (inv_J[e, j] * torque[e, j] * dil[e])
        _constrain_rates(c0, c1, f0, f1, vel, Q, omega, pcon_node, pcon_data, fcon_elem, fcon_data)
        if decay != 1.0:
            for i in range(n0, n0 + nn):
                for j in range(3):
                    vel[i, j] *= decay
            for e in range(e0, e0 + ne):
                for j in range(3):
                    omega[e, j] *= decay

        if step < n_steps - 1 or end_mid:
            _kinematic(n0, nn, e0, ne, pos, vel, Q, omega, dt)
        else:
            _kinematic(n0, nn, e0, ne, pos, vel, Q, omega, h)
        t += h
    _constrain_values(t + h if end_mid else t, c0, c1, f0, f1, pos, Q, pcon_node, pcon_data,
                      fcon_elem, fcon_Q0, fcon_data)
    status[r, 2] = n_steps
    return t


@njit(cache=True, error_model="numpy")
def _plane_contacts(n0, nn, planes, pos, vel, mass, node_radius, node_kmin, force, dt, contact_force):
    """Add plane contact forces to the rod's nodes (also added to ``contact_force``).

    ``planes`` rows: point(3), normal(3), stiffness, damping, mu_s, mu_k, auto flag; an
    automatic penalty uses each node's mass (contact frequency 0.2/dt, critically damped), but
    at least ``node_kmin`` (0.1 % of the elements' axial stiffness EA / dl).
    """
    for i in range(n0, n0 + nn):
        for p in range(planes.shape[0]):
            k, c = plane_penalty(planes, p, mass[i], node_kmin[i], dt)
            f0, f1, f2, _ = plane_contact_node(
                pos[i, 0], pos[i, 1], pos[i, 2], vel[i, 0], vel[i, 1], vel[i, 2],
                force[i, 0], force[i, 1], force[i, 2], mass[i], node_radius[i], dt,
                planes[p, 0], planes[p, 1], planes[p, 2], planes[p, 3], planes[p, 4], planes[p, 5],
                k, c, planes[p, 8], planes[p, 9])
            force[i, 0] += f0
            force[i, 1] += f1
            force[i, 2] += f2
            contact_force[i, 0] += f0
            contact_force[i, 1] += f1
            contact_force[i, 2] += f2


@njit(cache=True, nogil=True, error_model="numpy")
def advance_rods(r_begin, r_end, n_steps, t, dt, gravity, max_strain, times, rod_args, extra,
                 use_extra):
    """Advance rods ``r_begin .. r_end - 1``; releases the GIL so threads can share rods.

    ``rod_args`` are :func:`advance_rod`'s arguments between ``max_strain`` and ``extra``.
    """
    for r in range(r_begin, r_end):
        times[r] = advance_rod(r, n_steps, t, dt, gravity, max_strain, *rod_args, extra,
                               use_extra, False, False)
