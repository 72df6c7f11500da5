"""Newton systems of rods coupled by rod-rod contacts: banded factors plus a low-rank term.

Rods that touch are solved together (``advance_island_implicit``). Their Newton matrix is the
block diagonal ``D`` of the rods' own banded matrices plus rank-one terms per active contact,
``k_c g_c g_c^T``: along the normal (``g_c`` the gradient of the penetration, nonzero at the four
nodes of its two segments, which may sit far apart on one rod or on two rods) and, with
friction, along two tangents (its stiffness along and across the slip). By the Woodbury identity

    (D + G K G^T)^-1 b = y - Z (K^-1 + G^T Z)^-1 G^T y,    y = D^-1 b,   Z = D^-1 G,

the coupled system costs one banded solve per column and rod it touches (``Z``, kept while
the factors are reused) and a dense solve of the columns' matrix: exact, so two rods in
contact agree on where the other one ends the step however stiff the contact is. Each rod's
columns are solved together as one panel (``banded.block_solve_panel``, from the first block
any of them reaches), and the columns' matrix is eliminated in place without pivoting,
skipping the rows of columns on rods of their own (a pile: about half its entries are zero).
A rod whose own matrix carries the friction coupling of its collider contacts is factored by
block LU (nonsymmetric, see ``banded.block_lu``); the identity holds as it is, and the
columns' matrix is then nonsymmetric too: eliminated whole rather than its upper half.
"""

from __future__ import annotations

from numba import njit

