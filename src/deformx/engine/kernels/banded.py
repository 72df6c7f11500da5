"""Block-banded symmetric positive definite systems with 3x3 blocks (block L D L^T).

One rod's Newton matrix in the order x0, phi0, x1, phi1, ... couples blocks at most two apart.
``A[I, d]`` holds the 3x3 block (I, I - d) for d = 0, 1, 2; of the diagonal blocks only the
lower triangle is read. The factorisation runs in O(n) with fixed-size 3x3 kernels; afterwards
``A[I, 0]`` holds the inverse of the pivot block D_I, so the solve only multiplies. Each block
row waits for the previous pivot, so the pivot's latency sets the speed: a cofactor inverse
(one division) rather than a Cholesky of the block (three square roots and divisions in a chain).

The kernels work on blocks held in tuples (registers): a block is read once and written once.
Computing in place in ``A`` would make the compiler reload every operand after each store,
as it cannot tell that the blocks do not overlap.
"""

from __future__ import annotations

from numba import njit
from .refcount import NO_REFCOUNT

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
def _sub_abt_lower(s, x, y):
    """Lower triangle of s - x @ y^T (``s`` and the result as in :func:`_load_lower`), for a
    symmetric x @ y^T."""
    return (s[0] - (x[0] * y[0] + x[1] * y[1] + x[2] * y[2]),
            s[1] - (x[3] * y[0] + x[4] * y[1] + x[5] * y[2]),
            s[2] - (x[3] * y[3] + x[4] * y[4] + x[5] * y[5]),
            s[3] - (x[6] * y[0] + x[7] * y[1] + x[8] * y[2]),
            s[4] - (x[6] * y[3] + x[7] * y[4] + x[8] * y[5]),
            s[5] - (x[6] * y[6] + x[7] * y[7] + x[8] * y[8]))


@njit(cache=True, inline="always", error_model="numpy")
def _times_sym(m, s):
    """m @ S, ``S`` symmetric given by its lower triangle as in :func:`_load_lower`."""
    return (m[0] * s[0] + m[1] * s[1] + m[2] * s[3], m[0] * s[1] + m[1] * s[2] + m[2] * s[4],
            m[0] * s[3] + m[1] * s[4] + m[2] * s[5],
            m[3] * s[0] + m[4] * s[1] + m[5] * s[3], m[3] * s[1] + m[4] * s[2] + m[5] * s[4],
            m[3] * s[3] + m[4] * s[4] + m[5] * s[5],
            m[6] * s[0] + m[7] * s[1] + m[8] * s[3], m[6] * s[1] + m[7] * s[2] + m[8] * s[4],
            m[6] * s[3] + m[7] * s[4] + m[8] * s[5])


@njit(cache=True, inline="always", error_model="numpy")
def _sym_inverse(s):
    """(ok, inverse) of the symmetric 3x3 block whose lower triangle is ``s`` (both as in
    :func:`_load_lower`); ok is False unless it is positive definite (leading minors > 0).

    Cofactors over the determinant: one division, all products independent, so the pivot
    that each block row waits for is short (sqrt/division chains would dominate).
    """
    a, b, d, c, e, f = s
    m00 = d * f - e * e
    m01 = c * e - b * f
    m02 = b * e - c * d
    minor2 = a * d - b * b
    det = a * m00 + b * m01 + c * m02
    if not (a > 0.0 and minor2 > 0.0 and det > 0.0):
        return False, s
    inv = 1.0 / det
    return True, (m00 * inv, m01 * inv, (a * f - c * c) * inv, m02 * inv, (b * c - a * e) * inv,
                  minor2 * inv)


