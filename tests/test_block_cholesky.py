"""The block-banded Cholesky solver of the stable integrator against a dense solve."""

from __future__ import annotations

import numpy as np

from deformx.engine.kernels.banded import (LU_UPPER, block_cholesky, block_lu, block_lu_solve,
                                            block_solve, block_solve_panel, expand_upper)


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


def test_block_solve_panel_solves_sparse_right_hand_sides_like_dense():
    nb, first = 41, 17
    A, band = _random_spd_block_band(nb, seed=5)
    assert block_cholesky(band, nb) == 0
    rng = np.random.default_rng(6)
    for p in (1, 3, 14):
        b = np.zeros((nb, 3, p + 2))
        b[first:first + 3, :, :p] = rng.normal(size=(3, 3, p))  # zero before block `first`
        x = b.copy()
        block_solve_panel(band, nb, x, p, first)
        dense = np.linalg.solve(A, b[:, :, :p].reshape(3 * nb, p))
        assert np.allclose(x[:, :, :p].reshape(3 * nb, p), dense, rtol=1e-12, atol=1e-14)
        assert np.array_equal(x[:, :, p:], b[:, :, p:])  # the columns past p are left alone


def test_block_cholesky_reports_an_indefinite_pivot():
    A, band = _random_spd_block_band(10, seed=3)
    band[6, 0] -= 100.0 * np.eye(3)  # block row 6 is no longer positive definite
    assert block_cholesky(band, 10) == 7


def _full_band(A: np.ndarray, nb: int) -> np.ndarray:
    """A dense block-pentadiagonal matrix as ``block_lu`` takes it (lower, diagonal, upper)."""
    band = np.zeros((nb, 5, 3, 3))
    for I in range(nb):
        band[I, 0] = A[3 * I:3 * I + 3, 3 * I:3 * I + 3]
        for d in (1, 2):
            if I - d >= 0:
                band[I, d] = A[3 * I:3 * I + 3, 3 * (I - d):3 * (I - d) + 3]
                band[I, LU_UPPER + d - 1] = A[3 * (I - d):3 * (I - d) + 3, 3 * I:3 * I + 3]
    return band


def test_block_lu_solves_a_nonsymmetric_band_like_dense():
    nb = 41
    A, sym = _random_spd_block_band(nb, seed=4)
    rng = np.random.default_rng(5)
    for I in range(nb):  # a nonsymmetric coupling within the band, as friction adds
        for J in range(max(0, I - 2), min(nb, I + 3)):
            A[3 * I:3 * I + 3, 3 * J:3 * J + 3] += 3.0 * rng.normal(size=(3, 3))
    assert not np.allclose(A, A.T)
    band = _full_band(A, nb)
    b = rng.normal(size=(nb, 3))
    x = b.copy()
    assert block_lu(band, nb) == 0
    block_lu_solve(band, nb, x)
    assert np.allclose(x.ravel(), np.linalg.solve(A, b.ravel()), rtol=1e-11, atol=1e-13)


def test_block_solve_panel_with_an_lu_factor_solves_sparse_right_hand_sides_like_dense():
    # (rod-rod contacts' low-rank columns on a rod whose matrix carries friction coupling)
    nb, first = 41, 17
    A, _ = _random_spd_block_band(nb, seed=7)
    rng = np.random.default_rng(8)
    for I in range(nb):
        for J in range(max(0, I - 2), min(nb, I + 3)):
            A[3 * I:3 * I + 3, 3 * J:3 * J + 3] += 3.0 * rng.normal(size=(3, 3))
    band = _full_band(A, nb)
    assert block_lu(band, nb) == 0
    for p in (1, 3, 14):
        b = np.zeros((nb, 3, p))
        b[first:first + 3] = rng.normal(size=(3, 3, p))
        x = b.copy()
        block_solve_panel(band, nb, x, p, first, True)
        dense = np.linalg.solve(A, b.reshape(3 * nb, p))
        assert np.allclose(x.reshape(3 * nb, p), dense, rtol=1e-11, atol=1e-13)


def test_block_lu_of_a_symmetric_band_matches_cholesky_and_flags_indefinite_pivots():
    nb = 12
    A, sym = _random_spd_block_band(nb, seed=6)
    full = sym.copy()
    full = np.concatenate([full, np.zeros((nb, 2, 3, 3))], axis=1)
    expand_upper(full, nb)  # the lower band made full, as the integrator does
    assert np.allclose(full, _full_band(A, nb))
    b = np.random.default_rng(7).normal(size=(nb, 3))
    x, y = b.copy(), b.copy()
    assert block_lu(full, nb) == 0 and block_cholesky(sym, nb) == 0
    block_lu_solve(full, nb, x)
    block_solve(sym, nb, y)
    assert np.allclose(x, y, rtol=1e-12, atol=1e-14)
    bad = _full_band(A, nb)
    bad[6, 0] -= 100.0 * np.eye(3)
    assert block_lu(bad, nb) == 7
