"""The block-banded Cholesky solver of the stable integrator against a dense solve."""

from __future__ import annotations

import numpy as np

from deformx.engine.kernels.banded import block_cholesky, block_solve


def _random_spd_block_band(nb: int, seed: int):
    rng = np.random.default_rng(seed)
    n = 3 * nb
    A = np.zeros((n, n))
    for I in range(nb):
        for J in range(max(0, I - 2), I + 1):
            blk = rng.normal(size=(3, 3))
            if I == J:
                blk = blk + blk.T
            A[3 * I:3 * I + 3, 3 * J:3 * J + 3] = blk
            A[3 * J:3 * J + 3, 3 * I:3 * I + 3] = blk.T
    A += 30.0 * np.eye(n)  # diagonally dominant: SPD
    band = np.zeros((nb, 3, 3, 3))
    for I in range(nb):
        for d in range(3):
            if I - d >= 0:
                band[I, d] = A[3 * I:3 * I + 3, 3 * (I - d):3 * (I - d) + 3]
    return A, band


def test_block_cholesky_solves_like_dense():
    A, band = _random_spd_block_band(41, seed=1)
    b = np.random.default_rng(2).normal(size=(41, 3))
    x = b.copy()
    assert block_cholesky(band, 41) == 0
    block_solve(band, 41, x)
    assert np.allclose(x.ravel(), np.linalg.solve(A, b.ravel()), rtol=1e-12, atol=1e-14)


def test_block_cholesky_reports_an_indefinite_pivot():
    A, band = _random_spd_block_band(10, seed=3)
    band[6, 0] -= 100.0 * np.eye(3)  # block row 6 is no longer positive definite
    assert block_cholesky(band, 10) == 7
