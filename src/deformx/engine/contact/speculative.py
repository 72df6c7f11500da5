"""Contact of the stable integrator: contact planes found once per step, smooth force law.

A step of 10 ms moves a falling rope by centimetres, more than its radius, so contacts found at
the Newton iterates can be missed (a thin sheet passed between two iterates) and appear and
vanish from one iterate to the next (Newton then halves the step). Instead, at the start of each
step every node and every segment looks for the nearest surface features within its radius plus
the distance it and the collider can travel in the step (a speculative margin), and keeps, for
the whole step, the tangent plane of each (point and normal in the collider's frame, so it moves
with the collider). During the step the gap of a point is its signed distance to that plane: a
linear function of the unknowns, so the Newton matrix is exact, nothing moving less than the
margin can pass the surface, and the side a point is on is the side it started the step on.

Force law per plane (penetration ``d``, its value ``d0`` at the step start):

    N = k (d - d_off) + c (d - max(d0, 0)) / h,   N >= 0,   d_off = max(d0 - v_out h, 0)

The damping acts on the penetration gained in contact (not on the approach speed averaged over a
step that began in free flight), so N is continuous and zero at first touch; ``d_off`` lets a
point that starts the step deeper than ``v_out h`` (a rod placed inside a collider) come out at
no more than ``v_out`` instead of being launched. Friction is the spring-slider of
:mod:`.segments` (anchor in the collider frame, stick below ``mu_s N``, slide at ``mu_k N``),
saturated smoothly (``|f_t| = mu N tanh(|s| / (mu N))`` for the spring's trial force ``s``) so that
Newton sees no switch between stick and slip; the anchor is dragged along only between steps,
when a point ended its step sliding (which also selects ``mu_k`` over ``mu_s`` for the next one).

Within a step a plane that has pushed stays active, its force law applied even where it would
pull, until Newton is near convergence (an update within ``RELEASE_NEAR`` tolerances); planes
that pull then are released (and released ones pressed in since re-engaged) and the solve goes
on (an active set, so that contacts at the edge of touching cannot switch at every iterate; see
``switch_active``).

Per query slot (node ``i``, element ``N + e``) up to ``SP_K`` planes, the nearest (of world
planes and colliders; a collider may give two): ``sp_i[q, k]`` = (source, anchored, sliding at
the last step, active-set state), source
-1 for none, ``p`` for world plane ``p``, ``L + c`` for collider ``c``; ``sp_f[q, k]`` = point
(3), normal (3) in the source's frame, segment parameter, d0, anchor point (3) in the source's
frame, anchored segment parameter, current penetration and normal force (scratch), the offset,
the friction bound frozen for the step, and the stiffness multiplier of ``stiffen_deep``.
"""

from __future__ import annotations

import math

from numba import njit

from ..kernels.bundles import (
    N_CONTACT_FORCE, N_FORCE, N_MASS, N_NODE_KMIN, N_NODE_RADIUS, R_COUPLED,
)
from .plane import PL_AUTO, PL_MUK, PL_MUS, START_DEEP, V_OUT, plane_penalty
from .primitives import tangent_bound
from .segments import (
    MESH, P_AUTO, P_MUK, P_MUS, P_SHAPE, _add_reaction, _mesh_closest, _rotate, _shape_closest,
    _to_local, _to_world, collider_penalty,
)
from ..kernels.refcount import NO_REFCOUNT

SP_K = 2  # contact planes per query slot
SP_COLS_I, SP_COLS_F = 5, 21
SP_SRC, SP_ANCHORED, SP_SLIDING, SP_SET, SP_FLIPS = 0, 1, 2, 3, 4
SP_Q, SP_N, SP_S, SP_D0, SP_A, SP_AS, SP_PEN, SP_FN, SP_OFF, SP_FROZEN = (
    0, 3, 6, 7, 8, 11, 12, 13, 14, 15)
SP_KMUL = 16
# The friction's slope along the slip used at the last evaluation (-1: none yet this step) and
# the slip (3) it was evaluated at (``_slip_slope``).
SP_KP, SP_SP = 17, 18
# SP_SET: within a step a contact is inactive (0), active (1) or released (2: a plane that
# pulled near convergence, out for the rest of the step); SP_FLIPS counts its switches.
INACTIVE, ACTIVE, RELEASED = 0, 1, 2
# Switches within a step before an active contact stays active: none for the planes (a stiff
# wire on the floor would otherwise rock from iterate to iterate), two for rod-rod pairs
# (contacts activated by a predictor that overlaps the other rod let go at once).
PLANE_FLIPS, PAIR_FLIPS = 0, 2
# Friction saturates as mu N tanh(y), y = |trial force| / (mu N); a step that ends beyond
# Y_SLIDE counts as sliding (kinetic coefficient next step) and drags its anchor up to Y_ANCHOR
# behind the point (a spring loaded to 0.76 mu N: when the point stops it springs back by less
# than mu N / k instead of being held at the friction limit).
Y_SLIDE, Y_ANCHOR = 3.0, 1.0
# m: the smallest stick displacement the friction saturates over (with a contact stiffness k
# the spring's own mu N / k is used when larger): a stiff wire's mu N / k can be 0.01 um,
# finer than Newton resolves, and friction would then switch direction between iterates.
STICK_ZONE = 1e-6
# Along the slip Newton takes the chord of the friction's saturation between the last iterate
# and this one (the secant method), no less than this fraction of the secant |f_t| / |s| and
# only while the slip keeps its direction within SLIP_COS (see ``_slip_slope``).
SLOPE_FLOOR, SLIP_COS = 0.25, 0.99
SLIP_LINEAR = 0.3  # below this many smoothing widths of slip the secant (within 6 % of tanh')
# A segment whose middle lies this many radii closer to a shape than its ends' mean gets a
# plane at its middle (the surface curves under it).
SAG = 0.1
# A segment found this many radii deep at a converged iterate, at a point between its ends that
# its planes do not hold, gets a plane there and the step iterates on (``refind_segments``).
REFIND_DEPTH = 0.1
REFIND_MOVE = 0.03  # ... unless it moved less than this many radii along each axis in the step
# The automatic penalty stops an impact at this speed (m/s) within this fraction of the radius.
V_IMPACT, IMPACT_DEPTH = 5.0, 0.1
# A node within this many radii of a shape touches it (no plane where it is headed while the
# shape presses on it: its relative velocity points into the surface by more than PRESSED of
# its speed); a moving shape's plane where a node's flight first touches it is found to within
# that distance, in at most HEADED_ITERS steps.
HEADED_TOUCH, PRESSED, HEADED_ITERS = 0.02, 0.3, 16
MARGIN = 2.0  # the speculative margin is this many times the step's relative travel
# The friction's coupling to the normal force enters the Newton matrix where it is at least
# this fraction of mu times the normal stiffness (sliding, not sticking).
MIN_COUPLING = 0.01
# A pushing contact found deeper than this many radii at a converged iterate is stiffened (its
# automatic penalty, by the square of its depth over IMPACT_DEPTH, up to MAX_KMUL times) and the
# step iterates on: the automatic penalty is sized for an impact of the point's own mass, and a
# rope's tension pulling a node into a box's edge or the whip of its free end can press harder.
STIFFEN_DEPTH = 0.15
MAX_KMUL = 64.0


