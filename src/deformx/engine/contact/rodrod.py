"""Rod-rod and self-contact between capsule segments: broad phase and penalty forces.

Broad phase: sort-and-sweep of the segments' boxes along the axis of largest spread, padded by a
skin, gives a Verlet list of candidate pairs that stays valid until some node has moved more
than half the skin; cost grows ~linearly with the number of segments. Pairs of one rod closer
along the rod than ``excluded`` segments (neighbours, and those that overlap in the straight
rest shape because the radius exceeds the element length) are left out.

Narrow phase of the explicit integrator (the stable one uses :mod:`.pairplanes`): exact
closest points of the two segment axes; penetration ``d = r_i + r_j - |p_i - p_j|`` gives
``N = k d - c v_n`` along the line of centres, and regularised Coulomb friction
``min(mu N, c |v_t|)`` against the relative sliding velocity. Both forces act equal and opposite
on the two contact points and are spread on the nodes with the segments' linear weights, so
momentum is conserved exactly.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..geometry.closest import closest_segment_segment
from ..kernels.refcount import NO_REFCOUNT
from .plane import START_DEEP, V_OUT, start_offset
from ..kernels.bundles import (
    E_EXCLUDED,
    E_PAIR_OFF,
    E_SEG_A,
    E_SEG_B,
    E_SEG_CLOSED,
    E_SEG_K,
    E_SEG_NE,
    E_SEG_RADIUS,
    E_SEG_ROD,
    E_SCR_OFF,
    N_MASS,
    N_NODE_KMIN,
    R_GROUP,
)


@njit(cache=True, error_model="numpy")
def _sift_down(key, order, root, end):
    while True:
        child = 2 * root + 1
        if child >= end:
            return
        if child + 1 < end and key[order[child + 1]] > key[order[child]]:
            child += 1
        if key[order[root]] >= key[order[child]]:
            return
        order[root], order[child] = order[child], order[root]
        root = child


@njit(cache=True, error_model="numpy")
def argsort_heap(key):
    """Indices that sort ``key`` ascending (heapsort: O(n log n), and unlike ``np.argsort`` it
    adds well under a second to numba's first compile instead of ~10 s)."""
    n = key.shape[0]
    order = np.arange(n)
    for root in range(n // 2 - 1, -1, -1):
        _sift_down(key, order, root, n)
    for end in range(n - 1, 0, -1):
        order[0], order[end] = order[end], order[0]
        _sift_down(key, order, 0, end)
    return order


@njit(cache=True, error_model="numpy")
def build_pairs(rd, pos, pos2, skin, pairs):
    """Candidate pairs among the rods' segments (the rods' arrays ``rd``) whose padded boxes
    overlap at ``pos`` or ``pos2``; rods of different contact groups never pair.

    Segment (element) e joins nodes ``seg_a[e]``, ``seg_b[e]`` of rod ``seg_rod[e]`` (local
    index ``seg_k[e]`` of ``seg_ne[e]`` elements, closed or not). Returns (pairs, count) with
    pairs of element indices; ``pairs`` is grown (doubled) when full.
    """
    segs, seg_a, seg_b, seg_rod, seg_k = rd.segs, rd.ei[E_SEG_A], rd.ei[E_SEG_B], rd.ei[E_SEG_ROD], rd.ei[E_SEG_K]
    seg_ne, seg_closed, excluded, radius, rod_group = (rd.ei[E_SEG_NE], rd.ei[E_SEG_CLOSED], rd.ei[E_EXCLUDED],
                                                       rd.e1[E_SEG_RADIUS], rd.ri[R_GROUP])
    S = segs.shape[0]
    lo = np.empty((S, 3))
    hi = np.empty((S, 3))
    for q in range(S):
        i = segs[q]
        a, b = seg_a[i], seg_b[i]
        pad = radius[i] + 0.5 * skin
        for d in range(3):
            m = min(pos[a, d], pos[b, d], pos2[a, d], pos2[b, d])
            M = max(pos[a, d], pos[b, d], pos2[a, d], pos2[b, d])
            lo[q, d] = m - pad
            hi[q, d] = M + pad
    # Sweep along the axis where the boxes spread most (plain loops: numba compiles slicing
    # reductions and slice copies slowly, and this is on every first run's path).
    axis = 0
    best = -1.0
    for d in range(3):
        low = np.inf
        high = -np.inf
        for q in range(S):
            low = min(low, lo[q, d])
            high = max(high, lo[q, d])
        if high - low > best:
            best = high - low
            axis = d
    key = np.empty(S)
    for q in range(S):
        key[q] = lo[q, axis]
    order = argsort_heap(key)
    count = 0
    for oi in range(S):
        qi = order[oi]
        i = segs[qi]
        for oj in range(oi + 1, S):
            qj = order[oj]
            j = segs[qj]
            if lo[qj, axis] > hi[qi, axis]:
                break
            if (lo[qj, 0] > hi[qi, 0] or lo[qi, 0] > hi[qj, 0] or lo[qj, 1] > hi[qi, 1]
                    or lo[qi, 1] > hi[qj, 1] or lo[qj, 2] > hi[qi, 2] or lo[qi, 2] > hi[qj, 2]):
                continue
            if rod_group[seg_rod[i]] != rod_group[seg_rod[j]]:
                continue
            if seg_rod[i] == seg_rod[j]:
                gap = abs(seg_k[i] - seg_k[j])
                if seg_closed[i]:
                    gap = min(gap, seg_ne[i] - gap)
                if gap <= excluded[i]:
                    continue
            if count == pairs.shape[0]:
                grown = np.empty((2 * pairs.shape[0] + 16, 2), dtype=np.int64)
                for c in range(count):
                    grown[c, 0] = pairs[c, 0]
                    grown[c, 1] = pairs[c, 1]
                pairs = grown
            pairs[count, 0] = min(i, j)
            pairs[count, 1] = max(i, j)
            count += 1
    return pairs, count


@njit(cache=True, error_model="numpy")
def max_displacement(pos, ref, nodes) -> float:
    """Largest distance (m) of the listed nodes from their positions at the last build."""
    worst = 0.0
    for i in nodes:
        d = ((pos[i, 0] - ref[i, 0]) ** 2 + (pos[i, 1] - ref[i, 1]) ** 2
             + (pos[i, 2] - ref[i, 2]) ** 2)
        worst = max(worst, d)
    return math.sqrt(worst)


@njit(cache=True, inline="always", error_model="numpy")
def note_start_overlap(rd, i, j, kept, depth) -> None:
    """Elements ``i`` and ``j`` found ``depth`` (m) inside each other at their first step of
    contact, of which ``kept`` cannot be an approach: beyond ``START_DEEP`` of the thinner
    radius their rods get the world's warning (``stats[r, 9]``, the deepest such)."""
    radius, seg_rod = rd.e1[E_SEG_RADIUS], rd.ei[E_SEG_ROD]
    if kept > START_DEEP * min(radius[i], radius[j]):
        for e in (i, j):
            rd.stats[seg_rod[e], 9] = max(rd.stats[seg_rod[e], 9], depth)


@njit(cache=True, error_model="numpy")
def pair_penalty(m_i, m_j, k_floor, dt_ref, stiffness, damping):
    """Penalty stiffness (N/m) and damping (N s/m) of one rod-rod contact (automatic when
    ``stiffness`` < 0: contact frequency 0.2 / dt_ref for the lighter point, at least
    ``k_floor``; critical damping of the reduced mass when ``damping`` < 0)."""
    k = stiffness
    if k < 0.0:
        k = max(min(m_i, m_j) * (0.2 / dt_ref) ** 2, k_floor)
    c = damping
    if c < 0.0:
        c = 2.0 * math.sqrt(k * m_i * m_j / (m_i + m_j))
    return k, c


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def pair_contact(i, j, seg_a, seg_b, radius, pos_i, pos_j, vel_i, vel_j, mass, node_kmin,
                 dt_ref, stiffness, damping, mu, off_e):
    """Contact of segments i (nodes at ``pos_i``) and j (``pos_j``): (touching, s, t, force
    on i (lab, N), normal (j -> i), normal stiffness k + c/h split as (k, c), the overlap
    (m) and the part of it the force leaves alone). ``off_e``: each element's offset carried
    from the last step (-1: not in contact then); a new contact deeper than one step's
    approach explains (placed inside) leaves that much alone, as the collider contacts do."""
    a, b = seg_a[i], seg_b[i]
    c_, d_ = seg_a[j], seg_b[j]
    p0 = (pos_i[a, 0], pos_i[a, 1], pos_i[a, 2])
    p1 = (pos_i[b, 0], pos_i[b, 1], pos_i[b, 2])
    q0 = (pos_j[c_, 0], pos_j[c_, 1], pos_j[c_, 2])
    q1 = (pos_j[d_, 0], pos_j[d_, 1], pos_j[d_, 2])
    reach = radius[i] + radius[j]
    zero = (0.0, 0.0, 0.0)
    for k in range(3):  # boxes apart by the reach on an axis: most Verlet-list pairs, cheaply
        if (min(p0[k], p1[k]) - max(q0[k], q1[k]) >= reach
                or min(q0[k], q1[k]) - max(p0[k], p1[k]) >= reach):
            return False, 0.0, 0.0, zero, zero, 0.0, 0.0, 0.0, 0.0
    s, t = closest_segment_segment(p0, p1, q0, q1)
    x0 = p0[0] + s * (p1[0] - p0[0]) - q0[0] - t * (q1[0] - q0[0])
    x1 = p0[1] + s * (p1[1] - p0[1]) - q0[1] - t * (q1[1] - q0[1])
    x2 = p0[2] + s * (p1[2] - p0[2]) - q0[2] - t * (q1[2] - q0[2])
    dist = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
    if dist >= reach or dist <= 1e-14 * reach:
        return False, s, t, zero, zero, 0.0, 0.0, 0.0, 0.0
    n = (x0 / dist, x1 / dist, x2 / dist)
    m_i = (1.0 - s) * mass[a] + s * mass[b]
    m_j = (1.0 - t) * mass[c_] + t * mass[d_]
    k_floor = min((1.0 - s) * node_kmin[a] + s * node_kmin[b],
                  (1.0 - t) * node_kmin[c_] + t * node_kmin[d_])
    k, c = pair_penalty(m_i, m_j, k_floor, dt_ref, stiffness, damping)
    u0 = (1.0 - s) * vel_i[a, 0] + s * vel_i[b, 0] - (1.0 - t) * vel_j[c_, 0] - t * vel_j[d_, 0]
    u1 = (1.0 - s) * vel_i[a, 1] + s * vel_i[b, 1] - (1.0 - t) * vel_j[c_, 1] - t * vel_j[d_, 1]
    u2 = (1.0 - s) * vel_i[a, 2] + s * vel_i[b, 2] - (1.0 - t) * vel_j[c_, 2] - t * vel_j[d_, 2]
    un = u0 * n[0] + u1 * n[1] + u2 * n[2]
    depth = reach - dist
    carried = min(off_e[i], off_e[j])
    off = min(carried, depth) if carried >= 0.0 else start_offset(
        -1.0, depth, math.sqrt(u0 * u0 + u1 * u1 + u2 * u2), dt_ref, V_OUT)
    fn = k * (depth - off) - c * un
    if fn <= 0.0:
        return False, s, t, zero, n, k, c, depth, off
    f0 = fn * n[0]
    f1 = fn * n[1]
    f2 = fn * n[2]
    if mu > 0.0:
        t0 = u0 - un * n[0]
        t1 = u1 - un * n[1]
        t2 = u2 - un * n[2]
        tmag = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
        if tmag > 0.0:
            ft = min(mu * fn, c * tmag) / tmag
            f0 -= ft * t0
            f1 -= ft * t1
            f2 -= ft * t2
    return True, s, t, (f0, f1, f2), n, k, c, depth, off


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def pair_forces(pairs, n_pairs, rd, pos, vel, dt_ref, rr, out) -> int:
    """Equal and opposite forces of all touching pairs, added to ``out`` (N, per node);
    returns the number of touching pairs. ``rr``: stiffness, damping, friction. Each
    element's start offset (``pair_off``) is carried to the next step, less ``V_OUT dt``: ropes
    placed inside each other come apart at ``V_OUT`` instead of being launched (5.8 and 10 m/s
    at half and a whole radius before)."""
    seg_a, seg_b, radius, mass, node_kmin = rd.ei[E_SEG_A], rd.ei[E_SEG_B], rd.e1[E_SEG_RADIUS], rd.n1[N_MASS], rd.n1[N_NODE_KMIN]
    off_e, new_off = rd.e1[E_PAIR_OFF], rd.e1[E_SCR_OFF]
    stiffness, damping, mu = rr[0], rr[1], rr[2]
    for e in range(new_off.shape[0]):
        new_off[e] = -1.0
    touching = 0
    for p in range(n_pairs):
        i, j = pairs[p, 0], pairs[p, 1]
        hit, s, t, f, _, _, _, depth, off = pair_contact(i, j, seg_a, seg_b, radius, pos, pos,
                                                         vel, vel, mass, node_kmin, dt_ref,
                                                         stiffness, damping, mu, off_e)
        if depth > 0.0:
            if min(off_e[i], off_e[j]) < 0.0:  # a new contact: placed inside?
                note_start_overlap(rd, i, j, off, depth)
            kept = max(off - V_OUT * dt_ref, 0.0)
            new_off[i] = max(new_off[i], kept)
            new_off[j] = max(new_off[j], kept)
        if not hit:
            continue
        touching += 1
        a, b, c_, d_ = seg_a[i], seg_b[i], seg_a[j], seg_b[j]
        for d in range(3):
            out[a, d] += (1.0 - s) * f[d]
            out[b, d] += s * f[d]
            out[c_, d] -= (1.0 - t) * f[d]
            out[d_, d] -= t * f[d]
    for e in range(new_off.shape[0]):
        off_e[e] = new_off[e]
    return touching
