"""Stable large-step integrator: implicit Euler on positions and rotations, Newton, banded solve.

Each step solves the backward-Euler equations of the same discrete Cosserat rod as the explicit
integrator (same internal force/torque kernel, so the two agree as dt -> 0):

    m (v - v_n) / h + nu m v = F(x, Q, v)                    v = (x - x_n) / h
    J (w - w_n) / (h e) + nu J w / e = tau(x, Q, w)          Q = exp(-h [w]) Q_n

by Newton iterations on node displacements and element rotation vectors. The Newton matrix is
the mass/inertia term, the exact Hessian of the stretch-shear energy (quadratic in positions at
fixed frames) including its stress (geometric) terms, a Gauss-Newton bend-twist Hessian and the
contact stiffnesses. In the per-rod order x0, phi0, x1, phi1, ... it is block-pentadiagonal and
factors by banded Cholesky in O(n) (by block LU when sliding friction's coupling to the normal
force makes it nonsymmetric). Every stiff term is implicit, so the step is stable for any
stiffness; the numerical damping is backward Euler's: a mode of angular frequency w keeps
1/sqrt(1 + (w h)^2) of its amplitude per step.

Contact (world planes, meshes, primitives) uses contact planes found once per step at its start
with a speculative margin (see :mod:`deformx.engine.contact.speculative`): linear gaps, a force
continuous at first touch, stick/slip that cannot alternate within a step, so Newton converges
at large steps without halving them and nothing thinner than the margin is passed. Friction is
an elastic stick spring anchored where the point touched down: a static load below mu_s N holds
(bounded elastic shift F/k, no creep), and sliding costs mu_k N.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..contact.pairplanes import (PP_COLS, PS_COLS, commit_pairs, pair_plane, pair_plane_forces,
                                  refind_pairs, release_pulling_pairs, stiffen_pairs)
from ..contact.speculative import (SP_K, freeze_friction_bounds, gather_planes, plane_forces,
                                   project_predictor, refind_segments, release_pulling,
                                   reengage_deep, start_penetrations, stiffen_deep,
                                   unfreeze_friction_bounds)
from .banded import (BLOCK_BAND, LU_UPPER, add_lower, block_cholesky, block_lu, block_lu_solve,
                     block_solve, expand_upper, store_block)
from .lowrank import lowrank_apply, lowrank_factor
from .cosserat import rod_extent, rod_internal_loads
from .so3 import relative_rotation_vector, rotate_directors
from .bundles import (
    borrow,
    E_DIL, E_J, E_OMEGA, E_PAIR_OFF, E_Q, E_QE, E_QH, E_QN, E_REST_LEN, E_S, E_SEG_A, E_SEG_B,
    E_STRESS, E_TEXT,
    E_TN_EL, E_ALPHA, E_TORQUE, E_WE, E_WH, E_WN, N_ACC, N_CONTACT_FORCE,
    N_FEXT, N_FN_EL, N_FORCE, N_MASS, N_POS, N_VE, N_VEL, N_VH, N_VN, N_XE, N_XH, N_XN, N_XP,
    OPT_ITER, R_CLOSED, R_CONTACTS, R_COUPLED, R_ELEM0, R_FACT_AGE, R_FACT_H, R_FIRST_UPD,
    R_H_PREV, R_NE, R_NODE0, R_NU, R_RATE, R_TAU, R_TIMES, R_VOR0,
    SIM_DT, SIM_G, SIM_MAX_STRAIN, SIM_ORDER, SIM_RR, SIM_TOL, V_B, V_KAPPA, V_REST_VOR,
)
from .drivers import (
    add_frame_reaction,
    add_impulse,
    add_node_reaction,
    load_drivers,
    step_rod_drivers,
    clamp_rates,
    clamp_values,
    clear_reactions,
    collider_impulses,
    collider_poses,
)
from .verlet import OK, RUNAWAY_STRETCH, _check
from .refcount import NO_REFCOUNT

NOT_CONVERGED = 4  # status code: Newton failed even on dt / MAX_REFINE sub-steps
# stats per rod (bundles' ``stats``): steps, Newton iterations, sub-steps at the iteration cap,
# last relative update, step halvings, the deepest start penetration, BDF2 steps retried by
# backward Euler, steps started from an earlier step's factor, steps retried without the
# shortcuts below (quadratic stop, fresh second factor), the deepest start overlap with another
# rod (m; both warned about by the world).
CHORD_RATE = 0.1  # reuse the factor while each update is below this fraction of the last
REUSE_STEPS = 20.0  # a calm step may start from the factor of up to this many steps before
# An update made with an earlier step's factor is accepted within this fraction of the
# tolerance (it contracts less than a fresh one: at the full tolerance a rope sticking to a box
# accelerating under it crept 2.2 mm in 0.5 s at dt = 1e-3, and at 0.3 a steel bar at rest
# kept 0.3 mm/s of jitter), and such a factor is tried only after a step whose first update
# was as small (motion the predictor foresees: a fall, a rope at rest).
STALE_LIMIT = 0.03
EARLY_LIMIT = 10.0  # one-iteration steps only when the update is within this many tolerances
MAX_SET_ROUNDS = 4  # contact releases per step before the set is frozen
MAX_PAIR_ROUNDS = 6  # and for rod-rod pairs (a pile lets go of more, one layer at a time)
# Rounds of planes added at converged iterates (refind_segments, refind_pairs) per step (with
# two, half of a 1 mm rope of 2 cm elements, dropped 0.6 mm higher onto a box's edge, ended a
# step 29 % of its radius inside: its segment across the edge cut in again after the second).
MAX_REFIND = 4
ACCEPT = 1e-2  # an unconverged update above this fraction of an element length is rejected
# An iterate that stretches an element past max_strain is taken back half its update, up to
# this many times a step, before the step is halved.
MAX_BACKTRACK = 4
MAX_REFINE = 64.0  # a step is halved at most down to dt / MAX_REFINE before giving up
# Past the iteration cap Newton goes on, up to EXTEND times the cap, while each update is at
# most EXTEND_RATE times the last (it converges, only slowly: large rotations, contact).
EXTEND, EXTEND_RATE = 4, 0.8
# Contacts that pull are let go (and released ones pressed in since re-engaged) once an update
# is within this many tolerances, not only at convergence: each round of releases then costs
# the iterations from there, not the slow tail to the tolerance as well (pile of ropes 13.1 ->
# 9.5 iterations per step at 1e-2, rope on a cylinder 6.5 -> 4.4; docs/contact.md).
RELEASE_NEAR = 1000.0
# The friction's coupling to the normal force enters the Newton matrix once an update is within
# this fraction of an element.
COUPLE_NEAR = 0.3
# The second iteration refactors (rather than reusing the first factor, a chord step) where the
# first update exceeded this many tolerances: an impact's first update leaves a large residual
# that a chord step contracts slowly (cylinder drop at 10 ms: 4.1 -> 2.9 iterations per step).
FRESH_SECOND = 100.0
# Newton's own error estimate: after two freshly factored iterations with the same contacts,
# what is left after update u_k is about u_k^3 / u_(k-1)^2 (quadratic convergence); below the
# tolerance the step stops instead of taking one more iteration to see it, within this many
# tolerances of it.
QUAD_NEAR = 1000.0
# After this many iterations of a round, an update is cut to TRUST_RADIUS (elements or rad): a
# soft rope whipping round a cylinder at 10 ms otherwise swings between iterates 1-2 elements
# apart and the step is halved.
TRUST_AFTER, TRUST_RADIUS = 4, 0.3
MAX_STIFFEN = 2  # rounds of contacts stiffened at converged iterates (stiffen_deep) per step
# and for islands of touching rods (a pair's penalty doubles a round: a rope of the
# benchmark's pile, damping 1, seed 11, ended a step 23 % of r inside another after two; 15 %)
MAX_PAIR_STIFFEN = 3
# Anderson acceleration of the linear tails of islands of touching rods: once an update is
# within ANDERSON_NEAR (elements or rad), shrank by less than ANDERSON_RATE and the contacts
# stay the same, the update applied mixes the last ANDERSON_DEPTH ones (at most ANDERSON_CAP
# times as long as Newton's). Not for a rod alone: there it saved 0-2 % of the iterations and
# let a rope sliding off a box edge sink 21 % of its radius instead of 5 %.
ANDERSON_DEPTH, ANDERSON_NEAR, ANDERSON_RATE, ANDERSON_CAP = 2, 0.05, 0.3, 10.0
_DEBUG = False


@njit(cache=True, inline="always", error_model="numpy")
def _add_block(A, I, J, m):
    """Add the 3x3 block ``m`` (row-major tuple) at block row ``I``, block column ``J``.

    Blocks above the diagonal are stored as their transposes below it; a block farther from
    the diagonal than the band (the wrap-around coupling of a closed rod) is left out, which
    makes the matrix an approximate Newton matrix for that rod. Only used for the couplings
    of a closed rod's last element and Voronoi domain, which may wrap around.
    """
    transpose = I < J
    if transpose:
        I, J = J, I
    d = I - J
    if d > BLOCK_BAND:
        return
    for i in range(3):
        for j in range(3):
            A[I, d, i, j] += m[3 * j + i] if transpose else m[3 * i + j]


@njit(cache=True, inline="always", error_model="numpy")
def _qsq(Q, e, i, j, s0, s1, s2):
    """Entry (i, j) of Q[e]^T diag(s) Q[e]."""
    return Q[e, 0, i] * s0 * Q[e, 0, j] + Q[e, 1, i] * s1 * Q[e, 1, j] + Q[e, 2, i] * s2 * Q[e, 2, j]


@njit(cache=True, inline="always", error_model="numpy")
def _rel(Q, ea, eb, i, m):
    """Entry (i, m) of Q[eb] Q[ea]^T."""
    return Q[eb, i, 0] * Q[ea, m, 0] + Q[eb, i, 1] * Q[ea, m, 1] + Q[eb, i, 2] * Q[ea, m, 2]


@njit(cache=True, inline="always", error_model="numpy")
def _rtbr(R, i, m, b0, b1, b2):
    """Entry (i, m) of R^T diag(b) R, ``R`` a row-major tuple."""
    return R[i] * b0 * R[m] + R[3 + i] * b1 * R[3 + m] + R[6 + i] * b2 * R[6 + m]


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _assemble(h, ext, rd, nu, kv, geometric, A):
    """Newton matrix of one rod (extent ``ext``, see ``rod_extent``) into ``A`` (block band);
    returns the number of block rows.

    ``kv`` = 1 + (Kelvin-Voigt retardation time) / h scales the elastic stiffness. The stress
    (geometric) terms are added for elements in tension only, and only with ``geometric``:
    in compression they can make the matrix indefinite (buckling), and Gauss-Newton alone is
    positive definite by construction.

    Every block of the band is written directly (no zeroing pass), of the diagonal blocks only
    the lower triangle (all that the factorisation reads). Element k couples node blocks 2k,
    2k + 2 and rotation block 2k + 1; Voronoi domain j couples rotation blocks 2j + 1, 2j + 3.
    The sums are formed in the same order as by accumulating each term into a zeroed band.
    """
    n0, e0, v0, ne, nn, _, closed = ext
    pos, Q, dil, stress = rd.n3[N_POS], rd.e33[E_Q], rd.e1[E_DIL], rd.e3[E_STRESS]
    S, rest_len, B, rest_vor, mass, J = rd.e3[E_S], rd.e1[E_REST_LEN], rd.v3[V_B], rd.v1[V_REST_VOR], rd.n1[N_MASS], rd.e3[E_J]
    nb = 2 * ne + (0 if closed else 1)
    zero = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    store_block(A, 0, 1, zero)  # blocks before the first column: unused
    store_block(A, 0, 2, zero)
    store_block(A, 1, 2, zero)
    cm = 1.0 / (h * h) + nu / h
    cx = mass[n0] * cm
    # Lower triangle of node block 2k's diagonal before element k's term: mass + element k - 1.
    xdiag = (cx, 0.0, cx, 0.0, 0.0, cx)
    for k in range(ne):
        e = e0 + k
        ia = n0 + k
        wrap = k + 1 == nn  # a closed rod's last element ends at node 0
        ib = n0 if wrap else ia + 1
        bx = 2 * k
        bphi = 2 * k + 1
        by = 0 if wrap else 2 * k + 2
        l0 = rest_len[e]
        il0 = 1.0 / l0  # multiplications instead of a dozen divisions
        # a = Q dx / l0 (stretch times material tangent), n = material stress.
        dx0 = pos[ib, 0] - pos[ia, 0]
        dx1 = pos[ib, 1] - pos[ia, 1]
        dx2 = pos[ib, 2] - pos[ia, 2]
        a0 = (Q[e, 0, 0] * dx0 + Q[e, 0, 1] * dx1 + Q[e, 0, 2] * dx2) * il0
        a1 = (Q[e, 1, 0] * dx0 + Q[e, 1, 1] * dx1 + Q[e, 1, 2] * dx2) * il0
        a2 = (Q[e, 2, 0] * dx0 + Q[e, 2, 1] * dx1 + Q[e, 2, 2] * dx2) * il0
        n0_, n1_, n2_ = stress[e, 0] * kv, stress[e, 1] * kv, stress[e, 2] * kv
        if not geometric or n0_ * a0 + n1_ * a1 + n2_ * a2 <= 0.0:
            n0_, n1_, n2_ = 0.0, 0.0, 0.0
        Sk0, Sk1, Sk2 = S[e, 0] * kv, S[e, 1] * kv, S[e, 2] * kv
        # Node-node: Q^T S Q / l0 (sigma is linear in positions at fixed frames; the force's
        # 1 / e, as PyElastica's, is left out: along the tangent the block is stiffer than the
        # force's Jacobian by about twice the strain, 1.2 % at 0.5 % stretch against finite
        # differences, nothing Newton notices at a rope's strains).
        K = (_qsq(Q, e, 0, 0, Sk0, Sk1, Sk2) * il0, _qsq(Q, e, 0, 1, Sk0, Sk1, Sk2) * il0,
             _qsq(Q, e, 0, 2, Sk0, Sk1, Sk2) * il0, _qsq(Q, e, 1, 0, Sk0, Sk1, Sk2) * il0,
             _qsq(Q, e, 1, 1, Sk0, Sk1, Sk2) * il0, _qsq(Q, e, 1, 2, Sk0, Sk1, Sk2) * il0,
             _qsq(Q, e, 2, 0, Sk0, Sk1, Sk2) * il0, _qsq(Q, e, 2, 1, Sk0, Sk1, Sk2) * il0,
             _qsq(Q, e, 2, 2, Sk0, Sk1, Sk2) * il0)
        minus_K = (-K[0], -K[1], -K[2], -K[3], -K[4], -K[5], -K[6], -K[7], -K[8])
        # Node-rotation: H(x_b, phi) = Q^T C with C = S [a] - [n]; H(x_a, phi) = -H(x_b, phi).
        c01 = -Sk0 * a2 + n2_
        c02 = Sk0 * a1 - n1_
        c10 = Sk1 * a2 - n2_
        c12 = -Sk1 * a0 + n0_
        c20 = -Sk2 * a1 + n1_
        c21 = Sk2 * a0 - n0_
        H = (Q[e, 1, 0] * c10 + Q[e, 2, 0] * c20, Q[e, 0, 0] * c01 + Q[e, 2, 0] * c21,
             Q[e, 0, 0] * c02 + Q[e, 1, 0] * c12,
             Q[e, 1, 1] * c10 + Q[e, 2, 1] * c20, Q[e, 0, 1] * c01 + Q[e, 2, 1] * c21,
             Q[e, 0, 1] * c02 + Q[e, 1, 1] * c12,
             Q[e, 1, 2] * c10 + Q[e, 2, 2] * c20, Q[e, 0, 2] * c01 + Q[e, 2, 2] * c21,
             Q[e, 0, 2] * c02 + Q[e, 1, 2] * c12)
        # Rotation-rotation: l0 ([a]^T S [a] + sym(n a^T) - (n . a) I), plus the inertia.
        na = n0_ * a0 + n1_ * a1 + n2_ * a2
        ci = cm / dil[e]
        rdiag = (J[e, 0] * ci + l0 * (Sk1 * a2 * a2 + Sk2 * a1 * a1 + n0_ * a0 - na),
                 l0 * (-Sk2 * a0 * a1 + 0.5 * (n0_ * a1 + a0 * n1_)),
                 J[e, 1] * ci + l0 * (Sk0 * a2 * a2 + Sk2 * a0 * a0 + n1_ * a1 - na),
                 l0 * (-Sk1 * a0 * a2 + 0.5 * (n0_ * a2 + a0 * n2_)),
                 l0 * (-Sk0 * a1 * a2 + 0.5 * (n1_ * a2 + a1 * n2_)),
                 J[e, 2] * ci + l0 * (Sk0 * a1 * a1 + Sk1 * a0 * a0 + n2_ * a2 - na))
        store_block(A, bx, 0, (xdiag[0] + K[0], 0.0, 0.0, xdiag[1] + K[3], xdiag[2] + K[4], 0.0,
                               xdiag[3] + K[6], xdiag[4] + K[7], xdiag[5] + K[8]))
        store_block(A, bphi, 0, (rdiag[0], 0.0, 0.0, rdiag[1], rdiag[2], 0.0,
                                 rdiag[3], rdiag[4], rdiag[5]))
        # (phi, x_a) = -H^T
        store_block(A, bphi, 1, (-H[0], -H[3], -H[6], -H[1], -H[4], -H[7], -H[2], -H[5], -H[8]))
        if wrap:
            _add_block(A, by, by, K)
            _add_block(A, by, bx, minus_K)
            _add_block(A, by, bphi, H)
        else:
            store_block(A, by, 1, H)  # (x_b, phi)
            store_block(A, by, 2, minus_K)  # (x_b, x_a)
            cx = mass[ib] * cm
            xdiag = (cx + K[0], K[3], cx + K[4], K[6], K[7], cx + K[8])
    if not closed:
        store_block(A, nb - 1, 0, (xdiag[0], 0.0, 0.0, xdiag[1], xdiag[2], 0.0,
                                   xdiag[3], xdiag[4], xdiag[5]))
    # Bend / twist, Gauss-Newton: kappa ~ (phi_b - R phi_a) / rvl with R = Q_b Q_a^T.
    nv = ne if closed else ne - 1
    for j in range(nv):
        ea = e0 + j
        eb = ea + 1 if j + 1 < ne else e0
        vj = v0 + j
        inv = kv / rest_vor[vj]
        R = (_rel(Q, ea, eb, 0, 0), _rel(Q, ea, eb, 0, 1), _rel(Q, ea, eb, 0, 2),
             _rel(Q, ea, eb, 1, 0), _rel(Q, ea, eb, 1, 1), _rel(Q, ea, eb, 1, 2),
             _rel(Q, ea, eb, 2, 0), _rel(Q, ea, eb, 2, 1), _rel(Q, ea, eb, 2, 2))
        b0, b1, b2 = B[vj, 0], B[vj, 1], B[vj, 2]
        ba = 2 * j + 1
        bb = 2 * (j + 1) + 1 if j + 1 < ne else 1
        # (phi_a, phi_a) = R^T B R / rvl, (phi_b, phi_b) = B / rvl, (phi_b, phi_a) = -B R / rvl
        add_lower(A, ba, (_rtbr(R, 0, 0, b0, b1, b2) * inv, _rtbr(R, 1, 0, b0, b1, b2) * inv,
                          _rtbr(R, 1, 1, b0, b1, b2) * inv, _rtbr(R, 2, 0, b0, b1, b2) * inv,
                          _rtbr(R, 2, 1, b0, b1, b2) * inv, _rtbr(R, 2, 2, b0, b1, b2) * inv))
        A[bb, 0, 0, 0] += b0 * inv
        A[bb, 0, 1, 1] += b1 * inv
        A[bb, 0, 2, 2] += b2 * inv
        BR = (-b0 * R[0] * inv, -b0 * R[1] * inv, -b0 * R[2] * inv,
              -b1 * R[3] * inv, -b1 * R[4] * inv, -b1 * R[5] * inv,
              -b2 * R[6] * inv, -b2 * R[7] * inv, -b2 * R[8] * inv)
        if bb == ba + 2:
            store_block(A, bb, 2, BR)
        else:  # a closed rod's last domain
            _add_block(A, bb, ba, BR)
    return nb


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _rod_contacts(r, ext, h, rd, planes, cols, commit, near, chord):
    """Contact forces of rod ``r``'s slot planes (world planes, meshes, primitives) at the
    iterate into ``force`` and ``contact_force`` (cleared first), their stiffness into
    ``el_K``; ``commit`` (accepted step) stores the friction anchors and reactions instead of
    the stiffness (nothing reads it). Returns the number of active contacts (it changes when
    they do). ``near``: whether the rod's slots hold a plane this step; without one only
    ``contact_force`` and the colliders' reactions are cleared (``el_K`` is neither cleared
    nor added: a rope swinging above the ground walked and cleared every slot and element at
    every iteration, ~1/3 of its step). ``chord``: friction's slope along the slip by the secant
    method (``speculative._slip_slope``)."""
    n0, e0, _, ne, nn, _, _ = ext
    contact_force, el_K = rd.n3[N_CONTACT_FORCE], rd.el_K
    for i in range(n0, n0 + nn):
        for d in range(3):
            contact_force[i, d] = 0.0
    if cols is not None:  # the colliders' reactions on this rod (plane_forces adds them)
        for c in range(cols.kind.shape[0]):
            for j in range(6):
                cols.wrench[r, c, j] = 0.0
    if not near:
        return 0
    # The friction coupling blocks only where the last evaluation wrote some (most contacts
    # stick or are frictionless; ``r1[R_COUPLED]`` counts them).
    n_blocks = 7 if rd.r1[R_COUPLED][r] > 0.0 else 3
    if commit:  # (an accepted step's evaluation adds no stiffness)
        n_blocks = 0
    for e in range(e0, e0 + ne):
        for q in range(n_blocks):
            for i in range(3):
                for j in range(3):
                    el_K[e, q, i, j] = 0.0
    # As stiff as the explicit integrator's contact at dt <= 1e-4 s.
    return plane_forces(r, n0, nn, e0, ne, h, min(h, 1e-4), rd.n3[N_POS], rd.n3[N_XN],
                        rd.n3[N_VEL], planes, rd, cols, rd.sp_i, rd.sp_f, commit, rd.stats[r],
                        chord)


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _contacts_again(r, ext, h, rd, planes, cols, chord):
    """``_rod_contacts`` at the same iterate again (after planes were released): their
    forces are taken out of ``force`` first; returns the contact count."""
    n0, nn = ext[0], ext[4]
    force, contact_force = rd.n3[N_FORCE], rd.n3[N_CONTACT_FORCE]
    for i in range(n0, n0 + nn):
        for d in range(3):
            force[i, d] -= contact_force[i, d]
    return _rod_contacts(r, ext, h, rd, planes, cols, False, True, chord)


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _add_element_stiffness(A, e0, ne, nn, el_K):
    """Add each element's contact stiffness blocks (node a-a, b-a, b-b) to the Newton matrix."""
    for k in range(ne):
        e = e0 + k
        ba = 2 * k
        for i in range(3):
            for j in range(3):
                A[ba, 0, i, j] += el_K[e, 0, i, j]
        if k + 1 < nn:
            bb = ba + 2
            for i in range(3):
                for j in range(3):
                    A[bb, 0, i, j] += el_K[e, 2, i, j]
                    A[bb, 2, i, j] += el_K[e, 1, i, j]
        else:  # a closed rod's last element: node b is node 0, its a-b coupling is off-band
            for i in range(3):
                for j in range(3):
                    A[0, 0, i, j] += el_K[e, 2, i, j]


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _add_element_coupling(A, e0, ne, nn, el_K):
    """Add each element's friction coupling blocks (a-a, a-b, b-a, b-b; ``el_K[e, 3:]``) to the
    full band (see ``banded.block_lu``)."""
    for k in range(ne):
        e = e0 + k
        ba = 2 * k
        wrap = k + 1 >= nn  # a closed rod's last element: a-b and b-a are off the band
        bb = 0 if wrap else ba + 2
        for i in range(3):
            for j in range(3):
                A[ba, 0, i, j] += el_K[e, 3, i, j]
                A[bb, 0, i, j] += el_K[e, 6, i, j]
                if not wrap:
                    A[bb, LU_UPPER + 1, i, j] += el_K[e, 4, i, j]  # block (a, b)
                    A[bb, 2, i, j] += el_K[e, 5, i, j]  # block (b, a)