@njit(cache=True, inline="always", error_model="numpy")
def impact_frequency(h, radius):
    """Contact frequency (rad/s) of a critically damped penalty that stops a point arriving at
    ``V_IMPACT`` within ``IMPACT_DEPTH`` of its ``radius`` in one backward-Euler step ``h``:
    ``w^2 h + 2 w = V_IMPACT / (IMPACT_DEPTH radius)``."""
    x = h * V_IMPACT / (IMPACT_DEPTH * radius)
    return x / (h * (math.sqrt(1.0 + x) + 1.0))  # (sqrt(1 + x) - 1) / h without cancellation


@njit(cache=True, inline="always", error_model="numpy")
def switch_active(state, flips, fn, max_flips):
    """(acts, state, flips) of a contact whose force law gives ``fn`` (N) at the iterate: it
    acts where it pushes; after ``max_flips`` switches within the step an active contact
    stays active (its force may pull until the solve has converged and it is released)."""
    push = fn > 0.0
    if state == RELEASED or push == (state == ACTIVE):
        return push and state != RELEASED, state, flips
    if state == ACTIVE and flips >= max_flips:
        return True, state, flips
    return push, ACTIVE if push else INACTIVE, flips + 1


@njit(cache=True, error_model="numpy")
def _frame_point(src, n_planes, pose, q0, q1, q2):
    """World point of a point given in the frame of ``src`` (world planes: the world)."""
    if src < n_planes:
        return q0, q1, q2
    return _to_world(pose, src - n_planes, q0, q1, q2)


@njit(cache=True, error_model="numpy")
def _frame_vector(src, n_planes, pose, v0, v1, v2):
    if src < n_planes:
        return v0, v1, v2
    return _rotate(pose, src - n_planes, v0, v1, v2)


@njit(cache=True, error_model="numpy")
def _local_point(src, n_planes, pose, x0, x1, x2):
    if src < n_planes:
        return x0, x1, x2
    return _to_local(pose, src - n_planes, x0, x1, x2)


@njit(cache=True, error_model="numpy")
def _local_vector(src, n_planes, pose, v0, v1, v2):
    if src < n_planes:
        return v0, v1, v2
    c = src - n_planes
    return (pose[c, 0, 0] * v0 + pose[c, 1, 0] * v1 + pose[c, 2, 0] * v2,
            pose[c, 0, 1] * v0 + pose[c, 1, 1] * v1 + pose[c, 2, 1] * v2,
            pose[c, 0, 2] * v0 + pose[c, 1, 2] * v1 + pose[c, 2, 2] * v2)


@njit(cache=True, error_model="numpy")
def _surface_velocity(src, n_planes, pose, twist, q):
    """Velocity (m/s, world) of the surface point q (world) of ``src`` (planes do not move)."""
    if src < n_planes:
        return 0.0, 0.0, 0.0
    c = src - n_planes
    rx, ry, rz = q[0] - pose[c, 0, 3], q[1] - pose[c, 1, 3], q[2] - pose[c, 2, 3]
    return (twist[c, 0] + twist[c, 4] * rz - twist[c, 5] * ry,
            twist[c, 1] + twist[c, 5] * rx - twist[c, 3] * rz,
            twist[c, 2] + twist[c, 3] * ry - twist[c, 4] * rx)


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _offer(sp_i, sp_f, slot, keep_src, keep_f, keep_n, src, gap, q, n, s, pose, n_planes,
           radius):
    """Offer a plane of ``src`` (gap in m, point q and normal n in the world) to ``slot`` of
    ``radius`` (m): the ``SP_K`` nearest are kept (``keep_*`` holds the candidates, nearest
    first), a source's second plane counted a radius farther than it is.

    (A shape gives a fast node two planes, the nearest and the one where it is headed: a rope
    on the floor pushed by a cylinder lying on it would otherwise lose the floor's plane to
    them and sink 75 % of its radius into the floor in one step.)"""
    full = True
    for j in range(SP_K):
        full = full and keep_src[j] >= 0
    if full:
        # drop the least relevant of the kept planes and the offered one
        drop, drop_gap = SP_K, gap + (radius if _nearer_twin(keep_src, keep_f, SP_K, src, gap)
                                      else 0.0)
        for j in range(SP_K):
            gj = keep_f[j]
            if (src == keep_src[j] and gap < gj) or _nearer_twin(keep_src, keep_f, j,
                                                                 keep_src[j], gj):
                gj += radius
            if gj > drop_gap:
                drop, drop_gap = j, gj
        if drop == SP_K:
            return
        for j in range(drop, SP_K - 1):
            keep_src[j] = keep_src[j + 1]
            keep_f[j] = keep_f[j + 1]
            for d in range(8):
                keep_n[j, d] = keep_n[j + 1, d]
        keep_src[SP_K - 1] = -1
    k = -1
    for j in range(SP_K):
        if keep_src[j] < 0 or gap < keep_f[j]:
            k = j
            break
    if k < 0:
        return
    for j in range(SP_K - 1, k, -1):
        keep_src[j] = keep_src[j - 1]
        keep_f[j] = keep_f[j - 1]
        for d in range(8):
            keep_n[j, d] = keep_n[j - 1, d]
    keep_src[k] = src
    keep_f[k] = gap
    lq = _local_point(src, n_planes, pose, q[0], q[1], q[2])
    ln = _local_vector(src, n_planes, pose, n[0], n[1], n[2])
    for d in range(3):
        keep_n[k, d] = lq[d]
        keep_n[k, 3 + d] = ln[d]
    keep_n[k, 6] = s


@njit(cache=True, inline="always", error_model="numpy")
def _nearer_twin(keep_src, keep_f, j, src, gap):
    """Whether a kept plane other than ``j`` of the same source is nearer than ``gap`` (m)."""
    for i in range(SP_K):
        if i != j and keep_src[i] == src and (keep_f[i] < gap or (keep_f[i] == gap and i < j)):
            return True
    return False


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _store(sp_i, sp_f, slot, keep_src, keep_f, keep_n, x_start, s_start):
    """Replace the slot's planes by the candidates, carrying over the friction anchor of a
    source that was there before; a new anchor is the slot's point at the step start
    (``x_start``, in the source's frame; ``s_start`` its segment parameter)."""
    old_src = (sp_i[slot, 0, SP_SRC], sp_i[slot, 1, SP_SRC])
    old_on = (sp_i[slot, 0, SP_ANCHORED], sp_i[slot, 1, SP_ANCHORED])
    old_sliding = (sp_i[slot, 0, SP_SLIDING], sp_i[slot, 1, SP_SLIDING])
    old_a = ((sp_f[slot, 0, SP_A], sp_f[slot, 0, SP_A + 1], sp_f[slot, 0, SP_A + 2],
              sp_f[slot, 0, SP_AS], sp_f[slot, 0, SP_OFF], sp_f[slot, 0, SP_KMUL]),
             (sp_f[slot, 1, SP_A], sp_f[slot, 1, SP_A + 1], sp_f[slot, 1, SP_A + 2],
              sp_f[slot, 1, SP_AS], sp_f[slot, 1, SP_OFF], sp_f[slot, 1, SP_KMUL]))
    for k in range(SP_K):
        src = keep_src[k]
        sp_i[slot, k, SP_SRC] = src
        sp_i[slot, k, SP_SLIDING] = 0
        sp_i[slot, k, SP_ANCHORED] = 0
        sp_i[slot, k, SP_SET] = INACTIVE
        sp_i[slot, k, SP_FLIPS] = 0
        sp_f[slot, k, SP_FROZEN] = -1.0
        sp_f[slot, k, SP_KMUL] = 1.0
        if src < 0:
            continue
        for d in range(7):
            sp_f[slot, k, d] = keep_n[k, d]
        for j in range(SP_K):
            if old_src[j] == src and old_on[j] != 0:
                sp_i[slot, k, SP_ANCHORED] = 1
                sp_i[slot, k, SP_SLIDING] = old_sliding[j]
                for d in range(3):
                    sp_f[slot, k, SP_A + d] = old_a[j][d]
                sp_f[slot, k, SP_AS] = old_a[j][3]
                sp_f[slot, k, SP_OFF] = old_a[j][4]
                sp_f[slot, k, SP_KMUL] = max(old_a[j][5], 1.0)  # (the load that needed it lasts)
        if sp_i[slot, k, SP_ANCHORED] == 0:
            sp_f[slot, k, SP_A] = x_start[k, 0]
            sp_f[slot, k, SP_A + 1] = x_start[k, 1]
            sp_f[slot, k, SP_A + 2] = x_start[k, 2]
            sp_f[slot, k, SP_AS] = s_start