from ..contact.pairplanes import PP_KA, PP_KB, PP_KN, PP_N, PP_S, PP_SH, PP_T
from .banded import block_solve_panel
from .bundles import borrow
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
def lowrank_factor(plist, m, pairs, seg_a, seg_b, pp, node_block, node_rod, boff, A, fixed,
                   act, cdir, ck, csup, Z, S, lu, panels):
    """The active contacts' columns (per pair its normal and, with friction, two tangents:
    pair ``act[c]``, direction ``cdir[c]``, stiffness ``ck[c]``; returns their count), ``Z =
    D^-1 G`` and the LU factor (no pivoting; unit lower and upper in one) of ``K^-1 + G^T Z``
    into ``S``, eliminating only its upper half where no rod's factor is block LU (``lu[slot]
    != 0``) and the matrix is symmetric.
    ``node_block`` maps a node to its block in the island's system, ``node_rod`` to its rod's
    slot; ``boff`` the rods' block offsets. ``Z`` (flat) holds per rod slot ``k`` a panel
    (its blocks, 3, its columns) from ``zoff[k]``: the columns of the pairs that touch it,
    listed in ``cols[coff[k]:coff[k + 1]]`` (``panels`` = coff, cols, zoff, row)."""
    coff, cols, zoff, row = panels
    K = boff.shape[0] - 1
    nc = 0
    for q in range(m):
        p = plist[q]
        if pp[p, PP_KN] <= 0.0:
            continue
        n = (pp[p, PP_N], pp[p, PP_N + 1], pp[p, PP_N + 2])
        a = (pp[p, PP_SH], pp[p, PP_SH + 1], pp[p, PP_SH + 2])
        b = (n[1] * a[2] - n[2] * a[1], n[2] * a[0] - n[0] * a[2], n[0] * a[1] - n[1] * a[0])
        ka, kb = node_rod[seg_a[pairs[p, 0]]], node_rod[seg_a[pairs[p, 1]]]
        for dirn, k in ((n, pp[p, PP_KN]), (a, pp[p, PP_KA]), (b, pp[p, PP_KB])):
            if k > 0.0:
                act[nc] = p
                cdir[nc, 0], cdir[nc, 1], cdir[nc, 2] = dirn
                ck[nc] = k
                csup[nc, 0] = ka
                csup[nc, 1] = kb
                nc += 1
    S = borrow(S, 0, (nc, nc))  # compact: the flat buffer holds up to (3 m)^2
    # Each rod's columns, in column order (a self-contact's once).
    for k in range(K + 1):
        coff[k] = 0
    zoff[0] = 0
    for c in range(nc):
        coff[csup[c, 0] + 1] += 1
        if csup[c, 1] != csup[c, 0]:
            coff[csup[c, 1] + 1] += 1
    for k in range(K):
        coff[k + 1] += coff[k]
        zoff[k + 1] = zoff[k] + 3 * (boff[k + 1] - boff[k]) * (coff[k + 1] - coff[k])
    for c in range(nc):  # (coff[k] as rod k's cursor, then shifted back)
        for j in range(1 if csup[c, 0] == csup[c, 1] else 2):
            cols[coff[csup[c, j]]] = c
            coff[csup[c, j]] += 1
    for k in range(K, 0, -1):
        coff[k] = coff[k - 1]
    coff[0] = 0
    # Z = D^-1 G, rod by rod: its columns' nonzeros at the nodes of their segments, one
    # panel solve from the first of them; then S = K^-1 + G^T Z, each column's nodes on the
    # rod against the rod's panel.
    for c in range(nc):
        for e in range(nc):
            S[c, e] = 0.0
    for k in range(K):
        pk = coff[k + 1] - coff[k]
        if pk == 0:
            continue
        bo, nb = boff[k], boff[k + 1] - boff[k]
        P = borrow(Z, zoff[k], (nb, 3, pk))
        P[:] = 0.0
        first = nb
        for j in range(pk):
            c = cols[coff[k] + j]
            nodes, w = _corners(act[c], pairs, seg_a, seg_b, pp)
            for q in range(4):
                blk = node_block[nodes[q]]
                if node_rod[nodes[q]] == k and not fixed[blk]:
                    first = min(first, blk - bo)
                    for d in range(3):
                        P[blk - bo, d, j] += w[q] * cdir[c, d]
        block_solve_panel(A[bo:bo + nb], nb, P, pk, first, lu[k] != 0.0)
        for i in range(pk):
            c = cols[coff[k] + i]
            nodes, w = _corners(act[c], pairs, seg_a, seg_b, pp)
            for j in range(pk):
                row[j] = 0.0
            for q in range(4):
                blk = node_block[nodes[q]]
                if node_rod[nodes[q]] == k and not fixed[blk]:
                    g0, g1, g2 = w[q] * cdir[c, 0], w[q] * cdir[c, 1], w[q] * cdir[c, 2]
                    b = blk - bo
                    for j in range(pk):
                        row[j] += g0 * P[b, 0, j] + g1 * P[b, 1, j] + g2 * P[b, 2, j]
            for j in range(pk):
                S[c, cols[coff[k] + j]] += row[j]
    for c in range(nc):
        S[c, c] += 1.0 / ck[c]
    # LU without pivoting (S is near, or is, symmetric positive definite): unit lower L below
    # the diagonal, U on and above it. Symmetric: only U's rows are eliminated (L[c, e] =
    # U[e, c] / U[e, e]). Rows whose entry is zero (columns on rods of their own) are skipped.
    general = _any_lu(lu)
    for e in range(nc):
        pivot = max(S[e, e], 1e-300)
        S[e, e] = pivot
        for c in range(e + 1, nc):
            f = (S[c, e] if general else S[e, c]) / pivot
            S[c, e] = f
            if f != 0.0:
                for j in range(e + 1 if general else c, nc):
                    S[c, j] -= f * S[e, j]
    return nc


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def lowrank_apply(nc, act, cdir, csup, pairs, seg_a, seg_b, pp, node_block, node_rod, boff,
                  fixed, Z, S, u, y, panels) -> None:
    """``y`` (= D^-1 b on entry) becomes the coupled solution ``y - Z S^-1 G^T y`` (``S``,
    ``Z`` and ``panels`` as ``lowrank_factor`` left them)."""
    coff, cols, zoff, row = panels
    S = borrow(S, 0, (nc, nc))
    for c in range(nc):  # forward: L (unit lower) ...
        nodes, w = _corners(act[c], pairs, seg_a, seg_b, pp)
        v = _dot_column(nodes, w, c, cdir, node_block, node_rod, fixed, y, csup[c, 0],
                        csup[c, 1])
        for e in range(c):
            v -= S[c, e] * u[e]
        u[c] = v
    for c in range(nc - 1, -1, -1):  # ... backward: U
        v = u[c]
        for e in range(c + 1, nc):
            v -= S[c, e] * u[e]
        u[c] = v / S[c, c]
    for k in range(boff.shape[0] - 1):
        pk = coff[k + 1] - coff[k]
        if pk == 0:
            continue
        bo, nb = boff[k], boff[k + 1] - boff[k]
        P = borrow(Z, zoff[k], (nb, 3, pk))
        for j in range(pk):
            row[j] = u[cols[coff[k] + j]]
        for b in range(nb):
            for d in range(3):
                v = 0.0
                for j in range(pk):
                    v += P[b, d, j] * row[j]
                y[bo + b, d] -= v
