"""Banded symmetric positive definite systems (Cholesky in lower band storage).

``ab[i, k]`` holds ``A[i, i - k]`` for ``k = 0 .. p``: row-major lower band, so one rod's
block-pentadiagonal Newton matrix factors in O(n p^2) without fill-in.
"""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True, error_model="numpy")
def band_cholesky(ab, n, p) -> int:
    """In-place Cholesky ``A = L L^T`` of the leading ``n`` rows; returns 0 or the 1-based row
    of the first non-positive pivot (then the factor is unusable)."""
    for i in range(n):
        jmin = max(0, i - p)
        for j in range(jmin, i + 1):
            # s = A[i, j] - sum_k L[i, k] L[j, k]
            s = ab[i, i - j]
            kmin = max(jmin, j - p)
            for k in range(kmin, j):
                s -= ab[i, i - k] * ab[j, j - k]
            if j == i:
                if not (s > 0.0):
                    return i + 1
                ab[i, 0] = math.sqrt(s)
            else:
                ab[i, i - j] = s / ab[j, 0]
    return 0


@njit(cache=True, error_model="numpy")
def band_solve(ab, n, p, b) -> None:
    """Solve ``L L^T x = b`` in place with the factor from :func:`band_cholesky`."""
    for i in range(n):
        s = b[i]
        for k in range(max(0, i - p), i):
            s -= ab[i, i - k] * b[k]
        b[i] = s / ab[i, 0]
    for i in range(n - 1, -1, -1):
        s = b[i]
        for k in range(i + 1, min(n, i + p + 1)):
            s -= ab[k, k - i] * b[k]
        b[i] = s / ab[i, 0]