@njit(cache=True, inline="always", error_model="numpy")
def _n_queries(nn, ne, cols):
    """How many of a rod's slots can hold a plane: its nodes and, with colliders, its
    segments (world planes act on nodes only; colliders are never removed, so without any a
    segment slot stays empty and is not walked)."""
    n_cols = 0
    if cols is not None:
        n_cols = cols.kind.shape[0]
    return nn + ne if n_cols > 0 else nn


@njit(cache=True, inline="always", error_model="numpy")
def _slot(k, n0, nn, e0, n_nodes, node_radius):
    """The ``k``-th query of a rod (its nodes, then its elements): whether it is a node, its
    end nodes a, b (a == b for a node), element (-1 for a node), slot and radius (m)."""
    if k < nn:
        return True, n0 + k, n0 + k, -1, n0 + k, node_radius[n0 + k]
    a = n0 + k - nn
    b = a + 1 if k - nn + 1 < nn else n0
    return False, a, b, e0 + k - nn, n_nodes + e0 + k - nn, 0.5 * (node_radius[a] + node_radius[b])


@njit(cache=True, inline="always", error_model="numpy")
def _closest(cols, r, c, pose, slot, pa, pb, reach, lasting):
    """Deepest point of world segment pa-pb against collider ``c`` within ``reach`` (m), for
    query ``slot`` of rod ``r``: see ``_mesh_closest`` and ``_shape_closest``."""
    if cols.kind[c] == MESH:
        return _mesh_closest(
            c, cols.rng[c, 4], pose, cols.par, cols.MV, cols.MF, cols.Blo, cols.Bhi, cols.Bleft,
            cols.Bright, cols.Bstart, cols.Bcount, cols.Border, cols.Fn, cols.En, cols.Vn,
            cols.Fg, cols.qc_meta, cols.qc_geo, cols.qc_tris, cols.qc_dist, cols.tr_stack[r],
            cols.tr_bound[r], slot, pa, pb, reach, lasting)
    return _shape_closest(c, cols.kind[c], pose, cols.par, pa, pb, reach)


@njit(cache=True, inline="always", error_model="numpy")
def _moves(twist, c):
    """Whether collider ``c`` moves in this step (any linear or angular velocity)."""
    for d in range(6):
        if twist[c, d] != 0.0:
            return True
    return False


