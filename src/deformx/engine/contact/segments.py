"""Contact of rod segments (capsules) with meshes and analytic primitives: force and stiffness.

Rod points are spheres (nodes) and capsules (elements) of the rod radius. Against every
collider the kernel finds closest points: exact point- and segment-triangle closest points through
the mesh's BVH, or the convex signed distance of a primitive. A penetration ``d > 0`` gives the
penalty normal force ``N = k d - c v_n``. Nodes carry the contact of a rope lying on a surface;
a segment adds the part of its deepest penetration that its nodes do not account for (a sharp
edge or a thin plate between two nodes), spread on its nodes with the linear weights of the
contact point, so a rope cannot slip between its nodes through a thin plate or edge.

Friction is a spring-slider (Cundall & Strack): an anchor fixed on the collider (in its local
frame, so it moves with it) pulls the contact point back with stiffness ``k``; above ``mu_s N``
it slides with ``mu_k N`` and the anchor trails it. A static load below the limit holds with a
bounded elastic shift and no creep. One anchor per node and per element (for its first
collider); a point touching further colliders at once gets rate-regularised kinetic friction.

Every force is also summed, with opposite sign, into the collider's wrench (force, torque about
its origin, world frame). For the stable integrator the kernel also returns the contact
stiffness per element as three 3x3 blocks (node a-a, b-a, b-b).

Collider tables (the ``Colliders`` bundle of :mod:`deformx.engine.kernels.bundles`):
``kind (C,)``, per rod ``pose (R, C, 4, 4)`` world-from-local and ``twist (R, C, 6)`` (linear
velocity of the origin, angular velocity; world frame) as that rod sees them now, ``par (C, 12)`` (stiffness, damping, mu_s, mu_k, auto,
two_sided, repulsion, shape parameters x3, unused x2), the packed meshes and the per-query
caches of nearby triangles (see ``_mesh_nearest``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..geometry.bvh import _box_gap2, closest_segment_search, nearest_k_search, signed_side
from ..geometry.closest import bary_point, dist2, lerp, segment_triangle_dist2
from ..kernels.refcount import NO_REFCOUNT
from .plane import V_OUT, carry_offset, note_start_inside, start_offset
from .primitives import bounding_gap, segment_deepest, shape_sdf
from ..kernels.bundles import (
    E_SEG_OFF,
    N_CONTACT_FORCE,
    N_FORCE,
    N_MASS,
    N_PEN_OFF,
    N_NODE_KMIN,
    N_NODE_RADIUS,
)

MESH = 0
# par columns
P_K, P_C, P_MUS, P_MUK, P_AUTO, P_TWO_SIDED, P_REPULSION, P_SHAPE = 0, 1, 2, 3, 4, 5, 6, 7
N_PAR = 12
QUERY_CACHE = 32  # nearest triangles kept per query
# Query cache columns (``qc_meta`` integers, ``qc_geo`` floats; see kernels/bundles.py).
Q_COL, Q_N, Q_FLAT, Q_HINT = 0, 1, 2, 3
Q_FAR, Q_WITHIN = 6, 7  # qc_geo: the horizon, and the reach + skin it was filled for
_TINY = 1e-12  # m: below this a closest-point normal is undefined (segment crosses a face)
# Coplanarity tolerance of a flat patch, relative to the contact reach (5 nm for a 5 mm rope):
# the largest penetration a near-flat patch's shortcut can misjudge.
_FLAT_TOL = 1e-6


@njit(cache=True, error_model="numpy")
def _to_local(pose, c, x0, x1, x2):
    y0 = x0 - pose[c, 0, 3]
    y1 = x1 - pose[c, 1, 3]
    y2 = x2 - pose[c, 2, 3]
    return (pose[c, 0, 0] * y0 + pose[c, 1, 0] * y1 + pose[c, 2, 0] * y2,
            pose[c, 0, 1] * y0 + pose[c, 1, 1] * y1 + pose[c, 2, 1] * y2,
            pose[c, 0, 2] * y0 + pose[c, 1, 2] * y1 + pose[c, 2, 2] * y2)


@njit(cache=True, error_model="numpy")
def _rotate(pose, c, x0, x1, x2):
    return (pose[c, 0, 0] * x0 + pose[c, 0, 1] * x1 + pose[c, 0, 2] * x2,
            pose[c, 1, 0] * x0 + pose[c, 1, 1] * x1 + pose[c, 1, 2] * x2,
            pose[c, 2, 0] * x0 + pose[c, 2, 1] * x1 + pose[c, 2, 2] * x2)


@njit(cache=True, error_model="numpy")
def _to_world(pose, c, x0, x1, x2):
    """World position (m) of point x given in collider c's frame."""
    y = _rotate(pose, c, x0, x1, x2)
    return y[0] + pose[c, 0, 3], y[1] + pose[c, 1, 3], y[2] + pose[c, 2, 3]


@njit(cache=True, error_model="numpy")
def _height(Fg, f, x) -> float:
    """Height (m) of x above face f's plane (see :mod:`deformx.engine.geometry.faces`)."""
    return Fg[f, 0, 0] * x[0] + Fg[f, 0, 1] * x[1] + Fg[f, 0, 2] * x[2] - Fg[f, 0, 3]