@njit(cache=True, inline="always", error_model="numpy")
def _store_sym(A, I, s) -> None:
    """Store a symmetric block (lower triangle ``s`` as in :func:`_load_lower`) in A[I, 0]."""
    store_block(A, I, 0, (s[0], s[1], s[3], s[1], s[2], s[4], s[3], s[4], s[5]))


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def block_cholesky(A, nb) -> int:
    """In-place square-root-free block Cholesky ``A = L D L^T`` (``L`` unit block lower
    triangular) of the first ``nb`` block rows; 0, or 1 + the first block row whose pivot
    block ``D_I`` is not positive definite (then ``A`` is not).

    Afterwards ``A[I, 1]``, ``A[I, 2]`` hold L[I, I-1], L[I, I-2] and ``A[I, 0]`` holds D_I^-1.
    The last two D^-1 and the last L[I, I-1] D_{I-1} are carried along in locals.
    """
    if nb < 1:
        return 0
    ok, di2 = _sym_inverse(_load_lower(A, 0))  # di2, di1: D^-1 of blocks I-2, I-1
    if not ok:
        return 1
    _store_sym(A, 0, di2)
    if nb < 2:
        return 0
    u1 = _load(A, 1, 1)  # L[I-1, I-2] D_{I-2} (= the original A[I-1, I-2] for I = 2)
    l1 = _times_sym(u1, di2)
    store_block(A, 1, 1, l1)
    ok, di1 = _sym_inverse(_sub_abt_lower(_load_lower(A, 1), l1, u1))
    if not ok:
        return 2
    _store_sym(A, 1, di1)
    for I in range(2, nb):
        # L[I, I-2] D_{I-2} = A[I, I-2]; L[I, I-1] D_{I-1} = A[I, I-1] - L[I, I-2] D_{I-2} L[I-1, I-2]^T
        u2 = _load(A, I, 2)
        l2 = _times_sym(u2, di2)
        u1 = _sub_abt(_load(A, I, 1), l2, u1)
        l1 = _times_sym(u1, di1)
        store_block(A, I, 2, l2)
        store_block(A, I, 1, l1)
        # D_I = A[I, I] - L[I, I-1] D_{I-1} L[I, I-1]^T - L[I, I-2] D_{I-2} L[I, I-2]^T
        ok, di = _sym_inverse(_sub_abt_lower(_sub_abt_lower(_load_lower(A, I), l1, u1), l2, u2))
        if not ok:
            return I + 1
        _store_sym(A, I, di)
        di2 = di1
        di1 = di
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


@njit(cache=True, inline="always", error_model="numpy")
def _forward_row(A, I, x, p2, p1, di):
    """One forward row of the block solve for one right-hand side: returns y_I."""
    y = (x[I, 0], x[I, 1], x[I, 2])
    if I >= 2:
        y = _sub_ax(y, _load(A, I, 2), p2)
    if I >= 1:
        y = _sub_ax(y, _load(A, I, 1), p1)
    x[I, 0] = di[0] * y[0] + di[1] * y[1] + di[3] * y[2]
    x[I, 1] = di[1] * y[0] + di[2] * y[1] + di[4] * y[2]
    x[I, 2] = di[3] * y[0] + di[4] * y[1] + di[5] * y[2]
    return y


@njit(cache=True, inline="always", error_model="numpy")
def _backward_row(A, I, nb, x, n1, n2):
    """One backward row of the block solve: returns x_I."""
    r = (x[I, 0], x[I, 1], x[I, 2])
    if I + 1 < nb:
        r = _sub_atx(r, _load(A, I + 1, 1), n1)
    if I + 2 < nb:
        r = _sub_atx(r, _load(A, I + 2, 2), n2)
    x[I, 0], x[I, 1], x[I, 2] = r
    return r


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def block_solve(A, nb, x) -> None:
    """Solve ``L D L^T x = b`` in place (``x`` holds b, shape (nb, 3)) with the block factor.

    The last two solution blocks are carried along in locals rather than re-read from ``x``.
    """
    # Forward: y_I = b_I - L[I, I-2] y_{I-2} - L[I, I-1] y_{I-1}; x_I <- D_I^-1 y_I.
    p2 = (0.0, 0.0, 0.0)  # y_{I-2}
    p1 = (0.0, 0.0, 0.0)  # y_{I-1}
    for I in range(nb):
        y = _forward_row(A, I, x, p2, p1, _load_lower(A, I))
        p2 = p1
        p1 = y
    # Backward: x_I = D_I^-1 y_I - L[I+1, I]^T x_{I+1} - L[I+2, I]^T x_{I+2}.
    n1 = (0.0, 0.0, 0.0)  # x_{I+1}
    n2 = (0.0, 0.0, 0.0)  # x_{I+2}
    for I in range(nb - 1, -1, -1):
        r = _backward_row(A, I, nb, x, n1, n2)
        n2 = n1
        n1 = r


