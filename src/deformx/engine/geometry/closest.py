"""Closest points between points, segments and triangles (numba, no allocations).

Points are tuples of three floats (m); results are parameters, not points: ``t``/``s`` in
[0, 1] along a segment (``a + t (b - a)``) and barycentrics ``(u, v, w)`` on triangle corners
``(a, b, c)``, with ``u + v + w = 1`` and all >= 0. Rebuild the points with ``lerp`` and
``bary_point``. Every routine returns a point on its primitive even for degenerate input
(zero-length segments, collinear or collapsed triangles), which is what a contact search needs:
a pair that is exactly a closest pair, or a valid pair when the closest pair is not unique.
The region logic follows Ericson, "Real-Time Collision Detection", sections 5.1.2-5.1.9.
"""

from __future__ import annotations

from numba import njit

# A pair of segments is treated as parallel when sin^2 of their angle is below this; any s then
# gives a closest pair up to (length x angle), i.e. round-off.
_PARALLEL = 1e-24
# A triangle is treated as degenerate when sin^2 of its angle at ``a`` is below this; the
# closest point then lies on one of its edges.
_FLAT = 1e-14


@njit(cache=True, error_model="numpy")
def _clamp01(x: float) -> float:
    if x < 0.0:
        return 0.0
    if x > 1.0:
        return 1.0
    return x


@njit(cache=True, error_model="numpy")
def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(cache=True, error_model="numpy")
def _dot(a, b) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True, error_model="numpy")
def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit(cache=True, error_model="numpy")
def lerp(a, b, t: float):
    """Point ``a + t (b - a)`` (m) of segment ab."""
    return (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2]))


@njit(cache=True, error_model="numpy")
def bary_point(a, b, c, u: float, v: float, w: float):
    """Point ``u a + v b + w c`` (m) of triangle abc."""
    return (u * a[0] + v * b[0] + w * c[0],
            u * a[1] + v * b[1] + w * c[1],
            u * a[2] + v * b[2] + w * c[2])


@njit(cache=True, error_model="numpy")
def dist2(a, b) -> float:
    """Squared distance (m^2) between points a and b."""
    d0 = a[0] - b[0]
    d1 = a[1] - b[1]
    d2 = a[2] - b[2]
    return d0 * d0 + d1 * d1 + d2 * d2


@njit(cache=True, error_model="numpy")
def closest_point_segment(p, a, b) -> float:
    """Parameter t in [0, 1] of the point of segment ab closest to p (0 when a == b)."""
    ab = _sub(b, a)
    denom = _dot(ab, ab)
    if denom <= 0.0:
        return 0.0
    # A tiny denominator may give +-inf, never NaN (the numerator is finite); clamping fixes it.
    return _clamp01(_dot(_sub(p, a), ab) / denom)


@njit(cache=True, error_model="numpy")
def closest_segment_segment(p0, p1, q0, q1) -> tuple[float, float]:
    """Parameters (s, t) in [0, 1] of a closest pair of segments p0p1 and q0q1.

    The unconstrained line-line minimiser is clamped in s, t is re-solved for it, and s is
    re-solved once more if t had to be clamped: for this convex quadratic over the unit
    square that sequence lands on the minimum. Parallel segments take s = 0 first, which
    still yields a closest pair; zero-length segments reduce to point-segment queries.
    """
    d1 = _sub(p1, p0)
    d2 = _sub(q1, q0)
    r = _sub(p0, q0)
    a = _dot(d1, d1)
    e = _dot(d2, d2)
    f = _dot(d2, r)
    if a <= 0.0 and e <= 0.0:
        return 0.0, 0.0
    if a <= 0.0:
        return 0.0, _clamp01(f / e)
    c = _dot(d1, r)
    if e <= 0.0:
        return _clamp01(-c / a), 0.0
    b = _dot(d1, d2)
    # Line-line minimiser s = (b f - c e) / (a e - b^2), written with cross products (Lagrange's
    # identity): a e - b^2 loses all digits to cancellation when the lines are nearly parallel,
    # |d1 x d2|^2 keeps about half of them, so s stays usable down to angles of ~1e-12 rad.
    n = _cross(d1, d2)
    denom = _dot(n, n)
    s = 0.0
    if denom > _PARALLEL * a * e:
        s = _clamp01(_dot(n, _cross(d2, r)) / denom)
    t = (b * s + f) / e
    if t < 0.0:
        t = 0.0
        s = _clamp01(-c / a)
    elif t > 1.0:
        t = 1.0
        s = _clamp01((b - c) / a)
    return s, t


@njit(cache=True, error_model="numpy")
def _closest_point_triangle_edges(p, a, b, c) -> tuple[float, float, float]:
    """Barycentrics of the closest point to p on the boundary of abc (any triangle)."""
    t_ab = closest_point_segment(p, a, b)
    t_bc = closest_point_segment(p, b, c)
    t_ca = closest_point_segment(p, c, a)
    d_ab = dist2(p, lerp(a, b, t_ab))
    d_bc = dist2(p, lerp(b, c, t_bc))
    d_ca = dist2(p, lerp(c, a, t_ca))
    if d_ab <= d_bc and d_ab <= d_ca:
        return 1.0 - t_ab, t_ab, 0.0
    if d_bc <= d_ca:
        return 0.0, 1.0 - t_bc, t_bc
    return t_ca, 0.0, 1.0 - t_ca


