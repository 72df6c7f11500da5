"""Analytic primitives: a rope hangs over (or lies on) each shape, both integrators.

References: statics (the shape carries the weight of a rope resting on it alone), exact analytic
distances to each shape (no penetration beyond the penalty's elastic compression), and the
shapes' signed-distance kernels against dense sampling.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import deformx as dx
from deformx.engine.contact.primitives import (
    BOX,
    CAPSULE,
    CYLINDER,
    SPHERE,
    bounding_gap,
    segment_deepest,
    shape_sdf,
    tangent_bound,
)

SETUPS = {"verlet": 2e-5, "stable": 1e-3}
# A shape of each kind (its parameters, m) for the query-function checks below.
SHAPES = [(SPHERE, (0.05, 0, 0)), (BOX, (0.2, 0.1, 0.05)), (CAPSULE, (0.05, 0.2, 0)),
          (CYLINDER, (0.05, 0.2, 0))]
R = 0.002
G = 9.81
ROT_X = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # local z -> world y


def analytic_distance(kind: str, p: np.ndarray) -> np.ndarray:
    """Signed distance (m) of world points to the shapes placed by ``add_shape`` below."""
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    if kind == "sphere":
        return np.sqrt(x**2 + y**2 + z**2) - 0.05
    if kind == "cylinder":  # axis along y, radius 0.05, length 0.4
        rho = np.sqrt(x**2 + z**2)
        qr, qy = rho - 0.05, np.abs(y) - 0.2
        outside = np.sqrt(np.maximum(qr, 0) ** 2 + np.maximum(qy, 0) ** 2)
        return outside + np.minimum(np.maximum(qr, qy), 0)
    if kind == "capsule":  # axis along y, radius 0.05, length 0.4
        yc = np.clip(y, -0.2, 0.2)
        return np.sqrt(x**2 + (y - yc) ** 2 + z**2) - 0.05
    q = np.abs(p) - np.array([0.2, 0.2, 0.05])  # box
    return np.linalg.norm(np.maximum(q, 0), axis=1) + np.minimum(q.max(axis=1), 0)


def add_shape(world: dx.World, kind: str):
    if kind == "sphere":
        return world.add_sphere(0.05, friction=0.5)
    if kind == "box":
        return world.add_box((0.2, 0.2, 0.05), friction=0.5)
    if kind == "capsule":
        return world.add_capsule(0.05, 0.4, pose=((0, 0, 0), ROT_X), friction=0.5)
    return world.add_cylinder(0.05, 0.4, pose=((0, 0, 0), ROT_X), friction=0.5)


@pytest.mark.parametrize("integrator", sorted(SETUPS))
@pytest.mark.parametrize("kind", ["sphere", "box", "capsule", "cylinder"])
def test_rope_rests_on_primitive(kind, integrator):
    world = dx.World(dt=SETUPS[integrator], integrator=integrator)
    rod = world.add_rod(dx.Rod.straight(n_elements=24, start=(-0.12, 0.004, 0.0535),
                                        direction=(1, 0, 0), length=0.24, radius=R,
                                        youngs_modulus=1e6, density=1000.0, damping=3.0))
    shape = add_shape(world, kind)
    worst = np.inf
    for _ in range(20):
        world.run(0.04)
        t = np.linspace(0, 1, 11)[None, :, None]
        x = rod.positions
        pts = (x[:-1, None] * (1 - t) + x[1:, None] * t).reshape(-1, 3)
        worst = min(worst, analytic_distance(kind, pts).min())
    assert worst >= 0.9 * R, f"{kind}: a segment came {worst * 1e3:.3f} mm from the surface"
    rod.damping = 30.0  # settle the swinging ends quickly, then weigh
    world.run(0.5)
    assert shape.force[2] == pytest.approx(-rod.mass * G, rel=0.01)
    # Symmetric drape over the shape's top: no net torque about the vertical... and the
    # rope's ends hang below the top.
    if kind != "box":
        assert rod.positions[0, 2] < 0.03 and rod.positions[-1, 2] < 0.03


def _sdf_along(kind, par, a, b, t) -> np.ndarray:
    """The shape's signed distance (m) at the points a + t (b - a) of a segment."""
    return np.array([shape_sdf(kind, par, *(a + ti * (b - a)))[0] for ti in t])


def _random_segments(rng: np.random.Generator, n: int, spread: float, length: float):
    """n segments (a, b) drawn from ``rng``: a uniform in a cube of half-side ``spread`` (m),
    b - a normal with scale ``length`` (m)."""
    for _ in range(n):
        a = rng.uniform(-spread, spread, 3)
        yield a, a + rng.normal(scale=length, size=3)


