"""Rod-rod contact of the stable integrator: separating planes found once per step.

At a 10 ms step a falling rope moves by centimetres, many radii, so closest points taken at the
Newton iterates can jump past the other rod (the iterate lies beyond it, where the capsules no
longer overlap). As for colliders (:mod:`.speculative`), each candidate pair of segments is
looked at once at the step start: its closest points (segment parameters ``s``, ``t``) and the
unit normal ``n`` from the second segment's point to the first's. During the step the pair's
penetration is linear in the unknowns,

    d = r_i + r_j - n . (x_i(s) - x_j(t)),

so the Newton matrix of the pair is exact (``(k + c / h) g g^T`` with ``g`` the gradient of
``d``), and a rod cannot pass another rod that it started the step on one side of: the sides are
those of the plane, not of the iterates' closest points. Pairs whose start gap is wider than
``MARGIN`` times the two segments' predicted travel are left out of the step.

Force law, active set (semismooth, see ``switch_active``), start-inside offset as for the
collider planes: ``N = k (d - d_off) + c (d - max(d0, 0)) / h`` with ``d_off`` carried per
element while in contact (a rod placed inside another comes out at ``V_OUT``, a resting one
does not sink step by step). Friction is
``mu N0 tanh(c |u_t| / (mu N0))`` against the relative tangential velocity ``u_t``: smooth, at
most ``mu N0``, with ``N0`` the normal force at the step start (lagged, as in IPC). Both rods of a pair are solved together (see ``kernels/implicit.py``), and each
pair's force acts equal and opposite on both, so momentum is conserved exactly.

Per pair (rows of ``pp``): s, t, normal (3), d0, d_off, effective stiffness k + c / h, normal
force N, the friction's stiffness along and across the slip, the slip direction (3), the
lagged normal force N0 and the penalty's multiplier within the step (``stiffen_pairs``); ``ps``:
active-set state, whether the pair is near enough to take part this step, its switches.
"""

from __future__ import annotations

import math

from numba import njit

from ..geometry.closest import closest_segment_segment
from ..kernels.bundles import (
    E_PAIR_OFF, E_SEG_A, E_SEG_B, E_SEG_RADIUS, N_CONTACT_FORCE, N_FORCE, N_MASS,
    N_NODE_KMIN,
)
from .rodrod import note_start_overlap, pair_penalty
from .speculative import (ACTIVE, INACTIVE, MARGIN, MAX_KMUL, PAIR_FLIPS, REFIND_DEPTH,
                          STIFFEN_DEPTH, V_OUT, switch_active)
from ..kernels.refcount import NO_REFCOUNT

PP_S, PP_T, PP_N, PP_D0, PP_OFF, PP_KN, PP_FN, PP_KA, PP_KB, PP_SH, PP_LAG, PP_KMUL, PP_COLS = (
    0, 1, 2, 5, 6, 7, 8, 9, 10, 11, 14, 15, 16)
PS_SET, PS_NEAR, PS_FLIPS, PS_COLS = 0, 1, 2, 3
# A pair that has switched this many times within a step is no longer released: it sits at the
# edge of touching, pressed together without its force and pulling with it, and each release
# and re-engagement cost a whole solve (a pile cycled so through all its release rounds).
KEEP_FLIPS = 3


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _point(X, a, b, w):
    return ((1.0 - w) * X[a, 0] + w * X[b, 0], (1.0 - w) * X[a, 1] + w * X[b, 1],
            (1.0 - w) * X[a, 2] + w * X[b, 2])


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _travel(X, Xp, a):
    return math.sqrt((Xp[a, 0] - X[a, 0]) ** 2 + (Xp[a, 1] - X[a, 1]) ** 2
                     + (Xp[a, 2] - X[a, 2]) ** 2)


# (inlined, as pair_plane: a call that passes the rod bundle costs ~1,000 cycles, more than
# the work, and these run once per candidate pair and step)
@njit(cache=True, inline="always", error_model="numpy")
def _law(rd, a, b, c, d, s, t, dt_ref, rr):
    """Penalty stiffness (N/m) and damping (N s/m) of a contact at s on segment ab, t on cd."""
    mass, node_kmin = rd.n1[N_MASS], rd.n1[N_NODE_KMIN]
    m_i = (1.0 - s) * mass[a] + s * mass[b]
    m_j = (1.0 - t) * mass[c] + t * mass[d]
    k_floor = min((1.0 - s) * node_kmin[a] + s * node_kmin[b],
                  (1.0 - t) * node_kmin[c] + t * node_kmin[d])
    return pair_penalty(m_i, m_j, k_floor, dt_ref, rr[0], rr[1])