@njit(cache=True, error_model="numpy")
def _headed_plane(c, kind, pose, par, pa, pe, sd0, radius, reach, first_hit):
    """The tangent plane of shape ``c`` where a node of ``radius`` (m) flying from ``pa`` to
    ``pe`` (world points, the flight relative to the shape) is headed: nearest ``pe``; with
    ``first_hit``, where the flight first touches the shape (``sd0``: the centre's signed
    distance at ``pa``), found by conservative advancement (a signed distance changes no
    faster than the point moves), and none if it passes by (the plane nearest the end of a
    flight past a box's corner put the node 2.4 radii behind it at the step start). Returns as
    ``_shape_closest``."""
    if not first_hit:
        return _shape_closest(c, kind, pose, par, pe, pe, reach)
    d0, d1, d2 = pe[0] - pa[0], pe[1] - pa[1], pe[2] - pa[2]
    length = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    f = sd0 - radius
    t = 0.0
    p = pa
    for _ in range(HEADED_ITERS):
        t += f / length
        if t >= 1.0:
            return False, 0.0, 0.0, (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)
        p = (pa[0] + t * d0, pa[1] + t * d1, pa[2] + t * d2)
        hit, s, sd, m, q = _shape_closest(c, kind, pose, par, p, p, math.inf)
        f = sd - radius
        if f <= HEADED_TOUCH * radius:
            break
    return _shape_closest(c, kind, pose, par, p, p, math.inf)  # (where the search ended)


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def gather_planes(r, n0, nn, e0, ne, h, X, V, gravity, planes, rd, cols, sp_i, sp_f, keep_src,
                  keep_f, keep_n, x_start) -> int:
    """Find each slot's contact planes at the step start (positions ``X``, velocities ``V``;
    colliders at their start poses in ``cols.pose[r]``); returns how many slots have one.

    ``keep_*``, ``x_start``: scratch of ``SP_K`` rows. The margin is ``MARGIN`` times the
    distance the point and the collider can close in the step (speed times ``h`` plus half the
    gravity drop) plus half the radius.
    """
    node_radius = rd.n1[N_NODE_RADIUS]
    n_planes = planes.shape[0]
    n_nodes = X.shape[0]
    n_cols = 0
    if cols is not None:
        n_cols = cols.kind.shape[0]
    g = math.sqrt(gravity[0] ** 2 + gravity[1] ** 2 + gravity[2] ** 2)
    # Collider poses; without colliders an array of the same type that is never read (world
    # planes are given in the world frame).
    pose3 = rd.e33[0]
    if cols is not None:
        pose3 = cols.pose[r]
    found = 0
    for k in range(_n_queries(nn, ne, cols)):
        node, a, b, e, slot, radius = _slot(k, n0, nn, e0, n_nodes, node_radius)
        pa = (X[a, 0], X[a, 1], X[a, 2])
        pb = (X[b, 0], X[b, 1], X[b, 2])
        speed = max(math.sqrt(V[a, 0] ** 2 + V[a, 1] ** 2 + V[a, 2] ** 2),
                    math.sqrt(V[b, 0] ** 2 + V[b, 1] ** 2 + V[b, 2] ** 2))
        travel = speed * h + 0.5 * g * h * h
        for j in range(SP_K):
            keep_src[j] = -1
            keep_f[j] = 0.0
        if node:
            for p in range(n_planes):
                gap = ((pa[0] - planes[p, 0]) * planes[p, 3] + (pa[1] - planes[p, 1]) * planes[p, 4]
                       + (pa[2] - planes[p, 2]) * planes[p, 5]) - radius
                if gap < MARGIN * travel + 0.5 * radius:
                    q = (pa[0] - (gap + radius) * planes[p, 3], pa[1] - (gap + radius) * planes[p, 4],
                         pa[2] - (gap + radius) * planes[p, 5])
                    _offer(sp_i, sp_f, slot, keep_src, keep_f, keep_n, p, gap, q,
                           (planes[p, 3], planes[p, 4], planes[p, 5]), 0.0, pose3, n_planes, radius)
        if cols is not None:
            pose, twist = cols.pose[r], cols.twist[r]
            for c in range(n_cols):
                if cols.allowed[r, c] == 0:
                    continue
                # The collider's own travel: its origin's speed and its rotation's sweep.
                rx = 0.5 * (pa[0] + pb[0]) - pose[c, 0, 3]
                ry = 0.5 * (pa[1] + pb[1]) - pose[c, 1, 3]
                rz = 0.5 * (pa[2] + pb[2]) - pose[c, 2, 3]
                vc = (math.sqrt(twist[c, 0] ** 2 + twist[c, 1] ** 2 + twist[c, 2] ** 2)
                      + math.sqrt(twist[c, 3] ** 2 + twist[c, 4] ** 2 + twist[c, 5] ** 2)
                      * math.sqrt(rx * rx + ry * ry + rz * rz))
                reach = radius + MARGIN * (travel + vc * h) + 0.5 * radius
                # a mesh query's cache outlasts the step if the next step's reach exceeds
                # this one's less the skin (half of it) by more than the move (sqrt 3 per axis)
                lasting = 1 if math.sqrt(3.0) * (travel + vc * h) <= 0.5 * reach else 0
                hit, s, sd, n, q = _closest(cols, r, c, pose, slot, pa, pb, reach, lasting)
                if not hit:
                    continue
                if not node and cols.kind[c] != MESH and abs(s - 0.5) > 0.2:
                    # On a curved shape a segment's middle can sink in while both its ends
                    # rest on it (a 1 cm element round a 5 cm cylinder sags 0.25 mm), wherever
                    # the segment was deepest at the step start: its middle gets a plane too.
                    pm = (0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1]), 0.5 * (pa[2] + pb[2]))
                    hm, _, sdm, nm, qm = _shape_closest(c, cols.kind[c], pose, cols.par, pm, pm,
                                                        reach)
                    sda = _shape_closest(c, cols.kind[c], pose, cols.par, pa, pa, math.inf)[2]
                    sdb = _shape_closest(c, cols.kind[c], pose, cols.par, pb, pb, math.inf)[2]
                    if hm and 0.5 * (sda + sdb) - sdm > SAG * radius:
                        _offer(sp_i, sp_f, slot, keep_src, keep_f, keep_n, n_planes + c,
                               sdm - radius, qm, nm, 0.5, pose, n_planes, radius)
                if not node and (s <= 0.0 or s >= 1.0):
                    continue  # a segment's end: the node carries it
                _offer(sp_i, sp_f, slot, keep_src, keep_f, keep_n, n_planes + c, sd - radius,
                       q, n, s, pose, n_planes, radius)
                if not node or cols.kind[c] == MESH:
                    continue
                # A node moving fast over a curved shape: also the tangent plane where it is
                # headed, so that it cannot cut through the curve. Its flight relative to the
                # shape (from its speed in the world a rope carried along by a shape was held
                # by a plane where it was not, half its radius inside the floor); none for a
                # node the shape presses on (it is pushed, not flying: the plane nearest its
                # flight's end, under a shape lying on the floor, pressed it into the floor).
                vs = _surface_velocity(n_planes + c, n_planes, pose, twist, q)
                rel = (V[a, 0] - vs[0], V[a, 1] - vs[1], V[a, 2] - vs[2])
                rel_speed = math.sqrt(rel[0] ** 2 + rel[1] ** 2 + rel[2] ** 2)
                touching = sd - radius <= HEADED_TOUCH * radius
                if rel_speed * h > 0.5 * radius and not (
                        touching and rel[0] * n[0] + rel[1] * n[1] + rel[2] * n[2]
                        < -PRESSED * rel_speed):
                    pe = (pa[0] + h * rel[0], pa[1] + h * rel[1], pa[2] + h * rel[2])
                    hit, s, sd, m, q = _headed_plane(c, cols.kind[c], pose, cols.par, pa, pe,
                                                     sd, radius, reach,
                                                     _moves(twist, c) and not touching)
                    if hit and m[0] * n[0] + m[1] * n[1] + m[2] * n[2] < 0.99:
                        gap = ((pa[0] - q[0]) * m[0] + (pa[1] - q[1]) * m[1]
                               + (pa[2] - q[2]) * m[2]) - radius
                        _offer(sp_i, sp_f, slot, keep_src, keep_f, keep_n, n_planes + c, gap,
                               q, m, 0.0, pose, n_planes, radius)
        if keep_src[0] < 0 and sp_i[slot, 0, SP_SRC] < 0 and sp_i[slot, 1, SP_SRC] < 0:
            continue  # empty and staying so (an empty slot's other fields are never read)
        s0 = 0.0
        for j in range(SP_K):
            if keep_src[j] < 0:
                continue
            src = keep_src[j]
            s0 = keep_n[j, 6]
            xs = ((1.0 - s0) * pa[0] + s0 * pb[0], (1.0 - s0) * pa[1] + s0 * pb[1],
                  (1.0 - s0) * pa[2] + s0 * pb[2])
            ls = _local_point(src, n_planes, pose3, xs[0], xs[1], xs[2])
            x_start[j, 0], x_start[j, 1], x_start[j, 2] = ls
        _store(sp_i, sp_f, slot, keep_src, keep_f, keep_n, x_start, s0)
        if keep_src[0] >= 0:
            found += 1
    return found


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def refind_segments(r, n0, nn, e0, ne, X, Xs, planes, rd, cols, sp_i, sp_f) -> int:
    """At a converged iterate ``X`` (``Xs`` the step start): give each segment that now cuts
    into a collider deeper than ``REFIND_DEPTH`` of its radius, at a point between its ends
    that none of its planes holds, the tangent plane there; returns how many were added (the
    caller then iterates on).

    The planes found at the step start have fixed segment parameters: a segment that turns
    round a mesh's edge within the step (level over the top face at the start, deepest at an
    end, which its node carries) cuts the corner between its nodes' planes. A new plane acts
    with no offset and as if the point had started the step outside (``d0`` <= 0: a plane
    found at the end of the step may say nothing true of where the point was at its start)."""
    if cols is None:  # (pruned at compile time; the caller checks there are colliders)
        return 0
    n_cols = cols.kind.shape[0]
    node_radius = rd.n1[N_NODE_RADIUS]
    n_planes = planes.shape[0]
    n_nodes = X.shape[0]
    pose, twist = cols.pose[r], cols.twist[r]
    added = 0
    for k in range(nn, nn + ne):
        node, a, b, e, slot, radius = _slot(k, n0, nn, e0, n_nodes, node_radius)
        # A point's distance to a collider changes by at most what it moves (and, for a moving
        # collider, what its surface moves): a segment that moved less than REFIND_MOVE of its
        # radius in the step is about as deep as the last step's check left it (a rope at rest).
        move = REFIND_MOVE * radius
        still = (abs(X[a, 0] - Xs[a, 0]) < move and abs(X[a, 1] - Xs[a, 1]) < move
                 and abs(X[a, 2] - Xs[a, 2]) < move and abs(X[b, 0] - Xs[b, 0]) < move
                 and abs(X[b, 1] - Xs[b, 1]) < move and abs(X[b, 2] - Xs[b, 2]) < move)
        pa = (X[a, 0], X[a, 1], X[a, 2])
        pb = (X[b, 0], X[b, 1], X[b, 2])
        for c in range(n_cols):
            if cols.allowed[r, c] == 0:
                continue
            if still and not _moves(twist, c):
                continue
            reach = (1.0 - REFIND_DEPTH) * radius
            if cols.kind[c] != MESH:
                la = _to_local(pose, c, pa[0], pa[1], pa[2])
                lb = _to_local(pose, c, pb[0], pb[1], pb[2])
                shape = (cols.par[c, P_SHAPE], cols.par[c, P_SHAPE + 1], cols.par[c, P_SHAPE + 2])
                if tangent_bound(cols.kind[c], shape, la[0], la[1], la[2], lb[0], lb[1],
                                 lb[2]) > reach:
                    continue  # (a rope lying along a shape: no search)
            hit, s, sd, n, q = _closest(cols, r, c, pose, slot, pa, pb, reach, -1)
            if not hit or s <= 0.0 or s >= 1.0:
                continue
            src = n_planes + c
            pen = radius - sd
            # A plane of this source that feels the segment about as deep at its own point
            # holds it already (the point is as deep as that plane's force lets it be); not
            # one released for the rest of the step, which pushes no more (a 1 mm rope whipped
            # round a cylinder at 10 ms then ended steps 39-44 % of its radius deep).
            pick = -1
            held = False
            for j in range(SP_K):
                if sp_i[slot, j, SP_SRC] < 0:
                    if pick < 0:
                        pick = j
                    continue
                if sp_i[slot, j, SP_SRC] == src and sp_i[slot, j, SP_SET] != RELEASED:
                    qj, nj = _plane_of(sp_f, slot, j, src, n_planes, pose)
                    sj = sp_f[slot, j, SP_S]
                    xj = ((1.0 - sj) * pa[0] + sj * pb[0], (1.0 - sj) * pa[1] + sj * pb[1],
                          (1.0 - sj) * pa[2] + sj * pb[2])
                    pj = radius - ((xj[0] - qj[0]) * nj[0] + (xj[1] - qj[1]) * nj[1]
                                   + (xj[2] - qj[2]) * nj[2])
                    if pj >= pen - REFIND_DEPTH * radius:
                        held = True
            if held:
                continue
            if pick < 0:  # full: replace an inactive plane, else the one that pushes least
                pick = 0
                for j in range(1, SP_K):
                    on_j = sp_i[slot, j, SP_SET] == ACTIVE
                    on_pick = sp_i[slot, pick, SP_SET] == ACTIVE
                    if (on_pick and not on_j) or (
                            on_j == on_pick and sp_f[slot, j, SP_FN] < sp_f[slot, pick, SP_FN]):
                        pick = j
            lq = _local_point(src, n_planes, pose, q[0], q[1], q[2])
            ln = _local_vector(src, n_planes, pose, n[0], n[1], n[2])
            xs = ((1.0 - s) * Xs[a, 0] + s * Xs[b, 0], (1.0 - s) * Xs[a, 1] + s * Xs[b, 1],
                  (1.0 - s) * Xs[a, 2] + s * Xs[b, 2])
            d0 = radius - ((xs[0] - q[0]) * n[0] + (xs[1] - q[1]) * n[1] + (xs[2] - q[2]) * n[2])
            la = _local_point(src, n_planes, pose, xs[0], xs[1], xs[2])
            sp_i[slot, pick, SP_SRC] = src
            sp_i[slot, pick, SP_ANCHORED] = 0
            sp_i[slot, pick, SP_SLIDING] = 0
            sp_i[slot, pick, SP_SET] = INACTIVE
            sp_i[slot, pick, SP_FLIPS] = 0
            for d in range(3):
                sp_f[slot, pick, SP_Q + d] = lq[d]
                sp_f[slot, pick, SP_N + d] = ln[d]
                sp_f[slot, pick, SP_A + d] = la[d]
            sp_f[slot, pick, SP_S] = s
            sp_f[slot, pick, SP_AS] = s
            sp_f[slot, pick, SP_D0] = min(d0, 0.0)
            sp_f[slot, pick, SP_OFF] = 0.0
            sp_f[slot, pick, SP_FROZEN] = -1.0
            sp_f[slot, pick, SP_KMUL] = 1.0
            sp_f[slot, pick, SP_KP] = -1.0
            sp_f[slot, pick, SP_PEN] = pen
            sp_f[slot, pick, SP_FN] = 0.0
            added += 1
    return added


