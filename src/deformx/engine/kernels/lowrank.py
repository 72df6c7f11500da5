"""Newton systems of rods coupled by rod-rod contacts: banded factors plus a low-rank term.

Rods that touch are solved together (``advance_island_implicit``). Their Newton matrix is the
block diagonal ``D`` of the rods' own banded matrices plus rank-one terms per active contact,
``k_c g_c g_c^T``: along the normal (``g_c`` the gradient of the penetration, nonzero at the four
nodes of its two segments, which may sit far apart on one rod or on two rods) and, with
friction, along two tangents (its stiffness along and across the slip). By the Woodbury identity

    (D + G K G^T)^-1 b = y - Z (K^-1 + G^T Z)^-1 G^T y,    y = D^-1 b,   Z = D^-1 G,

the coupled system costs one banded solve per column and rod it touches (``Z``, kept while
the factors are reused; a pair's up to three columns share one pass, which starts at the
pair's first node) and a dense solve of the columns' matrix: exact, so two rods in
contact agree on where the other one ends the step however stiff the contact is. A rod whose
own matrix carries the friction coupling of its collider contacts is factored by block LU
(nonsymmetric, see ``banded.block_lu``); the identity holds as it is, the columns' matrix is
then nonsymmetric too and factored by LU rather than Cholesky.
"""

from __future__ import annotations

import math

from numba import njit

from ..contact.pairplanes import PP_KA, PP_KB, PP_KN, PP_N, PP_S, PP_SH, PP_T
from .banded import block_solve_columns
from .bundles import E_SEG_A, E_SEG_B
from .refcount import NO_REFCOUNT


@njit(cache=True, inline="always", error_model="numpy")
def _corners(p, pairs, seg_a, seg_b, pp):
    """The contact's four nodes and their weights in the relative displacement of its points."""
    i, j = pairs[p, 0], pairs[p, 1]
    s, t = pp[p, PP_S], pp[p, PP_T]
    return (seg_a[i], seg_b[i], seg_a[j], seg_b[j]), (1.0 - s, s, t - 1.0, -t)


@njit(cache=True, inline="always", error_model="numpy")
def _dot_column(nodes, w, c, cdir, node_block, node_rod, fixed, y, ka, kb):
    """Column c of G (weights ``w`` at ``nodes`` along ``cdir[c]``) dotted with ``y``, which is
    zero outside the blocks of the rods in slots ``ka``, ``kb``."""
    v = 0.0
    for k in range(4):
        blk = node_block[nodes[k]]
        kr = node_rod[nodes[k]]
        if not fixed[blk] and (kr == ka or kr == kb):
            v += w[k] * (cdir[c, 0] * y[blk, 0] + cdir[c, 1] * y[blk, 1] + cdir[c, 2] * y[blk, 2])
    return v