@njit(cache=True, inline="always", error_model="numpy")
def _implied_rates(n0, nn, e0, ne, inv_h, pos, xn, Q, Qn, vel, omega):
    """Backward-Euler velocities of the iterate: (x - x_n) / h and log(Q Q_n^T) / h."""
    for i in range(n0, n0 + nn):
        for d in range(3):
            vel[i, d] = (pos[i, d] - xn[i, d]) * inv_h
    for e in range(e0, e0 + ne):
        w0, w1, w2 = relative_rotation_vector(Qn, e, Q, e)
        omega[e, 0] = w0 * inv_h
        omega[e, 1] = w1 * inv_h
        omega[e, 2] = w2 * inv_h


@njit(cache=True, inline="always", error_model="numpy")
def _extent(rd, r):
    return rod_extent(r, rd.ri[R_NODE0], rd.ri[R_ELEM0], rd.ri[R_VOR0], rd.ri[R_NE], rd.ri[R_CLOSED])


@njit(cache=True, error_model="numpy")
def advance_island_implicit(isl, n_steps, t, sim, opts, rd, env, cols, pc):
    """Advance the rods ``isl`` (one, or several in contact with each other) together by
    ``n_steps`` backward-Euler steps of ``dt``; returns the new time.

    ``rod_nu`` is the uniform damping rate (1/s), ``rod_tau`` the Kelvin-Voigt retardation
    time (s): internal loads become F + tau dF/dt with dF/dt ~ (F - F_n) / h.

    Contact with planes, meshes and primitives enters each rod's Newton iteration through
    force and stiffness (``el_K``: per element, node blocks a-a, b-a, b-b). Rod-rod contacts
    ``pc`` = (pairs, the island's pairs ``plist``, their planes ``pp``, ``ps``) couple the
    rods' systems, solved exactly as banded factors plus a low-rank term (:mod:`.lowrank`):
    the rods share one Newton iteration, so each sees the others' end-of-step positions.
    Each rod sees the drivers as ``env.dloc[r]`` (advanced here).

    This sets up the island's work arrays (the Newton system in the packed rod buffers, the
    rest in two allocations); the steps run in ``_advance_island``, compiled without reference
    counting (it passes the rod bundle to a dozen calls per iteration).
    """
    m = pc[1].shape[0]
    K = isl.shape[0]
    n_nodes = rd.n3[N_POS].shape[0] if m > 0 else 0
    # The small work arrays are borrowed views of one int and one float allocation: a
    # one-rod step() made ~25 allocations, and counted views cost two atomic operations each
    # time they are made or passed (~4 us per call in all). Offsets, then contact-plane and
    # rod-rod scratch.
    nc = 3 * m  # per pair a normal column and, with friction, two tangent ones
    ints = np.zeros(3 * (K + 1) + SP_K + 2 * n_nodes + 5 * nc + 2 * (K + 1), dtype=np.int64)
    floats = np.zeros(8 * K + 12 * SP_K + 6 * nc)
    # The island's system stacks its rods' block rows; per rod its offsets in the stack.
    boff, noff, eoff = (borrow(ints, 0, (K + 1,)), borrow(ints, K + 1, (K + 1,)),
                        borrow(ints, 2 * K + 2, (K + 1,)))
    for k in range(K):
        n0, e0, v0, ne, nn, nv, closed = _extent(rd, isl[k])
        boff[k + 1] = boff[k] + 2 * ne + (0 if closed else 1)
        noff[k + 1] = noff[k] + nn
        eoff[k + 1] = eoff[k] + ne
    nbt = boff[K]
    offs = (boff, noff, eoff)
    # Per rod: scale, last sub-step, updates (this and the previous iteration), whether its
    # slots hold a contact plane this step, whether its contacts are calm (see below), the
    # step of its backward-Euler form (2/3 of the sub-step for BDF2), whether its matrix is
    # factored by block LU.
    per_rod = (borrow(floats, 0, (K,)), borrow(floats, K, (K,)), borrow(floats, 2 * K, (K,)),
               borrow(floats, 3 * K, (K,)), borrow(floats, 4 * K, (K,)),
               borrow(floats, 5 * K, (K,)), borrow(floats, 6 * K, (K,)),
               borrow(floats, 7 * K, (K,)))
    # Newton matrix, residual, prescribed unknowns; the predictor's h * (last step's
    # acceleration) per node and per element. One rod: its own rows of the packed system
    # (rods on threads never share them); an island (solved one at a time): the first rows.
    # Written before read, but the flags.
    b0 = n0 = e0 = 0
    if K == 1:
        n0, e0 = rd.ri[R_NODE0][isl[0]], rd.ri[R_ELEM0][isl[0]]
        b0 = n0 + e0
    fixed = rd.sys_fixed[b0:b0 + nbt]
    fixed[:] = 0
    system = (rd.sys_A[b0:b0 + nbt], rd.sys_rhs[b0:b0 + nbt], fixed,
              rd.n3[N_ACC][n0:n0 + noff[K]], rd.e3[E_ALPHA][e0:e0 + eoff[K]])
    # Contact planes per slot (see contact/speculative.py): scratch.
    o, f = 3 * K + 3, 8 * K
    keep = (borrow(ints, o, (SP_K,)), borrow(floats, f, (SP_K,)),
            borrow(floats, f + SP_K, (SP_K, 8)), borrow(floats, f + 9 * SP_K, (SP_K, 3)))
    # Rod-rod contacts: each node's block in the stack and rod slot, the low-rank terms.
    # Z and S are written before they are read (lowrank_factor zeroes each rod's panel of
    # columns and the columns' matrix it uses): not zeroing them all saves clearing megabytes
    # per step in a pile.
    o, f = o + SP_K, f + 12 * SP_K
    # (no pairs: empty views of ``floats``, no allocation)
    big = np.empty(nc * nbt * 3 + nc * nc + 12 * nbt) if m > 0 else floats
    Z, S = borrow(big, 0, (nc * nbt * 3,)), borrow(big, nc * nbt * 3, (nc * nc,))
    # Anderson's history (islands only): the last two raw updates and the last two applied.
    hist = borrow(big, nc * nbt * 3 + nc * nc, (4, nbt if m > 0 else 0, 3))
    o2 = o + 2 * n_nodes
    # Per rod slot its columns (offsets into a list of them) and its panel's offset in Z;
    # a row of scratch.
    o3 = o2 + 3 * nc
    panels = (borrow(ints, o3, (K + 1,)), borrow(ints, o3 + K + 1, (2 * nc,)),
              borrow(ints, o3 + 2 * nc + K + 1, (K + 1,)), borrow(floats, f + 5 * nc, (nc,)))
    lowrank = (borrow(ints, o, (n_nodes,)), borrow(ints, o + n_nodes, (n_nodes,)), Z, S,
               borrow(ints, o2, (nc,)), borrow(floats, f, (nc, 3)),
               borrow(floats, f + 3 * nc, (nc,)), borrow(ints, o2 + nc, (nc, 2)),
               borrow(floats, f + 4 * nc, (nc,)), panels)
    t = _advance_island(isl, n_steps, t, sim, opts, rd, env, cols, pc,
                        (offs, per_rod, system, keep, lowrank, hist))
    # The borrowed views' owners live until here.
    ints[0] = floats[0] = big.size
    return t


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _advance_island(isl, n_steps, t, sim, opts, rd, env, cols, pc, work):
    """The steps of ``advance_island_implicit`` in the work arrays ``work`` it allocated."""
    pairs, plist, pp, ps = pc
    offs, per_rod, system, keep, lowrank, hist = work
    (boff, noff, eoff), (scale, last_hs, upd, prev_upd, near, calm, hb, lu) = offs, per_rod
    A, rhs, fixed, acc, alpha = system
    keep_src, keep_f, keep_n, x_start = keep
    node_block, node_rod, Z, S, act, cdir, ck, csup, u, panels = lowrank
    seg_a, seg_b = rd.ei[E_SEG_A], rd.ei[E_SEG_B]
    m = plist.shape[0]
    dt = sim[SIM_DT]
    gravity = sim[SIM_G:SIM_G + 3]
    max_strain, tol, max_iter = sim[SIM_MAX_STRAIN], sim[SIM_TOL], opts[OPT_ITER]
    rr = sim[SIM_RR:SIM_RR + 3]
    rod_nu, rod_tau = rd.r1[R_NU], rd.r1[R_TAU]
    pos, vel, Q, omega = rd.n3[N_POS], rd.n3[N_VEL], rd.e33[E_Q], rd.e3[E_OMEGA]
    xn, vn, Qn, wn, fn_el, tn_el = rd.n3[N_XN], rd.n3[N_VN], rd.e33[E_QN], rd.e3[E_WN], rd.n3[N_FN_EL], rd.e3[E_TN_EL]
    h_prev, rate, pair_off = rd.r1[R_H_PREV], rd.r1[R_RATE], rd.e1[E_PAIR_OFF]
    fact_h, fact_age, first_upd = rd.r1[R_FACT_H], rd.r1[R_FACT_AGE], rd.r1[R_FIRST_UPD]
    mass, J, rest_len, rest_vor = rd.n1[N_MASS], rd.e3[E_J], rd.e1[E_REST_LEN], rd.v1[V_REST_VOR]
    fext, text, xp = rd.n3[N_FEXT], rd.e3[E_TEXT], rd.n3[N_XP]
    force, torque, dil, kappa = rd.n3[N_FORCE], rd.e3[E_TORQUE], rd.e1[E_DIL], rd.v3[V_KAPPA]
    el_K, stats, status = rd.el_K, rd.stats, rd.status
    # BDF2 solves the backward-Euler equations from the extrapolated start (xh, vh, Qh, wh) =
    # (4 x_n - x_n-1) / 3 etc. with 2/3 of the step (for that rod: ``hb``), on steps that follow
    # one of the same size and find the rod as that step left it (xe, ve, Qe, we).
    order2 = sim[SIM_ORDER] == 2.0
    xe, ve, Qe, we = rd.n3[N_XE], rd.n3[N_VE], rd.e33[E_QE], rd.e3[E_WE]
    xb, vb, Qb, wb = xn, vn, Qn, wn  # the start the Newton equations step from
    if order2:
        xb, vb, Qb, wb = rd.n3[N_XH], rd.n3[N_VH], rd.e33[E_QH], rd.e3[E_WH]
    planes = env.planes
    h = dt
    K = isl.shape[0]
    nbt = boff[K]
    # Per rod: mean element length (the update's scale) and last accepted sub-step.
    for k in range(K):
        r = isl[k]
        n0, e0, v0, ne, nn, nv, closed = _extent(rd, r)
        length = 0.0
        for e in range(e0, e0 + ne):
            length += rest_len[e]
        scale[k] = length / ne
        last_hs[k] = h_prev[r]
    # Clamped unknowns: their values are prescribed, so their rows/columns drop out.
    for k in range(K):
        r = isl[k]
        n0, e0 = rd.ri[R_NODE0][r], rd.ri[R_ELEM0][r]
        for c in range(env.rod_pcon[r], env.rod_pcon[r + 1]):
            fixed[boff[k] + 2 * (env.pcon_node[c] - n0)] = True
        for c in range(env.rod_fcon[r], env.rod_fcon[r + 1]):
            fixed[boff[k] + 2 * (env.fcon_elem[c] - e0) + 1] = True
    has_planes = planes.shape[0] > 0
    n_cols = 0
    if cols is not None:  # None without colliders (the branch is pruned at compile time)
        n_cols = cols.kind.shape[0]
    sources = has_planes or n_cols > 0
    any_contact = sources or m > 0
    if m > 0:
        for k in range(K):
            n0, nn = rd.ri[R_NODE0][isl[k]], _extent(rd, isl[k])[4]
            for i in range(nn):
                node_block[n0 + i] = boff[k] + 2 * i
                node_rod[n0 + i] = k
    n_act = 0

    done = 0  # full steps completed
    hs = h  # current sub-step (halved when Newton fails, back to h at each full step)
    elapsed = 0.0  # time done within the current full step
    fresh_step = True  # the drivers' rates of a new full step are still to be set
    # A step tries the shortcuts (quadratic stop, fresh second factor) first; one that fails to
    # converge is retried once without them before it is halved.
    shortcuts = True
    while done < n_steps:
        if fresh_step:
            for k in range(K):
                step_rod_drivers(env.dloc[isl[k]], dt, isl[k], env, cols, False)
            fresh_step = False
        # Contact planes of this step, found at its start (colliders at their start poses).
        touching = m > 0
        for k in range(K):
            r = isl[k]
            n0, e0, v0, ne, nn, nv, closed = _extent(rd, r)
            near[k] = 0.0
            if sources:
                if cols is not None:
                    collider_poses(r, elapsed, cols, env.dloc[r])
                if gather_planes(r, n0, nn, e0, ne, hs, pos, vel, gravity, planes, rd, cols,
                                 rd.sp_i, rd.sp_f, keep_src, keep_f, keep_n, x_start) > 0:
                    touching = True
                    near[k] = 1.0
                    start_penetrations(r, n0, nn, e0, ne, hs, pos, planes, rd, cols, rd.sp_i,
                                       rd.sp_f, pos.shape[0])
        for q in range(m):
            pair_plane(plist[q], pairs, rd, pos, xp, hs, rr, pp, ps)
        for k in range(K):
            r = isl[k]
            n0, e0, v0, ne, nn, nv, closed = _extent(rd, r)
            # Predictor: x + h v + h (v - v_prev), i.e. extrapolating the last step's
            # acceleration (vn still holds the previous step's start velocity): ~0.7 Newton
            # iterations fewer on smooth motion. Contact makes velocities jump and then this
            # misleads Newton, so a rod near a contact only gets a small third-order term
            # h^2 (v - v_prev).
            extrapolate = 0.0 if last_hs[k] != hs else (hs if touching else 1.0)
            bdf = order2 and last_hs[k] == hs and _as_left(n0, nn, e0, ne, pos, vel, Q, omega,
                                                           xe, ve, Qe, we)
            third = 1.0 / 3.0 if bdf else 0.0
            hb[k] = 2.0 * hs / 3.0 if bdf else hs
            for i in range(n0, n0 + nn):
                for d in range(3):
                    acc[noff[k] + i - n0, d] = extrapolate * (vel[i, d] - vn[i, d])
                    if order2:
                        xb[i, d] = pos[i, d] + third * (pos[i, d] - xn[i, d])
                        vb[i, d] = vel[i, d] + third * (vel[i, d] - vn[i, d])
                    xn[i, d] = pos[i, d]
                    vn[i, d] = vel[i, d]
            for e in range(e0, e0 + ne):
                if order2:  # a third of the last step's rotation on from Q_n
                    for a in range(3):
                        wb[e, a] = omega[e, a] + third * (omega[e, a] - wn[e, a])
                        for b in range(3):
                            Qb[e, a, b] = Q[e, a, b]
                    if bdf:
                        w0, w1, w2 = relative_rotation_vector(Qn, e, Q, e)
                        rotate_directors(Qb, e, third, w0, w1, w2)
                for a in range(3):
                    alpha[eoff[k] + e - e0, a] = extrapolate * (omega[e, a] - wn[e, a])
                    wn[e, a] = omega[e, a]
                    for b in range(3):
                        Qn[e, a, b] = Q[e, a, b]
            if rod_tau[r] > 0.0:  # internal loads at the step start, for the viscous term
                rod_internal_loads(r, rd)
                for i in range(n0, n0 + nn):
                    for d in range(3):
                        fn_el[i, d] = force[i, d]
                for e in range(e0, e0 + ne):
                    for d in range(3):
                        tn_el[e, d] = torque[e, d]
            for i in range(n0, n0 + nn):
                for d in range(3):
                    pos[i, d] += hs * (vel[i, d] + acc[noff[k] + i - n0, d])
            for e in range(e0, e0 + ne):
                g = eoff[k] + e - e0
                rotate_directors(Q, e, hs, omega[e, 0] + alpha[g, 0], omega[e, 1] + alpha[g, 1],
                                 omega[e, 2] + alpha[g, 2])
            clamp_values(elapsed + hs, env.rod_pcon[r], env.rod_pcon[r + 1], env.rod_fcon[r],
                         env.rod_fcon[r + 1], pos, Q, env, env.dloc[r])
            if cols is not None:
                collider_poses(r, elapsed + hs, cols, env.dloc[r])
            # Calm: no contact about to engage (nothing projected) after a step of this size;
            # with the same contact count at the first iterate as at the last step's end, its
            # contacts neither switch on nor off, and it may stop after one iteration as a rod
            # in free flight does.
            calm[k] = 1.0 if last_hs[k] == hs else 0.0
            if near[k] != 0.0:
                if project_predictor(r, n0, nn, pos, planes, rd, cols, rd.sp_i, rd.sp_f,
                                     fixed[boff[k]:boff[k + 1]]) > 0:
                    calm[k] = 0.0
        t_new = t + hs
        set_rounds = near_rounds = refinds = stiffened = 0
        frozen = False  # friction bounds fixed for the rest of the step
        # Iteration at which the contact set last changed. Rods in contact with each other get
        # a fresh budget after each release (a pile lets go one layer at a time); a rod alone
        # against colliders does not: a step that needs more has outgrown the contact planes
        # found at its start (a fast wrap round a cylinder) and is better halved.
        round_start = 0
        # Near contacts Newton may take twice the iterations before the step is halved.
        budget = max_iter if not touching else 2 * max_iter
        step_scale = 1.0
        last_update = math.inf
        proposed = proposed_prev = math.inf  # undamped updates of this and the last iteration

        converged = False
        failed = OK
        fail_at = -1
        fail_rod = isl[0]
        it = 0
        update = math.inf  # so the second iteration reuses the first one's factor (chord)
        previous = math.inf
        # whether the last two iterations were freshly factored, and their contact counts
        fresh_last = fresh_before = False
        active_last = active_before = -1
        for k in range(K):
            n0, e0, v0, ne, nn, nv, closed = _extent(rd, isl[k])
            _implied_rates(n0, nn, e0, ne, 1.0 / hb[k], pos, xb, Q, Qb, vel, omega)
        backtracks = 0
        active = 0
        n_hist = 0  # valid entries of Anderson's history
        # A calm step (same sub-step, contacts neither switching on nor off) of a rod alone
        # starts from the factor an earlier step left in its rows, as CVODE reuses its Newton
        # matrix over steps: its matrix changes little from step to step, and assembling and
        # factoring it was ~a quarter of such a step. The world forgets the factor
        # (r1[R_FACT_H] = 0) wherever the rod's parameters, state or clamps are changed, and
        # the coupled kernel after each island of several rods (which solves in the first rows).
        # (fact_h < 0: factored by block LU; the contacts it was made with are taken to be
        # those the last step ended with, and a first iterate with others refactors)
        r = isl[0]
        reuse = (m == 0 and K == 1 and calm[0] != 0.0 and abs(fact_h[r]) == hb[0]
                 and fact_age[r] < REUSE_STEPS and first_upd[r] <= STALE_LIMIT * tol)
        factored_active = -1
        if reuse:
            factored_active = int(rd.r1[R_CONTACTS][r])
            lu[0] = 1.0 if fact_h[r] < 0.0 else 0.0
        stale = False  # the first iterate was solved with an earlier step's factor
        while it < budget:
            it += 1
            for k in range(K):
                r = isl[k]
                n0, e0, v0, ne, nn, nv, closed = _extent(rd, r)
                rod_internal_loads(r, rd)
                failed, fail_at = _check(e0, ne, v0, nv, dil, kappa, rest_vor, torque,
                                         max_strain if it > 1 else math.inf, math.inf)
                if failed == OK and it == 1:
                    failed, fail_at = _predictor_strain(n0, nn, e0, ne, hs, pos, xn, vn, dil,
                                                        rest_len, fixed[boff[k]:boff[k + 1]],
                                                        max_strain)
                if failed != OK:
                    fail_rod = r
                    break
                tau = rod_tau[r]
                if tau > 0.0:
                    for i in range(n0, n0 + nn):
                        for d in range(3):
                            force[i, d] += (tau / hs) * (force[i, d] - fn_el[i, d])
                    for e in range(e0, e0 + ne):
                        for d in range(3):
                            torque[e, d] += (tau / hs) * (torque[e, d] - tn_el[e, d])
                for i in range(n0, n0 + nn):
                    for d in range(3):
                        force[i, d] += mass[i] * gravity[d] + fext[i, d]
            if failed == RUNAWAY_STRETCH and backtracks < MAX_BACKTRACK:
                # An iterate (or the predictor) stretched an element past max_strain: go back
                # half of what was applied (a line search) rather than halve the step.
                backtracks += 1
                failed = OK
                for k in range(K):
                    n0, e0, v0, ne, nn, nv, closed = _extent(rd, isl[k])
                    if it == 1:  # (acc / alpha: the last update applied, or the predictor's)
                        _predicted(n0, nn, e0, ne, pos, xn, Q, Qn, fixed[boff[k]:boff[k + 1]],
                                   acc[noff[k]:], alpha[eoff[k]:])
                    for i in range(nn):
                        for d in range(3):
                            acc[noff[k] + i, d] *= 0.5
                            pos[n0 + i, d] -= acc[noff[k] + i, d]
                    for j in range(ne):
                        g = eoff[k] + j
                        for d in range(3):
                            alpha[g, d] *= 0.5
                        rotate_directors(Q, e0 + j, -1.0, alpha[g, 0], alpha[g, 1], alpha[g, 2])
                    _implied_rates(n0, nn, e0, ne, 1.0 / hb[k], pos, xb, Q, Qb, vel, omega)
                n_hist = 0
                if it == 1:
                    it = 0  # the predictor, shortened: still the first iterate
                else:
                    budget += 1
                    update *= 0.5
                    last_update = update
                continue
            if failed != OK:
                break
            active = 0
            # The friction's slope along the slip by the secant method for a rod alone (an
            # island's rod-rod contacts took more iterations: a pile of eight ropes 6.59 ->
            # 7.04 per step at 1e-2), not after a damped update nor in a careful retry.
            chord = shortcuts and m == 0 and step_scale == 1.0
            if any_contact:
                for k in range(K):
                    on = _rod_contacts(isl[k], _extent(rd, isl[k]), hs, rd, planes, cols,
                                       False, near[k] != 0.0, chord)
                    if it == 1 and on != rd.r1[R_CONTACTS][isl[k]]:
                        calm[k] = 0.0
                    active += on
                if m > 0:  # after every rod's own contacts: they clear contact_force
                    active += 1000003 * pair_plane_forces(plist, m, pairs, rd, pos, vel, hs,
                                                          min(hs, 1e-4), rr, pp, ps)
            if (m == 0 and sources and it > 1 and update <= RELEASE_NEAR * tol
                    and near_rounds < MAX_SET_ROUNDS):
                # Near convergence, planes that pull at this iterate are let go before its
                # matrix is made, so the round costs no iteration solved with them still in
                # (the release below decides on the forces of the iterate before). Not for
                # rod-rod pairs, whose release stays below.
                released = 0
                for k in range(K):
                    n0, e0, v0, ne, nn, nv, closed = _extent(rd, isl[k])
                    released += release_pulling(n0, nn, e0, ne, pos.shape[0], rd.sp_i, rd.sp_f)
                if released > 0:
                    near_rounds += 1
                    active = 0
                    for k in range(K):
                        active += _contacts_again(isl[k], _extent(rd, isl[k]), hs, rd, planes,
                                                  cols, chord)
                    budget = max(budget, it + max_iter)
                    round_start = it - 1  # this iteration is the new round's first
                    previous = 0.0  # forces a fresh factorisation
                    last_update = math.inf
            for k in range(K):
                r = isl[k]
                n0, e0, v0, ne, nn, nv, closed = _extent(rd, r)
                nu = rod_nu[r]
                bo = boff[k]
                ihb = 1.0 / hb[k]
                # Residual (negated): forces minus inertia and damping.
                for i in range(nn):
                    g = n0 + i
                    for d in range(3):
                        rhs[bo + 2 * i, d] = force[g, d] - mass[g] * (
                            (vel[g, d] - vb[g, d]) * ihb + nu * vel[g, d])
                for j in range(ne):
                    e = e0 + j
                    inv_dil = 1.0 / dil[e]
                    for d in range(3):
                        rhs[bo + 2 * j + 1, d] = (torque[e, d] + text[e, d] - J[e, d] * inv_dil * (
                            (omega[e, d] - wb[e, d]) * ihb + nu * omega[e, d]))
                c0, c1 = env.rod_pcon[r], env.rod_pcon[r + 1]
                f0, f1 = env.rod_fcon[r], env.rod_fcon[r + 1]
                if c1 > c0 or f1 > f0:  # what the clamps hold is the residual of their rows
                    _clamp_reactions(r, elapsed + hs, n0, e0, c0, c1, f0, f1, pos, Q,
                                     rhs[bo:boff[k + 1]], env, env.dloc[r])
            for q in range(nbt):
                if fixed[q]:
                    rhs[q, 0] = 0.0
                    rhs[q, 1] = 0.0
                    rhs[q, 2] = 0.0
            # Newton matrix, refactored only when the last update did not shrink fast enough
            # (chord iterations are ~3x cheaper); if the stress terms make it indefinite,
            # retry with Gauss-Newton.
            bad = 0
            # A contact switching on or off changes the matrix: a chord step would overshoot.
            refactor = ((it == 1 and not reuse) or (it == 2 and stale)
                        or update > CHORD_RATE * previous or active != factored_active
                        or (shortcuts and it == 2 and m == 0 and update > FRESH_SECOND * tol))
            fresh_before, fresh_last = fresh_last, refactor
            active_before, active_last = active_last, active
            stale = it == 1 and not refactor
            if stale:
                stats[isl[0], 7] += 1
            factored_active = active if refactor else factored_active
            previous = update
            for k in range(K):
                prev_upd[k] = upd[k]
            for k in range(K):
                if not refactor:
                    break
                r = isl[k]
                ext = _extent(rd, r)
                n0, e0, v0, ne, nn, nv, closed = ext
                bo, nb = boff[k], boff[k + 1] - boff[k]
                Ak = A[bo:bo + nb]
                # Friction whose bound follows the normal force makes the matrix nonsymmetric:
                # then block LU (rod-rod contacts' low-rank terms then take an LU of their
                # columns' matrix too). Newton then converges where it crawled at ~0.5 per
                # iteration (a rope dragged over a kerb: 9.2 -> 6.2 iterations per step; a
                # pile of eight ropes on the ground: 8.9 -> 7.5). Not for a rod alone in contact
                # with itself: a 0.5 mm steel wire looping on the ground then diverged.
                # Only near the solution (far from it, at an impact, the coupling's linearisation
                # misleads more than it helps) and, should that matrix not factor, without it.
                # (R_COUPLED is this iteration's count: the rod is near, its contacts evaluated)
                couple = (near[k] != 0.0 and (m == 0 or K > 1) and rd.r1[R_COUPLED][r] > 0.0
                          and update <= COUPLE_NEAR)
                for attempt in range(3):
                    # On a BDF2 step's first iteration the stress terms (of the predictor,
                    # extrapolated from two steps) mislead more than they help: Gauss-Newton
                    # there (the hit-target rope under random commands: 3.2 -> 2.5 iterations
                    # per step and, with the extension's rate below, a tenth of the halvings;
                    # on backward-Euler steps it cost a rope dragged over a kerb 9 %).
                    geometric = attempt == 0 and (it > 1 or hb[k] == hs)
                    lu[k] = 1.0 if couple and attempt < 2 else 0.0
                    if attempt == 2 and not couple:
                        break
                    _assemble(hb[k], ext, rd, rod_nu[r], 1.0 + rod_tau[r] / hs, geometric, Ak)
                    if near[k] != 0.0:
                        _add_element_stiffness(Ak, e0, ne, nn, el_K)
                    if lu[k] != 0.0:
                        expand_upper(Ak, nb)
                        _add_element_coupling(Ak, e0, ne, nn, el_K)
                    for q in range(nb):
                        if fixed[bo + q]:  # prescribed unknowns: identity row and column
                            for d in range(1, BLOCK_BAND + 1):
                                Ak[q, d] = 0.0
                                Ak[q, LU_UPPER + d - 1] = 0.0
                                if q + d < nb:
                                    Ak[q + d, d] = 0.0
                                    Ak[q + d, LU_UPPER + d - 1] = 0.0
                            Ak[q, 0] = 0.0
                            for d in range(3):
                                Ak[q, 0, d, d] = 1.0
                    bad = block_lu(Ak, nb) if lu[k] != 0.0 else block_cholesky(Ak, nb)
                    if bad == 0:
                        break
                fact_h[r] = 0.0 if bad != 0 else (-hb[k] if lu[k] != 0.0 else hb[k])
                fact_age[r] = 0.0
                if bad != 0:
                    fail_rod = r
                    break
            if bad != 0:
                failed = NOT_CONVERGED
                fail_at = (bad - 1) // 2
                break
            if refactor and m > 0:
                n_act = lowrank_factor(plist, m, pairs, seg_a, seg_b, pp, node_block, node_rod,
                                       boff, A, fixed, act, cdir, ck, csup, Z, S, lu, panels)
            for k in range(K):
                bo, nb = boff[k], boff[k + 1] - boff[k]
                if lu[k] != 0.0:
                    block_lu_solve(A[bo:bo + nb], nb, rhs[bo:bo + nb])
                else:
                    block_solve(A[bo:bo + nb], nb, rhs[bo:bo + nb])
            if n_act > 0:
                lowrank_apply(n_act, act, cdir, csup, pairs, seg_a, seg_b, pp, node_block,
                              node_rod, boff, fixed, Z, S, u, rhs, panels)
            # Update size relative to each rod's element length; the island's is the largest.
            update = 0.0
            for k in range(K):
                bo, nb = boff[k], boff[k + 1] - boff[k]
                worst = 0.0
                for q in range(0, nb, 2):
                    for d in range(3):
                        worst = max(worst, abs(rhs[bo + q, d]))
                worst_phi = 0.0
                for q in range(1, nb, 2):
                    worst_phi = max(worst_phi, abs(rhs[bo + q, 0]) + abs(rhs[bo + q, 1])
                                    + abs(rhs[bo + q, 2]))
                upd[k] = max(worst / scale[k], worst_phi)
                if it == 1:
                    first_upd[isl[k]] = upd[k]
                update = max(update, upd[k])
            # Damped Newton: when the update stops shrinking the iterate is overshooting
            # (a locally non-convex problem, e.g. a compressed soft rod), so take a shorter step.
            step_scale = step_scale * 0.5 if update >= last_update else 1.0
            if update > TRUST_RADIUS and it - round_start > TRUST_AFTER:
                step_scale = min(step_scale, TRUST_RADIUS / update)
            last_update = update
            if _DEBUG:
                print(t, hs, it, update, step_scale, active % 1000003, active // 1000003)
            proposed_prev, proposed = proposed, update
            # A linear tail (a contact set that stays, friction's secant, the twist of a rod
            # bent over another) is accelerated by Anderson's mixing of the last updates.
            # (the history is of consecutive iterates: any other iteration, a backtrack and a
            # new round or step restart it)
            accelerate = m > 0 and step_scale == 1.0 and update <= ANDERSON_NEAR
            if not accelerate or active != active_before or it - round_start < 2:
                n_hist = 0
            if accelerate:
                _anderson(K, boff, scale, rhs, hist, n_hist,
                          update > tol and update > ANDERSON_RATE * proposed_prev)
                n_hist = min(n_hist + 1, ANDERSON_DEPTH)
            update *= step_scale
            # Apply the update: positions add, frames rotate by the material rotation vector;
            # and the implied rates of the new iterate (as _implied_rates), while it is at hand.
            for k in range(K):
                upd[k] *= step_scale
                n0, e0, v0, ne, nn, nv, closed = _extent(rd, isl[k])
                bo = boff[k]
                ihb = 1.0 / hb[k]
                for i in range(nn):
                    g = n0 + i
                    for d in range(3):
                        acc[noff[k] + i, d] = step_scale * rhs[bo + 2 * i, d]
                        pos[g, d] += step_scale * rhs[bo + 2 * i, d]
                        vel[g, d] = (pos[g, d] - xb[g, d]) * ihb
                for j in range(ne):
                    b = bo + 2 * j + 1
                    e = e0 + j
                    for d in range(3):
                        alpha[eoff[k] + j, d] = step_scale * rhs[b, d]
                    rotate_directors(Q, e, step_scale, rhs[b, 0], rhs[b, 1], rhs[b, 2])
                    w0, w1, w2 = relative_rotation_vector(Qb, e, Q, e)
                    omega[e, 0] = w0 * ihb
                    omega[e, 1] = w1 * ihb
                    omega[e, 2] = w2 * ihb
            # Convergence: what is left after this update is about rate * update, with the
            # contraction rate measured on this and earlier steps (CVODE's test), so smooth
            # steps can stop after one iteration. Not in rod-rod contact, nor near a contact
            # plane unless the rod's contacts are calm (a force switching on within the step
            # needs another iteration).
            early = it == 1 and m == 0
            for k in range(K):
                r = isl[k]
                if it >= 2 and prev_upd[k] > 0.0 and previous > 0.0 and previous < math.inf:
                    rate[r] = max(0.3 * rate[r], upd[k] / prev_upd[k])
                # (not after a BDF2 step's Gauss-Newton first iteration: what is left after
                # it is not the contraction rate times the update)
                early = (early and upd[k] <= (STALE_LIMIT if stale else EARLY_LIMIT) * tol
                         and rate[r] * upd[k] <= tol
                         and (calm[k] != 0.0 or not touching) and hb[k] == hs)
            # (the rate against the update Newton proposed last, not the damped part applied:
            # after a damped iteration the next update is the other half of the same one)
            if (it == budget and update <= EXTEND_RATE * max(previous, proposed_prev)
                    and previous < math.inf
                    and it < (round_start if m > 0 else 0) + EXTEND * max_iter):
                budget += 1  # still contracting: a few more iterations cost less than halving
            if it == budget and update > tol and not early and not frozen and sources:
                # About to give up: fix the colliders' friction bounds and go on.
                frozen = True
                count = 0
                for k in range(K):
                    n0, e0, v0, ne, nn, nv, closed = _extent(rd, isl[k])
                    count += freeze_friction_bounds(n0, nn, e0, ne, pos.shape[0],
                                                    planes.shape[0], rd.sp_i, rd.sp_f)
                if count > 0:
                    budget = it + 2 * max_iter
                    round_start = it
                    previous = 0.0  # forces a fresh factorisation
                    continue
            small = update <= (STALE_LIMIT * tol if stale else tol)
            if (shortcuts and not small and m == 0 and it - 1 > round_start and fresh_last
                    and fresh_before and active_last == active_before and step_scale == 1.0
                    and update <= QUAD_NEAR * tol and 0.0 < previous < math.inf
                    and update * update * update <= tol * previous * previous):
                small = True
            done_iterating = early or small or it == budget
            # (rounds near convergence are counted apart: they must not use up the ones at
            # convergence, the last chance to re-engage a plane released too early)
            near_round = (not done_iterating and update <= RELEASE_NEAR * tol
                          and near_rounds < (MAX_PAIR_ROUNDS if m > 0 else MAX_SET_ROUNDS))
            if done_iterating or near_round:
                released = 0
                rounds = near_rounds if near_round else set_rounds
                if rounds < MAX_SET_ROUNDS and sources:
                    for k in range(K):
                        n0, e0, v0, ne, nn, nv, closed = _extent(rd, isl[k])
                        released += release_pulling(n0, nn, e0, ne, pos.shape[0], rd.sp_i,
                                                    rd.sp_f)
                if rounds < MAX_PAIR_ROUNDS and m > 0:
                    released += release_pulling_pairs(plist, m, pp, ps)
                if released > 0:
                    # Contacts that pull were released: solve again without them.
                    if near_round:
                        near_rounds += 1
                    else:
                        set_rounds += 1
                    budget = it + (2 * max_iter if m > 0 else max_iter)
                    round_start = it
                    previous = 0.0  # forces a fresh factorisation
                    last_update = math.inf  # a new problem: its first update is not damped
                    continue
                if not done_iterating:
                    continue
                converged = early or small
                # (an unconverged iterate about to be accepted is checked as well)
                settled = converged or update <= ACCEPT
                added = 0
                if settled and (sources or m > 0) and refinds < MAX_REFIND:
                    # Segments that cut into a collider between their planes get one there,
                    # pairs that overlap away from theirs a new one, and planes released deep
                    # behind act again.
                    for k in range(K):
                        if near[k] != 0.0 and n_cols > 0:
                            n0, e0, v0, ne, nn, nv, closed = _extent(rd, isl[k])
                            added += refind_segments(isl[k], n0, nn, e0, ne, pos, xn, planes,
                                                     rd, cols, rd.sp_i, rd.sp_f)
                        if near[k] != 0.0 and sources:
                            n0, e0, v0, ne, nn, nv, closed = _extent(rd, isl[k])
                            added += reengage_deep(n0, nn, e0, ne, pos.shape[0], rd, rd.sp_i,
                                                   rd.sp_f)
                    if m > 0:
                        added += refind_pairs(plist, m, pairs, rd, pos, xn, pp, ps)
                    refinds += 1 if added > 0 else 0
                if (added == 0 and settled and (sources or m > 0)
                        and stiffened < (MAX_PAIR_STIFFEN if m > 0 else MAX_STIFFEN)):
                    # Contacts pressed deeper than their penalty was sized for get stiffer.
                    for k in range(K):
                        if near[k] != 0.0 and sources:
                            n0, e0, v0, ne, nn, nv, closed = _extent(rd, isl[k])
                            added += stiffen_deep(n0, nn, e0, ne, pos.shape[0], planes, rd, cols,
                                                  rd.sp_i, rd.sp_f)
                    if m > 0:
                        added += stiffen_pairs(plist, m, pairs, rd, pos, rr, pp, ps)
                    stiffened += 1 if added > 0 else 0
                    if added > 0 and frozen:
                        # Friction bounds fixed at the normal forces before the stiffening
                        # would hold no more (a 1 mm rope met by a capsule lying on the floor:
                        # its bound 0.016 N, its normal force then 7 N; the capsule pushed it
                        # along its normal only, the floor's friction held, and the wedge
                        # locked it 75 % of its radius deep): they follow them again.
                        for k in range(K):
                            n0, e0, v0, ne, nn, nv, closed = _extent(rd, isl[k])
                            unfreeze_friction_bounds(n0, nn, e0, ne, pos.shape[0], rd.sp_i,
                                                     rd.sp_f)
                        frozen = False
                if added > 0:  # iterate on with the new planes or stiffnesses
                    # (islands as after a release: a pile's stiffened pair took 5-8 iterations
                    # to settle again, and with 4 halved one step in 100 on 5 of 14 seeds)
                    budget = it + (2 * max_iter if m > 0 else max_iter)
                    round_start = it
                    previous = 0.0
                    last_update = math.inf
                    continue
                break
        if failed == OK and not converged and update > ACCEPT:
            failed = NOT_CONVERGED
            fail_at = 0
        if failed != OK:
            # Roll back and retry the step in halves; give up only at a tiny fraction of dt.
            second = False
            for k in range(K):
                n0, e0, v0, ne, nn, nv, closed = _extent(rd, isl[k])
                _copy_state(n0, nn, e0, ne, (xn, vn, wn, Qn), (pos, vel, omega, Q))
                second = second or hb[k] != hs
                last_hs[k] = 0.0  # (the retry is a backward-Euler step)
                fact_h[isl[k]] = 0.0
            if second and failed == NOT_CONVERGED:
                # A BDF2 step that did not converge is first retried whole by backward Euler,
                # which damps what BDF2 keeps (a rope whipped by random commands: 7x fewer
                # halvings), and without the shortcuts.
                stats[isl[0], 6] += 1
                shortcuts = False
                continue
            if shortcuts and failed == NOT_CONVERGED and m == 0:
                shortcuts = False
                stats[isl[0], 8] += 1
                continue
            if hs > h / MAX_REFINE:
                hs *= 0.5
                stats[isl[0], 4] += 1
                continue
            for k in range(K):
                status[isl[k], 2] = done
            status[fail_rod, 0] = failed
            status[fail_rod, 1] = max(fail_at, 0)
            return t
        # Accepted (velocities are the last iterate's): friction anchors and clamp rates.
        for k in range(K):
            r = isl[k]
            ext = _extent(rd, r)
            n0, e0, v0, ne, nn, nv, closed = ext
            c0, c1 = env.rod_pcon[r], env.rod_pcon[r + 1]
            f0, f1 = env.rod_fcon[r], env.rod_fcon[r + 1]
            rd.r1[R_CONTACTS][r] = 0.0
            if any_contact:
                rd.r1[R_CONTACTS][r] = _rod_contacts(r, ext, hs, rd, planes, cols, True,
                                                     near[k] != 0.0, False)
            if cols is not None:
                collider_impulses(r, hs, cols, env)
            clamp_rates(elapsed + hs, c0, c1, f0, f1, pos, vel, Q, omega, env, env.dloc[r])
            if c1 > c0 or f1 > f0:
                add_impulse(r, hs, c0, c1, f0, f1, env)
            if m > 0:
                for e in range(e0, e0 + ne):
                    pair_off[e] = -1.0
            last_hs[k] = hs
            fact_age[r] += 1.0
            if order2:  # what the next step checks it finds (nothing changed in between)
                _copy_state(n0, nn, e0, ne, (pos, vel, omega, Q), (xe, ve, we, Qe))
            stats[r, 1] += it
            if not converged:
                stats[r, 2] += 1
            stats[r, 3] = upd[k]
        if m > 0:  # the pairs' share of contact_force, cleared above; their offsets carry over
            pair_plane_forces(plist, m, pairs, rd, pos, vel, hs, min(hs, 1e-4), rr, pp, ps)
            commit_pairs(plist, m, pairs, rd, pp)
        t = t_new
        shortcuts = True
        elapsed += hs
        if elapsed >= h * (1.0 - 1e-9):
            done += 1
            for k in range(K):
                r = isl[k]
                step_rod_drivers(env.dloc[r], dt, r, env, cols, True)
                stats[r, 0] += 1
                if hs != h:
                    last_hs[k] = 0.0
            fresh_step = True
            elapsed = 0.0
            hs = h
    for k in range(K):
        status[isl[k], 2] = n_steps
        h_prev[isl[k]] = last_hs[k]
    return t


@njit(cache=True, inline="always", error_model="numpy")
def _mixed(hist, q, d, f, c1, c2, n_hist):
    """Component (q, d) of Anderson's update from the raw one ``f`` and coefficients."""
    a = f - c1 * (hist[2, q, d] + f - hist[0, q, d])
    if n_hist > 1:
        a -= c2 * (hist[3, q, d] + hist[0, q, d] - hist[1, q, d])
    return a


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _anderson(K, boff, scale, rhs, hist, n_hist, mix):
    """Anderson acceleration (type II) of the Newton update ``rhs`` (positions weighted by
    1 / element length, rotations in rad), from the ``n_hist`` last raw updates ``hist[0:2]``
    and applied ones ``hist[2:4]`` (newest first); with ``mix`` false the update is kept. The
    raw and the applied update are pushed into the history.

    The mixing minimises the linearised update at the next iterate over the span of the last
    iterates: a tail contracting by a constant factor r per iteration is extrapolated by
    1 / (1 - r), two such modes at once with a history of two (an island's twist and a
    contact's friction), where Newton with an inexact matrix crawls.
    """
    g11 = g12 = g22 = b1 = b2 = ff = 0.0
    for k in range(K if mix and n_hist > 0 else 0):
        w_x = 1.0 / (scale[k] * scale[k])
        for q in range(boff[k], boff[k + 1]):
            w = w_x if (q - boff[k]) % 2 == 0 else 1.0
            for d in range(3):
                f = rhs[q, d]
                ff += w * f * f
                d1 = f - hist[0, q, d]
                g11 += w * d1 * d1
                b1 += w * d1 * f
                if n_hist > 1:
                    d2 = hist[0, q, d] - hist[1, q, d]
                    g12 += w * d1 * d2
                    g22 += w * d2 * d2
                    b2 += w * d2 * f
    c1 = c2 = 0.0
    if mix and n_hist > 1 and g11 * g22 - g12 * g12 > 1e-8 * g11 * g22:
        det = g11 * g22 - g12 * g12
        c1 = (b1 * g22 - b2 * g12) / det
        c2 = (g11 * b2 - g12 * b1) / det
    elif mix and n_hist > 0 and g11 > 0.0:
        c1 = b1 / g11
    if c1 != 0.0 or c2 != 0.0:  # an extrapolation far beyond the update is not trusted
        aa = 0.0
        for k in range(K):
            w_x = 1.0 / (scale[k] * scale[k])
            for q in range(boff[k], boff[k + 1]):
                w = w_x if (q - boff[k]) % 2 == 0 else 1.0
                for d in range(3):
                    a = _mixed(hist, q, d, rhs[q, d], c1, c2, n_hist)
                    aa += w * a * a
        if aa > ANDERSON_CAP * ANDERSON_CAP * ff:
            c1 = c2 = 0.0
    mixed = c1 != 0.0 or c2 != 0.0
    for q in range(boff[K]):
        for d in range(3):
            f = rhs[q, d]
            # (the history is uninitialised memory until filled: read only when mixing)
            a = _mixed(hist, q, d, f, c1, c2, n_hist) if mixed else f
            hist[1, q, d] = hist[0, q, d]
            hist[0, q, d] = f
            hist[3, q, d] = hist[2, q, d]
            hist[2, q, d] = a
            rhs[q, d] = a


@njit(cache=True, inline="always", error_model="numpy")
def _copy_state(n0, nn, e0, ne, src, dst):
    """Copy a rod's (positions, velocities, angular velocities, frames) from ``src`` to
    ``dst``."""
    for i in range(n0, n0 + nn):
        for d in range(3):
            dst[0][i, d] = src[0][i, d]
            dst[1][i, d] = src[1][i, d]
    for e in range(e0, e0 + ne):
        for a in range(3):
            dst[2][e, a] = src[2][e, a]
            for b in range(3):
                dst[3][e, a, b] = src[3][e, a, b]


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _as_left(n0, nn, e0, ne, pos, vel, Q, omega, xe, ve, Qe, we):
    """Whether the rod's state is exactly as its last step left it (a write between steps,
    such as a reset or a teleport, breaks the history a second-order step needs)."""
    for i in range(n0, n0 + nn):
        for d in range(3):
            if pos[i, d] != xe[i, d] or vel[i, d] != ve[i, d]:
                return False
    for e in range(e0, e0 + ne):
        for a in range(3):
            if omega[e, a] != we[e, a]:
                return False
            for b in range(3):
                if Q[e, a, b] != Qe[e, a, b]:
                    return False
    return True


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _predicted(n0, nn, e0, ne, pos, xn, Q, Qn, fixed, dx, phi) -> None:
    """The predictor's displacement ``dx`` (m) and rotation vector ``phi`` from the step start,
    zero for prescribed unknowns."""
    for i in range(nn):
        for d in range(3):
            dx[i, d] = 0.0 if fixed[2 * i] else pos[n0 + i, d] - xn[n0 + i, d]
    for j in range(ne):
        w = relative_rotation_vector(Qn, e0 + j, Q, e0 + j)
        for d in range(3):
            phi[j, d] = 0.0 if fixed[2 * j + 1] else w[d]


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _predictor_strain(n0, nn, e0, ne, h, pos, xn, vn, dil, rest_len, fixed, max_strain):
    """(code, element) of the predictor's first runaway strain, as ``_check``, leaving out the
    elements next to a prescribed node that did not move as its start velocity says (a clamp
    set moving: x + h v everywhere else stretches that element, which says nothing of the
    step). Elsewhere, and next to clamps moving steadily or at rest, the predictor is checked
    as Newton's iterates are: a hanging rod that overstretches is caught here."""
    for j in range(ne):
        if abs(dil[e0 + j] - 1.0) <= max_strain:
            continue
        jumped = False
        for i in (j, (j + 1) % nn):
            if fixed[2 * i]:
                g = n0 + i
                dx = math.sqrt((pos[g, 0] - xn[g, 0] - h * vn[g, 0]) ** 2
                               + (pos[g, 1] - xn[g, 1] - h * vn[g, 1]) ** 2
                               + (pos[g, 2] - xn[g, 2] - h * vn[g, 2]) ** 2)
                jumped = jumped or dx > 0.1 * rest_len[e0 + j]
        if not jumped:
            return RUNAWAY_STRETCH, j
    return OK, -1


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _clamp_reactions(r, tau, n0, e0, c0, c1, f0, f1, pos, Q, rhs, env, dl) -> None:
    """The load of rod ``r`` on its clamps' drivers: the residual (forces minus inertia) of
    the clamped rows, which the prescribed motion takes up."""
    clear_reactions(r, c0, c1, f0, f1, env)
    for c in range(c0, c1):
        i = env.pcon_node[c]
        q = 2 * (i - n0)
        add_node_reaction(r, env.pcon_drv[c], tau, pos[i, 0], pos[i, 1], pos[i, 2], rhs[q, 0],
                          rhs[q, 1], rhs[q, 2], env, dl)
    for c in range(f0, f1):
        e = env.fcon_elem[c]
        q = 2 * (e - e0) + 1
        add_frame_reaction(r, env.fcon_drv[c], Q, e, rhs[q, 0], rhs[q, 1], rhs[q, 2], env)


@njit(cache=True, nogil=True, error_model="numpy")
def advance_rods_implicit(r_begin, r_end, n_steps, t, sim, opts, rd, env, cols, drv, load):
    """Advance rods ``r_begin .. r_end - 1`` (none touching another), each alone and with its
    own copy of the drivers (loaded from ``drv`` first when ``load``); releases the GIL so
    threads can share rods."""
    isl = np.empty(1, dtype=np.int64)
    # No pairs: empty views borrowed from arrays alive for the call.
    pc = (borrow(isl, 0, (0, 2)), borrow(isl, 0, (0,)), borrow(sim, 0, (0, PP_COLS)),
          borrow(isl, 0, (0, PS_COLS)))
    for r in range(r_begin, r_end):
        if load:
            load_drivers(env.dloc[r], drv, r, env, cols)
        isl[0] = r
        rd.r1[R_TIMES][r] = advance_island_implicit(isl, n_steps, t, sim, opts, rd, env, cols, pc)