@njit(cache=True, inline="always", error_model="numpy")
def _plane_of(sp_f, slot, k, src, n_planes, pose):
    q = _frame_point(src, n_planes, pose, sp_f[slot, k, SP_Q], sp_f[slot, k, SP_Q + 1],
                     sp_f[slot, k, SP_Q + 2])
    n = _frame_vector(src, n_planes, pose, sp_f[slot, k, SP_N], sp_f[slot, k, SP_N + 1],
                      sp_f[slot, k, SP_N + 2])
    return q, n


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _node_pen(sp_i, sp_f, i, src):
    """Penetration (m, >= 0) of node ``i`` into the plane it has from ``src`` (0 if none), as
    last evaluated."""
    for k in range(SP_K):
        if sp_i[i, k, SP_SRC] == src:
            return max(sp_f[i, k, SP_PEN], 0.0)
    return 0.0


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _law(src, n_planes, planes, par, mass, kmin, dt_ref):
    """Penalty stiffness (N/m), damping (N s/m) and friction coefficients of a source."""
    if src < n_planes:
        k, c = plane_penalty(planes, src, mass, kmin, dt_ref)
        return k, c, planes[src, PL_MUS], planes[src, PL_MUK]
    col = src - n_planes
    k, c = collider_penalty(par, col, mass, kmin, dt_ref)
    return k, c, par[col, P_MUS], par[col, P_MUK]


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _add_contact_K(el_K, e, q, wn, wt, kn, ka, kb, n, sh):
    """Add one contact's stiffness to block ``q`` of element ``e``: ``wn kn n n^T`` (normal)
    plus ``wt`` times the friction's (``ka`` along the force direction ``sh``, ``kb`` across it
    in the tangent plane)."""
    for i in range(3):
        for j in range(3):
            tij = (1.0 if i == j else 0.0) - n[i] * n[j] - sh[i] * sh[j]
            el_K[e, q, i, j] += wn * kn * n[i] * n[j] + wt * (ka * sh[i] * sh[j] + kb * tij)


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _add_coupling(el_K, e, q, w, u, n):
    """Add ``w u n^T`` to the coupling block ``q`` (3 + a-a, a-b, b-a, b-b) of element ``e``."""
    for i in range(3):
        for j in range(3):
            el_K[e, 3 + q, i, j] += w * u[i] * n[j]


