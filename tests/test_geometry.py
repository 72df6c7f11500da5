"""Mesh geometry kernels: closest points, the triangle BVH and inside/outside by pseudonormals.

Closest-point routines are checked against dense sampling (the sampled minimum can only
overestimate the true distance, so a correct routine is never above it) and, for points and
triangles, against trimesh's independent implementation. The BVH query is checked against a
loop over all triangles, and the pseudonormal sign against generalized winding numbers.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from numba import njit

from deformx.engine.geometry.bvh import (
    MeshBVH,
    bvh_closest_segment,
    bvh_from_mesh,
    pseudonormals,
    signed_side,
)
from deformx.engine.geometry.closest import (
    bary_point,
    closest_point_segment,
    closest_point_triangle,
    closest_segment_segment,
    closest_segment_triangle,
    lerp,
)
from deformx.engine.geometry.faces import face_frames

N_CASES = 500
TOL = 1e-9  # m, round-off allowance on unit-sized inputs


def _t(x) -> tuple[float, float, float]:
    return (float(x[0]), float(x[1]), float(x[2]))


def _pt_seg_dist(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Exact distance from points p (..., 3) to segment ab (reference, numpy)."""
    ab = b - a
    den = ab @ ab
    t = np.zeros(p.shape[:-1]) if den == 0.0 else np.clip((p - a) @ ab / den, 0.0, 1.0)
    return np.linalg.norm(p - (a + t[..., None] * ab), axis=-1)


def _bary_grid(n: int) -> np.ndarray:
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    keep = i + j <= n
    u, v = i[keep] / n, j[keep] / n
    return np.stack([u, v, 1.0 - u - v], axis=1)


def _check_bary(u, v, w):
    assert min(u, v, w) >= 0.0
    assert abs(u + v + w - 1.0) < 1e-12


def _random_segments(rng, n, near_parallel):
    """Pairs of segments: general position, nearly parallel, and exactly parallel ones."""
    p0, p1, q0, q1 = (rng.uniform(-1, 1, (n, 3)) for _ in range(4))
    k = n // 3
    d = p1[:k] - p0[:k]
    q1[:k] = q0[:k] + d * rng.uniform(-1.5, 1.5, (k, 1)) + near_parallel * rng.normal(size=(k, 3))
    q1[k:2 * k] = q0[k:2 * k] + (p1[k:2 * k] - p0[k:2 * k]) * rng.uniform(-2, 2, (k, 1))
    return p0, p1, q0, q1


# ---------------------------------------------------------------------------- closest points


def test_point_segment_vs_sampling():
    rng = np.random.default_rng(1)
    samples = np.linspace(0.0, 1.0, 2001)[:, None]
    for _ in range(N_CASES):
        p, a, b = rng.uniform(-1, 1, (3, 3))
        t = closest_point_segment(_t(p), _t(a), _t(b))
        assert 0.0 <= t <= 1.0
        d = np.linalg.norm(p - (a + t * (b - a)))
        assert d <= np.linalg.norm(p - (a + samples * (b - a)), axis=1).min() + TOL
        assert d == pytest.approx(_pt_seg_dist(p, a, b), abs=TOL)
    assert closest_point_segment((1.0, 2.0, 3.0), (0.5, 0.5, 0.5), (0.5, 0.5, 0.5)) == 0.0


@pytest.mark.parametrize("near_parallel", [1e-1, 1e-9])
def test_segment_segment_vs_sampling(near_parallel):
    rng = np.random.default_rng(2)
    samples = np.linspace(0.0, 1.0, 2001)[:, None]
    p0, p1, q0, q1 = _random_segments(rng, N_CASES, near_parallel)
    for i in range(N_CASES):
        s, t = closest_segment_segment(_t(p0[i]), _t(p1[i]), _t(q0[i]), _t(q1[i]))
        assert 0.0 <= s <= 1.0 and 0.0 <= t <= 1.0
        d = np.linalg.norm(np.array(lerp(_t(p0[i]), _t(p1[i]), s)) - lerp(_t(q0[i]), _t(q1[i]), t))
        ref = min(_pt_seg_dist(p0[i] + samples * (p1[i] - p0[i]), q0[i], q1[i]).min(),
                  _pt_seg_dist(q0[i] + samples * (q1[i] - q0[i]), p0[i], p1[i]).min())
        assert d <= ref + TOL


