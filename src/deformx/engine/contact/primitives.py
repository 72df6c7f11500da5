"""Analytic convex colliders in their local frame: signed distance and outward normal.

Shapes are centred at the local origin; capsules and cylinders lie along the local z axis.
The signed distance of a convex shape is a convex function, so along a rod segment it has one
minimum: the deepest point of the segment is found by a golden-section search (exact closed
forms for the sphere and capsule, whose distance is that to a point or a segment).
"""

from __future__ import annotations

import math

from numba import njit

from ..geometry.closest import closest_point_segment, closest_segment_segment, dist2, lerp

SPHERE, BOX, CAPSULE, CYLINDER = 1, 2, 3, 4
_GOLDEN = 0.6180339887498949
_LOG_GOLDEN = math.log(_GOLDEN)
_ORIGIN = (0.0, 0.0, 0.0)
_SEARCH_STEPS = 48  # golden-section steps at most: the bracket shrinks to 1e-10 of the segment
# The search stops once the bracket is this short (m): at a kink of the distance (a box's edge)
# the deepest distance found is then within twice this, elsewhere within far less.
_SEARCH_TOL = 1e-10


@njit(cache=True, error_model="numpy")
def _box_sdf(x, y, z, hx, hy, hz):
    """Signed distance (m) and outward unit normal of a point to a box of half extents h."""
    qx = abs(x) - hx
    qy = abs(y) - hy
    qz = abs(z) - hz
    if qx <= 0.0 and qy <= 0.0 and qz <= 0.0:  # inside: the nearest face
        if qx >= qy and qx >= qz:
            return qx, math.copysign(1.0, x), 0.0, 0.0
        if qy >= qz:
            return qy, 0.0, math.copysign(1.0, y), 0.0
        return qz, 0.0, 0.0, math.copysign(1.0, z)
    ox = max(qx, 0.0)
    oy = max(qy, 0.0)
    oz = max(qz, 0.0)
    d = math.sqrt(ox * ox + oy * oy + oz * oz)
    return d, math.copysign(ox / d, x), math.copysign(oy / d, y), math.copysign(oz / d, z)


@njit(cache=True, error_model="numpy")
def _cylinder_sdf(x, y, z, radius, half):
    """Signed distance and outward normal to a capped cylinder along z."""
    rho = math.sqrt(x * x + y * y)
    if rho > 1e-300:
        ux, uy = x / rho, y / rho
    else:
        ux, uy = 1.0, 0.0
    qr = rho - radius
    qz = abs(z) - half
    sz = math.copysign(1.0, z)
    if qr <= 0.0 and qz <= 0.0:
        if qr >= qz:
            return qr, ux, uy, 0.0
        return qz, 0.0, 0.0, sz
    orr = max(qr, 0.0)
    oz = max(qz, 0.0)
    d = math.sqrt(orr * orr + oz * oz)
    return d, ux * orr / d, uy * orr / d, sz * oz / d


@njit(cache=True, error_model="numpy")
def _capsule_sdf(x, y, z, radius, half):
    zc = min(max(z, -half), half)
    dz = z - zc
    d = math.sqrt(x * x + y * y + dz * dz)
    if d > 1e-300:
        return d - radius, x / d, y / d, dz / d
    return -radius, 1.0, 0.0, 0.0


@njit(cache=True, error_model="numpy")
def shape_sdf(kind, params, x, y, z):
    """Signed distance (m, < 0 inside) and outward normal of local point (x, y, z).

    ``params``: sphere (radius), box (hx, hy, hz), capsule / cylinder (radius, half length).
    """
    if kind == SPHERE:
        d = math.sqrt(x * x + y * y + z * z)
        if d > 1e-300:
            return d - params[0], x / d, y / d, z / d
        return -params[0], 0.0, 0.0, 1.0
    if kind == BOX:
        return _box_sdf(x, y, z, params[0], params[1], params[2])
    if kind == CAPSULE:
        return _capsule_sdf(x, y, z, params[0], params[1])
    return _cylinder_sdf(x, y, z, params[0], params[1])


@njit(cache=True, error_model="numpy")
def bounding_gap(kind, params, a0, a1, a2, b0, b1, b2):
    """A lower bound (m) of the signed distance along local segment ab: its distance to the
    origin less the radius of a ball about the origin that holds the shape."""
    if kind == SPHERE:
        radius = params[0]
    elif kind == BOX:
        radius = math.sqrt(params[0] * params[0] + params[1] * params[1] + params[2] * params[2])
    elif kind == CAPSULE:
        radius = params[0] + params[1]
    else:
        radius = math.sqrt(params[0] * params[0] + params[1] * params[1])
    a, b = (a0, a1, a2), (b0, b1, b2)
    return math.sqrt(dist2(lerp(a, b, closest_point_segment(_ORIGIN, a, b)), _ORIGIN)) - radius


