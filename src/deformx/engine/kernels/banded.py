"""Block-banded symmetric positive definite systems with 3x3 blocks (block Cholesky).

One rod's Newton matrix in the order x0, phi0, x1, phi1, ... couples blocks at most two apart.
``A[I, d]`` holds the 3x3 block (I, I - d) for d = 0, 1, 2 (diagonal blocks in full). The
factorisation runs in O(n) with fixed-size 3x3 kernels; afterwards ``A[I, 0]`` holds the inverse
of the diagonal Cholesky block, so both triangular sweeps only multiply.
"""

from __future__ import annotations

import math

from numba import njit

BLOCK_BAND = 2  # coupled blocks are at most this many apart


@njit(cache=True, inline="always", error_model="numpy")
def _chol3_inverse(A, I) -> bool:
    """Replace the SPD block A[I, 0] by the inverse of its lower Cholesky factor."""
    a00 = A[I, 0, 0, 0]
    if not (a00 > 0.0):
        return False
    l00 = math.sqrt(a00)
    l10 = A[I, 0, 1, 0] / l00
    l20 = A[I, 0, 2, 0] / l00
    a11 = A[I, 0, 1, 1] - l10 * l10
    if not (a11 > 0.0):
        return False
    l11 = math.sqrt(a11)
    l21 = (A[I, 0, 2, 1] - l20 * l10) / l11
    a22 = A[I, 0, 2, 2] - l20 * l20 - l21 * l21
    if not (a22 > 0.0):
        return False
    l22 = math.sqrt(a22)
    i00 = 1.0 / l00
    i11 = 1.0 / l11
    i22 = 1.0 / l22
    i10 = -l10 * i00 * i11
    i21 = -l21 * i11 * i22
    i20 = -(l20 * i00 + l21 * i10) * i22
    A[I, 0, 0, 0] = i00
    A[I, 0, 0, 1] = 0.0
    A[I, 0, 0, 2] = 0.0
    A[I, 0, 1, 0] = i10
    A[I, 0, 1, 1] = i11
    A[I, 0, 1, 2] = 0.0
    A[I, 0, 2, 0] = i20
    A[I, 0, 2, 1] = i21
    A[I, 0, 2, 2] = i22
    return True


@njit(cache=True, inline="always", error_model="numpy")
def _sub_abt(A, I, d, P, p, Q, q):
    """A[I, d] -= A[P, p] @ A[Q, q]^T (3x3 blocks)."""
    for a in range(3):
        x0 = A[P, p, a, 0]
        x1 = A[P, p, a, 1]
        x2 = A[P, p, a, 2]
        for b in range(3):
            A[I, d, a, b] -= x0 * A[Q, q, b, 0] + x1 * A[Q, q, b, 1] + x2 * A[Q, q, b, 2]


@njit(cache=True, inline="always", error_model="numpy")
def _times_inv_t(A, I, d, J):
    """A[I, d] <- A[I, d] @ A[J, 0]^T, where A[J, 0] holds an inverse lower Cholesky block."""
    for a in range(3):
        s0 = A[I, d, a, 0]
        s1 = A[I, d, a, 1]
        s2 = A[I, d, a, 2]
        A[I, d, a, 0] = s0 * A[J, 0, 0, 0]
        A[I, d, a, 1] = s0 * A[J, 0, 1, 0] + s1 * A[J, 0, 1, 1]
        A[I, d, a, 2] = s0 * A[J, 0, 2, 0] + s1 * A[J, 0, 2, 1] + s2 * A[J, 0, 2, 2]


@njit(cache=True, error_model="numpy")
def block_cholesky(A, nb) -> int:
    """In-place block Cholesky of the first ``nb`` block rows; 0, or 1 + the first block row
    whose pivot block is not positive definite."""
    for I in range(nb):
        if I >= 2:  # L[I, I-2] = A[I, I-2] L[I-2, I-2]^-T
            _times_inv_t(A, I, 2, I - 2)
        if I >= 1:  # L[I, I-1] = (A[I, I-1] - L[I, I-2] L[I-1, I-2]^T) L[I-1, I-1]^-T
            if I >= 2:
                _sub_abt(A, I, 1, I, 2, I - 1, 1)
            _times_inv_t(A, I, 1, I - 1)
            _sub_abt(A, I, 0, I, 1, I, 1)
        if I >= 2:
            _sub_abt(A, I, 0, I, 2, I, 2)
        if not _chol3_inverse(A, I):
            return I + 1
    return 0


@njit(cache=True, error_model="numpy")
def block_solve(A, nb, x) -> None:
    """Solve ``L L^T x = b`` in place (``x`` holds b, shape (nb, 3)) with the block factor."""
    for I in range(nb):
        r0 = x[I, 0]
        r1 = x[I, 1]
        r2 = x[I, 2]
        for K in range(max(I - BLOCK_BAND, 0), I):
            d = I - K
            r0 -= A[I, d, 0, 0] * x[K, 0] + A[I, d, 0, 1] * x[K, 1] + A[I, d, 0, 2] * x[K, 2]
            r1 -= A[I, d, 1, 0] * x[K, 0] + A[I, d, 1, 1] * x[K, 1] + A[I, d, 1, 2] * x[K, 2]
            r2 -= A[I, d, 2, 0] * x[K, 0] + A[I, d, 2, 1] * x[K, 1] + A[I, d, 2, 2] * x[K, 2]
        x[I, 0] = A[I, 0, 0, 0] * r0
        x[I, 1] = A[I, 0, 1, 0] * r0 + A[I, 0, 1, 1] * r1
        x[I, 2] = A[I, 0, 2, 0] * r0 + A[I, 0, 2, 1] * r1 + A[I, 0, 2, 2] * r2
    for I in range(nb - 1, -1, -1):
        r0 = x[I, 0]
        r1 = x[I, 1]
        r2 = x[I, 2]
        for K in range(I + 1, min(I + BLOCK_BAND + 1, nb)):
            d = K - I
            # subtract L_KI^T x_K
            r0 -= A[K, d, 0, 0] * x[K, 0] + A[K, d, 1, 0] * x[K, 1] + A[K, d, 2, 0] * x[K, 2]
            r1 -= A[K, d, 0, 1] * x[K, 0] + A[K, d, 1, 1] * x[K, 1] + A[K, d, 2, 1] * x[K, 2]
            r2 -= A[K, d, 0, 2] * x[K, 0] + A[K, d, 1, 2] * x[K, 1] + A[K, d, 2, 2] * x[K, 2]
        # x_I = L_II^-T r
        x[I, 0] = A[I, 0, 0, 0] * r0 + A[I, 0, 1, 0] * r1 + A[I, 0, 2, 0] * r2
        x[I, 1] = A[I, 0, 1, 1] * r1 + A[I, 0, 2, 1] * r2
        x[I, 2] = A[I, 0, 2, 2] * r2