@njit(cache=True, error_model="numpy")
def _outer_side(ha: float, hb: float, two_sided: bool) -> bool:
    """Whether heights ha, hb (m) put both ends of a segment strictly on the outer side of a
    plane (either side for an open mesh), so that it does not cross it."""
    return (ha > 0.0 and hb > 0.0) or (two_sided and ha < 0.0 and hb < 0.0)


@njit(cache=True, error_model="numpy")
def _bary(Fg, f, x):
    """Barycentrics (u, v, w) of x's projection onto face f's plane (see
    :mod:`deformx.engine.geometry.faces`)."""
    v = Fg[f, 1, 0] * x[0] + Fg[f, 1, 1] * x[1] + Fg[f, 1, 2] * x[2] - Fg[f, 1, 3]
    w = Fg[f, 2, 0] * x[0] + Fg[f, 2, 1] * x[1] + Fg[f, 2, 2] * x[2] - Fg[f, 2, 3]
    return 1.0 - v - w, v, w


@njit(cache=True, error_model="numpy")
def _flat_patch(slot, verts, faces, Fg, qc_tris, qc_dist, n, far, within, tol):
    """The first cached face if every face within ``within`` (m) of the slot's segment lies in
    its plane (to ``tol`` m, same orientation) and the cache holds all of them; else -1."""
    if n == 0 or far < within:
        return -1
    ref = qc_tris[slot, 0]
    g0, g1, g2, o = Fg[ref, 0, 0], Fg[ref, 0, 1], Fg[ref, 0, 2], Fg[ref, 0, 3]
    for k in range(n):
        if qc_dist[slot, k] > within:
            break
        f = qc_tris[slot, k]
        if not Fg[f, 0, 0] * g0 + Fg[f, 0, 1] * g1 + Fg[f, 0, 2] * g2 > 0.0:
            return -1  # turned over, degenerate (NaN) or not in the plane
        for corner in range(3):
            i = faces[f, corner]
            if not abs(g0 * verts[i, 0] + g1 * verts[i, 1] + g2 * verts[i, 2] - o) <= tol:
                return -1
    return ref


@njit(cache=True, error_model="numpy")
def _patch_face(slot, end, x, within, Fg, qc_tris, qc_dist, qc_meta):
    """A cached face within ``within`` (m) whose plane projection of x contains it, and its
    barycentrics (u, v, w); -1 if none. Tries the face that held end ``end`` last time first."""
    hint = qc_meta[slot, Q_HINT + end]
    for j in range(-1, qc_meta[slot, Q_N]):
        k = hint if j < 0 else j
        if k < 0 or (j >= 0 and k == hint):
            continue
        if qc_dist[slot, k] > within:
            if j < 0:
                continue
            break
        f = qc_tris[slot, k]
        u, v, w = _bary(Fg, f, x)
        if u >= 0.0 and v >= 0.0 and w >= 0.0:
            qc_meta[slot, Q_HINT + end] = k
            return f, u, v, w
    return -1, 0.0, 0.0, 0.0


@njit(cache=True, error_model="numpy")
def _inside(Fg, f, x) -> bool:
    """Whether x projects into face f."""
    u, v, w = _bary(Fg, f, x)
    return u >= 0.0 and v >= 0.0 and w >= 0.0


@njit(cache=True, error_model="numpy")
def _moved(qc_geo, slot, la, lb) -> float:
    """Largest coordinate change (m) of local ends la, lb since the slot's cache was filled."""
    return max(abs(la[0] - qc_geo[slot, 0]), abs(la[1] - qc_geo[slot, 1]),
               abs(la[2] - qc_geo[slot, 2]), abs(lb[0] - qc_geo[slot, 3]),
               abs(lb[1] - qc_geo[slot, 4]), abs(lb[2] - qc_geo[slot, 5]))