# ---------------------------------------------------------------- nonsymmetric band (block LU)
# A Newton matrix made nonsymmetric by friction (the friction bound mu N follows the normal
# force, a coupling the symmetric matrix leaves out) is held as the lower blocks above plus the
# upper ones: ``A[I, 3]`` the block (I - 1, I), ``A[I, 4]`` the block (I - 2, I), and a full
# diagonal block ``A[I, 0]``. LU without pivoting: the matrix is the symmetric positive definite
# one plus a small coupling, so its pivots stay near the Cholesky ones.
LU_UPPER = 3  # A[I, LU_UPPER + d - 1] holds the block (I - d, I)


@njit(cache=True, inline="always", error_model="numpy")
def _mul(x, y):
    """x @ y (3x3, row-major tuples)."""
    return (x[0] * y[0] + x[1] * y[3] + x[2] * y[6], x[0] * y[1] + x[1] * y[4] + x[2] * y[7],
            x[0] * y[2] + x[1] * y[5] + x[2] * y[8],
            x[3] * y[0] + x[4] * y[3] + x[5] * y[6], x[3] * y[1] + x[4] * y[4] + x[5] * y[7],
            x[3] * y[2] + x[4] * y[5] + x[5] * y[8],
            x[6] * y[0] + x[7] * y[3] + x[8] * y[6], x[6] * y[1] + x[7] * y[4] + x[8] * y[7],
            x[6] * y[2] + x[7] * y[5] + x[8] * y[8])


@njit(cache=True, inline="always", error_model="numpy")
def _sub_ab(m, x, y):
    """m - x @ y (3x3, row-major tuples)."""
    p = _mul(x, y)
    return (m[0] - p[0], m[1] - p[1], m[2] - p[2], m[3] - p[3], m[4] - p[4], m[5] - p[5],
            m[6] - p[6], m[7] - p[7], m[8] - p[8])


