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

import math

from numba import njit

from ..contact.plane import (V_OUT, carry_offset, note_start_inside, plane_contact_node,
                             plane_penalty, start_offset)
from ..contact.segments import rod_collider_contacts
from .bundles import (
    D_W, E_DIL, E_INV_J, E_J, E_OMEGA, E_Q, E_TEXT, E_TORQUE, N_CONTACT_FORCE, N_EXTRA, N_FEXT,
    N_FORCE, N_MASS, N_NODE_KMIN, N_NODE_RADIUS, N_PEN_OFF, N_POS, N_VEL, R_CLOSED, R_DECAY,
    R_ELEM0,
    R_NE, R_NODE0, R_TIMES, R_VOR0, SIM_DT, SIM_G, SIM_MAX_STRAIN, V_KAPPA, V_REST_VOR,
)
from .cosserat import rod_extent, rod_internal_loads
from .drivers import (
    add_frame_reaction,
    add_impulse,
    add_node_reaction,
    load_drivers,
    step_rod_drivers,
    clamp_rate,
    clamp_rates,
    clamp_values,
    clear_reactions,
    collider_impulses,
    collider_poses,
    origin_at,
)
from .refcount import NO_REFCOUNT
from .so3 import rotate_directors

# Divergence codes returned in status[r, 0].
OK, NOT_FINITE, RUNAWAY_STRETCH, RUNAWAY_BEND = 0, 1, 2, 3
# Explicit steps stop when neighbouring frames turn by more than 3 rad (~172 deg): near the log
# map's half-turn cut the couple flips direction within a step, and at explicit step sizes that
# is where a blow-up shows first. The stable integrator steps through such a fold (a whipped
# soft rope doubles back over one node; its energy is continuous across the cut): only NaN stops
# it there.
FOLD_TURN2 = 9.0


@njit(cache=True, error_model="numpy")
def _kinematic(n0, nn, e0, ne, pos, vel, Q, omega, h):
    """Positions += h v; directors rotated by h * omega (material frame)."""
    for i in range(n0, n0 + nn):
        for j in range(3):
            pos[i, j] += h * vel[i, j]
    for e in range(e0, e0 + ne):
        rotate_directors(Q, e, h, omega[e, 0], omega[e, 1], omega[e, 2])