@njit(cache=True, inline="always", error_model="numpy")
def _mesh_nearest(c, slot, root, lo, hi, left, right, start, count, order, verts, faces, Fg, la,
                  lb, reach, skin, two_sided, qc_meta, qc_geo, qc_tris, qc_dist, stack, bound,
                  lasting):
    """Nearest triangle to local segment la-lb within ``reach`` (m), through a per-slot cache;
    ``stack``, ``bound``: BVH traversal scratch (the rod's rows of ``tr_stack``, ``tr_bound``).

    The cache holds the triangles nearest to where the slot's segment was when it was filled,
    sorted by their exact distance then, and a horizon that no other triangle comes closer
    than (``nearest_k_search``). After the ends moved by at most ``delta`` every triangle is at
    least its cached distance minus ``delta`` away, so the sorted scan stops at the first
    triangle that cannot beat the best so far (most steps test one or two), and the answer is
    exact while the best found lies within the horizon minus ``delta``; otherwise, or after
    moving more than ``skin``, the cache is refilled. Also returns whether the cache was
    (re)filled or bypassed on this call. ``root``: the mesh's BVH root in the packed tables.

    Flat patches (a floor, a table top, a box face) take a shortcut: when every triangle
    within ``reach + skin`` of the filled segment lies in one plane (column ``Q_FLAT``), those are
    the only ones that can come within ``reach`` before the next refill, so a point whose
    projection falls in one of them is exactly its height above the plane away. A segment
    above such a patch with both ends' projections in it, or farther than ``reach``, has no
    contact beyond what its ends carry (its distance is at least the linear interpolation of
    theirs), and gets -1: callers ask segments only for that excess.

    A cache is worth filling only where it outlasts the step: ``lasting`` (1: the caller
    expects the slot to move less than the skin per step; 0: more; -1: keep the slot's mode)
    sends a slot whose cache of a curved or edged patch (not flat) ran out, and that moves
    faster than its skin, to a direct nearest-triangle search (pruned by the best distance so
    far: a handful of exact tests, where a refill computes every triangle within the reach and
    skin: 40-50 round a 48-sided post) until it slows down (``Q_COL`` is then ``-2 - c``).
    """
    point = la[0] == lb[0] and la[1] == lb[1] and la[2] == lb[2]
    moved = 0.0
    delta2 = 0.0
    fresh = False
    within = reach + skin
    direct = qc_meta[slot, Q_COL] == -2 - c and lasting <= 0
    if qc_meta[slot, Q_COL] == c:
        moved = _moved(qc_geo, slot, la, lb)
        delta2 = max(dist2(la, (qc_geo[slot, 0], qc_geo[slot, 1], qc_geo[slot, 2])),
                     dist2(lb, (qc_geo[slot, 3], qc_geo[slot, 4], qc_geo[slot, 5])))
    # Valid while the ends moved less than the reach the cache was filled for exceeds this one.
    refill = qc_meta[slot, Q_COL] != c or moved * math.sqrt(3.0) > qc_geo[slot, Q_WITHIN] - reach
    if refill and lasting == 0 and qc_meta[slot, Q_COL] == c and qc_meta[slot, Q_FLAT] < 0:
        direct = True
    if direct:
        if lasting == 0:
            qc_meta[slot, Q_COL] = -2 - c
        tri, s, u, v, w, d2 = closest_segment_search(lo, hi, left, right, start, count, order,
                                                     verts, faces, la, lb, reach, root, stack,
                                                     bound)
        if tri >= 0 and not point and _outer_side(_height(Fg, tri, la), _height(Fg, tri, lb),
                                                 two_sided) and _inside(Fg, tri, la) \
                and _inside(Fg, tri, lb):
            # Above one face end to end: no contact beyond what its ends carry (as a flat
            # patch's shortcut says, should the slot have moved onto one).
            return -1, 0.0, 0.0, 0.0, 0.0, np.inf, False
        return tri, s, u, v, w, d2, True
    while True:
        if refill:
            n, far = nearest_k_search(lo, hi, left, right, start, count, order, verts, faces,
                                      la, lb, within, qc_tris[slot], qc_dist[slot], root, stack,
                                      bound)
            fresh = True
            delta2 = 0.0
            qc_meta[slot, Q_COL] = c
            qc_meta[slot, Q_N] = n
            qc_geo[slot, Q_FAR] = far
            qc_geo[slot, Q_WITHIN] = within
            qc_meta[slot, Q_FLAT] = _flat_patch(slot, verts, faces, Fg, qc_tris, qc_dist, n, far,
                                                within, _FLAT_TOL * reach)
            qc_meta[slot, Q_HINT] = -1
            qc_meta[slot, Q_HINT + 1] = -1
            for d in range(3):
                qc_geo[slot, d] = la[d]
                qc_geo[slot, 3 + d] = lb[d]
        ref = qc_meta[slot, Q_FLAT]
        if ref >= 0:
            ha = _height(Fg, ref, la)
            if point:
                f, u, v, w = _patch_face(slot, 0, la, within, Fg, qc_tris, qc_dist, qc_meta)
                if f >= 0:
                    if ha * ha > reach * reach:
                        return -1, 0.0, 0.0, 0.0, 0.0, np.inf, fresh
                    return f, 0.0, u, v, w, ha * ha, fresh
            else:
                hb = _height(Fg, ref, lb)
                if _outer_side(ha, hb, two_sided):
                    if min(abs(ha), abs(hb)) > reach or (
                            _patch_face(slot, 0, la, within, Fg, qc_tris, qc_dist,
                                        qc_meta)[0] >= 0
                            and _patch_face(slot, 1, lb, within, Fg, qc_tris, qc_dist,
                                            qc_meta)[0] >= 0):
                        return -1, 0.0, 0.0, 0.0, 0.0, np.inf, fresh
        delta = math.sqrt(delta2)
        best = reach * reach
        tri = -1
        rs = ru = rv = rw = 0.0
        for k in range(qc_meta[slot, Q_N]):
            low = qc_dist[slot, k] - delta
            if low > 0.0 and low * low > best:
                break  # sorted: no later triangle can be nearer either
            f = qc_tris[slot, k]
            va = (verts[faces[f, 0], 0], verts[faces[f, 0], 1], verts[faces[f, 0], 2])
            vb = (verts[faces[f, 1], 0], verts[faces[f, 1], 1], verts[faces[f, 1], 2])
            vc = (verts[faces[f, 2], 0], verts[faces[f, 2], 1], verts[faces[f, 2], 2])
            s, u, v, w, d2 = segment_triangle_dist2(la, lb, point, va, vb, vc)
            if d2 < best or (tri < 0 and d2 <= best):
                best = d2
                tri = f
                rs, ru, rv, rw = s, u, v, w
        low = qc_geo[slot, Q_FAR] - delta
        if low > 0.0 and low * low > best:
            break  # no triangle left out of the cache can be as near
        if fresh:  # more than the cache's size tie at the nearest distance: search the tree
            qc_meta[slot, Q_COL] = -1
            tri, s, u, v, w, d2 = closest_segment_search(lo, hi, left, right, start, count,
                                                         order, verts, faces, la, lb, reach,
                                                         root, stack, bound)
            return tri, s, u, v, w, d2, True
        refill = True
    if tri < 0:
        return -1, 0.0, 0.0, 0.0, 0.0, np.inf, fresh
    return tri, rs, ru, rv, rw, best, fresh


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _mesh_closest(c, root, pose, par, MV, MF, Blo, Bhi, Bleft, Bright, Bstart, Bcount, Border, Fn,
                  En, Vn, Fg, qc_meta, qc_geo, qc_tris, qc_dist, stack, bound, slot, pa, pb,
                  reach, lasting=1):
    """Deepest point of world segment pa-pb against mesh collider ``c`` (BVH root ``root`` in
    the packed tables) within ``reach`` (m).

    Returns (hit, s, signed distance of the segment axis, normal (world), surface point
    (world)); hit is False when the segment is farther than ``reach``, or when it provably
    touches nothing beyond what its ends touch (see ``_mesh_nearest``). ``slot`` names the
    query (node i or element N + e) in the query cache; ``stack``, ``bound``: BVH traversal
    scratch. Compiled without reference counting (see :mod:`deformx.engine.kernels.refcount`);
    the packed tables use global indices (see ``pack``) so that no per-query views are needed.
    ``lasting``: whether the slot's query cache can outlast a step (see ``_mesh_nearest``).
    """
    la = _to_local(pose, c, pa[0], pa[1], pa[2])
    lb = _to_local(pose, c, pb[0], pb[1], pb[2])
    tri, s, u, v, w, d2, fresh = _mesh_nearest(c, slot, root, Blo, Bhi, Bleft, Bright, Bstart,
                                               Bcount, Border, MV, MF, Fg, la, lb, reach,
                                               0.5 * reach, par[c, P_TWO_SIDED] != 0.0,
                                               qc_meta, qc_geo, qc_tris, qc_dist, stack,
                                               bound, lasting)
    if (tri < 0 and fresh and par[c, P_TWO_SIDED] == 0.0 and par[c, P_REPULSION] > 0.0
            and _box_gap2(Blo, Bhi, root, la, la) == 0.0
            and _box_gap2(Blo, Bhi, root, lb, lb) == 0.0):
        # Nothing near the surface: the segment may still be inside a closed mesh, less
        # than the repulsion distance deep (checked when the cache is refilled, or on
        # every call while it is inside). Not with an end outside the mesh's box: that end
        # is outside, and a segment clear of the surface lies on one side of it (a search
        # as far as the repulsion distance took ~4/5 of a query that moves faster than its
        # cache lasts: a rope dragged over a mesh kerb at 10 ms).
        tri, s, u, v, w, d2 = closest_segment_search(Blo, Bhi, Bleft, Bright, Bstart, Bcount,
                                                     Border, MV, MF, la, lb,
                                                     reach + par[c, P_REPULSION], root, stack,
                                                     bound)
        if tri >= 0:
            p = lerp(la, lb, s)
            q = bary_point((MV[MF[tri, 0], 0], MV[MF[tri, 0], 1], MV[MF[tri, 0], 2]),
                           (MV[MF[tri, 1], 0], MV[MF[tri, 1], 1], MV[MF[tri, 1], 2]),
                           (MV[MF[tri, 2], 0], MV[MF[tri, 2], 1], MV[MF[tri, 2], 2]), u, v, w)
            if signed_side(Fn, En, Vn, MF, tri, u, v, w, p, q) > 0.0:
                tri = -1  # outside and clear of the surface
            else:
                qc_meta[slot, Q_COL] = -1  # deep inside: search afresh until it is out
    if tri < 0:
        return False, 0.0, 0.0, (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)
    ia, ib, ic = MF[tri, 0], MF[tri, 1], MF[tri, 2]
    q = (u * MV[ia, 0] + v * MV[ib, 0] + w * MV[ic, 0],
         u * MV[ia, 1] + v * MV[ib, 1] + w * MV[ic, 1],
         u * MV[ia, 2] + v * MV[ib, 2] + w * MV[ic, 2])
    p = (la[0] + s * (lb[0] - la[0]), la[1] + s * (lb[1] - la[1]), la[2] + s * (lb[2] - la[2]))
    dist = math.sqrt(d2)
    if dist > _TINY:
        n = ((p[0] - q[0]) / dist, (p[1] - q[1]) / dist, (p[2] - q[2]) / dist)
        sd = dist
        if par[c, P_TWO_SIDED] == 0.0:
            if signed_side(Fn, En, Vn, MF, tri, u, v, w, p, q) < 0.0:
                # Inside a closed mesh: push out the nearest way.
                n = (-n[0], -n[1], -n[2])
                sd = -dist
        elif dist > reach:
            return False, 0.0, 0.0, (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)
    else:  # the axis crosses a face: push along its normal (outward for a closed mesh)
        n = (Fn[tri, 0], Fn[tri, 1], Fn[tri, 2])
        sd = 0.0
        if par[c, P_TWO_SIDED] != 0.0:
            # Two-sided: back to the side the segment's far end is on.
            far = lb if s < 0.5 else la
            side = (far[0] - q[0]) * n[0] + (far[1] - q[1]) * n[1] + (far[2] - q[2]) * n[2]
            if side > 0.0:
                n = (-n[0], -n[1], -n[2])
    if sd > reach:
        return False, 0.0, 0.0, (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)
    return True, s, sd, _rotate(pose, c, n[0], n[1], n[2]), _to_world(pose, c, q[0], q[1], q[2])


