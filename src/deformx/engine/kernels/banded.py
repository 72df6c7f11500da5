"""Block-banded symmetric positive definite systems with 3x3 blocks (block Cholesky).

One rod's Newton matrix in the order x0, phi0, x1, phi1, ... couples blocks at most two apart.
``A[I, d]`` holds the 3x3 block (I, I - d) for d = 0, 1, 2; of the diagonal blocks only the
lower triangle is read. The factorisation runs in O(n) with fixed-size 3x3 kernels; afterwards
``A[I, 0]`` holds the inverse of the diagonal Cholesky block (lower triangular), so both
triangular sweeps only multiply.

The kernels work on blocks held in tuples (registers): a block is read once and written once.
Computing in place in ``A`` would make the compiler reload every operand after each store,
as it cannot tell that the blocks do not overlap.
"""

from __future__ import annotations

import math

from numba import njit

BLOCK_BAND = 2  # coupled blocks are at most this many apart


@njit(cache=True, inline="always", error_model="numpy")
def _load(A, I, d):
    """Block A[I, d] as a tuple, row-major."""
    return (A[I, d, 0, 0], A[I, d, 0, 1], A[I, d, 0, 2],
            A[I, d, 1, 0], A[I, d, 1, 1], A[I, d, 1, 2],
            A[I, d, 2, 0], A[I, d, 2, 1], A[I, d, 2, 2])


@njit(cache=True, inline="always", error_model="numpy")
def store_block(A, I, d, m) -> None:
    """A[I, d] <- the block ``m`` (row-major tuple)."""
    A[I, d, 0, 0], A[I, d, 0, 1], A[I, d, 0, 2] = m[0], m[1], m[2]
    A[I, d, 1, 0], A[I, d, 1, 1], A[I, d, 1, 2] = m[3], m[4], m[5]
    A[I, d, 2, 0], A[I, d, 2, 1], A[I, d, 2, 2] = m[6], m[7], m[8]


@njit(cache=True, inline="always", error_model="numpy")
def _load_lower(A, I):
    """Lower triangle of the diagonal block A[I, 0]: (00, 10, 11, 20, 21, 22)."""
    return (A[I, 0, 0, 0], A[I, 0, 1, 0], A[I, 0, 1, 1], A[I, 0, 2, 0], A[I, 0, 2, 1],
            A[I, 0, 2, 2])


@njit(cache=True, inline="always", error_model="numpy")
def add_lower(A, I, s) -> None:
    """A[I, 0] += ``s`` on the lower triangle (``s`` as in :func:`_load_lower`)."""
    A[I, 0, 0, 0] += s[0]
    A[I, 0, 1, 0] += s[1]
    A[I, 0, 1, 1] += s[2]
    A[I, 0, 2, 0] += s[3]
    A[I, 0, 2, 1] += s[4]
    A[I, 0, 2, 2] += s[5]


@njit(cache=True, inline="always", error_model="numpy")
def _sub_abt(m, x, y):
    """m - x @ y^T (3x3, row-major tuples)."""
    return (m[0] - (x[0] * y[0] + x[1] * y[1] + x[2] * y[2]),
            m[1] - (x[0] * y[3] + x[1] * y[4] + x[2] * y[5]),
            m[2] - (x[0] * y[6] + x[1] * y[7] + x[2] * y[8]),
            m[3] - (x[3] * y[0] + x[4] * y[1] + x[5] * y[2]),
            m[4] - (x[3] * y[3] + x[4] * y[4] + x[5] * y[5]),
            m[5] - (x[3] * y[6] + x[4] * y[7] + x[5] * y[8]),
            m[6] - (x[6] * y[0] + x[7] * y[1] + x[8] * y[2]),
            m[7] - (x[6] * y[3] + x[7] * y[4] + x[8] * y[5]),
            m[8] - (x[6] * y[6] + x[7] * y[7] + x[8] * y[8]))


@njit(cache=True, inline="always", error_model="numpy")
def _sub_aat(s, x):
    """Lower triangle of s - x @ x^T (``s`` and the result as in :func:`_load_lower`)."""
    return (s[0] - (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]),
            s[1] - (x[3] * x[0] + x[4] * x[1] + x[5] * x[2]),
            s[2] - (x[3] * x[3] + x[4] * x[4] + x[5] * x[5]),
            s[3] - (x[6] * x[0] + x[7] * x[1] + x[8] * x[2]),
            s[4] - (x[6] * x[3] + x[7] * x[4] + x[8] * x[5]),
            s[5] - (x[6] * x[6] + x[7] * x[7] + x[8] * x[8]))


@njit(cache=True, inline="always", error_model="numpy")
def _times_inv_t(m, li):
    """m @ Li^T, where ``li`` is an inverse lower Cholesky block as in :func:`_load_lower`."""
    return (m[0] * li[0], m[0] * li[1] + m[1] * li[2], m[0] * li[3] + m[1] * li[4] + m[2] * li[5],
            m[3] * li[0], m[3] * li[1] + m[4] * li[2], m[3] * li[3] + m[4] * li[4] + m[5] * li[5],
            m[6] * li[0], m[6] * li[1] + m[7] * li[2], m[6] * li[3] + m[7] * li[4] + m[8] * li[5])