@njit(cache=True, inline="always", error_model="numpy")
def _any_lu(lu):
    for k in range(lu.shape[0]):
        if lu[k] != 0.0:
            return True
    return False


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def lowrank_factor(plist, m, pairs, rd, pp, node_block, node_rod, boff, A, fixed, act, cdir,
                   ck, csup, Z, S, lu):
    """The active contacts' columns (per pair its normal and, with friction, two tangents:
    pair ``act[c]``, direction ``cdir[c]``, stiffness ``ck[c]``; returns their count), ``Z =
    D^-1 G`` and the factor of ``K^-1 + G^T Z`` into ``S``: Cholesky (lower), or, where a
    rod's factor is block LU (``lu[slot] != 0``), LU (unit lower and upper in one).
    ``node_block`` maps a node to its block in the island's system, ``node_rod`` to its rod's
    slot; ``boff`` the rods' block offsets. ``Z[c]`` is only written (and read) on the blocks
    of the one or two rods of its pair (slots ``csup[c]``)."""
    seg_a, seg_b = rd.ei[E_SEG_A], rd.ei[E_SEG_B]
    nc = 0
    for q in range(m):
        p = plist[q]
        if pp[p, PP_KN] <= 0.0:
            continue
        n = (pp[p, PP_N], pp[p, PP_N + 1], pp[p, PP_N + 2])
        a = (pp[p, PP_SH], pp[p, PP_SH + 1], pp[p, PP_SH + 2])
        b = (n[1] * a[2] - n[2] * a[1], n[2] * a[0] - n[0] * a[2], n[0] * a[1] - n[1] * a[0])
        for dirn, k in ((n, pp[p, PP_KN]), (a, pp[p, PP_KA]), (b, pp[p, PP_KB])):
            if k > 0.0:
                act[nc] = p
                cdir[nc, 0], cdir[nc, 1], cdir[nc, 2] = dirn
                ck[nc] = k
                nc += 1
    c = 0
    while c < nc:  # a pair's columns (consecutive) share their nodes: solved together
        p = act[c]
        g = 1
        while g < 3 and c + g < nc and act[c + g] == p:
            g += 1
        nodes, w = _corners(p, pairs, seg_a, seg_b, pp)
        ka = node_rod[nodes[0]]
        kb = node_rod[nodes[2]]
        for j in range(c, c + g):
            csup[j, 0] = ka
            csup[j, 1] = kb
            for kr in (ka, kb):
                for b in range(boff[kr], boff[kr + 1]):
                    Z[j, b, 0] = 0.0
                    Z[j, b, 1] = 0.0
                    Z[j, b, 2] = 0.0
                if kb == ka:  # a self-contact: one rod
                    break
            for k in range(4):
                blk = node_block[nodes[k]]
                if not fixed[blk]:
                    for d in range(3):
                        Z[j, blk, d] += w[k] * cdir[j, d]
        for kr in (ka, kb):
            bo, nb = boff[kr], boff[kr + 1] - boff[kr]
            first = nb
            for k in range(4):
                if node_rod[nodes[k]] == kr:
                    first = min(first, node_block[nodes[k]] - bo)
            block_solve_columns(A[bo:bo + nb], nb, Z[c, bo:bo + nb],
                                Z[c + min(1, g - 1), bo:bo + nb], Z[c + g - 1, bo:bo + nb], g,
                                first, lu[kr] != 0.0)
            if kb == ka:
                break
        c += g
    general = _any_lu(lu)
    for c in range(nc):  # S = K^-1 + G^T Z (lower triangle; all of it when not symmetric)
        nodes, w = _corners(act[c], pairs, seg_a, seg_b, pp)
        for e in range(nc if general else c + 1):
            S[c, e] = _dot_column(nodes, w, c, cdir, node_block, node_rod, fixed, Z[e],
                                  csup[e, 0], csup[e, 1])
        S[c, c] += 1.0 / ck[c]
    if general:  # LU without pivoting: S is near the symmetric positive definite one
        for e in range(nc):
            pivot = max(S[e, e], 1e-300)
            S[e, e] = pivot
            for c in range(e + 1, nc):
                f = S[c, e] / pivot
                S[c, e] = f
                for j in range(e + 1, nc):
                    S[c, j] -= f * S[e, j]
        return nc
    for c in range(nc):
        for e in range(c + 1):
            v = S[c, e]
            for k in range(e):
                v -= S[c, k] * S[e, k]
            if c == e:
                S[c, c] = math.sqrt(max(v, 1e-300))
            else:
                S[c, e] = v / S[e, e]
    return nc


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def lowrank_apply(nc, act, cdir, csup, pairs, rd, pp, node_block, node_rod, boff, fixed, Z, S,
                  u, y, lu) -> None:
    """``y`` (= D^-1 b on entry) becomes the coupled solution ``y - Z S^-1 G^T y`` (``S`` as
    ``lowrank_factor`` left it for the same ``lu``)."""
    seg_a, seg_b = rd.ei[E_SEG_A], rd.ei[E_SEG_B]
    general = _any_lu(lu)
    for c in range(nc):  # forward: L (unit lower with LU) ...
        nodes, w = _corners(act[c], pairs, seg_a, seg_b, pp)
        v = _dot_column(nodes, w, c, cdir, node_block, node_rod, fixed, y, node_rod[nodes[0]],
                        node_rod[nodes[2]])
        for e in range(c):
            v -= S[c, e] * u[e]
        u[c] = v if general else v / S[c, c]
    for c in range(nc - 1, -1, -1):  # ... backward: U, or the Cholesky factor's transpose
        v = u[c]
        for e in range(c + 1, nc):
            v -= (S[c, e] if general else S[e, c]) * u[e]
        u[c] = v / S[c, c]
    for c in range(nc):
        uc = u[c]
        for j in range(1 if csup[c, 0] == csup[c, 1] else 2):  # a self-contact: one rod
            kr = csup[c, j]
            for b in range(boff[kr], boff[kr + 1]):
                y[b, 0] -= uc * Z[c, b, 0]
                y[b, 1] -= uc * Z[c, b, 1]
                y[b, 2] -= uc * Z[c, b, 2]
