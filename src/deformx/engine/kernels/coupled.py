"""Stepping a world whose rods touch each other: one step of every rod at a time.

Rod-rod contact couples the rods, so they cannot each run all their steps alone as in
``advance_rods``. Each step first refreshes the candidate pairs (a Verlet list, rebuilt only
when a node has moved more than half the skin) and then advances every rod by one step:

* explicit: the pair forces are computed once at the step's mid-point positions ``x + dt/2 v``
  (where position Verlet evaluates forces) and applied equal and opposite, so momentum is
  conserved exactly;
* stable: pairs get separating planes at the step start, and rods linked by pairs that can
  touch within the step are solved together as one Newton system (an island), so each sees
  the others' end-of-step positions.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..contact.pairplanes import PP_COLS, PS_COLS, PS_NEAR, pair_plane
from ..contact.rodrod import build_pairs, max_displacement, pair_forces
from .bundles import (
    E_SEG_ROD, N_EXTRA, N_POS, N_REF, N_VEL, N_XP, R_FACT_H, R_NE, R_TIMES, SIM_DT, SIM_G,
    SIM_RR, SIM_SKIN,
)
from .implicit import advance_island_implicit
from .refcount import NO_REFCOUNT
from .verlet import OK, advance_rod


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def _step_rods(t, sim, rd, env, cols, first, last):
    """One explicit step of every rod with the rod-rod forces ``rd.n3[N_EXTRA]``; returns the first
    rod that diverged, or -1. A function of its own, without reference counting (see
    :mod:`.refcount`)."""
    for r in range(rd.ri[R_NE].shape[0]):
        rd.r1[R_TIMES][r] = advance_rod(r, 1, t, sim, rd, env, cols, env.dloc[r], True,
                                  not first, not last)
        if rd.status[r, 0] != OK:
            return r
    return -1


@njit(cache=True, error_model="numpy")
def _refresh_pairs(pos, pos2, skin, force_build, rd, pairs):
    """Rebuild the candidate pairs when needed; returns the (possibly grown) pair array."""
    state, ref, nodes = rd.pair_state, rd.n3[N_REF], rd.nodes
    if force_build or state[1] == 0 or max(max_displacement(pos, ref, nodes),
                                           max_displacement(pos2, ref, nodes)) > 0.5 * skin:
        pairs, n = build_pairs(rd, pos, pos2, skin, pairs)
        state[0] = n
        state[1] = 1
        state[2] += 1
        for i in nodes:
            for d in range(3):
                ref[i, d] = 0.5 * (pos[i, d] + pos2[i, d])
    return pairs


@njit(cache=True, error_model="numpy")
def advance_world_verlet(n_steps, t, sim, rd, env, cols, pairs):
    """Advance all rods ``n_steps`` explicit steps with rod-rod contact; returns the pairs."""
    dt = sim[SIM_DT]
    h = 0.5 * dt
    pos, vel, xp, extra, nodes = rd.n3[N_POS], rd.n3[N_VEL], rd.n3[N_XP], rd.n3[N_EXTRA], rd.nodes
    for step in range(n_steps):
        # Mid-step positions: after the first step the rods are left there (see advance_rod).
        drift = h if step == 0 else 0.0
        for i in nodes:
            for d in range(3):
                xp[i, d] = pos[i, d] + drift * vel[i, d]
        pairs = _refresh_pairs(xp, xp, sim[SIM_SKIN], False, rd, pairs)
        for i in nodes:
            for d in range(3):
                extra[i, d] = 0.0
        rd.pair_state[3] = pair_forces(pairs, rd.pair_state[0], rd, xp, vel, dt,
                                       sim[SIM_RR:SIM_RR + 3], extra)
        bad = _step_rods(t, sim, rd, env, cols, step == 0, step == n_steps - 1)
        if bad >= 0:
            rd.status[bad, 2] = step
            return pairs
        t = rd.r1[R_TIMES][0]
    for r in range(rd.ri[R_NE].shape[0]):
        rd.status[r, 2] = n_steps
    return pairs


@njit(cache=True, error_model="numpy")
def _find(parent, r):
    while parent[r] != r:
        parent[r] = parent[parent[r]]
        r = parent[r]
    return r


@njit(cache=True, error_model="numpy")
def advance_world_implicit(n_steps, t, sim, opts, rd, env, cols, pairs):
    """Advance all rods ``n_steps`` stable steps with rod-rod contact; returns the pairs.

    Each step: candidate pairs over the swept boxes, their separating planes at the step start
    (:mod:`..contact.pairplanes`), islands of rods linked by pairs near enough to touch within
    the step, and each island solved as one system (``advance_island_implicit``)."""
    dt = sim[SIM_DT]
    g = sim[SIM_G:SIM_G + 3]
    pos, vel, xp, nodes = rd.n3[N_POS], rd.n3[N_VEL], rd.n3[N_XP], rd.nodes
    seg_rod = rd.ei[E_SEG_ROD]
    n_rods = rd.ri[R_NE].shape[0]
    parent = np.empty(n_rods, dtype=np.int64)
    size = np.empty(n_rods, dtype=np.int64)
    npairs = np.empty(n_rods, dtype=np.int64)
    for step in range(n_steps):
        for i in nodes:
            for d in range(3):
                xp[i, d] = pos[i, d] + dt * (vel[i, d] + dt * g[d])
        # The boxes span the step's start and predicted end: the Newton iterates lie between.
        pairs = _refresh_pairs(pos, xp, sim[SIM_SKIN], True, rd, pairs)
        n_pairs = rd.pair_state[0]
        pp = np.empty((n_pairs, PP_COLS))
        ps = np.empty((n_pairs, PS_COLS), dtype=np.int64)
        for r in range(n_rods):
            parent[r] = r
            size[r] = 0
            npairs[r] = 0
        touching = 0
        for p in range(n_pairs):
            pair_plane(p, pairs, rd, pos, xp, dt, sim[SIM_RR:SIM_RR + 3], pp, ps)
            if ps[p, PS_NEAR]:
                touching += 1
                a = _find(parent, seg_rod[pairs[p, 0]])
                b = _find(parent, seg_rod[pairs[p, 1]])
                if a != b:
                    parent[max(a, b)] = min(a, b)
        rd.pair_state[3] = touching
        for r in range(n_rods):
            size[_find(parent, r)] += 1
        for p in range(n_pairs):
            if ps[p, PS_NEAR]:
                npairs[_find(parent, seg_rod[pairs[p, 0]])] += 1
        for root in range(n_rods):
            if parent[root] != root:
                continue
            isl = np.empty(size[root], dtype=np.int64)
            k = 0
            for r in range(n_rods):
                if _find(parent, r) == root:
                    isl[k] = r
                    k += 1
            plist = np.empty(npairs[root], dtype=np.int64)
            k = 0
            for p in range(n_pairs):
                if ps[p, PS_NEAR] and _find(parent, seg_rod[pairs[p, 0]]) == root:
                    plist[k] = p
                    k += 1
            # np.int64(1), not the literal 1: a literal argument would compile a second copy of
            # the island solver (Literal[int](1)) beside advance_rods_implicit's int64 one
            t_isl = advance_island_implicit(isl, np.int64(1), t, sim, opts, rd, env, cols,
                                            (pairs, plist, pp, ps))
            if isl.shape[0] > 1:  # it solved in the first rows: their rods' factors are gone
                rd.r1[R_FACT_H][:] = 0.0
            for r in isl:
                rd.r1[R_TIMES][r] = t_isl
                if rd.status[r, 0] != OK:
                    rd.status[r, 2] = step
                    return pairs
        t = rd.r1[R_TIMES][0]
    for r in range(n_rods):
        rd.status[r, 2] = n_steps
    return pairs
