"""Infinite plane: penalty normal force with dissipation and Coulomb friction.

Normal: ``N = max(0, k d - c v_n)`` for the penetration ``d = r - (x - p).n`` of a node sphere
of the rod radius. Friction is a velocity-level stick force, the tangential force that brings
the node's sliding velocity to zero in one step, accepted while it is at most ``mu_s N``; beyond
that the node slides with kinetic friction ``mu_k N`` against its sliding velocity. A static load
below the friction limit therefore holds exactly (no creep), and sliding follows Coulomb's law.
The contact stiffness for implicit integrators is ``k n n^T`` (``k`` is returned).
"""

from __future__ import annotations

import math

from numba import njit

# Plane table columns: point (3), unit normal (3), stiffness, damping, mu_s, mu_k, automatic.
PL_P, PL_N, PL_K, PL_C, PL_MUS, PL_MUK, PL_AUTO = 0, 3, 6, 7, 8, 9, 10
V_OUT = 0.1  # m/s: the fastest a point starting inside a collider is pushed out
# Sliding speed (m/s) below which the kinetic direction follows the applied load, not velocity.
_SLIP_EPS = 1e-12


@njit(cache=True, inline="always", error_model="numpy")
def start_offset(carried, depth, speed, dt, v_out):
    """Depth (m) a node's contact force leaves alone (explicit integrator): the offset carried
    from the last step, or for a node not in contact then, what of ``depth`` one step's
    approach at ``speed`` cannot explain (it was placed inside), less ``v_out dt``."""
    if carried >= 0.0:
        return carried
    return max(depth - 2.0 * speed * dt - v_out * dt, 0.0)


# A point (or a pair of rods) found inside deeper than this fraction of its radius when its
# contact begins was placed so: the world warns (``stats[r, 5]``; rod pairs ``stats[r, 9]``).
START_DEEP = 0.2


@njit(cache=True, inline="always", error_model="numpy")
def note_start_inside(stats, r, carried, kept, depth, radius) -> None:
    """Rod ``r``'s node or segment ``depth`` (m) inside a collider or plane, with the offset it
    ``carried`` into this step and the one it ``kept`` (:func:`carry_offset`): a new offset
    deeper than ``START_DEEP`` of its ``radius`` is noted for the world's warning."""
    if carried < 0.0 and kept > 0.0 and depth > START_DEEP * radius:
        stats[r, 5] = max(stats[r, 5], depth)


@njit(cache=True, inline="always", error_model="numpy")
def carry_offset(carried, depth, speed2, dt, v_out):
    """The offset (m) a node or segment at ``depth`` (<= 0: out of contact, then -1) keeps
    next step: from the one it ``carried`` (-1: none; then what :func:`start_offset` finds at
    the squared speed ``speed2``), never more than ``depth``, less ``v_out dt``."""
    if depth <= 0.0:
        return -1.0
    if carried < 0.0:
        return start_offset(-1.0, depth, math.sqrt(speed2), dt, v_out)
    return max(min(carried, depth) - v_out * dt, 0.0)


@njit(cache=True, inline="always", error_model="numpy")
def plane_penalty(planes, p, mass, k_floor, dt_ref):
    """Penalty stiffness (N/m) and damping (N s/m) of plane ``p`` for a node of ``mass``.

    The automatic stiffness gives a contact frequency of 0.2 / ``dt_ref`` but at least
    ``k_floor``; the automatic damping is critical for that stiffness.
    """
    k = planes[p, PL_K]
    if planes[p, PL_AUTO] > 0.0:
        k = max(mass * (0.2 / dt_ref) ** 2, k_floor)
    c = planes[p, PL_C]
    if c < 0.0:
        c = 2.0 * math.sqrt(k * mass)
    return k, c


@njit(cache=True, inline="always", error_model="numpy")
def plane_contact_node(x0, x1, x2, v0, v1, v2, fo0, fo1, fo2, mass, radius, dt,
                       p0, p1, p2, n0, n1, n2, stiffness, damping, mu_s, mu_k, off):
    """Contact force (N, lab) on one node and the normal stiffness (N/m; 0 if apart).

    ``fo`` is the node's total non-contact force, used to predict sticking; ``off`` (m) the
    depth the force leaves alone (a node placed inside, see ``carry_offsets``).
    """
    gap = (x0 - p0) * n0 + (x1 - p1) * n1 + (x2 - p2) * n2 - radius + off
    if gap >= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    vn = v0 * n0 + v1 * n1 + v2 * n2
    fn = -stiffness * gap - damping * vn
    if fn <= 0.0:
        return 0.0, 0.0, 0.0, stiffness
    f0 = fn * n0
    f1 = fn * n1
    f2 = fn * n2
    if mu_s <= 0.0 and mu_k <= 0.0:
        return f0, f1, f2, stiffness
    fon = fo0 * n0 + fo1 * n1 + fo2 * n2
    vt0 = v0 - vn * n0
    vt1 = v1 - vn * n1
    vt2 = v2 - vn * n2
    # Tangential force that cancels the sliding velocity within this step.
    s0 = -(mass * vt0 / dt + fo0 - fon * n0)
    s1 = -(mass * vt1 / dt + fo1 - fon * n1)
    s2 = -(mass * vt2 / dt + fo2 - fon * n2)
    smag = math.sqrt(s0 * s0 + s1 * s1 + s2 * s2)
    if smag <= mu_s * fn:
        return f0 + s0, f1 + s1, f2 + s2, stiffness
    vmag = math.sqrt(vt0 * vt0 + vt1 * vt1 + vt2 * vt2)
    if vmag > _SLIP_EPS:
        scale = -mu_k * fn / vmag
        return f0 + scale * vt0, f1 + scale * vt1, f2 + scale * vt2, stiffness
    scale = mu_k * fn / smag
    return f0 + scale * s0, f1 + scale * s1, f2 + scale * s2, stiffness