@njit(cache=True, inline="always", error_model="numpy")
def _slip_slope(sp_f, slot, j, s0, s1, s2, smag, delta, th, kt, kb, chord):
    """Friction's stiffness along the slip ``s`` (m) of plane ``j`` of ``slot`` (N/m): with
    ``chord``, the chord of kt tanh(|s| / delta) between the slip of the last evaluation and this
    one where the slip kept its direction, no less than the tangent or SLOPE_FLOOR kb and no more
    than kb (the secant |f_t| / |s|); else kb. Stores this evaluation's slope and slip.

    Newton with the secant along a slip between sticking and sliding (tanh's tangent 0.07-0.4
    of its secant) converges linearly, 0.5-0.85 per iteration (a rope dragged over a kerb, the
    rope leaving a cylinder it wraps); the chord tends to the tangent as the iterates converge.
    Not the tangent itself, nor the chord unbounded: tanh's Newton diverges from a slip more than
    about one smoothing width away, and a steel wire resting on a cylinder was kicked."""
    ka = kb
    kp = sp_f[slot, j, SP_KP]
    p0, p1, p2 = sp_f[slot, j, SP_SP], sp_f[slot, j, SP_SP + 1], sp_f[slot, j, SP_SP + 2]
    if kp >= 0.0:
        if p0 == s0 and p1 == s1 and p2 == s2:  # the same iterate again (after a release)
            ka = kp
        elif chord and smag > SLIP_LINEAR * delta:  # (below, tanh's slopes are all ~kt)
            pm = math.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
            if (pm > 0.0 and s0 * p0 + s1 * p1 + s2 * p2 > SLIP_COS * smag * pm
                    and abs(smag - pm) > 1e-6 * smag):
                y, yp = smag / delta, pm / delta
                chord_slope = kt * (th - math.tanh(yp)) / (y - yp)
                ka = min(kb, max(chord_slope, kt * (1.0 - th * th), SLOPE_FLOOR * kb))
    sp_f[slot, j, SP_KP] = ka
    sp_f[slot, j, SP_SP] = s0
    sp_f[slot, j, SP_SP + 1] = s1
    sp_f[slot, j, SP_SP + 2] = s2
    return ka


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def plane_forces(r, n0, nn, e0, ne, h, dt_ref, X, Xs, V, planes, rd, cols, sp_i, sp_f, commit,
                 stats, chord) -> int:
    """Add the contact forces of rod ``r``'s slot planes at the iterate (positions ``X``,
    velocities ``V``; ``Xs`` the step start), their stiffness into ``el_K`` (per element: node
    blocks a-a, b-a, b-b; then the friction's coupling to the normal force, counted in
    ``r1[R_COUPLED]``) and, with ``commit`` (accepted step), instead of the stiffness store
    the friction anchors and the colliders' reactions; returns the contact count.
    ``stats[5]`` keeps the deepest start penetration (m) of a contact deeper than one step
    resolves and 20 % of the radius. ``chord``: friction's slope along the slip by the secant
    method (``_slip_slope``), else the secant |f_t| / |s|."""
    mass, node_kmin, node_radius = rd.n1[N_MASS], rd.n1[N_NODE_KMIN], rd.n1[N_NODE_RADIUS]
    force, contact_force, el_K = rd.n3[N_FORCE], rd.n3[N_CONTACT_FORCE], rd.el_K
    n_planes = planes.shape[0]
    n_nodes = X.shape[0]
    # Collider tables; without colliders arrays of the same types that are never read.
    pose, twist, par = rd.e33[0], rd.n3[0], planes
    has_cols = cols is not None
    if has_cols:  # (the caller clears the reactions in cols.wrench[r])
        pose, twist, par = cols.pose[r], cols.twist[r], cols.par
    count = 0
    coupled = 0
    for k in range(_n_queries(nn, ne, cols)):
        node, a, b, e, slot, radius = _slot(k, n0, nn, e0, n_nodes, node_radius)
        for j in range(SP_K):
            src = sp_i[slot, j, SP_SRC]
            if src < 0:
                continue
            q, n = _plane_of(sp_f, slot, j, src, n_planes, pose)
            s = sp_f[slot, j, SP_S]
            wa = 1.0 - s
            wb = s
            x = (wa * X[a, 0] + wb * X[b, 0], wa * X[a, 1] + wb * X[b, 1],
                 wa * X[a, 2] + wb * X[b, 2])
            pen = radius - ((x[0] - q[0]) * n[0] + (x[1] - q[1]) * n[1] + (x[2] - q[2]) * n[2])
            if not node:  # a segment: only what its nodes' contacts do not carry
                pen -= wa * _node_pen(sp_i, sp_f, a, src) + wb * _node_pen(sp_i, sp_f, b, src)
            sp_f[slot, j, SP_PEN] = pen
            sp_f[slot, j, SP_FN] = 0.0
            state = sp_i[slot, j, SP_SET]
            if state == RELEASED or (state == INACTIVE and pen <= 0.0):
                continue
            d0 = sp_f[slot, j, SP_D0]
            m = wa * mass[a] + wb * mass[b]
            kmin = wa * node_kmin[a] + wb * node_kmin[b]
            # (a stiffness multiplier kmul shortens the reference step by sqrt(kmul))
            kc, cc, mu_s, mu_k = _law(src, n_planes, planes, par, m, kmin,
                                      min(dt_ref, 0.2 / impact_frequency(h, radius))
                                      / math.sqrt(sp_f[slot, j, SP_KMUL]))
            d_off = sp_f[slot, j, SP_OFF]
            fn = kc * (pen - d_off) + cc * (pen - max(d0, 0.0)) / h
            sp_f[slot, j, SP_FN] = fn
            push, sp_i[slot, j, SP_SET], sp_i[slot, j, SP_FLIPS] = switch_active(
                state, sp_i[slot, j, SP_FLIPS], fn, PLANE_FLIPS)
            if not push:
                continue
            if commit and fn <= 0.0:
                continue
            if commit and d_off > 0.0 and d0 > START_DEEP * radius and d0 > stats[5]:
                # A point inside a convex body lies behind all its tangent planes, no deeper
                # than behind the shallowest: a node behind only the plane where it is headed
                # (past the edge of a box's face) is not inside.
                for jj in range(SP_K):
                    if sp_i[slot, jj, SP_SRC] == src:
                        d0 = min(d0, sp_f[slot, jj, SP_D0])
                if d0 > START_DEEP * radius:
                    stats[5] = max(stats[5], d0)
            f = (fn * n[0], fn * n[1], fn * n[2])
            ka = 0.0  # tangential stiffness along the friction force, and across it (N/m)
            kb = 0.0
            sh = (0.0, 0.0, 0.0)
            ta = wa
            sa = wb
            cu = 0.0  # d|f_t| / d(penetration) (N/m), while the bound follows the normal force
            if mu_s > 0.0 or mu_k > 0.0:
                u = (wa * V[a, 0] + wb * V[b, 0], wa * V[a, 1] + wb * V[b, 1],
                     wa * V[a, 2] + wb * V[b, 2])
                vs = _surface_velocity(src, n_planes, pose, twist, q)
                A = _frame_point(src, n_planes, pose, sp_f[slot, j, SP_A],
                                 sp_f[slot, j, SP_A + 1], sp_f[slot, j, SP_A + 2])
                w = (u[0] - vs[0], u[1] - vs[1], u[2] - vs[2])
                # Friction holds the material point of a segment where the contact began.
                sa = sp_f[slot, j, SP_AS] if not node else 0.0
                ta = 1.0 - sa
                pm = (ta * X[a, 0] + sa * X[b, 0], ta * X[a, 1] + sa * X[b, 1],
                      ta * X[a, 2] + sa * X[b, 2])
                wn = w[0] * n[0] + w[1] * n[1] + w[2] * n[2]
                t0, t1, t2 = w[0] - wn * n[0], w[1] - wn * n[1], w[2] - wn * n[2]
                d0_, d1_, d2_ = pm[0] - A[0], pm[1] - A[1], pm[2] - A[2]
                dn = d0_ * n[0] + d1_ * n[1] + d2_ * n[2]
                # Stick displacement from the anchor plus the tangential damping's share (m),
                # and the friction it gives, saturated smoothly at mu N:
                # |f_t| = mu N tanh(|s| / delta), delta = max(mu N / k, STICK_ZONE).
                g = cc / kc
                s0 = d0_ - dn * n[0] + g * t0
                s1 = d1_ - dn * n[1] + g * t1
                s2 = d2_ - dn * n[2] + g * t2
                smag = math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
                mu = mu_k if sp_i[slot, j, SP_SLIDING] != 0 else mu_s
                # The normal force the bound takes, unless frozen for the rest of the step
                # (see freeze_friction_bounds).
                frozen = sp_f[slot, j, SP_FROZEN]
                limit = mu * (frozen if frozen >= 0.0 else max(fn, 0.0))
                if limit > 0.0:
                    delta = max(limit / kc, STICK_ZONE)
                    kt = limit / delta * (1.0 + g / h)  # d|f_t|/dx at zero slip (N/m)
                    ka = kb = kt
                    if smag > 1e-300:
                        y = smag / delta
                        th = math.tanh(y)
                        sh = (s0 / smag, s1 / smag, s2 / smag)
                        scale = limit * th / smag
                        f = (f[0] - scale * s0, f[1] - scale * s1, f[2] - scale * s2)
                        # Secant stiffness (|f_t| / |s|) across the force; along it the
                        # tangent kt (1 - th^2) vanishes once saturated, and Newton would then
                        # overshoot the stick point and flip the friction every iterate: the
                        # secant there too, or the bounded chord of ``_slip_slope``.
                        kb = kt * th / y
                        if not commit:  # (an accepted step's evaluation adds no stiffness)
                            ka = _slip_slope(sp_f, slot, j, s0, s1, s2, smag, delta, th, kt, kb,
                                             chord)
                        if frozen < 0.0:
                            # |f_t| = mu N tanh(|s| k / (mu N)): d|f_t|/dN = mu (th - y (1 - th^2))
                            cu = mu * (th - y * (1.0 - th * th))
                            cu = cu * (kc + cc / h) if cu >= MIN_COUPLING * mu else 0.0
                        if commit:
                            sliding = y > Y_SLIDE
                            sp_i[slot, j, SP_SLIDING] = 1 if sliding else 0
                            if sliding:  # the anchor trails the sliding point
                                back = 1.0 - Y_ANCHOR / y
                                A = (A[0] + back * s0, A[1] + back * s1, A[2] + back * s2)
                if commit:
                    la = _local_point(src, n_planes, pose, A[0], A[1], A[2])
                    sp_f[slot, j, SP_A], sp_f[slot, j, SP_A + 1], sp_f[slot, j, SP_A + 2] = la
                    sp_f[slot, j, SP_AS] = sa
            if commit:  # in contact at the end of this step: anchor and offset carry over
                sp_i[slot, j, SP_ANCHORED] = 1
            count += 1
            fnn = f[0] * n[0] + f[1] * n[1] + f[2] * n[2]
            for d in range(3):
                ft = f[d] - fnn * n[d]
                fa = wa * fnn * n[d] + ta * ft
                force[a, d] += fa
                contact_force[a, d] += fa
                if not node:
                    fb = wb * fnn * n[d] + sa * ft
                    force[b, d] += fb
                    contact_force[b, d] += fb
            if has_cols and commit and src >= n_planes:
                c = src - n_planes
                rq = (q[0] - pose[c, 0, 3], q[1] - pose[c, 1, 3], q[2] - pose[c, 2, 3])
                _add_reaction(cols.wrench, r, c, rq, f)
            if commit:  # the stiffness is for Newton's matrix only
                continue
            kn = kc + cc / h
            # The friction force -|f_t| sh grows with the penetration: -d f / dx carries
            # u n^T with u = -cu sh (nonsymmetric; rows weighted as the friction, columns as
            # the penetration).
            u = (-cu * sh[0], -cu * sh[1], -cu * sh[2])
            if node:  # the node's diagonal block lives in an adjacent element's a-a / b-b
                ea, qa = (e0 + k, 0) if k < ne else (e0 + ne - 1, 2)
                _add_contact_K(el_K, ea, qa, 1.0, 1.0, kn, ka, kb, n, sh)
                if cu != 0.0:
                    _add_coupling(el_K, ea, 0 if qa == 0 else 3, 1.0, u, n)
            else:
                _add_contact_K(el_K, e, 0, wa * wa, ta * ta, kn, ka, kb, n, sh)
                _add_contact_K(el_K, e, 1, wa * wb, ta * sa, kn, ka, kb, n, sh)
                _add_contact_K(el_K, e, 2, wb * wb, sa * sa, kn, ka, kb, n, sh)
                if cu != 0.0:
                    _add_coupling(el_K, e, 0, ta * wa, u, n)
                    _add_coupling(el_K, e, 1, ta * wb, u, n)
                    _add_coupling(el_K, e, 2, sa * wa, u, n)
                    _add_coupling(el_K, e, 3, sa * wb, u, n)
            if cu != 0.0:
                coupled += 1
    if not commit:  # (the last iteration's count says which coupling blocks to clear)
        rd.r1[R_COUPLED][r] = coupled
    return count


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def start_penetrations(r, n0, nn, e0, ne, h, X, planes, rd, cols, sp_i, sp_f, n_nodes):
    """Store each slot plane's penetration at the step start (``X``) as its ``d0``, and the
    depth its force leaves alone this step (``SP_OFF``): for a plane new to the slot what lies
    deeper than ``V_OUT h``, for one in contact at the last step its last offset less
    ``V_OUT h`` (a point placed inside comes out at ``V_OUT``; an impact is not softened)."""
    node_radius = rd.n1[N_NODE_RADIUS]
    n_planes = planes.shape[0]
    pose = rd.e33[0]  # as in plane_forces
    if cols is not None:
        pose = cols.pose[r]
    for k in range(_n_queries(nn, ne, cols)):
        node, a, b, e, slot, radius = _slot(k, n0, nn, e0, n_nodes, node_radius)
        for j in range(SP_K):
            src = sp_i[slot, j, SP_SRC]
            if src < 0:
                continue
            q, n = _plane_of(sp_f, slot, j, src, n_planes, pose)
            s = sp_f[slot, j, SP_S]
            x = ((1.0 - s) * X[a, 0] + s * X[b, 0], (1.0 - s) * X[a, 1] + s * X[b, 1],
                 (1.0 - s) * X[a, 2] + s * X[b, 2])
            pen = radius - ((x[0] - q[0]) * n[0] + (x[1] - q[1]) * n[1] + (x[2] - q[2]) * n[2])
            if not node:
                pen -= (1.0 - s) * _node_pen(sp_i, sp_f, a, src) + s * _node_pen(sp_i, sp_f, b, src)
            sp_f[slot, j, SP_PEN] = pen
            sp_f[slot, j, SP_KP] = -1.0
            sp_f[slot, j, SP_D0] = pen
            off = min(sp_f[slot, j, SP_OFF], pen) if sp_i[slot, j, SP_ANCHORED] != 0 else pen
            sp_f[slot, j, SP_OFF] = max(off - V_OUT * h, 0.0)


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def project_predictor(r, n0, nn, X, planes, rd, cols, sp_i, sp_f, fixed) -> int:
    """Move predicted node positions ``X`` that penetrate their contact planes back onto them
    (a Newton starting guess that already respects the contacts; ``fixed`` marks the
    prescribed unknowns, node i's at 2 (i - n0), which stay where they are); returns how many
    of them started the step outside (contacts about to engage)."""
    moved = 0
    node_radius = rd.n1[N_NODE_RADIUS]
    n_planes = planes.shape[0]
    pose = rd.e33[0]  # as in plane_forces
    if cols is not None:
        pose = cols.pose[r]
    for i in range(n0, n0 + nn):
        if fixed[2 * (i - n0)]:
            continue
        for j in range(SP_K):
            src = sp_i[i, j, SP_SRC]
            if src < 0:
                continue
            q, n = _plane_of(sp_f, i, j, src, n_planes, pose)
            pen = node_radius[i] - ((X[i, 0] - q[0]) * n[0] + (X[i, 1] - q[1]) * n[1]
                                    + (X[i, 2] - q[2]) * n[2])
            d0 = sp_f[i, j, SP_D0]
            pen -= max(d0, 0.0)  # no deeper than it started
            if pen > 0.0:
                if d0 <= 0.0:  # a contact about to engage (not one resting since before)
                    moved += 1
                for d in range(3):
                    X[i, d] += pen * n[d]
    return moved


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def release_pulling(n0, nn, e0, ne, n_nodes, sp_i, sp_f) -> int:
    """Near convergence: release the active planes whose force pulls, and re-engage
    released planes that are now deeper than where their force starts (a release elsewhere
    or another rod may have pressed them in since). Returns how many changed."""
    count = 0
    for k in range(nn + ne):
        slot = n0 + k if k < nn else n_nodes + e0 + k - nn
        for j in range(SP_K):
            state = sp_i[slot, j, SP_SET]
            if state == ACTIVE and sp_f[slot, j, SP_FN] < 0.0:
                sp_i[slot, j, SP_SET] = RELEASED
                count += 1
            elif state == RELEASED and sp_f[slot, j, SP_PEN] > max(
                    sp_f[slot, j, SP_OFF], sp_f[slot, j, SP_D0], 0.0):
                sp_i[slot, j, SP_SET] = ACTIVE
                count += 1
    return count


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def reengage_deep(n0, nn, e0, ne, n_nodes, rd, sp_i, sp_f) -> int:
    """At a converged iterate: re-engage each released plane whose point is now deeper behind
    it than ``REFIND_DEPTH`` of its radius, once the release rounds are spent (a 1 mm steel
    wire pushed along the floor by a cylinder ended a step 97 % of its radius in the floor,
    its plane released); returns how many (the caller then iterates on)."""
    node_radius = rd.n1[N_NODE_RADIUS]
    count = 0
    for k in range(nn + ne):
        node, a, b, e, slot, radius = _slot(k, n0, nn, e0, n_nodes, node_radius)
        for j in range(SP_K):
            if sp_i[slot, j, SP_SET] == RELEASED and sp_f[slot, j, SP_PEN] - max(
                    sp_f[slot, j, SP_OFF], sp_f[slot, j, SP_D0], 0.0) > REFIND_DEPTH * radius:
                sp_i[slot, j, SP_SET] = ACTIVE
                count += 1
    return count


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def freeze_friction_bounds(n0, nn, e0, ne, n_nodes, n_planes, sp_i, sp_f) -> int:
    """Fix the friction bound (mu N) of each acting collider plane at its normal force at the
    iterate, for the rest of the step; returns how many. World planes keep theirs: a rope
    cannot wrap a flat plane, and their friction is solved as before.

    Newton stalls where friction at an edge feeds back on the normal force through the rod's
    tension (a rope dragged over a kerb or round a post: a capstan), a coupling that the
    symmetric Newton matrix leaves out: it then contracts by only ~0.9 per iteration. With the
    bound fixed (IPC's lagged friction, here only for a step that has used up its iterations,
    so that every step that converged within them is solved as before) it converges in a few
    iterations. Bounds lagged over whole steps instead were tried: a bound above the current
    normal force feeds the tension that presses the rod on, step after step (a steel wire
    folded itself round a cylinder), and resolving impacts at full steps that used to be
    halved let stiff wires sink deeper."""
    count = 0
    for k in range(nn + ne):
        slot = n0 + k if k < nn else n_nodes + e0 + k - nn
        for j in range(SP_K):
            if (sp_i[slot, j, SP_SRC] >= n_planes and sp_i[slot, j, SP_SET] == ACTIVE
                    and sp_f[slot, j, SP_FROZEN] < 0.0):
                sp_f[slot, j, SP_FROZEN] = max(sp_f[slot, j, SP_FN], 0.0)
                count += 1
    return count


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def unfreeze_friction_bounds(n0, nn, e0, ne, n_nodes, sp_i, sp_f) -> None:
    """Let the friction bounds fixed by ``freeze_friction_bounds`` follow the normal force
    again (after contacts were stiffened: the forces they were fixed at are gone)."""
    for k in range(nn + ne):
        slot = n0 + k if k < nn else n_nodes + e0 + k - nn
        for j in range(SP_K):
            sp_f[slot, j, SP_FROZEN] = -1.0


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def stiffen_deep(n0, nn, e0, ne, n_nodes, planes, rd, cols, sp_i, sp_f) -> int:
    """At a (nearly) converged iterate: stiffen the automatic penalty of each pushing plane
    whose point is deeper than ``STIFFEN_DEPTH`` of its radius (a segment's point counted with
    what its nodes' planes carry); returns how many (the caller then iterates on). A user's
    own stiffness is left alone."""
    node_radius = rd.n1[N_NODE_RADIUS]
    n_planes = planes.shape[0]
    count = 0
    for k in range(_n_queries(nn, ne, cols)):
        node, a, b, e, slot, radius = _slot(k, n0, nn, e0, n_nodes, node_radius)
        for j in range(SP_K):
            src = sp_i[slot, j, SP_SRC]
            if src < 0 or sp_i[slot, j, SP_SET] != ACTIVE or sp_f[slot, j, SP_FN] <= 0.0:
                continue
            auto = False
            if src < n_planes:
                auto = planes[src, PL_AUTO] > 0.0
            elif cols is not None:
                auto = cols.par[src - n_planes, P_AUTO] > 0.0
            if not auto:
                continue
            deep = sp_f[slot, j, SP_PEN] - sp_f[slot, j, SP_OFF]
            if not node:
                s = sp_f[slot, j, SP_S]
                deep += (1.0 - s) * _node_pen(sp_i, sp_f, a, src) + s * _node_pen(sp_i, sp_f, b,
                                                                                   src)
            kmul = sp_f[slot, j, SP_KMUL]
            if deep > STIFFEN_DEPTH * radius and kmul < MAX_KMUL:
                grow = (deep / (IMPACT_DEPTH * radius)) ** 2
                sp_f[slot, j, SP_KMUL] = min(kmul * max(grow, 2.0), MAX_KMUL)
                count += 1
    return count