@njit(cache=True, error_model="numpy")
def closest_point_triangle(p, a, b, c) -> tuple[float, float, float]:
    """Barycentrics (u, v, w) of the point of triangle abc closest to p.

    Voronoi regions of the vertices, then the edges, then the face. A degenerate triangle
    (collinear or coincident corners) has no face region, so when the face test is reached
    with a vanishing area the answer comes from its three edges instead.
    """
    ab = _sub(b, a)
    ac = _sub(c, a)
    ap = _sub(p, a)
    d1 = _dot(ab, ap)
    d2 = _dot(ac, ap)
    if d1 <= 0.0 and d2 <= 0.0:
        return 1.0, 0.0, 0.0  # vertex a
    bp = _sub(p, b)
    d3 = _dot(ab, bp)
    d4 = _dot(ac, bp)
    if d3 >= 0.0 and d4 <= d3:
        return 0.0, 1.0, 0.0  # vertex b
    vc = d1 * d4 - d3 * d2
    # In the edge regions the denominator is the squared edge length; it vanishes only for a
    # collapsed edge, which the edge fallback handles.
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0 and d1 - d3 > 0.0:
        v = d1 / (d1 - d3)
        return 1.0 - v, v, 0.0  # edge ab
    cp = _sub(p, c)
    d5 = _dot(ab, cp)
    d6 = _dot(ac, cp)
    if d6 >= 0.0 and d5 <= d6:
        return 0.0, 0.0, 1.0  # vertex c
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0 and d2 - d6 > 0.0:
        w = d2 / (d2 - d6)
        return 1.0 - w, 0.0, w  # edge ac
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0 and (d4 - d3) + (d5 - d6) > 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return 0.0, 1.0 - w, w  # edge bc
    # Face region: va + vb + vc = |ab x ac|^2 (Lagrange identity).
    denom = va + vb + vc
    if va < 0.0 or vb < 0.0 or vc < 0.0 or denom <= _FLAT * _dot(ab, ab) * _dot(ac, ac):
        return _closest_point_triangle_edges(p, a, b, c)
    v = vb / denom
    w = vc / denom
    return 1.0 - v - w, v, w


@njit(cache=True, error_model="numpy")
def closest_segment_triangle(p0, p1, a, b, c) -> tuple[float, float, float, float]:
    """A closest pair (s, u, v, w) of segment p0p1 (parameter s) and triangle abc.

    If the segment crosses the triangle the crossing is returned (distance 0). Otherwise a
    closest pair of these convex sets has an endpoint of the segment, or an edge of the
    triangle, in it (a pair of interiors is only closest when the segment is parallel to the
    plane, and then sliding it to an endpoint or an edge keeps the distance), so the answer is
    the nearest of the two endpoint-triangle and three segment-edge pairs.
    """
    ab = _sub(b, a)
    ac = _sub(c, a)
    n = _cross(ab, ac)
    nn = _dot(n, n)
    h0 = _dot(n, _sub(p0, a))
    h1 = _dot(n, _sub(p1, a))
    if nn > 0.0 and ((h0 <= 0.0 <= h1) or (h1 <= 0.0 <= h0)) and h0 != h1:
        s = h0 / (h0 - h1)
        x = lerp(p0, p1, s)
        # Signed sub-areas, exact in sign up to round-off: all >= 0 means x is inside.
        xa = _sub(a, x)
        xb = _sub(b, x)
        xc = _sub(c, x)
        u = _dot(n, _cross(xb, xc))
        v = _dot(n, _cross(xc, xa))
        w = _dot(n, _cross(xa, xb))
        if u >= 0.0 and v >= 0.0 and w >= 0.0 and u + v + w > 0.0:
            inv = 1.0 / (u + v + w)
            return s, u * inv, v * inv, w * inv
        # Crossing outside (or on) the boundary: the edge pairs below find it.

    u0, v0, w0 = closest_point_triangle(p0, a, b, c)
    best = dist2(p0, bary_point(a, b, c, u0, v0, w0))
    rs, ru, rv, rw = 0.0, u0, v0, w0

    u1, v1, w1 = closest_point_triangle(p1, a, b, c)
    d = dist2(p1, bary_point(a, b, c, u1, v1, w1))
    if d < best:
        best = d
        rs, ru, rv, rw = 1.0, u1, v1, w1

    s, t = closest_segment_segment(p0, p1, a, b)
    d = dist2(lerp(p0, p1, s), lerp(a, b, t))
    if d < best:
        best = d
        rs, ru, rv, rw = s, 1.0 - t, t, 0.0

    s, t = closest_segment_segment(p0, p1, b, c)
    d = dist2(lerp(p0, p1, s), lerp(b, c, t))
    if d < best:
        best = d
        rs, ru, rv, rw = s, 0.0, 1.0 - t, t

    s, t = closest_segment_segment(p0, p1, c, a)
    d = dist2(lerp(p0, p1, s), lerp(c, a, t))
    if d < best:
        rs, ru, rv, rw = s, t, 0.0, 1.0 - t
    return rs, ru, rv, rw


@njit(cache=True, inline="always", error_model="numpy")
def segment_triangle_dist2(p0, p1, point: bool, a, b, c) -> tuple[float, float, float, float,
                                                                     float]:
    """A closest pair (s, u, v, w) of segment p0p1 and triangle abc and its squared distance
    (m^2). ``point`` says that p0 == p1, which takes the much cheaper point-triangle test."""
    if point:
        u, v, w = closest_point_triangle(p0, a, b, c)
        return 0.0, u, v, w, dist2(p0, bary_point(a, b, c, u, v, w))
    s, u, v, w = closest_segment_triangle(p0, p1, a, b, c)
    return s, u, v, w, dist2(lerp(p0, p1, s), bary_point(a, b, c, u, v, w))