def _seg_seg_dist(p0, p1, q0, q1) -> float:
    s, t = closest_segment_segment(p0, p1, q0, q1)
    return float(np.linalg.norm(np.subtract(lerp(p0, p1, s), lerp(q0, q1, t))))


def test_segment_segment_degenerate():
    x = (1.0, 0.0, 0.0)
    o = (0.0, 0.0, 0.0)
    # Parallel and overlapping: any pair at the line distance will do.
    assert _seg_seg_dist(o, x, (0.5, 1.0, 0.0), (2.0, 1.0, 0.0)) == pytest.approx(1.0, abs=1e-15)
    assert _seg_seg_dist(o, x, (2.0, 1.0, 0.0), (0.5, 1.0, 0.0)) == pytest.approx(1.0, abs=1e-15)
    # Collinear and disjoint, both orders and orientations.
    assert closest_segment_segment(o, x, (2.0, 0.0, 0.0), (3.0, 0.0, 0.0)) == (1.0, 0.0)
    assert closest_segment_segment(o, x, (3.0, 0.0, 0.0), (2.0, 0.0, 0.0)) == (1.0, 1.0)
    assert closest_segment_segment((2.0, 0.0, 0.0), (3.0, 0.0, 0.0), x, o) == (0.0, 0.0)
    # Parallel, one beyond the other's end: endpoint to endpoint.
    assert _seg_seg_dist(o, x, (2.0, 1.0, 0.0), (3.0, 1.0, 0.0)) == pytest.approx(np.sqrt(2.0))
    # Zero-length segments: point-segment and point-point.
    p = (0.3, 2.0, 0.0)
    s, t = closest_segment_segment(p, p, o, x)
    assert s == 0.0 and t == pytest.approx(0.3)
    s, t = closest_segment_segment(o, x, p, p)
    assert t == 0.0 and s == pytest.approx(0.3)
    assert closest_segment_segment(p, p, o, o) == (0.0, 0.0)
    # Crossing segments meet.
    assert _seg_seg_dist((0.5, -1.0, 0.0), (0.5, 1.0, 0.0), o, x) == pytest.approx(0.0, abs=1e-15)


def _random_triangles(rng, n):
    tri = rng.uniform(-1, 1, (n, 3, 3))
    k = n // 5  # thin slivers
    tri[:k, 2] = tri[:k, 0] + 0.5 * (tri[:k, 1] - tri[:k, 0]) + 1e-4 * rng.normal(size=(k, 3))
    return tri


def test_point_triangle_vs_trimesh_and_sampling():
    rng = np.random.default_rng(3)
    tri = _random_triangles(rng, N_CASES)
    pts = rng.uniform(-1.5, 1.5, (N_CASES, 3))
    ref = trimesh.triangles.closest_point(tri, pts)
    grid = _bary_grid(150)
    for i in range(N_CASES):
        a, b, c = tri[i]
        u, v, w = closest_point_triangle(_t(pts[i]), _t(a), _t(b), _t(c))
        _check_bary(u, v, w)
        d = np.linalg.norm(pts[i] - bary_point(_t(a), _t(b), _t(c), u, v, w))
        assert d == pytest.approx(np.linalg.norm(pts[i] - ref[i]), abs=TOL)
        assert d <= np.linalg.norm(pts[i] - grid @ tri[i], axis=1).min() + TOL


@pytest.mark.parametrize("tri", [
    [(0, 0, 0), (1, 0, 0), (2, 0, 0)],  # collinear, c beyond b
    [(0, 0, 0), (2, 0, 0), (1, 0, 0)],  # collinear, c between a and b
    [(1, 0, 0), (0, 0, 0), (0, 0, 0)],  # two corners coincide
    [(0, 0, 0), (0, 0, 0), (1, 1, 0)],
    [(0.3, 0.3, 0.3)] * 3,  # a point
])
def test_point_triangle_degenerate(tri):
    a, b, c = (tuple(float(x) for x in v) for v in tri)
    rng = np.random.default_rng(4)
    edges = [(np.array(a), np.array(b)), (np.array(b), np.array(c)), (np.array(c), np.array(a))]
    for p in rng.uniform(-2, 3, (200, 3)):
        u, v, w = closest_point_triangle(_t(p), a, b, c)
        _check_bary(u, v, w)
        d = np.linalg.norm(p - bary_point(a, b, c, u, v, w))
        assert d == pytest.approx(min(_pt_seg_dist(p, e0, e1) for e0, e1 in edges), abs=TOL)