@pytest.mark.parametrize("kind,params", SHAPES)
def test_segment_deepest_point_matches_dense_sampling(kind, params):
    rng = np.random.default_rng(kind)
    par = np.array(params, dtype=float)
    t = np.linspace(0, 1, 1001)
    for a, b in _random_segments(rng, 60, 0.3, 0.2):
        s = segment_deepest(kind, par, *a, *b)
        f = shape_sdf(kind, par, *(a + s * (b - a)))[0]
        fine = _sdf_along(kind, par, a, b, t)
        assert f <= fine.min() + 1e-9, (kind, a, b, s)
        assert segment_deepest(kind, par, *a, *a) == 0.0  # a node's query: a point
    # Normals are unit and point along the distance gradient.
    for _ in range(100):
        p = rng.uniform(-0.3, 0.3, 3)
        d, n0, n1, n2 = shape_sdf(kind, par, *p)
        n = np.array([n0, n1, n2])
        assert np.linalg.norm(n) == pytest.approx(1.0, abs=1e-12)
        h = 1e-6
        d2 = shape_sdf(kind, par, *(p + h * n))[0]
        assert (d2 - d) / h == pytest.approx(1.0, abs=1e-3)


@pytest.mark.parametrize("kind,params", SHAPES)
def test_bounding_gap_never_exceeds_the_segments_least_signed_distance(kind, params):
    """The early-out of shape contact (a segment farther from the shape's bounding ball than
    the contact reach is skipped) must never skip a segment that comes within reach."""
    par = np.array(params, dtype=float)
    t = np.linspace(0, 1, 1001)
    gaps = []
    for a, b in _random_segments(np.random.default_rng(10 + kind), 200, 0.6, 0.2):
        bound = bounding_gap(kind, par, *a, *b)
        least = _sdf_along(kind, par, a, b, t).min()
        assert bound <= least + 1e-12, (kind, a, b)
        gaps.append(least - bound)
    if kind == SPHERE:  # the ball is the sphere: exact up to the sampling
        assert max(gaps) < 1e-6
    assert np.median(gaps) < 0.25  # a bound, but not a vacuous one


@pytest.mark.parametrize("kind,params", SHAPES)
def test_tangent_bound_never_exceeds_the_segments_least_signed_distance(kind, params):
    """The end-of-step check of segments skips those whose tangent bound (the shape's signed
    distance is convex) lies beyond the depth it looks for: it must be a true lower bound, and
    exact for a segment whose deepest point is an end."""
    par = np.array(params, dtype=float)
    t = np.linspace(0, 1, 1001)
    for a, b in _random_segments(np.random.default_rng(20 + kind), 200, 0.3, 0.05):
        bound = tangent_bound(kind, par, *a, *b)
        f = _sdf_along(kind, par, a, b, t)
        assert bound <= f.min() + 1e-12, (kind, a, b)
        if f.argmin() in (0, t.size - 1) and f.min() > 0.0:
            assert bound == pytest.approx(f.min(), abs=1e-12)
    # A 1 cm segment lying 2 mm off a flat side, along it: the bound is that gap (so a rope
    # resting on the shape is not searched).
    if kind == BOX:
        a, b = np.array([-0.004, 0.0, 0.052]), np.array([0.006, 0.0, 0.052])
    else:  # beside the side of the sphere, capsule, cylinder (axis z)
        a, b = np.array([0.052, 0.0, -0.004]), np.array([0.052, 0.0, 0.006])
    gap = 0.002 if kind != SPHERE else 0.0017  # (the sphere's side curves away)
    assert tangent_bound(kind, par, *a, *b) == pytest.approx(gap, abs=1e-4)


def test_primitive_input_validation():
    world = dx.World()
    with pytest.raises(ValueError, match="radius"):
        world.add_sphere(-1.0)
    with pytest.raises(ValueError, match="half_extents"):
        world.add_box((0.1, 0.0, 0.1))
    with pytest.raises(ValueError, match="length"):
        world.add_cylinder(0.1, 0.0)
    with pytest.raises(ValueError, match="unknown contact parameter"):
        world.add_capsule(0.1, 0.2, stiffnes=3.0)
    with pytest.raises(ValueError, match="rotation"):
        world.add_box((0.1, 0.1, 0.1), pose=((0, 0, 0), 2 * np.eye(3)))
    c = world.add_box((0.1, 0.1, 0.1), pose=(0.0, 0.0, 1.0))
    c.set_pose(position=(1.0, 2.0, 3.0), rotation=ROT_X)
    np.testing.assert_allclose(c.pose[:3, 3], (1, 2, 3))
    assert math.isclose(np.linalg.det(c.pose[:3, :3]), 1.0)