@njit(cache=True, error_model="numpy")
def _shape_closest(c, kind, pose, par, pa, pb, reach):
    """Deepest point of world segment pa-pb against analytic shape collider ``c`` within
    ``reach`` (m); returns as ``_mesh_closest``."""
    la = _to_local(pose, c, pa[0], pa[1], pa[2])
    lb = _to_local(pose, c, pb[0], pb[1], pb[2])
    shape = (par[c, P_SHAPE], par[c, P_SHAPE + 1], par[c, P_SHAPE + 2])
    # The shape lies in a ball about its origin: a segment farther from that ball than
    # ``reach`` cannot touch it (this skips the box's and cylinder's golden-section search)
    if bounding_gap(kind, shape, la[0], la[1], la[2], lb[0], lb[1], lb[2]) > reach:
        return False, 0.0, 0.0, (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)
    s = segment_deepest(kind, shape, la[0], la[1], la[2], lb[0], lb[1], lb[2])
    p0 = la[0] + s * (lb[0] - la[0])
    p1 = la[1] + s * (lb[1] - la[1])
    p2 = la[2] + s * (lb[2] - la[2])
    sd, n0, n1, n2 = shape_sdf(kind, shape, p0, p1, p2)
    if sd > reach:
        return False, 0.0, 0.0, (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)
    return True, s, sd, _rotate(pose, c, n0, n1, n2), _to_world(pose, c, p0 - sd * n0,
                                                                 p1 - sd * n1, p2 - sd * n2)


