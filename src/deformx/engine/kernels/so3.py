"""SO(3) helpers shared by the kernels (PyElastica's conventions).

Directors ``Q`` are stored with rows d1, d2, d3, so ``Q`` maps lab vectors to the material frame.
Small angles use Taylor polynomials accurate to round-off, which avoids most of the cost of
sin/cos/acos in the hot loops without changing results beyond the last bits.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_SMALL = 0.05  # rad; below it the truncated series are exact to double precision
_R6, _R12, _R20, _R30, _R42, _R56, _R72, _R90 = (1.0 / k for k in (6, 12, 20, 30, 42, 56, 72, 90))


@njit(cache=True, inline="always", error_model="numpy")
def rodrigues_coefficients(t2: float) -> tuple[float, float]:
    """(sin(t)/t, (1 - cos t)/t^2) for t^2 = ``t2``, by series below ``_SMALL`` (exact to
    double precision there, and no sqrt, division or sin/cos)."""
    if t2 < _SMALL * _SMALL:
        # Products with reciprocals: eight divisions cost a third of a director update.
        s = 1.0 - t2 * _R6 * (1.0 - t2 * _R20 * (1.0 - t2 * _R42 * (1.0 - t2 * _R72)))
        c = 0.5 * (1.0 - t2 * _R12 * (1.0 - t2 * _R30 * (1.0 - t2 * _R56 * (1.0 - t2 * _R90))))
        return s, c
    theta = math.sqrt(t2)
    return math.sin(theta) / theta, (1.0 - math.cos(theta)) / t2


@njit(cache=True, inline="always", error_model="numpy")
def rotate_directors(Q: np.ndarray, e: int, scale: float, w0: float, w1: float, w2: float) -> None:
    """In place ``Q[e] <- exp(-scale [w]x) Q[e]`` for a material-frame angular velocity ``w``.

    Rodrigues' formula as in PyElastica's ``_get_rotation_matrix``, written in the rotation
    vector ``phi = scale * w`` so that small angles need no sqrt, division or sin/cos.
    """
    p0 = scale * w0
    p1 = scale * w1
    p2 = scale * w2
    t2 = p0 * p0 + p1 * p1 + p2 * p2
    # R = I - s [phi] + c [phi]^2 with s = sin(t)/t, c = (1 - cos t)/t^2, t = |phi|.
    s, c = rodrigues_coefficients(t2)
    r00 = 1.0 - c * (p1 * p1 + p2 * p2)
    r11 = 1.0 - c * (p0 * p0 + p2 * p2)
    r22 = 1.0 - c * (p0 * p0 + p1 * p1)
    r01 = s * p2 + c * p0 * p1
    r10 = -s * p2 + c * p0 * p1
    r02 = -s * p1 + c * p0 * p2
    r20 = s * p1 + c * p0 * p2
    r12 = s * p0 + c * p1 * p2
    r21 = -s * p0 + c * p1 * p2
    for j in range(3):
        a = Q[e, 0, j]
        b = Q[e, 1, j]
        d = Q[e, 2, j]
        Q[e, 0, j] = r00 * a + r01 * b + r02 * d
        Q[e, 1, j] = r10 * a + r11 * b + r12 * d
        Q[e, 2, j] = r20 * a + r21 * b + r22 * d


@njit(cache=True, inline="always", error_model="numpy")
def relative_rotation_vector(Qa: np.ndarray, a: int, Qb: np.ndarray, b: int) -> tuple[float, float, float]:
    """Rotation vector phi (rad, material frame) with ``Qb[b] = exp(-[phi]) Qa[a]``.

    The log map of ``Qb[b] Qa[a]^T`` with PyElastica's conventions (``_inv_rotate``).
    """
    v0 = (Qb[b, 2, 0] * Qa[a, 1, 0] + Qb[b, 2, 1] * Qa[a, 1, 1] + Qb[b, 2, 2] * Qa[a, 1, 2]) - (
        Qb[b, 1, 0] * Qa[a, 2, 0] + Qb[b, 1, 1] * Qa[a, 2, 1] + Qb[b, 1, 2] * Qa[a, 2, 2])
    v1 = (Qb[b, 0, 0] * Qa[a, 2, 0] + Qb[b, 0, 1] * Qa[a, 2, 1] + Qb[b, 0, 2] * Qa[a, 2, 2]) - (
        Qb[b, 2, 0] * Qa[a, 0, 0] + Qb[b, 2, 1] * Qa[a, 0, 1] + Qb[b, 2, 2] * Qa[a, 0, 2])
    v2 = (Qb[b, 1, 0] * Qa[a, 0, 0] + Qb[b, 1, 1] * Qa[a, 0, 1] + Qb[b, 1, 2] * Qa[a, 0, 2]) - (
        Qb[b, 0, 0] * Qa[a, 1, 0] + Qb[b, 0, 1] * Qa[a, 1, 1] + Qb[b, 0, 2] * Qa[a, 1, 2])
    trace = ((Qb[b, 0, 0] * Qa[a, 0, 0] + Qb[b, 0, 1] * Qa[a, 0, 1] + Qb[b, 0, 2] * Qa[a, 0, 2])
             + (Qb[b, 1, 0] * Qa[a, 1, 0] + Qb[b, 1, 1] * Qa[a, 1, 1] + Qb[b, 1, 2] * Qa[a, 1, 2])
             + (Qb[b, 2, 0] * Qa[a, 2, 0] + Qb[b, 2, 1] * Qa[a, 2, 1] + Qb[b, 2, 2] * Qa[a, 2, 2]))
    # |v| = 2 sin(theta), trace = 1 + 2 cos(theta): theta / sin(theta) without acos when small.
    s2 = 0.25 * (v0 * v0 + v1 * v1 + v2 * v2)
    if s2 < _SMALL * _SMALL and trace > 1.0:  # asin(s)/s series, s = sin(theta)
        ratio = 1.0 + s2 * (1.0 / 6.0 + s2 * (3.0 / 40.0 + s2 * (5.0 / 112.0 + s2 * (
            35.0 / 1152.0 + s2 * (63.0 / 2816.0 + s2 * (231.0 / 13312.0 + s2 * (143.0 / 10240.0)))))))
    else:
        trace = min(trace, 3.0)
        trace = max(trace, -1.0)
        theta = math.acos(0.5 * trace - 0.5) + 1e-14
        ratio = theta / math.sin(theta)
    mag = -0.5 * ratio
    return v0 * mag, v1 * mag, v2 * mag


@njit(cache=True, error_model="numpy")
def curvature_from_directors(directors: np.ndarray, rest_voronoi: np.ndarray, closed: bool) -> np.ndarray:
    """Discrete curvature/twist (1/m) at the Voronoi domains of one rod, material frame."""
    n = directors.shape[0]
    nv = rest_voronoi.shape[0]
    out = np.zeros((nv, 3))
    for v in range(nv):
        r0, r1, r2 = relative_rotation_vector(directors, v, directors, v + 1 if v + 1 < n else 0)
        out[v, 0] = r0 / rest_voronoi[v]
        out[v, 1] = r1 / rest_voronoi[v]
        out[v, 2] = r2 / rest_voronoi[v]
    return out


def axis_angle_matrix(axis: np.ndarray, angle: float) -> np.ndarray:
    """Lab-frame rotation matrix of ``angle`` rad about unit ``axis`` (active rotation)."""
    a = np.asarray(axis, dtype=np.float64)
    n = np.linalg.norm(a)
    if n == 0.0 or angle == 0.0:
        return np.eye(3)
    a = a / n
    K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)