@njit(cache=True, error_model="numpy")
def _check(e0, ne, v0, nv, dil, kappa, rest_vor, torque, max_strain, max_turn2=FOLD_TURN2):
    """(code, element) of the first NaN or runaway strain in a rod; (OK, -1) if fine.

    ``max_turn2``: square of the largest rotation (rad^2) between neighbouring frames; the
    stable integrator passes inf (it steps through a fold, see ``FOLD_TURN2``)."""
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
        if not (ang2 < max_turn2):  # neighbouring frames turned too far (or NaN)
            return (RUNAWAY_BEND if ang2 == ang2 else NOT_FINITE), j
    return OK, -1


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def advance_rod(r, n_steps, t, sim, rd, env, cols, dl, use_extra, start_mid,
                end_mid):
    """Advance rod ``r`` by ``n_steps`` steps from time ``t``; returns the new time.

    ``rd``: the rods' arrays (state, model, loads, scratch; see :mod:`.bundles`); ``env``
    clamps, planes and driver reactions; ``cols`` the colliders (None without any); ``dl``
    the drivers as this rod sees them (advanced here, step by step). Contact: planes,
    colliders (friction anchors in ``cols``, reactions into ``cols.wrench[r]``) and, with
    ``use_extra``, the node forces ``rd.n3[N_EXTRA]`` (rod-rod contact, computed by the caller at
    this step's mid-point). On divergence stops with ``rd.status[r]`` = (code, element,
    steps done).

    A caller stepping one step at a time (rod-rod contact) may leave the rod at the next
    step's mid-point (``end_mid``: positions and frames at ``t + h``, drivers' rates already
    those of the next step) and start from there (``start_mid``): the two half drifts
    between steps become one, as within a call.
    """
    dt = sim[SIM_DT]
    h = 0.5 * dt
    pos, vel, Q, omega = rd.n3[N_POS], rd.n3[N_VEL], rd.e33[E_Q], rd.e3[E_OMEGA]
    mass, node_radius, node_kmin = rd.n1[N_MASS], rd.n1[N_NODE_RADIUS], rd.n1[N_NODE_KMIN]
    force, contact_force, torque, dil = rd.n3[N_FORCE], rd.n3[N_CONTACT_FORCE], rd.e3[E_TORQUE], rd.e1[E_DIL]
    fext, text, inv_J = rd.n3[N_FEXT], rd.e3[E_TEXT], rd.e3[E_INV_J]
    n0, e0, v0, ne, nn, nv, closed = rod_extent(r, rd.ri[R_NODE0], rd.ri[R_ELEM0], rd.ri[R_VOR0], rd.ri[R_NE], rd.ri[R_CLOSED])
    c0, c1 = env.rod_pcon[r], env.rod_pcon[r + 1]
    f0, f1 = env.rod_fcon[r], env.rod_fcon[r + 1]
    decay = rd.r1[R_DECAY][r]
    g0, g1, g2 = sim[SIM_G], sim[SIM_G + 1], sim[SIM_G + 2]
    planes = env.planes
    n_planes = planes.shape[0]
    # ``cols`` is None without colliders: numba then prunes the collider branch at compile
    # time, which keeps the mesh code (and its compile time) out of plain worlds.
    n_cols = 0
    if cols is not None:
        n_cols = cols.kind.shape[0]
    touching = n_planes > 0 or n_cols > 0 or use_extra
    clamped = c1 > c0 or f1 > f0

    if not start_mid:
        _kinematic(n0, nn, e0, ne, pos, vel, Q, omega, h)
    for step in range(n_steps):
        if step > 0 or not start_mid:
            step_rod_drivers(dl, dt, r, env, cols, False)
        t += h
        clamp_values(h, c0, c1, f0, f1, pos, Q, env, dl)

        rod_internal_loads(r, rd)
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
                                contact_force, rd.n1[N_PEN_OFF])
            if cols is not None:
                collider_poses(r, h, cols, dl)
                rod_collider_contacts(r, n0, nn, e0, ne, dt, dt, pos, vel, pos, rd, cols,
                                      True, False)
                collider_impulses(r, dt, cols, env)
            _carry_offsets(r, n0, nn, planes, pos, vel, node_radius, rd.n1[N_PEN_OFF], dt, cols,
                           rd.stats)
            if use_extra:
                extra = rd.n3[N_EXTRA]
                for i in range(n0, n0 + nn):
                    for j in range(3):
                        force[i, j] += extra[i, j]
                        contact_force[i, j] += extra[i, j]

        code, k = _check(e0, ne, v0, nv, dil, rd.v3[V_KAPPA], rd.v1[V_REST_VOR], torque, sim[SIM_MAX_STRAIN])
        if code != OK:
            rd.status[r, 0] = code
            rd.status[r, 1] = k
            rd.status[r, 2] = step
            return t

        if clamped:
            _clamp_reactions(r, h, dt, c0, c1, f0, f1, rd, env, dl)
        for i in range(n0, n0 + nn):
            inv_m = 1.0 / mass[i]
            for j in range(3):
                vel[i, j] += dt * (force[i, j] * inv_m)
        for e in range(e0, e0 + ne):
            for j in range(3):
                omega[e, j] += dt * (inv_J[e, j] * torque[e, j] * dil[e])
        clamp_rates(h, c0, c1, f0, f1, pos, vel, Q, omega, env, dl)
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
        step_rod_drivers(dl, dt, r, env, cols, True)
        t += h
    if end_mid:
        step_rod_drivers(dl, dt, r, env, cols, False)
        clamp_values(h, c0, c1, f0, f1, pos, Q, env, dl)
    else:
        clamp_values(0.0, c0, c1, f0, f1, pos, Q, env, dl)
    rd.status[r, 2] = n_steps
    return t


@njit(cache=True, error_model="numpy")
def _clamp_reactions(r, tau, dt, c0, c1, f0, f1, rd, env, dl) -> None:
    """What the rod puts on its clamps' drivers this step: the total load on each clamped
    node and frame minus the part the clamp's prescribed motion uses up (explicit step:
    the constraint turns the free velocity update into the prescribed one)."""
    pos, vel, Q, omega = rd.n3[N_POS], rd.n3[N_VEL], rd.e33[E_Q], rd.e3[E_OMEGA]
    clear_reactions(r, c0, c1, f0, f1, env)
    inv_dt = 1.0 / dt
    for c in range(c0, c1):
        i = env.pcon_node[c]
        d = env.pcon_drv[c]
        p = origin_at(dl, d, tau)
        v = clamp_rate(dl, d, pos[i, 0] - p[0], pos[i, 1] - p[1], pos[i, 2] - p[2])
        m = rd.n1[N_MASS][i]
        add_node_reaction(r, d, tau, pos[i, 0], pos[i, 1], pos[i, 2],
                          rd.n3[N_FORCE][i, 0] - m * (v[0] - vel[i, 0]) * inv_dt,
                          rd.n3[N_FORCE][i, 1] - m * (v[1] - vel[i, 1]) * inv_dt,
                          rd.n3[N_FORCE][i, 2] - m * (v[2] - vel[i, 2]) * inv_dt, env, dl)
    for c in range(f0, f1):
        e = env.fcon_elem[c]
        d = env.fcon_drv[c]
        t0 = _frame_load(Q, e, 0, dl, d, omega, rd.e3[E_J], rd.e3[E_TORQUE], rd.e1[E_DIL], inv_dt)
        t1 = _frame_load(Q, e, 1, dl, d, omega, rd.e3[E_J], rd.e3[E_TORQUE], rd.e1[E_DIL], inv_dt)
        t2 = _frame_load(Q, e, 2, dl, d, omega, rd.e3[E_J], rd.e3[E_TORQUE], rd.e1[E_DIL], inv_dt)
        add_frame_reaction(r, d, Q, e, t0, t1, t2, env)
    add_impulse(r, dt, c0, c1, f0, f1, env)