@njit(cache=True, error_model="numpy")
def collider_penalty(par, c, mass, k_floor, dt_ref):
    """Penalty stiffness (N/m) and damping (N s/m) of collider ``c`` for a contact of ``mass``:
    automatic (contact frequency 0.2 / dt_ref, at least ``k_floor``, critically damped) or the
    user's values."""
    k = par[c, P_K]
    if par[c, P_AUTO] > 0.0:
        k = max(mass * (0.2 / dt_ref) ** 2, k_floor)
    damp = par[c, P_C]
    if damp < 0.0:
        damp = 2.0 * math.sqrt(k * mass)
    return k, damp


@njit(cache=True, error_model="numpy")
def _relative_velocity(pose, twist, c, u, q):
    """Velocity (m/s) of a rod point moving with ``u`` relative to collider ``c``'s surface
    point ``q`` (world), and q's offset from the collider's origin (m)."""
    rx = q[0] - pose[c, 0, 3]
    ry = q[1] - pose[c, 1, 3]
    rz = q[2] - pose[c, 2, 3]
    return ((u[0] - (twist[c, 0] + twist[c, 4] * rz - twist[c, 5] * ry),
             u[1] - (twist[c, 1] + twist[c, 5] * rx - twist[c, 3] * rz),
             u[2] - (twist[c, 2] + twist[c, 3] * ry - twist[c, 4] * rx)), (rx, ry, rz))


@njit(cache=True, error_model="numpy")
def _add_reaction(wrench, r, c, rq, f) -> None:
    """Adds -f acting at offset ``rq`` (m) from collider c's origin to its wrench."""
    wrench[r, c, 0] -= f[0]
    wrench[r, c, 1] -= f[1]
    wrench[r, c, 2] -= f[2]
    wrench[r, c, 3] -= rq[1] * f[2] - rq[2] * f[1]
    wrench[r, c, 4] -= rq[2] * f[0] - rq[0] * f[2]
    wrench[r, c, 5] -= rq[0] * f[1] - rq[1] * f[0]


@njit(cache=True, inline="always", error_model="numpy")
def _penalty_friction(kc, cc, mu_s, mu_k, h, p, w, n, depth, A, use_anchor):
    """Force (N, world) of one contact of penetration ``depth`` (m) at point ``p`` moving with
    ``w`` relative to the surface (normal ``n``): penalty ``kc`` (N/m), ``cc`` (N s/m), and the
    tangential stiffness (N/m, 0 when sliding); scalars only (inlined with no reference
    counting).

    With ``use_anchor`` the friction is the spring-slider anchored at ``A`` (world); the
    anchor's next position is returned (it trails a sliding point at ``mu_k N``). Otherwise
    rate-regularised kinetic friction.
    """
    wn = w[0] * n[0] + w[1] * n[1] + w[2] * n[2]
    fn = kc * depth - cc * wn
    if fn <= 0.0:
        return False, (0.0, 0.0, 0.0), 0.0, A
    f0 = fn * n[0]
    f1 = fn * n[1]
    f2 = fn * n[2]
    kt = 0.0
    if mu_s > 0.0 or mu_k > 0.0:
        t0 = w[0] - wn * n[0]
        t1 = w[1] - wn * n[1]
        t2 = w[2] - wn * n[2]
        if use_anchor:
            d0 = p[0] - A[0]
            d1 = p[1] - A[1]
            d2 = p[2] - A[2]
            dn = d0 * n[0] + d1 * n[1] + d2 * n[2]
            # Sticking: the spring plus critical damping of the tangential velocity.
            s0 = kc * (d0 - dn * n[0]) + cc * t0
            s1 = kc * (d1 - dn * n[1]) + cc * t1
            s2 = kc * (d2 - dn * n[2]) + cc * t2
            smag2 = s0 * s0 + s1 * s1 + s2 * s2
            limit = mu_s * fn
            if smag2 <= limit * limit:
                kt = kc + cc / h
                f0 -= s0
                f1 -= s1
                f2 -= s2
            else:  # sliding against the trial force; the anchor trails at mu_k N
                back = mu_k * fn / math.sqrt(smag2)
                f0 -= back * s0
                f1 -= back * s1
                f2 -= back * s2
                back /= kc
                A = (p[0] - back * s0, p[1] - back * s1, p[2] - back * s2)
        else:
            tmag = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
            if tmag > 0.0:
                ft = min(mu_k * fn, cc * tmag) / tmag
                f0 -= ft * t0
                f1 -= ft * t1
                f2 -= ft * t2
    return True, (f0, f1, f2), kt, A