@njit(cache=True, inline="always", error_model="numpy")
def _chol3_inverse(s):
    """(ok, inverse of the lower Cholesky factor) of the 3x3 block whose lower triangle is
    ``s`` (both as in :func:`_load_lower`); ok is False if it is not positive definite."""
    a00 = s[0]
    if not (a00 > 0.0):
        return False, s
    l00 = math.sqrt(a00)
    l10 = s[1] / l00
    l20 = s[3] / l00
    a11 = s[2] - l10 * l10
    if not (a11 > 0.0):
        return False, s
    l11 = math.sqrt(a11)
    l21 = (s[4] - l20 * l10) / l11
    a22 = s[5] - l20 * l20 - l21 * l21
    if not (a22 > 0.0):
        return False, s
    l22 = math.sqrt(a22)
    i00 = 1.0 / l00
    i11 = 1.0 / l11
    i22 = 1.0 / l22
    i10 = -l10 * i00 * i11
    i21 = -l21 * i11 * i22
    i20 = -(l20 * i00 + l21 * i10) * i22
    return True, (i00, i10, i11, i20, i21, i22)


@njit(cache=True, inline="always", error_model="numpy")
def _store_inverse(A, I, li) -> None:
    """Store an inverse lower Cholesky block (as in :func:`_load_lower`) in A[I, 0], in full."""
    store_block(A, I, 0, (li[0], 0.0, 0.0, li[1], li[2], 0.0, li[3], li[4], li[5]))


@njit(cache=True, error_model="numpy")
def block_cholesky(A, nb) -> int:
    """In-place block Cholesky of the first ``nb`` block rows; 0, or 1 + the first block row
    whose pivot block is not positive definite.

    The factor blocks that the next rows need (the last two inverse diagonal blocks, the last
    L[I, I-1]) are carried along in locals.
    """
    if nb < 1:
        return 0
    ok, li2 = _chol3_inverse(_load_lower(A, 0))  # li2, li1: L^-1 of blocks I-2, I-1
    if not ok:
        return 1
    _store_inverse(A, 0, li2)
    if nb < 2:
        return 0
    # L[1, 0] = A[1, 0] L[0, 0]^-T
    l1 = _times_inv_t(_load(A, 1, 1), li2)
    store_block(A, 1, 1, l1)
    ok, li1 = _chol3_inverse(_sub_aat(_load_lower(A, 1), l1))
    if not ok:
        return 2
    _store_inverse(A, 1, li1)
    for I in range(2, nb):
        # L[I, I-2] = A[I, I-2] L[I-2, I-2]^-T
        l2 = _times_inv_t(_load(A, I, 2), li2)
        # L[I, I-1] = (A[I, I-1] - L[I, I-2] L[I-1, I-2]^T) L[I-1, I-1]^-T
        l1 = _times_inv_t(_sub_abt(_load(A, I, 1), l2, l1), li1)
        store_block(A, I, 2, l2)
        store_block(A, I, 1, l1)
        # Pivot block A[I, I] - L[I, I-1] L[I, I-1]^T - L[I, I-2] L[I, I-2]^T, lower triangle.
        ok, li = _chol3_inverse(_sub_aat(_sub_aat(_load_lower(A, I), l1), l2))
        if not ok:
            return I + 1
        _store_inverse(A, I, li)
        li2 = li1
        li1 = li
    return 0


@njit(cache=True, inline="always", error_model="numpy")
def _sub_ax(r, m, x):
    """r - m @ x (3-vectors as tuples, ``m`` a row-major block)."""
    return (r[0] - (m[0] * x[0] + m[1] * x[1] + m[2] * x[2]),
            r[1] - (m[3] * x[0] + m[4] * x[1] + m[5] * x[2]),
            r[2] - (m[6] * x[0] + m[7] * x[1] + m[8] * x[2]))


@njit(cache=True, inline="always", error_model="numpy")
def _sub_atx(r, m, x):
    """r - m^T @ x."""
    return (r[0] - (m[0] * x[0] + m[3] * x[1] + m[6] * x[2]),
            r[1] - (m[1] * x[0] + m[4] * x[1] + m[7] * x[2]),
            r[2] - (m[2] * x[0] + m[5] * x[1] + m[8] * x[2]))


@njit(cache=True, error_model="numpy")
def block_solve(A, nb, x) -> None:
    """Solve ``L L^T x = b`` in place (``x`` holds b, shape (nb, 3)) with the block factor.

    The last two solution blocks are carried along in locals rather than re-read from ``x``.
    """
    # Forward: x_I = L_II^-1 (b_I - L[I, I-2] x_{I-2} - L[I, I-1] x_{I-1}).
    p2 = (0.0, 0.0, 0.0)  # x_{I-2}
    p1 = (0.0, 0.0, 0.0)  # x_{I-1}
    for I in range(nb):
        r = (x[I, 0], x[I, 1], x[I, 2])
        if I >= 2:
            r = _sub_ax(r, _load(A, I, 2), p2)
        if I >= 1:
            r = _sub_ax(r, _load(A, I, 1), p1)
        li = _load_lower(A, I)
        y = (li[0] * r[0], li[1] * r[0] + li[2] * r[1], li[3] * r[0] + li[4] * r[1] + li[5] * r[2])
        x[I, 0], x[I, 1], x[I, 2] = y
        p2 = p1
        p1 = y
    # Backward: x_I = L_II^-T (y_I - L[I+1, I]^T x_{I+1} - L[I+2, I]^T x_{I+2}).
    n1 = (0.0, 0.0, 0.0)  # x_{I+1}
    n2 = (0.0, 0.0, 0.0)  # x_{I+2}
    for I in range(nb - 1, -1, -1):
        r = (x[I, 0], x[I, 1], x[I, 2])
        if I + 1 < nb:
            r = _sub_atx(r, _load(A, I + 1, 1), n1)
        if I + 2 < nb:
            r = _sub_atx(r, _load(A, I + 2, 2), n2)
        li = _load_lower(A, I)
        y = (li[0] * r[0] + li[1] * r[1] + li[3] * r[2], li[2] * r[1] + li[4] * r[2], li[5] * r[2])
        x[I, 0], x[I, 1], x[I, 2] = y
        n2 = n1
        n1 = y