def _seg_tri_dist(p0, p1, a, b, c) -> float:
    s, u, v, w = closest_segment_triangle(p0, p1, a, b, c)
    assert 0.0 <= s <= 1.0
    _check_bary(u, v, w)
    return float(np.linalg.norm(np.subtract(lerp(p0, p1, s), bary_point(a, b, c, u, v, w))))


def test_segment_triangle_vs_sampling():
    rng = np.random.default_rng(5)
    tri = _random_triangles(rng, N_CASES)
    p0 = rng.uniform(-1.5, 1.5, (N_CASES, 3))
    p1 = p0 + rng.uniform(-1, 1, (N_CASES, 3))
    n_cross = N_CASES // 4  # aim some through the triangle (may still miss near its edges)
    hit = (tri[:n_cross] * rng.dirichlet([1, 1, 1], n_cross)[:, :, None]).sum(axis=1)
    p0[:n_cross] = hit - 0.6 * (p1[:n_cross] - p0[:n_cross])
    p1[:n_cross] = hit + (p1[:n_cross] - hit) * 0.5
    samples = np.linspace(0.0, 1.0, 401)[:, None]
    seg_pts = p0[:, None, :] + samples[None] * (p1 - p0)[:, None, :]
    to_tri = trimesh.triangles.closest_point(np.repeat(tri, len(samples), axis=0),
                                             seg_pts.reshape(-1, 3))
    from_seg = np.linalg.norm(seg_pts.reshape(-1, 3) - to_tri, axis=1).reshape(N_CASES, -1)
    grid = _bary_grid(60)
    for i in range(N_CASES):
        d = _seg_tri_dist(_t(p0[i]), _t(p1[i]), *(_t(x) for x in tri[i]))
        ref = min(from_seg[i].min(), _pt_seg_dist(grid @ tri[i], p0[i], p1[i]).min())
        assert d <= ref + TOL


