"""Stepping a world whose rods touch each other: one step of every rod at a time.

Rod-rod contact couples the rods, so they cannot each run all their steps alone as in
``advance_rods``. Each step first refreshes the candidate pairs (a Verlet list, rebuilt only
when a node has moved more than half the skin) and then advances every rod by one step:

* explicit: the pair forces are computed once at the step's mid-point positions ``x + dt/2 v``
  (where position Verlet evaluates forces) and applied equal and opposite, so momentum is
  conserved exactly;
* stable: each rod's Newton solve treats its own segments implicitly and the other rods at their
  predicted positions ``x + dt v`` (a block Jacobi splitting between rods).
"""

from __future__ import annotations

from numba import njit

from ..contact.rodrod import build_pairs, max_displacement, pair_forces
from .implicit import advance_rod_implicit
from .refcount import NO_REFCOUNT
from .verlet import OK, advance_rod


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _step_rods(n_rods, t, dt, gravity, max_strain, rod_args, extra, status, times, first, last):
    """One explicit step of every rod with the rod-rod forces ``extra``; returns the first rod
    that diverged, or -1. A function of its own, without reference counting: unpacking the ~55
    rod arrays for each rod and step would otherwise cost two atomic operations per array."""
    for r in range(n_rods):
        times[r] = advance_rod(r, 1, t, dt, gravity, max_strain, *rod_args, extra, True,
                               not first, not last)
        if status[r, 0] != OK:
            return r
    return -1


@njit(cache=True, error_model="numpy")
def _refresh_pairs(pos, pos2, ref, skin, force_build, state, pairs, segs, seg_a, seg_b, seg_rod,
                   seg_k, seg_ne, seg_closed, excluded, seg_radius, nodes):
    """Rebuild the candidate pairs when needed; returns the (possibly grown) pair array."""
    if force_build or state[1] == 0 or max(max_displacement(pos, ref, nodes),
                                           max_displacement(pos2, ref, nodes)) > 0.5 * skin:
        pairs, n = build_pairs(segs, seg_a, seg_b, seg_rod, seg_k, seg_ne, seg_closed, excluded,
                               seg_radius, pos, pos2, skin, pairs)
        state[0] = n
        state[1] = 1
        state[2] += 1
        for i in nodes:
            for d in range(3):
                ref[i, d] = 0.5 * (pos[i, d] + pos2[i, d])
    return pairs


@njit(cache=True, error_model="numpy")
def advance_world_verlet(n_steps, t, dt, gravity, max_strain, n_rods, rod_args, pos, vel, mass,
                         node_kmin, status, times, contact):
    """Advance all rods ``n_steps`` explicit steps with rod-rod contact; returns the pairs."""
    (segs, seg_a, seg_b, seg_rod, seg_k, seg_ne, seg_closed, excluded, seg_radius, nodes,
     pairs, state, ref, skin, rr, extra, xp) = contact
    h = 0.5 * dt
    for step in range(n_steps):
        # Mid-step positions: after the first step the rods are left there (see advance_rod).
        drift = h if step == 0 else 0.0
        for i in nodes:
            for d in range(3):
                xp[i, d] = pos[i, d] + drift * vel[i, d]
        pairs = _refresh_pairs(xp, xp, ref, skin, False, state, pairs, segs, seg_a, seg_b,
                               seg_rod, seg_k, seg_ne, seg_closed, excluded, seg_radius, nodes)
        for i in nodes:
            for d in range(3):
                extra[i, d] = 0.0
        state[3] = pair_forces(pairs, state[0], seg_a, seg_b, seg_radius, xp, vel, mass,
                               node_kmin, dt, rr[0], rr[1], rr[2], extra)
        bad = _step_rods(n_rods, t, dt, gravity, max_strain, rod_args, extra, status, times,
                         step == 0, step == n_steps - 1)
        if bad >= 0:
            status[bad, 2] = step
            return pairs
        t = times[0]
    for r in range(n_rods):
        status[r, 2] = n_steps
    return pairs


@njit(cache=True, error_model="numpy")
def advance_world_implicit(n_steps, t, dt, gravity, max_strain, max_iter, tol, n_rods, rod_args,
                           pos, vel, status, times, contact):
    """Advance all rods ``n_steps`` stable steps with rod-rod contact; returns the pairs."""
    (segs, seg_a, seg_b, seg_rod, seg_k, seg_ne, seg_closed, excluded, seg_radius, nodes,
     pairs, state, ref, skin, rr, vp, xp) = contact
    for step in range(n_steps):
        for i in nodes:
            for d in range(3):
                xp[i, d] = pos[i, d] + dt * vel[i, d]
                vp[i, d] = vel[i, d]
        # The boxes span the step's start and predicted end: the Newton iterates lie between.
        pairs = _refresh_pairs(pos, xp, ref, skin, True, state, pairs, segs, seg_a, seg_b,
                               seg_rod, seg_k, seg_ne, seg_closed, excluded, seg_radius, nodes)
        for r in range(n_rods):
            times[r] = advance_rod_implicit(r, 1, t, dt, gravity, max_strain, max_iter, tol,
                                            *rod_args, pairs, state[0], seg_a, seg_b, seg_rod,
                                            seg_radius, xp, vp, rr)
            if status[r, 0] != OK:
                status[r, 2] = step
                return pairs
        t = times[0]
    for r in range(n_rods):
        status[r, 2] = n_steps
    return pairs
