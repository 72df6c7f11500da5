"""The coupled Newton solve of rods in contact (banded factors plus rod-rod terms by Woodbury,
``kernels/lowrank.py``) against a dense solve of the same matrix."""

from __future__ import annotations

import numpy as np
import pytest

from deformx.engine.contact.pairplanes import (PP_COLS, PP_KA, PP_KB, PP_KN, PP_N, PP_S, PP_SH,
                                               PP_T)
from deformx.engine.kernels.banded import (LU_UPPER, block_cholesky, block_lu, block_lu_solve,
                                            block_solve)
from deformx.engine.kernels.lowrank import lowrank_apply, lowrank_factor

from .test_block_cholesky import _full_band

N_ELEMENTS = 6  # per rod: 7 node blocks and 6 element blocks, interleaved


def _band(rng, nb, symmetric):
    """A random diagonally dominant block-pentadiagonal matrix: dense, and as the solver
    stores it (lower blocks, and the upper ones where not symmetric)."""
    n = 3 * nb
    A = np.zeros((n, n))
    for I in range(nb):
        for J in range(max(0, I - 2), min(nb, I + 3)):
            A[3 * I:3 * I + 3, 3 * J:3 * J + 3] = rng.normal(size=(3, 3))
    if symmetric:
        A = A + A.T
    A += 30.0 * np.eye(n)
    return A, _full_band(A, nb)


def _unit(v):
    return v / np.linalg.norm(v)


@pytest.mark.parametrize("lu_rods", [(), (2,), (0, 1, 2)])
def test_rods_coupled_by_contacts_solve_like_dense(lu_rods):
    rng = np.random.default_rng(11 + len(lu_rods))
    K, nb = 3, 2 * N_ELEMENTS + 1
    nbt = K * nb
    boff = np.arange(K + 1) * nb
    nodes_per_rod = N_ELEMENTS + 1
    node_block = np.array([boff[k] + 2 * i for k in range(K) for i in range(nodes_per_rod)])
    node_rod = np.repeat(np.arange(K), nodes_per_rod)
    # Element (segment) e of rod k joins nodes k * 7 + e and k * 7 + e + 1.
    seg_a = np.array([k * nodes_per_rod + e for k in range(K) for e in range(N_ELEMENTS)])
    seg_b = seg_a + 1
    fixed = np.zeros(nbt, dtype=np.bool_)
    fixed[0] = True  # rod 0's first node is clamped
    dense = np.zeros((3 * nbt, 3 * nbt))
    A = np.zeros((nbt, 5, 3, 3))
    lu = np.zeros(K)
    for k in range(K):
        Ak, band = _band(rng, nb, symmetric=k not in lu_rods)
        dense[3 * boff[k]:3 * boff[k + 1], 3 * boff[k]:3 * boff[k + 1]] = Ak
        A[boff[k]:boff[k + 1]] = band
        lu[k] = 1.0 if k in lu_rods else 0.0
    for q in np.flatnonzero(fixed):  # prescribed unknowns: identity row and column
        dense[3 * q:3 * q + 3, :] = 0.0
        dense[:, 3 * q:3 * q + 3] = 0.0
        dense[3 * q:3 * q + 3, 3 * q:3 * q + 3] = np.eye(3)
        A[q] = 0.0
        A[q, 0] = np.eye(3)
        for d in (1, 2):
            if q + d < nbt:
                A[q + d, d] = 0.0
                A[q + d, LU_UPPER + d - 1] = 0.0
    # Pairs of segments (element indices): across rods 0-1 (at rod 0's clamped end), 1-2,
    # 0-2 twice on the same segments, a self-contact of rod 2, one frictionless, one inactive.
    pairs = np.array([[0, 8], [9, 15], [3, 14], [3, 14], [12, 16], [4, 10], [2, 7]])
    m = len(pairs)
    pp = np.zeros((m, PP_COLS))
    for p in range(m):
        n = _unit(rng.normal(size=3))
        pp[p, PP_S], pp[p, PP_T] = rng.uniform(0.1, 0.9, 2)
        pp[p, PP_N:PP_N + 3] = n
        pp[p, PP_SH:PP_SH + 3] = _unit(np.cross(n, rng.normal(size=3)))
        pp[p, PP_KN], pp[p, PP_KA], pp[p, PP_KB] = rng.uniform(5.0, 50.0, 3)
    pp[5, PP_KA] = pp[5, PP_KB] = 0.0  # frictionless: its normal column only
    pp[6, PP_KN] = 0.0  # inactive: no columns
    for p in range(m):
        if pp[p, PP_KN] <= 0.0:  # not in contact: none of its terms
            continue
        i, j = pairs[p]
        nodes = (seg_a[i], seg_a[i] + 1, seg_a[j], seg_a[j] + 1)
        s, t = pp[p, PP_S], pp[p, PP_T]
        weights = (1.0 - s, s, t - 1.0, -t)
        n, a = pp[p, PP_N:PP_N + 3], pp[p, PP_SH:PP_SH + 3]
        for direction, k in ((n, pp[p, PP_KN]), (a, pp[p, PP_KA]), (np.cross(n, a), pp[p, PP_KB])):
            if k <= 0.0:
                continue
            g = np.zeros(3 * nbt)
            for node, w in zip(nodes, weights):
                blk = node_block[node]
                if not fixed[blk]:
                    g[3 * blk:3 * blk + 3] += w * direction
            dense += k * np.outer(g, g)
    b = rng.normal(size=(nbt, 3))
    b[fixed] = 0.0
    expected = np.linalg.solve(dense, b.ravel())

    for k in range(K):
        sl = slice(boff[k], boff[k + 1])
        assert (block_lu(A[sl], nb) if lu[k] else block_cholesky(A[sl], nb)) == 0
    nc_max = 3 * m
    act, csup = np.zeros(nc_max, dtype=np.int64), np.zeros((nc_max, 2), dtype=np.int64)
    cdir, ck, u = np.zeros((nc_max, 3)), np.zeros(nc_max), np.zeros(nc_max)
    Z, S = np.full(nc_max * nbt * 3, np.nan), np.full(nc_max * nc_max, np.nan)
    panels = (np.zeros(K + 1, dtype=np.int64), np.zeros(2 * nc_max, dtype=np.int64),
              np.zeros(K + 1, dtype=np.int64), np.zeros(nc_max))
    plist = np.arange(m)
    nc = lowrank_factor(plist, m, pairs, seg_a, seg_b, pp, node_block, node_rod, boff, A, fixed,
                        act, cdir, ck, csup, Z, S, lu, panels)
    assert nc == 3 * 5 + 1  # five pairs with friction, one frictionless, one inactive
    y = b.copy()
    for k in range(K):
        sl = slice(boff[k], boff[k + 1])
        (block_lu_solve if lu[k] else block_solve)(A[sl], nb, y[sl])
    lowrank_apply(nc, act, cdir, csup, pairs, seg_a, seg_b, pp, node_block, node_rod, boff, fixed,
                  Z, S, u, y, panels)
    assert np.allclose(y.ravel(), expected, rtol=1e-10, atol=1e-12)