def test_segment_triangle_explicit_cases():
    a, b, c = (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)
    # Through the interior: the crossing point, at distance 0.
    s, u, v, w = closest_segment_triangle((0.2, 0.3, -1.0), (0.2, 0.3, 3.0), a, b, c)
    assert s == pytest.approx(0.25) and (u, v, w) == pytest.approx((0.5, 0.2, 0.3))
    # Oblique crossing.
    assert _seg_tri_dist((0.0, 0.0, -1.0), (0.5, 0.5, 1.0), a, b, c) == pytest.approx(0.0, abs=1e-15)
    # Parallel above the interior, and parallel above and beyond it.
    assert _seg_tri_dist((0.1, 0.1, 0.7), (0.3, 0.2, 0.7), a, b, c) == pytest.approx(0.7)
    assert _seg_tri_dist((-1.0, 0.2, 0.7), (3.0, 0.2, 0.7), a, b, c) == pytest.approx(0.7)
    # In the plane: through the triangle, and beside it.
    assert _seg_tri_dist((-1.0, 0.2, 0.0), (3.0, 0.2, 0.0), a, b, c) == pytest.approx(0.0, abs=1e-15)
    assert _seg_tri_dist((1.0, 1.0, 0.0), (2.0, 1.0, 0.0), a, b, c) == pytest.approx(np.sqrt(0.5))
    # Piercing the plane outside the triangle: its nearest point, here corner b.
    assert _seg_tri_dist((2.0, 0.5, -1.0), (2.0, 0.5, 1.0), a, b, c) == pytest.approx(np.sqrt(1.25))
    # Zero-length segment reduces to the point query.
    assert _seg_tri_dist((0.2, 0.2, 0.5), (0.2, 0.2, 0.5), a, b, c) == pytest.approx(0.5)
    # Degenerate (collinear) triangle: distance to its hull, a segment.
    flat = (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (2.0, 0.0, 0.0)
    assert _seg_tri_dist((0.5, -1.0, 1.0), (0.5, 1.0, 1.0), *flat) == pytest.approx(1.0)
    assert _seg_tri_dist((1.5, -1.0, 0.0), (1.5, 1.0, 0.0), *flat) == pytest.approx(0.0, abs=1e-15)


# ---------------------------------------------------------------------------- BVH


def _icosphere():
    m = trimesh.creation.icosphere(subdivisions=4)
    return np.asarray(m.vertices), np.asarray(m.faces, dtype=np.int64)


def _soup():
    rng = np.random.default_rng(6)
    n = 1500
    centres = rng.uniform(-1, 1, (n, 1, 3))
    v = (centres + 0.15 * rng.normal(size=(n, 3, 3))).reshape(-1, 3)
    return v, np.arange(3 * n, dtype=np.int64).reshape(n, 3)


@njit(cache=True)
def _brute_closest(vertices, faces, p0, p1):
    best = np.inf
    for f in range(faces.shape[0]):
        a = (vertices[faces[f, 0], 0], vertices[faces[f, 0], 1], vertices[faces[f, 0], 2])
        b = (vertices[faces[f, 1], 0], vertices[faces[f, 1], 1], vertices[faces[f, 1], 2])
        c = (vertices[faces[f, 2], 0], vertices[faces[f, 2], 1], vertices[faces[f, 2], 2])
        s, u, v, w = closest_segment_triangle(p0, p1, a, b, c)
        x = lerp(p0, p1, s)
        y = bary_point(a, b, c, u, v, w)
        best = min(best, (x[0] - y[0]) ** 2 + (x[1] - y[1]) ** 2 + (x[2] - y[2]) ** 2)
    return best


def _check_structure(bvh: MeshBVH, vertices, faces):
    n_faces = len(faces)
    assert np.array_equal(np.sort(bvh.order), np.arange(n_faces))
    leaf = bvh.left < 0
    assert np.array_equal(leaf, bvh.right < 0)
    assert np.all((bvh.count[leaf] >= 1) & (bvh.count[leaf] <= 4)) and np.all(bvh.count[~leaf] == 0)
    # Leaves tile ``order`` without overlap.
    covered = np.zeros(n_faces, dtype=int)
    for i in np.flatnonzero(leaf):
        covered[bvh.start[i]:bvh.start[i] + bvh.count[i]] += 1
        tri = vertices[faces[bvh.order[bvh.start[i]:bvh.start[i] + bvh.count[i]]]]
        assert np.all(tri.min(axis=(0, 1)) >= bvh.lo[i]) and np.all(tri.max(axis=(0, 1)) <= bvh.hi[i])
    assert np.all(covered == 1)
    inner = np.flatnonzero(~leaf)
    for child in (bvh.left[inner], bvh.right[inner]):
        assert np.all(bvh.lo[child] >= bvh.lo[inner]) and np.all(bvh.hi[child] <= bvh.hi[inner])
    # Every node but the root is some node's child, exactly once.
    children = np.concatenate([bvh.left[inner], bvh.right[inner]])
    assert np.array_equal(np.sort(children), np.arange(1, len(bvh.lo)))


@pytest.mark.parametrize("mesh", [_icosphere, _soup])
def test_bvh_matches_brute_force(mesh):
    vertices, faces = mesh()
    bvh = bvh_from_mesh(vertices, faces)
    _check_structure(bvh, vertices, faces)
    rng = np.random.default_rng(7)
    n = 300
    p0 = rng.uniform(-1.4, 1.4, (n, 3))
    p1 = p0 + rng.normal(scale=0.3, size=(n, 3))
    p1[:30] = p0[:30]  # point queries
    n_none = 0
    for i in range(n):
        a, b = _t(p0[i]), _t(p1[i])
        ref = _brute_closest(vertices, faces, a, b)
        for max_dist in (np.inf, 0.05):
            tri, s, u, v, w, d2 = bvh_closest_segment(*bvh, vertices, faces, a, b, max_dist)
            if ref > max_dist**2:
                assert tri == -1 and d2 == np.inf
                n_none += 1
                continue
            assert tri >= 0 and abs(d2 - ref) <= 1e-12
            # The returned pair is a real pair on triangle ``tri`` at that distance.
            corners = [_t(x) for x in vertices[faces[tri]]]
            x = np.subtract(lerp(a, b, s), bary_point(*corners, u, v, w))
            assert x @ x == pytest.approx(d2, rel=1e-12, abs=1e-15)
    assert n_none > 20  # the finite search radius was exercised


def test_bvh_far_query_and_small_meshes():
    vertices, faces = _icosphere()
    bvh = bvh_from_mesh(vertices, faces)
    far = (10.0, 0.0, 0.0)
    assert bvh_closest_segment(*bvh, vertices, faces, far, far, 1.0)[0] == -1
    tri, *_, d2 = bvh_closest_segment(*bvh, vertices, faces, far, far, 9.0)  # exactly at max_dist
    assert tri >= 0 and d2 == pytest.approx(81.0)
    # One triangle; and many copies of one triangle (all centroids equal) still split evenly.
    v = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    one = bvh_from_mesh(v, [[0, 1, 2]])
    assert len(one.lo) == 1 and one.count[0] == 1
    same = bvh_from_mesh(v, np.tile([0, 1, 2], (1000, 1)))
    _check_structure(same, v, np.tile([0, 1, 2], (1000, 1)))
    p = (0.2, 0.2, 1.0)
    tri, *_, d2 = bvh_closest_segment(*same, v, np.tile([0, 1, 2], (1000, 1)), p, p, np.inf)
    assert 0 <= tri < 1000 and d2 == pytest.approx(1.0)


def test_bvh_from_mesh_validation():
    v = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    f = np.array([[0, 1, 2]])
    bad_v = v.copy()
    bad_v[1, 2] = np.nan
    with pytest.raises(ValueError, match="vertices"):
        bvh_from_mesh(bad_v, f)
    with pytest.raises(ValueError, match="vertices"):
        bvh_from_mesh(np.full((3, 3), np.inf), f)
    with pytest.raises(ValueError, match="vertices"):
        bvh_from_mesh(np.zeros((0, 3)), f)
    with pytest.raises(ValueError, match="vertices"):
        bvh_from_mesh(v[:, :2], f)
    with pytest.raises(ValueError, match="faces"):
        bvh_from_mesh(v, [[0, 1, 3]])
    with pytest.raises(ValueError, match="faces"):
        bvh_from_mesh(v, [[0, -1, 2]])
    with pytest.raises(ValueError, match="faces"):
        bvh_from_mesh(v, np.zeros((0, 3), dtype=np.int64))
    with pytest.raises(ValueError, match="faces"):
        bvh_from_mesh(v, [[0, 1]])
    with pytest.raises(ValueError, match="faces"):
        bvh_from_mesh(v, [[0.0, 1.0, 2.0]])


# ---------------------------------------------------------------------------- inside / outside


def _winding(vertices, faces, points) -> np.ndarray:
    """Generalized winding number (1 inside, 0 outside a closed mesh), Van Oosterom-Strackee."""
    r = vertices[faces][None] - points[:, None, None, :]  # (P, F, 3, 3)
    a, b, c = r[:, :, 0], r[:, :, 1], r[:, :, 2]
    la, lb, lc = (np.linalg.norm(x, axis=-1) for x in (a, b, c))
    det = np.einsum("pfk,pfk->pf", a, np.cross(b, c))
    den = (la * lb * lc + np.einsum("pfk,pfk->pf", a, b) * lc
           + np.einsum("pfk,pfk->pf", a, c) * lb + np.einsum("pfk,pfk->pf", b, c) * la)
    return np.arctan2(det, den).sum(axis=1) / (2.0 * np.pi)


def _star():
    """A closed non-convex mesh: an icosphere with every other vertex pulled in."""
    m = trimesh.creation.icosphere(subdivisions=2)
    v = np.array(m.vertices)
    v[::2] *= 0.6
    return v, np.asarray(m.faces, dtype=np.int64)


def _mesh_of(name):
    if name == "star":
        return _star()
    m = {"icosphere": trimesh.creation.icosphere(subdivisions=3),
         "box": trimesh.creation.box(),
         "torus": trimesh.creation.torus(major_radius=0.7, minor_radius=0.3)}[name]
    return np.asarray(m.vertices), np.asarray(m.faces, dtype=np.int64)


def _sides(vertices, faces, points):
    """signed_side of each point with the feature (0 face, 1 edge, 2 vertex) it used."""
    bvh = bvh_from_mesh(vertices, faces)
    face_n, edge_n, vertex_n = pseudonormals(vertices, faces)
    out, feature = [], []
    for p in points:
        p = _t(p)
        tri, _, u, v, w, _ = bvh_closest_segment(*bvh, vertices, faces, p, p, np.inf)
        c = bary_point(*(_t(x) for x in vertices[faces[tri]]), u, v, w)
        out.append(signed_side(face_n, edge_n, vertex_n, faces, tri, u, v, w, p, c))
        feature.append(int(sum(x <= 1e-6 for x in (u, v, w))))
    return np.array(out), np.array(feature)


@pytest.mark.parametrize("name", ["icosphere", "box", "torus", "star"])
def test_signed_side_matches_winding_number(name):
    vertices, faces = _mesh_of(name)
    rng = np.random.default_rng(8)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    pts = [rng.uniform(lo - 0.3, hi + 0.3, (300, 3))]
    # Near vertices (closest feature: the vertex or its edges), both sides.
    _, _, vertex_n = pseudonormals(vertices, faces)
    idx = rng.choice(len(vertices), 100)
    off = rng.uniform(-0.05, 0.05, (100, 1)) * (vertex_n[idx] + 0.5 * rng.normal(size=(100, 3)))
    pts.append(vertices[idx] + off)
    # Near edge midpoints, both sides.
    e = rng.integers(0, len(faces), 100)
    mid = 0.5 * (vertices[faces[e, 0]] + vertices[faces[e, 1]])
    pts.append(mid + rng.normal(scale=0.03, size=(100, 3)))
    pts = np.concatenate(pts)
    wn = _winding(vertices, faces, pts)
    clear = np.abs(wn - 0.5) > 0.45  # skip points too close to the surface to call
    sign, feature = _sides(vertices, faces, pts[clear])
    np.testing.assert_array_equal(sign, np.where(wn[clear] > 0.5, -1.0, 1.0))
    assert np.sum(feature == 1) >= 10 and np.sum(feature == 2) >= 10  # edges and vertices used


def test_signed_side_box_analytic():
    vertices, faces = _mesh_of("box")  # unit cube centred at the origin
    corner = np.array([0.5, 0.5, 0.5])
    pts = np.array([
        corner + 0.1,  # outside, closest feature a vertex
        corner + [0.1, 0.1, -0.2],  # outside, an edge
        corner + [0.1, -0.2, -0.2],  # outside, a face
        corner - 0.01,  # inside, near a corner
        [0.49, 0.49, 0.0],  # inside, near an edge
        [0.0, 0.0, 0.0],  # inside, centre
        [0.2, 0.2, 0.49],  # inside, near a face diagonal (a flat edge of the triangulation)
        [0.2, 0.2, 0.51],  # outside, above the same diagonal
    ])
    sign, feature = _sides(vertices, faces, pts)
    np.testing.assert_array_equal(sign, [1, 1, 1, -1, -1, -1, -1, 1])
    assert feature[0] == 2 and feature[1] == 1 and feature[2] == 0


def test_pseudonormals_open_mesh_and_convention():
    # Two consistently wound triangles folded at a right angle along the edge (0, 1), normals
    # +z and -y: an open mesh.
    v = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]])
    f = np.array([[0, 1, 2], [1, 0, 3]])
    face_n, edge_n, vertex_n = pseudonormals(v, f)
    np.testing.assert_allclose(face_n, [[0, 0, 1], [0, -1, 0]], atol=1e-15)
    shared = np.array([0.0, -1.0, 1.0]) / np.sqrt(2.0)
    np.testing.assert_allclose(edge_n[0, 0], shared, atol=1e-15)  # edge 0 joins corners 0, 1
    np.testing.assert_allclose(edge_n[1, 0], shared, atol=1e-15)
    np.testing.assert_allclose(edge_n[0, 1], face_n[0], atol=1e-15)  # open edges
    np.testing.assert_allclose(edge_n[1, 2], face_n[1], atol=1e-15)
    # Vertex 0: angle pi/2 in both faces, so the plain mean of the two normals.
    np.testing.assert_allclose(vertex_n[0], shared, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(vertex_n, axis=1), 1.0)


def test_face_frames_give_heights_and_projection_barycentrics():
    """Per-face affine maps against direct geometry and trimesh's barycentric coordinates;
    degenerate faces never contain a point."""
    rng = np.random.default_rng(5)
    tri = rng.normal(size=(50, 3, 3))
    V = tri.reshape(-1, 3)
    F = np.arange(150).reshape(50, 3)
    G = face_frames(V, F)
    x = rng.normal(size=(50, 3))
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    height = np.einsum("ij,ij->i", G[:, 0, :3], x) - G[:, 0, 3]
    np.testing.assert_allclose(height, np.einsum("ij,ij->i", x - tri[:, 0], n), atol=1e-12)
    v = np.einsum("ij,ij->i", G[:, 1, :3], x) - G[:, 1, 3]
    w = np.einsum("ij,ij->i", G[:, 2, :3], x) - G[:, 2, 3]
    expected = trimesh.triangles.points_to_barycentric(tri, x - height[:, None] * n)
    np.testing.assert_allclose(np.column_stack([1.0 - v - w, v, w]), expected, atol=1e-9)

    flat = face_frames(np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0]]), np.array([[0, 1, 2]]))
    assert np.all(np.isnan(flat))