@njit(cache=True, inline="always", error_model="numpy")
def pair_plane(p, pairs, rd, X, Xp, h, rr, pp, ps) -> None:
    """Separating plane of pair ``p`` at the (sub-)step start ``X`` (``Xp``: predicted end, for
    the margin): closest-point parameters, normal, start penetration, offset, near flag."""
    seg_a, seg_b, radius = rd.ei[E_SEG_A], rd.ei[E_SEG_B], rd.e1[E_SEG_RADIUS]
    off_e = rd.e1[E_PAIR_OFF]
    i, j = pairs[p, 0], pairs[p, 1]
    a, b, c, d = seg_a[i], seg_b[i], seg_a[j], seg_b[j]
    p0, p1 = (X[a, 0], X[a, 1], X[a, 2]), (X[b, 0], X[b, 1], X[b, 2])
    q0, q1 = (X[c, 0], X[c, 1], X[c, 2]), (X[d, 0], X[d, 1], X[d, 2])
    s, t = closest_segment_segment(p0, p1, q0, q1)
    x = _point(X, a, b, s)
    y = _point(X, c, d, t)
    v = (x[0] - y[0], x[1] - y[1], x[2] - y[2])
    dist = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    reach = radius[i] + radius[j]
    if dist <= 1e-6 * reach:  # axes cross: separate across both of them
        u = (p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2])
        w = (q1[0] - q0[0], q1[1] - q0[1], q1[2] - q0[2])
        v = (u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0])
        nv = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
        if nv <= 1e-12 * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]):  # parallel: any normal
            v = (u[1], -u[0], 0.0) if abs(u[2]) < abs(u[0]) + abs(u[1]) else (0.0, u[2], -u[1])
            nv = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
        dist = nv
    pp[p, PP_S] = s
    pp[p, PP_T] = t
    for k in range(3):
        pp[p, PP_N + k] = v[k] / dist
    d0 = reach - math.sqrt((x[0] - y[0]) ** 2 + (x[1] - y[1]) ** 2 + (x[2] - y[2]) ** 2)
    pp[p, PP_D0] = d0
    # In contact at the last step (both elements): the offset carries over, less V_OUT h.
    carried = min(off_e[i], off_e[j])
    off = min(carried, d0) if carried >= 0.0 else d0
    pp[p, PP_OFF] = max(off - V_OUT * h, 0.0)
    if carried < 0.0:  # a new contact: placed inside?
        note_start_overlap(rd, i, j, d0, d0)
    # Friction is bounded by the normal force at the step start (lagged, as in IPC): Newton
    # then sees no coupling of friction to the normal motion, which it cannot represent.
    kc, _ = _law(rd, a, b, c, d, s, t, min(h, 1e-4), rr)
    pp[p, PP_LAG] = max(kc * (d0 - pp[p, PP_OFF]), 0.0)
    pp[p, PP_KN] = 0.0
    pp[p, PP_FN] = 0.0
    pp[p, PP_KMUL] = 1.0
    ps[p, PS_SET] = INACTIVE
    ps[p, PS_FLIPS] = 0
    travel = max(_travel(X, Xp, a), _travel(X, Xp, b)) + max(_travel(X, Xp, c), _travel(X, Xp, d))
    ps[p, PS_NEAR] = 1 if -d0 < MARGIN * travel + 0.5 * reach else 0


@njit(cache=True, inline="always", error_model="numpy")
def n_dot(pp, p, v):
    return pp[p, PP_N] * v[0] + pp[p, PP_N + 1] * v[1] + pp[p, PP_N + 2] * v[2]