@njit(cache=True, error_model="numpy")
def _add_K(el_K, e, q, w, kn, kt, n):
    for i in range(3):
        for j in range(3):
            el_K[e, q, i, j] += w * ((kn - kt) * n[i] * n[j] + (kt if i == j else 0.0))


@njit(cache=True, inline="always", error_model="numpy")
def _kept_depth(pen, carried, vel, i, h):
    """The depth (m) node ``i``'s contact force acts on: its penetration ``pen`` (-1e30: no
    contact) less the start offset it keeps (explicit integrator)."""
    if pen <= 0.0:
        return 0.0
    speed = math.sqrt(vel[i, 0] ** 2 + vel[i, 1] ** 2 + vel[i, 2] ** 2)
    return max(pen - start_offset(carried, pen, speed, h, V_OUT), 0.0)


@njit(cache=True, error_model="numpy")
def rod_collider_contacts(r, n0, nn, e0, ne, h, dt_ref, pos, vel, x_ref, rd, cols, commit,
                          want_K) -> int:
    """Add the contact forces of rod ``r`` with every collider; returns the contact count.

    Two kinds of contact, so that a lying rope is supported evenly and a thin edge between two
    nodes still holds it: node spheres (radius of the rod), with the anchored spring-slider
    friction; and, per segment, the part of the segment's deepest penetration that exceeds
    the linear interpolation of its nodes' penetrations (zero on a flat face, all of it on a
    sharp edge or thin plate under the segment, or a chord of a curved surface). Each node and
    each element has one friction anchor (slots ``i`` and ``N + e`` of ``anchor`` (N + E, 4):
    the point in the collider frame and, for elements, the segment parameter it holds).

    ``vel`` are node velocities (m/s) for damping and friction; ``x_ref`` where a new contact
    anchors (the step start for the stable integrator). ``want_K`` adds the contact
    stiffness (damping as ``c / h``, ``h`` in s) to ``el_K`` (per element: node blocks a-a,
    b-a, b-b); ``commit`` stores the friction anchors (once per accepted step). ``pen`` (N, C)
    is scratch; ``wrench[r]`` is overwritten with the reactions.
    """
    mass, node_radius, node_kmin = rd.n1[N_MASS], rd.n1[N_NODE_RADIUS], rd.n1[N_NODE_KMIN]
    pen_off, seg_off = rd.n1[N_PEN_OFF], rd.e1[E_SEG_OFF]
    el_K, force, contact_force = rd.el_K, rd.n3[N_FORCE], rd.n3[N_CONTACT_FORCE]
    kind, par, mesh_rng, allowed = cols.kind, cols.par, cols.rng, cols.allowed
    # Poses and velocities of the colliders as this rod sees them now (see drivers).
    pose, twist = cols.pose[r], cols.twist[r]
    MV, MF, Blo, Bhi, Bleft, Bright = cols.MV, cols.MF, cols.Blo, cols.Bhi, cols.Bleft, cols.Bright
    Bstart, Bcount, Border, Fn, En, Vn = (cols.Bstart, cols.Bcount, cols.Border, cols.Fn,
                                          cols.En, cols.Vn)
    Fg, qc_meta, qc_geo, qc_tris, qc_dist = cols.Fg, cols.qc_meta, cols.qc_geo, cols.qc_tris, cols.qc_dist
    anchor, anchor_col, pen, wrench = cols.anchor, cols.anchor_id, cols.pen, cols.wrench
    tr_stack, tr_bound = cols.tr_stack, cols.tr_bound
    n_col = kind.shape[0]
    n_nodes = pos.shape[0]
    # The rod's own BVH traversal scratch: nothing here allocates (see NO_REFCOUNT), and rods
    # stepped on different threads never share it.
    stack = tr_stack[r]
    bound = tr_bound[r]
    for c in range(n_col):
        for j in range(6):
            wrench[r, c, j] = 0.0
    count = 0
    for k in range(nn):
        i = n0 + k
        radius = node_radius[i]
        p = (pos[i, 0], pos[i, 1], pos[i, 2])
        u = (vel[i, 0], vel[i, 1], vel[i, 2])
        anchored = False
        for c in range(n_col):
            pen[i, c] = -1e30
            if allowed[r, c] == 0:
                continue
            done = False
            if kind[c] == MESH and qc_meta[i, Q_FLAT] >= 0:
                # The flat-patch shortcut (see _mesh_nearest), written out here: a function
                # inlined by numba increfs and decrefs every array it takes, which would cost
                # more than the whole test.
                la = _to_local(pose, c, p[0], p[1], p[2])
                ref = qc_meta[i, Q_FLAT]
                if (qc_meta[i, Q_COL] == c and qc_meta[i, Q_HINT] >= 0
                        and _moved(qc_geo, i, la, la) * math.sqrt(3.0)
                        <= qc_geo[i, Q_WITHIN] - radius
                        and _inside(Fg, qc_tris[i, qc_meta[i, Q_HINT]], la)):
                    height = _height(Fg, ref, la)
                    if abs(height) > radius:
                        done = True
                        hit = False
                    elif abs(height) > _TINY:
                        # Closed meshes: signed (the face normal points out); open ones:
                        # towards the node.
                        sign = 1.0 if (par[c, P_TWO_SIDED] == 0.0 or height > 0.0) else -1.0
                        n = _rotate(pose, c, sign * Fg[ref, 0, 0], sign * Fg[ref, 0, 1],
                                    sign * Fg[ref, 0, 2])
                        sd = sign * height
                        q = (p[0] - sd * n[0], p[1] - sd * n[1], p[2] - sd * n[2])
                        done = True
                        hit = True
            if done:
                pass
            elif kind[c] == MESH:
                hit, s, sd, n, q = _mesh_closest(c, mesh_rng[c, 4], pose, par, MV, MF, Blo, Bhi,
                                                 Bleft, Bright, Bstart, Bcount, Border, Fn, En,
                                                 Vn, Fg, qc_meta, qc_geo, qc_tris, qc_dist, stack,
                                                 bound, i, p, p, radius)
            else:
                hit, s, sd, n, q = _shape_closest(c, kind[c], pose, par, p, p, radius)
            if not hit:
                continue
            pen[i, c] = radius - sd
            # Less what a node placed inside keeps (see kernels/verlet.py, _carry_offsets).
            depth = pen[i, c] - start_offset(pen_off[i], pen[i, c], math.sqrt(
                u[0] * u[0] + u[1] * u[1] + u[2] * u[2]), h, V_OUT)
            if depth <= 0.0:
                continue
            use_anchor = not anchored and (anchor_col[i] == c or anchor_col[i] < 0)
            # Written out rather than one helper taking the arrays (see above); a new contact
            # anchors where the point started the step.
            A = (x_ref[i, 0], x_ref[i, 1], x_ref[i, 2])
            if use_anchor and anchor_col[i] == c:
                A = _to_world(pose, c, anchor[i, 0], anchor[i, 1], anchor[i, 2])
            kc, cc = collider_penalty(par, c, mass[i], node_kmin[i], dt_ref)
            w, rq = _relative_velocity(pose, twist, c, u, q)
            on, f, kt, A = _penalty_friction(kc, cc, par[c, P_MUS], par[c, P_MUK], h, p, w, n,
                                             depth, A, use_anchor)
            if not on:
                continue
            kn = kc + cc / h
            _add_reaction(wrench, r, c, rq, f)
            if commit and use_anchor and (par[c, P_MUS] > 0.0 or par[c, P_MUK] > 0.0):
                anchor_col[i] = c
                anchor[i, 0], anchor[i, 1], anchor[i, 2] = _to_local(pose, c, A[0], A[1], A[2])
            anchored = anchored or use_anchor
            count += 1
            for d in range(3):
                force[i, d] += f[d]
                contact_force[i, d] += f[d]
            if want_K:  # the node's diagonal block lives in an adjacent element's a-a / b-b
                if k < ne:
                    _add_K(el_K, e0 + k, 0, 1.0, kn, kt, n)
                else:
                    _add_K(el_K, e0 + ne - 1, 2, 1.0, kn, kt, n)
        if commit and not anchored:
            anchor_col[i] = -1
    for k in range(ne):
        e = e0 + k
        a = n0 + k
        b = a + 1 if k + 1 < nn else n0
        radius = 0.5 * (node_radius[a] + node_radius[b])
        pa = (pos[a, 0], pos[a, 1], pos[a, 2])
        pb = (pos[b, 0], pos[b, 1], pos[b, 2])
        slot = n_nodes + e  # element queries and anchors follow the nodes
        anchored = False
        speed = math.sqrt(max(vel[a, 0] ** 2 + vel[a, 1] ** 2 + vel[a, 2] ** 2,
                              vel[b, 0] ** 2 + vel[b, 1] ** 2 + vel[b, 2] ** 2))
        deepest = 0.0
        for c in range(n_col):
            if allowed[r, c] == 0:
                continue
            if kind[c] == MESH and qc_meta[slot, Q_FLAT] >= 0:
                # Flat patch: nothing beyond what the ends carry when the segment lies on its
                # outer side (either side of an open mesh) with both ends over it or beyond
                # reach (see _mesh_nearest; written out for the reason given above).
                la = _to_local(pose, c, pa[0], pa[1], pa[2])
                lb = _to_local(pose, c, pb[0], pb[1], pb[2])
                ref = qc_meta[slot, Q_FLAT]
                if (qc_meta[slot, Q_COL] == c and qc_meta[slot, Q_HINT] >= 0
                        and qc_meta[slot, Q_HINT + 1] >= 0
                        and _moved(qc_geo, slot, la, lb) * math.sqrt(3.0)
                        <= qc_geo[slot, Q_WITHIN] - radius):
                    ha = _height(Fg, ref, la)
                    hb = _height(Fg, ref, lb)
                    if _outer_side(ha, hb, par[c, P_TWO_SIDED] != 0.0) and (
                            min(abs(ha), abs(hb)) > radius
                            or (_inside(Fg, qc_tris[slot, qc_meta[slot, Q_HINT]], la)
                                and _inside(Fg, qc_tris[slot, qc_meta[slot, Q_HINT + 1]], lb))):
                        continue
            if kind[c] == MESH:
                hit, s, sd, n, q = _mesh_closest(c, mesh_rng[c, 4], pose, par, MV, MF, Blo, Bhi,
                                                 Bleft, Bright, Bstart, Bcount, Border, Fn, En,
                                                 Vn, Fg, qc_meta, qc_geo, qc_tris, qc_dist, stack,
                                                 bound, slot, pa, pb, radius)
            else:
                hit, s, sd, n, q = _shape_closest(c, kind[c], pose, par, pa, pb, radius)
            if not hit or s <= 0.0 or s >= 1.0:
                continue
            wa = 1.0 - s
            wb = s
            # What the segment's depth, less what a segment placed inside keeps (as a node
            # does), exceeds over its ends' depths, less theirs. (Across a box's edge, its end
            # past the edge touching nothing, a rope placed 3 mm inside was launched at 5-7 m/s
            # while its nodes' offsets held; an end that touches nothing counts as not inside:
            # with its -1e30 in the mean, the segment next to a node resting on a curve took
            # that node's whole depth again when its other neighbour lifted off.)
            depth = radius - sd
            deepest = max(deepest, depth)
            excess = (depth - start_offset(seg_off[e], depth, speed, h, V_OUT)
                      - wa * _kept_depth(pen[a, c], pen_off[a], vel, a, h)
                      - wb * _kept_depth(pen[b, c], pen_off[b], vel, b, h))
            if excess <= 0.0:
                continue
            p = (wa * pa[0] + wb * pb[0], wa * pa[1] + wb * pb[1], wa * pa[2] + wb * pb[2])
            u = (wa * vel[a, 0] + wb * vel[b, 0], wa * vel[a, 1] + wb * vel[b, 1],
                 wa * vel[a, 2] + wb * vel[b, 2])
            use_anchor = not anchored and (anchor_col[slot] == c or anchor_col[slot] < 0)
            # Friction holds the material point of the segment where the contact began (on a
            # curved surface the deepest point stays put while the rope slides through it).
            sa = anchor[slot, 3] if (use_anchor and anchor_col[slot] == c) else s
            ta = 1.0 - sa
            pm = (ta * pa[0] + sa * pb[0], ta * pa[1] + sa * pb[1], ta * pa[2] + sa * pb[2])
            x0 = (ta * x_ref[a, 0] + sa * x_ref[b, 0], ta * x_ref[a, 1] + sa * x_ref[b, 1],
                  ta * x_ref[a, 2] + sa * x_ref[b, 2])
            A = x0
            if use_anchor and anchor_col[slot] == c:
                A = _to_world(pose, c, anchor[slot, 0], anchor[slot, 1], anchor[slot, 2])
            kc, cc = collider_penalty(par, c, wa * mass[a] + wb * mass[b],
                                      wa * node_kmin[a] + wb * node_kmin[b], dt_ref)
            w, rq = _relative_velocity(pose, twist, c, u, q)
            on, f, kt, A = _penalty_friction(kc, cc, par[c, P_MUS], par[c, P_MUK], h, pm, w, n,
                                             excess, A, use_anchor)
            if not on:
                continue
            kn = kc + cc / h
            _add_reaction(wrench, r, c, rq, f)
            if commit and use_anchor and (par[c, P_MUS] > 0.0 or par[c, P_MUK] > 0.0):
                anchor_col[slot] = c
                anchor[slot, 0], anchor[slot, 1], anchor[slot, 2] = _to_local(pose, c, A[0],
                                                                              A[1], A[2])
                anchor[slot, 3] = sa
            anchored = anchored or use_anchor
            count += 1
            # Normal force at the deepest point, friction at the anchored material point.
            fn = f[0] * n[0] + f[1] * n[1] + f[2] * n[2]
            for d in range(3):
                ft = f[d] - fn * n[d]
                fa = wa * fn * n[d] + ta * ft
                fb = wb * fn * n[d] + sa * ft
                force[a, d] += fa
                force[b, d] += fb
                contact_force[a, d] += fa
                contact_force[b, d] += fb
            if want_K:
                _add_K(el_K, e, 0, wa * wa, kn, 0.0, n)
                _add_K(el_K, e, 1, wa * wb, kn, 0.0, n)
                _add_K(el_K, e, 2, wb * wb, kn, 0.0, n)
                if kt > 0.0:
                    _add_K(el_K, e, 0, ta * ta, 0.0, kt, n)
                    _add_K(el_K, e, 1, ta * sa, 0.0, kt, n)
                    _add_K(el_K, e, 2, sa * sa, 0.0, kt, n)
        if commit and not anchored:
            anchor_col[slot] = -1
        if commit:  # the segment's offset for the next step (kernels/verlet.py, _carry_offsets)
            kept = carry_offset(seg_off[e], deepest, speed * speed, h, V_OUT)
            note_start_inside(rd.stats, r, seg_off[e], kept, deepest, radius)
            seg_off[e] = kept
    return count