@njit(cache=True, inline="always", error_model="numpy")
def _frame_load(Q, e, j, dl, d, omega, J, torque, dil, inv_dt) -> float:
    """Material component j of the torque on clamped element e beyond what its prescribed
    spin uses up."""
    w = Q[e, j, 0] * dl[d, D_W] + Q[e, j, 1] * dl[d, D_W + 1] + Q[e, j, 2] * dl[d, D_W + 2]
    return torque[e, j] - J[e, j] * (w - omega[e, j]) * inv_dt / dil[e]


@njit(cache=True, error_model="numpy")
def _carry_offsets(r, n0, nn, planes, pos, vel, node_radius, pen_off, dt, cols, stats) -> None:
    """Per node, the depth its contact forces leave alone next step: a node found deeper in a
    plane or collider than one step's approach explains (placed inside) keeps that depth,
    less ``V_OUT dt`` per step, so it is pushed out at ``V_OUT`` instead of being launched;
    an impact gets none. -1: not in contact. ``stats[r, 5]``: the deepest such start (m)
    beyond 20 % of the radius, for the world's warning."""
    for i in range(n0, n0 + nn):
        radius = node_radius[i]
        depth = -1e30
        for p in range(planes.shape[0]):
            depth = max(depth, radius - ((pos[i, 0] - planes[p, 0]) * planes[p, 3]
                                         + (pos[i, 1] - planes[p, 1]) * planes[p, 4]
                                         + (pos[i, 2] - planes[p, 2]) * planes[p, 5]))
        if cols is not None:
            for c in range(cols.kind.shape[0]):
                depth = max(depth, cols.pen[i, c])
        kept = carry_offset(pen_off[i], depth, vel[i, 0] ** 2 + vel[i, 1] ** 2 + vel[i, 2] ** 2,
                            dt, V_OUT)
        note_start_inside(stats, r, pen_off[i], kept, depth, radius)
        pen_off[i] = kept


@njit(cache=True, error_model="numpy")
def _plane_contacts(n0, nn, planes, pos, vel, mass, node_radius, node_kmin, force, dt,
                    contact_force, pen_off):
    """Add plane contact forces to the rod's nodes (also added to ``contact_force``).

    ``planes`` rows: point(3), normal(3), stiffness, damping, mu_s, mu_k, auto flag; an
    automatic penalty uses each node's mass (contact frequency 0.2/dt, critically damped), but
    at least ``node_kmin`` (0.1 % of the elements' axial stiffness EA / dl); ``pen_off`` the
    depth each node's force leaves alone (see ``_carry_offsets``).
    """
    for i in range(n0, n0 + nn):
        speed = math.sqrt(vel[i, 0] ** 2 + vel[i, 1] ** 2 + vel[i, 2] ** 2)
        for p in range(planes.shape[0]):
            k, c = plane_penalty(planes, p, mass[i], node_kmin[i], dt)
            f0, f1, f2, _ = plane_contact_node(
                pos[i, 0], pos[i, 1], pos[i, 2], vel[i, 0], vel[i, 1], vel[i, 2],
                force[i, 0], force[i, 1], force[i, 2], mass[i], node_radius[i], dt,
                planes[p, 0], planes[p, 1], planes[p, 2], planes[p, 3], planes[p, 4], planes[p, 5],
                k, c, planes[p, 8], planes[p, 9],
                start_offset(pen_off[i], node_radius[i] - (
                    (pos[i, 0] - planes[p, 0]) * planes[p, 3] + (pos[i, 1] - planes[p, 1])
                    * planes[p, 4] + (pos[i, 2] - planes[p, 2]) * planes[p, 5]), speed, dt, V_OUT))
            force[i, 0] += f0
            force[i, 1] += f1
            force[i, 2] += f2
            contact_force[i, 0] += f0
            contact_force[i, 1] += f1
            contact_force[i, 2] += f2


@njit(cache=True, nogil=True, error_model="numpy")
def advance_rods(r_begin, r_end, n_steps, t, sim, rd, env, cols, drv, load):
    """Advance rods ``r_begin .. r_end - 1`` independently (no rod-rod contact), each with its
    own copy of the drivers (loaded from ``drv`` first when ``load``); releases the GIL so
    threads can share rods."""
    for r in range(r_begin, r_end):
        dl = env.dloc[r]
        if load:
            load_drivers(dl, drv, r, env, cols)
        rd.r1[R_TIMES][r] = advance_rod(r, n_steps, t, sim, rd, env, cols, dl, False,
                                  False, False)