@njit(cache=True, error_model="numpy")
def tangent_bound(kind, params, a0, a1, a2, b0, b1, b2):
    """A lower bound (m) of the signed distance along local segment ab from its ends' distances
    and normals alone: a convex shape's signed distance is convex, so it lies above its tangent
    lines at both ends (two closed-form queries instead of a search)."""
    fa, na0, na1, na2 = shape_sdf(kind, params, a0, a1, a2)
    fb, nb0, nb1, nb2 = shape_sdf(kind, params, b0, b1, b2)
    d0, d1, d2 = b0 - a0, b1 - a1, b2 - a2
    ga = na0 * d0 + na1 * d1 + na2 * d2  # slopes (m per unit s) at a and at b
    gb = nb0 * d0 + nb1 * d1 + nb2 * d2
    # max(fa + ga s, fb - gb (1 - s)) is least at an end or where the two lines cross
    low = min(max(fa, fb - gb), max(fa + ga, fb))
    if gb > ga:
        s = (fb - gb - fa) / (ga - gb)
        if 0.0 < s < 1.0:
            low = min(low, fa + ga * s)
    return low


@njit(cache=True, error_model="numpy")
def segment_deepest(kind, params, a0, a1, a2, b0, b1, b2):
    """Parameter s in [0, 1] of the point of local segment ab with the least signed distance."""
    if kind == SPHERE:  # distance to a point: closed form
        return closest_point_segment(_ORIGIN, (a0, a1, a2), (b0, b1, b2))
    if kind == CAPSULE:  # distance to the axis segment: closed form
        half = params[1]
        return closest_segment_segment((a0, a1, a2), (b0, b1, b2), (0.0, 0.0, -half),
                                       (0.0, 0.0, half))[0]
    length = math.sqrt((b0 - a0) ** 2 + (b1 - a1) ** 2 + (b2 - a2) ** 2)
    if length <= _SEARCH_TOL:  # a point (a node's query): nothing to search
        return 0.0
    # The signed distance is convex: where it does not fall from an end towards the other, that
    # end is the deepest (most segments of a rope lying on a shape: two queries, not ~40).
    fa, na0, na1, na2 = shape_sdf(kind, params, a0, a1, a2)
    if na0 * (b0 - a0) + na1 * (b1 - a1) + na2 * (b2 - a2) >= 0.0:
        return 0.0
    fb, nb0, nb1, nb2 = shape_sdf(kind, params, b0, b1, b2)
    if nb0 * (b0 - a0) + nb1 * (b1 - a1) + nb2 * (b2 - a2) <= 0.0:
        return 1.0
    steps = min(_SEARCH_STEPS, int(math.ceil(math.log(_SEARCH_TOL / length) / _LOG_GOLDEN)))
    lo, hi = 0.0, 1.0
    x1 = hi - _GOLDEN * (hi - lo)
    x2 = lo + _GOLDEN * (hi - lo)
    f1 = shape_sdf(kind, params, a0 + x1 * (b0 - a0), a1 + x1 * (b1 - a1), a2 + x1 * (b2 - a2))[0]
    f2 = shape_sdf(kind, params, a0 + x2 * (b0 - a0), a1 + x2 * (b1 - a1), a2 + x2 * (b2 - a2))[0]
    for _ in range(steps):
        if f1 <= f2:
            hi = x2
            x2, f2 = x1, f1
            x1 = hi - _GOLDEN * (hi - lo)
            f1 = shape_sdf(kind, params, a0 + x1 * (b0 - a0), a1 + x1 * (b1 - a1),
                           a2 + x1 * (b2 - a2))[0]
        else:
            lo = x1
            x1, f1 = x2, f2
            x2 = lo + _GOLDEN * (hi - lo)
            f2 = shape_sdf(kind, params, a0 + x2 * (b0 - a0), a1 + x2 * (b1 - a1),
                           a2 + x2 * (b2 - a2))[0]
    # The ends can be the minimum of a convex function that is flat there.
    s = 0.5 * (lo + hi)
    fs = shape_sdf(kind, params, a0 + s * (b0 - a0), a1 + s * (b1 - a1), a2 + s * (b2 - a2))[0]
    if fa <= fs and fa <= fb:
        return 0.0
    if fb <= fs:
        return 1.0
    return s