@njit(cache=True, inline="always", error_model="numpy")
def plane_pen(pp, p, X, a, b, c, d, reach):
    """Penetration (m) of pair ``p`` (segments ab and cd, radii summing to ``reach``) at its
    plane's points, at positions ``X``."""
    x = _point(X, a, b, pp[p, PP_S])
    y = _point(X, c, d, pp[p, PP_T])
    return reach - n_dot(pp, p, (x[0] - y[0], x[1] - y[1], x[2] - y[2]))


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def pair_plane_forces(plist, m, pairs, rd, X, V, h, dt_ref, rr, pp, ps) -> int:
    """Forces of the island's pairs ``plist[:m]`` at the iterate (``X``, ``V``), equal and
    opposite on both segments, into ``force`` and ``contact_force``; each active pair's
    effective stiffness into ``pp[:, PP_KN]`` (0: not in the Newton matrix) and the friction's
    (``PP_KA`` along the slip direction ``PP_SH``, ``PP_KB`` across it). Returns the number
    of active pairs."""
    seg_a, seg_b, radius = rd.ei[E_SEG_A], rd.ei[E_SEG_B], rd.e1[E_SEG_RADIUS]
    force, contact_force = rd.n3[N_FORCE], rd.n3[N_CONTACT_FORCE]
    count = 0
    for q in range(m):
        p = plist[q]
        pp[p, PP_KN] = 0.0
        pp[p, PP_FN] = 0.0
        pp[p, PP_KA] = 0.0
        pp[p, PP_KB] = 0.0
        state = ps[p, PS_SET]
        i, j = pairs[p, 0], pairs[p, 1]
        a, b, c, d = seg_a[i], seg_b[i], seg_a[j], seg_b[j]
        s, t = pp[p, PP_S], pp[p, PP_T]
        n = (pp[p, PP_N], pp[p, PP_N + 1], pp[p, PP_N + 2])
        pen = plane_pen(pp, p, X, a, b, c, d, radius[i] + radius[j])
        if state == INACTIVE and pen <= 0.0:
            continue
        # (a stiffness multiplier kmul shortens the reference step by sqrt(kmul))
        kc, cc = _law(rd, a, b, c, d, s, t, dt_ref / math.sqrt(pp[p, PP_KMUL]), rr)
        fn = kc * (pen - pp[p, PP_OFF]) + cc * (pen - max(pp[p, PP_D0], 0.0)) / h
        push, ps[p, PS_SET], ps[p, PS_FLIPS] = switch_active(state, ps[p, PS_FLIPS], fn,
                                                             PAIR_FLIPS)
        if not push:
            continue
        pp[p, PP_FN] = fn
        pp[p, PP_KN] = kc + cc / h
        count += 1
        f = (fn * n[0], fn * n[1], fn * n[2])
        limit = rr[2] * pp[p, PP_LAG]
        if limit > 0.0 and cc > 0.0:
            ua, ub = _point(V, a, b, s), _point(V, c, d, t)
            u = (ua[0] - ub[0], ua[1] - ub[1], ua[2] - ub[2])
            un = u[0] * n[0] + u[1] * n[1] + u[2] * n[2]
            ut = (u[0] - un * n[0], u[1] - un * n[1], u[2] - un * n[2])
            umag = math.sqrt(ut[0] * ut[0] + ut[1] * ut[1] + ut[2] * ut[2])
            # d|f_t|/dx is c / h at rest; secant stiffness across the slip and along it too
            # once saturated (as for the collider planes: Newton then does not overshoot).
            kt = cc / h
            y = cc * umag / limit
            if y > 1e-12:
                th = math.tanh(y)
                scale = limit * th / umag
                f = (f[0] - scale * ut[0], f[1] - scale * ut[1], f[2] - scale * ut[2])
                sh = (ut[0] / umag, ut[1] / umag, ut[2] / umag)
                pp[p, PP_KB] = kt * th / y
                pp[p, PP_KA] = max(kt * (1.0 - th * th), pp[p, PP_KB])
            else:  # no slip: any tangent
                sh = (n[1], -n[0], 0.0) if abs(n[2]) < abs(n[0]) + abs(n[1]) else (0.0, n[2], -n[1])
                norm = math.sqrt(sh[0] * sh[0] + sh[1] * sh[1] + sh[2] * sh[2])
                sh = (sh[0] / norm, sh[1] / norm, sh[2] / norm)
                pp[p, PP_KA] = kt
                pp[p, PP_KB] = kt
            pp[p, PP_SH], pp[p, PP_SH + 1], pp[p, PP_SH + 2] = sh
        for k in range(3):
            fa, fb = (1.0 - s) * f[k], s * f[k]
            fc, fd = (1.0 - t) * f[k], t * f[k]
            force[a, k] += fa
            force[b, k] += fb
            force[c, k] -= fc
            force[d, k] -= fd
            contact_force[a, k] += fa
            contact_force[b, k] += fb
            contact_force[c, k] -= fc
            contact_force[d, k] -= fd
    return count


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def refind_pairs(plist, m, pairs, rd, X, Xs, pp, ps) -> int:
    """At a converged iterate ``X`` (``Xs`` the step start): give each pair whose segments now
    overlap deeper than ``REFIND_DEPTH`` of the thinner radius, and deeper than its plane sees
    by half as much, the plane of its closest points at ``X``, with the normal they had at the
    step start (the sides stay those of the start); returns how many (the caller iterates on).

    A pair's plane keeps the closest points of the step start: segments that slide along each
    other or turn within a 10 ms step can overlap elsewhere (a pile of eight ropes dropped from
    other places: 24-38 % of the radius; with a lag of a whole REFIND_DEPTH allowed, 22 %
    where the plane saw 13 %). As for ``speculative.refind_segments``, the new plane acts with
    no offset and as if the segments had started the step apart."""
    seg_a, seg_b, radius = rd.ei[E_SEG_A], rd.ei[E_SEG_B], rd.e1[E_SEG_RADIUS]
    added = 0
    for q in range(m):
        p = plist[q]
        i, j = pairs[p, 0], pairs[p, 1]
        a, b, c, d = seg_a[i], seg_b[i], seg_a[j], seg_b[j]
        reach = radius[i] + radius[j]
        depth = REFIND_DEPTH * min(radius[i], radius[j])
        s, t = closest_segment_segment((X[a, 0], X[a, 1], X[a, 2]), (X[b, 0], X[b, 1], X[b, 2]),
                                       (X[c, 0], X[c, 1], X[c, 2]), (X[d, 0], X[d, 1], X[d, 2]))
        x, y = _point(X, a, b, s), _point(X, c, d, t)
        pen = reach - math.sqrt((x[0] - y[0]) ** 2 + (x[1] - y[1]) ** 2 + (x[2] - y[2]) ** 2)
        if pen <= depth:
            continue
        if plane_pen(pp, p, X, a, b, c, d, reach) >= pen - 0.5 * depth:
            continue  # its plane holds it
        xs, ys = _point(Xs, a, b, s), _point(Xs, c, d, t)
        v = (xs[0] - ys[0], xs[1] - ys[1], xs[2] - ys[2])
        dist = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
        if dist <= 1e-6 * reach:  # (the same points touched at the start: the side now)
            v = (x[0] - y[0], x[1] - y[1], x[2] - y[2])
            dist = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
            if dist <= 1e-6 * reach:
                continue
        pp[p, PP_S] = s
        pp[p, PP_T] = t
        for k in range(3):
            pp[p, PP_N + k] = v[k] / dist
        pp[p, PP_D0] = min(reach - dist, 0.0)
        pp[p, PP_OFF] = 0.0
        ps[p, PS_SET] = INACTIVE
        ps[p, PS_FLIPS] = 0
        ps[p, PS_NEAR] = 1
        added += 1
    return added


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def stiffen_pairs(plist, m, pairs, rd, X, rr, pp, ps) -> int:
    """At a (nearly) converged iterate ``X``: double the automatic penalty of each pushing
    pair pressed deeper than ``STIFFEN_DEPTH`` of the thinner radius (up to ``MAX_KMUL``
    times, for the rest of the step), as ``speculative.stiffen_deep`` does for the collider
    planes; returns how many (the caller then iterates on). The penalty is sized for the
    lighter point's own impact; a rope landing on a pile presses the ropes under it with more
    (piles of eight dropped from 14 places: 21-23 % of r in 4 of them, 10-19 % since). Not
    grown by the square of the depth, as the planes': more steps of the piles were halved."""
    if rr[0] >= 0.0:  # the user's own stiffness is left alone
        return 0
    seg_a, seg_b, radius = rd.ei[E_SEG_A], rd.ei[E_SEG_B], rd.e1[E_SEG_RADIUS]
    count = 0
    for q in range(m):
        p = plist[q]
        if ps[p, PS_SET] != ACTIVE or pp[p, PP_FN] <= 0.0 or pp[p, PP_KMUL] >= MAX_KMUL:
            continue
        i, j = pairs[p, 0], pairs[p, 1]
        deep = (plane_pen(pp, p, X, seg_a[i], seg_b[i], seg_a[j], seg_b[j],
                          radius[i] + radius[j]) - pp[p, PP_OFF])
        if deep > STIFFEN_DEPTH * min(radius[i], radius[j]):
            pp[p, PP_KMUL] = min(2.0 * pp[p, PP_KMUL], MAX_KMUL)
            count += 1
    return count


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def release_pulling_pairs(plist, m, pp, ps) -> int:
    """Release the active pairs whose force pulls near convergence (unless they have switched
    ``KEEP_FLIPS`` times in the step); returns how many. A released pair acts again where it
    pushes (another rod may press its segments together once it has let go)."""
    released = 0
    for q in range(m):
        p = plist[q]
        if ps[p, PS_SET] == ACTIVE and pp[p, PP_FN] < 0.0 and ps[p, PS_FLIPS] < KEEP_FLIPS:
            ps[p, PS_SET] = INACTIVE
            released += 1
    return released


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def commit_pairs(plist, m, pairs, rd, pp) -> None:
    """Accepted step: the offsets of the pairs that push carry over to their elements (the
    caller has set the island's elements to -1, not in contact)."""
    off_e = rd.e1[E_PAIR_OFF]
    for q in range(m):
        p = plist[q]
        if pp[p, PP_FN] > 0.0:
            for e in (pairs[p, 0], pairs[p, 1]):
                off_e[e] = max(off_e[e], pp[p, PP_OFF])