@njit(cache=True, inline="always", error_model="numpy")
def _pivot_inverse(m):
    """(ok, inverse) of a 3x3 pivot block; ok is False unless its leading principal minors are
    positive, i.e. the scalar pivots of the whole matrix are: for a symmetric matrix the test
    the Cholesky factorisation makes, so an indefinite Newton matrix is caught the same way.
    (The symmetric part is no test: friction's coupling ``u n^T`` makes it indefinite.)"""
    c00 = m[4] * m[8] - m[5] * m[7]
    c01 = m[5] * m[6] - m[3] * m[8]
    c02 = m[3] * m[7] - m[4] * m[6]
    det = m[0] * c00 + m[1] * c01 + m[2] * c02
    if not (m[0] > 0.0 and m[0] * m[4] - m[1] * m[3] > 0.0 and det > 0.0):
        return False, m
    inv = 1.0 / det
    return True, (c00 * inv, (m[2] * m[7] - m[1] * m[8]) * inv, (m[1] * m[5] - m[2] * m[4]) * inv,
                  c01 * inv, (m[0] * m[8] - m[2] * m[6]) * inv, (m[2] * m[3] - m[0] * m[5]) * inv,
                  c02 * inv, (m[1] * m[6] - m[0] * m[7]) * inv, (m[0] * m[4] - m[1] * m[3]) * inv)


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def expand_upper(A, nb) -> None:
    """Make the symmetric band ``A`` (lower blocks, lower triangles of the diagonal ones) a
    full one: diagonal blocks mirrored, upper blocks the transposes of the lower ones."""
    for I in range(nb):
        for i in range(3):
            for j in range(i + 1, 3):
                A[I, 0, i, j] = A[I, 0, j, i]
        for d in range(1, BLOCK_BAND + 1):
            for i in range(3):
                for j in range(3):
                    A[I, LU_UPPER + d - 1, i, j] = A[I, d, j, i] if I >= d else 0.0


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def block_lu(A, nb) -> int:
    """In-place block LU (``L`` unit lower, no pivoting) of the full band ``A`` (see
    ``LU_UPPER``); 0, or 1 + the first block row with a scalar pivot <= 0 (see
    ``_pivot_inverse``). Afterwards ``A[I, 1]``, ``A[I, 2]`` hold L[I, I-1], L[I, I-2],
    ``A[I, 0]`` the inverse pivot and ``A[I, 3]``, ``A[I, 4]`` the factor's U[I-1, I],
    U[I-2, I]."""
    zero = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    pinv2 = pinv1 = l1 = l2 = zero
    for I in range(nb):
        p = _load(A, I, 0)
        if I >= 2:
            l2 = _mul(_load(A, I, 2), pinv2)
            store_block(A, I, 2, l2)
            p = _sub_ab(p, l2, _load(A, I, LU_UPPER + 1))
        if I >= 1:
            a1 = _load(A, I, 1)
            if I >= 2:
                a1 = _sub_ab(a1, l2, _load(A, I - 1, LU_UPPER))
            l1 = _mul(a1, pinv1)
            store_block(A, I, 1, l1)
            p = _sub_ab(p, l1, _load(A, I, LU_UPPER))
        ok, pinv = _pivot_inverse(p)
        if not ok:
            return I + 1
        store_block(A, I, 0, pinv)
        if I >= 1 and I + 1 < nb:  # U[I, I+1] = A[I, I+1] - L[I, I-1] U[I-1, I+1]
            store_block(A, I + 1, LU_UPPER, _sub_ab(_load(A, I + 1, LU_UPPER), l1,
                                                    _load(A, I + 1, LU_UPPER + 1)))
        pinv2 = pinv1
        pinv1 = pinv
    return 0


@njit(cache=True, inline="always", error_model="numpy")
def _lu_forward_row(A, I, x, p2, p1):
    """One forward row of the unit lower solve: y_I (stored in ``x`` and returned)."""
    y = (x[I, 0], x[I, 1], x[I, 2])
    if I >= 2:
        y = _sub_ax(y, _load(A, I, 2), p2)
    if I >= 1:
        y = _sub_ax(y, _load(A, I, 1), p1)
    x[I, 0], x[I, 1], x[I, 2] = y
    return y


@njit(cache=True, inline="always", error_model="numpy")
def _lu_backward_row(A, I, nb, x, n1, n2):
    """One backward row of the upper solve: x_I (stored in ``x`` and returned)."""
    r = (x[I, 0], x[I, 1], x[I, 2])
    if I + 1 < nb:
        r = _sub_ax(r, _load(A, I + 1, LU_UPPER), n1)
    if I + 2 < nb:
        r = _sub_ax(r, _load(A, I + 2, LU_UPPER + 1), n2)
    pinv = _load(A, I, 0)
    xi = (pinv[0] * r[0] + pinv[1] * r[1] + pinv[2] * r[2],
          pinv[3] * r[0] + pinv[4] * r[1] + pinv[5] * r[2],
          pinv[6] * r[0] + pinv[7] * r[1] + pinv[8] * r[2])
    x[I, 0], x[I, 1], x[I, 2] = xi
    return xi


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def block_lu_solve(A, nb, x) -> None:
    """Solve ``L U x = b`` in place (``x`` holds b, shape (nb, 3)) with ``block_lu``'s factor."""
    p2 = p1 = (0.0, 0.0, 0.0)
    for I in range(nb):
        y = _lu_forward_row(A, I, x, p2, p1)
        p2 = p1
        p1 = y
    n1 = n2 = (0.0, 0.0, 0.0)  # x_{I+1}, x_{I+2}
    for I in range(nb - 1, -1, -1):
        xi = _lu_backward_row(A, I, nb, x, n1, n2)
        n2 = n1
        n1 = xi



# ---------------------------------------------------------------- panels of right-hand sides
@njit(cache=True, inline="always", error_model="numpy")
def _panel_sub(P, I, J, m, transpose, p) -> None:
    """P[I] -= m @ P[J] (or m^T @ P[J]) for the ``p`` columns of the (nb, 3, p) panel ``P``."""
    if transpose:
        m = (m[0], m[3], m[6], m[1], m[4], m[7], m[2], m[5], m[8])
    for j in range(p):
        x0, x1, x2 = P[J, 0, j], P[J, 1, j], P[J, 2, j]
        P[I, 0, j] -= m[0] * x0 + m[1] * x1 + m[2] * x2
        P[I, 1, j] -= m[3] * x0 + m[4] * x1 + m[5] * x2
        P[I, 2, j] -= m[6] * x0 + m[7] * x1 + m[8] * x2


@njit(cache=True, inline="always", error_model="numpy")
def _panel_mul(P, I, m, p) -> None:
    """P[I] <- m @ P[I] (``m`` row-major)."""
    for j in range(p):
        x0, x1, x2 = P[I, 0, j], P[I, 1, j], P[I, 2, j]
        P[I, 0, j] = m[0] * x0 + m[1] * x1 + m[2] * x2
        P[I, 1, j] = m[3] * x0 + m[4] * x1 + m[5] * x2
        P[I, 2, j] = m[6] * x0 + m[7] * x1 + m[8] * x2


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def block_solve_panel(A, nb, P, p, first, lu=False) -> None:
    """:func:`block_solve` (or, with ``lu``, :func:`block_lu_solve`) for the ``p`` right-hand
    sides of the panel ``P`` (shape (nb, 3, >= p): block row, component, column), all zero
    before block ``first``. Each row's work runs along the columns (a pile's rod-rod columns,
    ~15 per rod: ~1.1x faster than three interleaved recurrences at a time; numba's loops
    vectorise only 2 wide here)."""
    # Forward (unit lower L, both factors): y_I = b_I - L[I, I-2] y_{I-2} - L[I, I-1] y_{I-1}.
    for I in range(first, nb):
        if I - 2 >= first:
            _panel_sub(P, I, I - 2, _load(A, I, 2), False, p)
        if I - 1 >= first:
            _panel_sub(P, I, I - 1, _load(A, I, 1), False, p)
    # Backward: Cholesky x_I = D_I^-1 y_I - L[I+1, I]^T x_{I+1} - L[I+2, I]^T x_{I+2};
    # LU x_I = U_II^-1 (y_I - U[I, I+1] x_{I+1} - U[I, I+2] x_{I+2}).
    for I in range(nb - 1, -1, -1):
        if lu:
            if I + 1 < nb:
                _panel_sub(P, I, I + 1, _load(A, I + 1, LU_UPPER), False, p)
            if I + 2 < nb:
                _panel_sub(P, I, I + 2, _load(A, I + 2, LU_UPPER + 1), False, p)
            _panel_mul(P, I, _load(A, I, 0), p)
        else:
            d = _load_lower(A, I)
            _panel_mul(P, I, (d[0], d[1], d[3], d[1], d[2], d[4], d[3], d[4], d[5]), p)
            if I + 1 < nb:
                _panel_sub(P, I, I + 1, _load(A, I + 1, 1), True, p)
            if I + 2 < nb:
                _panel_sub(P, I, I + 2, _load(A, I + 2, 2), True, p)
