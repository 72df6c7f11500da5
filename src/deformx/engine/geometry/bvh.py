"""Static bounding-volume hierarchy over a triangle mesh, and inside/outside by pseudonormals.

The tree lives in flat arrays in the mesh's local frame (m): node ``i`` has the box
``lo[i]``-``hi[i]`` of its triangles; an inner node has children ``left[i]`` and ``right[i]``
(``-1`` at a leaf) and a leaf owns the triangles ``order[start[i]:start[i] + count[i]]``.
Node 0 is the root. The build splits at the median centroid along the longest axis of the
centroid bounds, so the tree is balanced (depth <= log2(F) + 1) and a small fixed traversal
stack always suffices.

Edge convention for the pseudonormals: edge ``i`` of a face joins its corners ``i`` and
``(i + 1) % 3``, i.e. edge 0 is where ``w = 0``, edge 1 where ``u = 0``, edge 2 where ``v = 0``
for barycentrics ``(u, v, w)`` on corners ``(0, 1, 2)``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from deformx.engine.geometry.closest import (
    bary_point,
    closest_point_segment,
    dist2,
    lerp,
    segment_triangle_dist2,
)

LEAF_SIZE = 4  # triangles per leaf at most
TRAVERSAL_STACK = 64  # entries; a balanced tree of F triangles needs about log2(F)
# Barycentric below this fraction of u + v + w counts as zero when picking the closest feature;
# far above round-off, and harmless when wrong (a nearby feature's pseudonormal has the same
# sign of dot(p - c, n) unless the surface folds back on itself there).
_FEATURE_TOL = 1e-6


class MeshBVH(NamedTuple):
    """Flat BVH arrays (see the module docstring); ``N`` nodes over ``F`` triangles."""

    lo: np.ndarray  # (N, 3) float64, box minimum (m)
    hi: np.ndarray  # (N, 3) float64, box maximum (m)
    left: np.ndarray  # (N,) int64, left child or -1 at a leaf
    right: np.ndarray  # (N,) int64, right child or -1 at a leaf
    start: np.ndarray  # (N,) int64, first slot of a leaf in ``order``
    count: np.ndarray  # (N,) int64, triangles of a leaf (0 for inner nodes)
    order: np.ndarray  # (F,) int64, triangle ids grouped by leaf


@njit(cache=True, error_model="numpy")
def _select(order: np.ndarray, key: np.ndarray, lo: int, hi: int, k: int) -> None:
    """Reorders ``order[lo:hi]`` in place so that slot k holds the k-th smallest key, with no
    larger key before it and no smaller one after it (quickselect, Hoare partition)."""
    hi -= 1
    while hi > lo:
        # Median of three as the pivot keeps sorted and mirrored inputs linear.
        mid = (lo + hi) // 2
        ka = key[order[lo]]
        kb = key[order[mid]]
        kc = key[order[hi]]
        if ka < kb:
            pivot = kb if kb < kc else max(ka, kc)
        else:
            pivot = ka if ka < kc else max(kb, kc)
        i = lo
        j = hi
        while i <= j:
            while key[order[i]] < pivot:
                i += 1
            while key[order[j]] > pivot:
                j -= 1
            if i <= j:
                tmp = order[i]
                order[i] = order[j]
                order[j] = tmp
                i += 1
                j -= 1
        # Now keys in [lo, j] <= pivot <= keys in [i, hi], and slots j+1..i-1 equal the pivot.
        if k <= j:
            hi = j
        elif k >= i:
            lo = i
        else:
            return


@njit(cache=True, error_model="numpy")
def build_bvh(vertices: np.ndarray, faces: np.ndarray):
    """Builds the BVH of triangles ``vertices[faces]``; returns (lo, hi, left, right, start,
    count, order) as described in the module docstring. Expects validated input."""
    n_faces = faces.shape[0]
    tlo = np.empty((n_faces, 3))
    thi = np.empty((n_faces, 3))
    cen = np.empty((3, n_faces))  # per-axis rows, so a split reads one contiguous key array
    for f in range(n_faces):
        for k in range(3):
            x0 = vertices[faces[f, 0], k]
            x1 = vertices[faces[f, 1], k]
            x2 = vertices[faces[f, 2], k]
            tlo[f, k] = min(x0, x1, x2)
            thi[f, k] = max(x0, x1, x2)
            cen[k, f] = (x0 + x1 + x2) / 3.0
    # Median splits of more than LEAF_SIZE (>= 4) triangles leave >= 2 per leaf, so there are
    # at most F / 2 leaves and F - 1 nodes (one node when F <= LEAF_SIZE).
    max_nodes = max(n_faces, 1)
    lo = np.empty((max_nodes, 3))
    hi = np.empty((max_nodes, 3))
    left = np.full(max_nodes, -1, dtype=np.int64)
    right = np.full(max_nodes, -1, dtype=np.int64)
    start = np.zeros(max_nodes, dtype=np.int64)
    count = np.zeros(max_nodes, dtype=np.int64)
    order = np.arange(n_faces, dtype=np.int64)

    stack = np.empty(TRAVERSAL_STACK, dtype=np.int64)
    start[0] = 0
    count[0] = n_faces
    n_nodes = 1
    stack[0] = 0
    sp = 1
    while sp > 0:
        sp -= 1
        node = stack[sp]
        s0 = start[node]
        n = count[node]
        blo0 = blo1 = blo2 = np.inf
        bhi0 = bhi1 = bhi2 = -np.inf
        clo0 = clo1 = clo2 = np.inf
        chi0 = chi1 = chi2 = -np.inf
        for i in range(s0, s0 + n):
            f = order[i]
            blo0 = min(blo0, tlo[f, 0])
            blo1 = min(blo1, tlo[f, 1])
            blo2 = min(blo2, tlo[f, 2])
            bhi0 = max(bhi0, thi[f, 0])
            bhi1 = max(bhi1, thi[f, 1])
            bhi2 = max(bhi2, thi[f, 2])
            clo0 = min(clo0, cen[0, f])
            clo1 = min(clo1, cen[1, f])
            clo2 = min(clo2, cen[2, f])
            chi0 = max(chi0, cen[0, f])
            chi1 = max(chi1, cen[1, f])
            chi2 = max(chi2, cen[2, f])
        lo[node, 0] = blo0
        lo[node, 1] = blo1
        lo[node, 2] = blo2
        hi[node, 0] = bhi0
        hi[node, 1] = bhi1
        hi[node, 2] = bhi2
        if n <= LEAF_SIZE:
            continue
        e0 = chi0 - clo0
        e1 = chi1 - clo1
        e2 = chi2 - clo2
        axis = 0
        if e1 > e0 and e1 >= e2:
            axis = 1
        elif e2 > e0 and e2 > e1:
            axis = 2
        # Median split: balanced even when all centroids coincide, so the depth stays bounded.
        half = n // 2
        _select(order, cen[axis], s0, s0 + n, s0 + half)
        a = n_nodes
        b = n_nodes + 1
        n_nodes += 2
        left[node] = a
        right[node] = b
        start[a] = s0
        count[a] = half
        start[b] = s0 + half
        count[b] = n - half
        count[node] = 0
        stack[sp] = b
        stack[sp + 1] = a
        sp += 2
    return (lo[:n_nodes].copy(), hi[:n_nodes].copy(), left[:n_nodes].copy(),
            right[:n_nodes].copy(), start[:n_nodes].copy(), count[:n_nodes].copy(), order)


def _check_mesh(vertices, faces) -> tuple[np.ndarray, np.ndarray]:
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    f = np.asarray(faces)
    if v.ndim != 2 or v.shape[1] != 3 or v.shape[0] == 0:
        raise ValueError(f"vertices must be a non-empty (V, 3) array, got shape {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError("vertices must be finite")
    if f.ndim != 2 or f.shape[1] != 3 or f.shape[0] == 0:
        raise ValueError(f"faces must be a non-empty (F, 3) array, got shape {f.shape}")
    if f.dtype.kind not in "iu":
        raise ValueError(f"faces must be integer vertex indices, got dtype {f.dtype}")
    if f.min() < 0 or f.max() >= v.shape[0]:
        raise ValueError(f"faces must index vertices in [0, {v.shape[0]}), "
                         f"got values in [{f.min()}, {f.max()}]")
    return v, np.ascontiguousarray(f, dtype=np.int64)


def bvh_from_mesh(vertices, faces) -> MeshBVH:
    """Validates a triangle mesh ((V, 3) vertices in m, (F, 3) vertex indices) and builds its
    BVH. Raises ValueError naming the offending parameter."""
    v, f = _check_mesh(vertices, faces)
    return MeshBVH(*build_bvh(v, f))


def pseudonormals(vertices, faces) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit face normals (F, 3), edge pseudonormals (F, 3, 3) and vertex pseudonormals (V, 3).

    Angle-weighted pseudonormals (Baerentzen and Aanaes, 2005) for a consistently wound mesh
    with outward face normals ``(b - a) x (c - a)``: an edge's is the normalised sum of its
    faces' normals (an open edge gets its one face's normal), a vertex's the normalised sum of
    its faces' normals weighted by the corner angles. ``edge_n[f, i]`` belongs to the edge
    joining corners ``i`` and ``(i + 1) % 3`` of face ``f``. Degenerate faces get a zero normal
    and contribute nothing.
    """
    v, f = _check_mesh(vertices, faces)
    tri = v[f]  # (F, 3 corners, 3)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    face_n = _normalized(n)

    # Edges as sorted vertex pairs; faces sharing a pair share an edge.
    # Edges as unordered vertex pairs, keyed by one integer; faces sharing a key share an edge.
    f_next = np.roll(f, -1, axis=1)
    key = (np.minimum(f, f_next) * v.shape[0] + np.maximum(f, f_next)).reshape(-1)
    _, edge_id = np.unique(key, return_inverse=True)
    edge_sum = _scatter_add(edge_id, np.repeat(face_n, 3, axis=0), edge_id.max() + 1)
    edge_n = _normalized(edge_sum)[edge_id].reshape(-1, 3, 3)

    # Corner angles from the two edges leaving each corner; arctan2 stays accurate near 0 and pi.
    e_next = np.roll(tri, -1, axis=1) - tri
    e_prev = np.roll(tri, 1, axis=1) - tri
    angle = np.arctan2(np.linalg.norm(np.cross(e_next, e_prev), axis=-1),
                       np.einsum("fck,fck->fc", e_next, e_prev))
    vertex_sum = _scatter_add(f.reshape(-1), (angle[:, :, None] * face_n[:, None, :]).reshape(-1, 3),
                              v.shape[0])
    return face_n, edge_n, _normalized(vertex_sum)


def _scatter_add(index: np.ndarray, values: np.ndarray, n: int) -> np.ndarray:
    """Row sums ``out[i] = sum of values[index == i]`` for (M, 3) values (np.add.at, faster)."""
    return np.stack([np.bincount(index, weights=values[:, k], minlength=n) for k in range(3)], axis=1)


def _normalized(x: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(x, axis=-1, keepdims=True)
    return np.divide(x, norm, out=np.zeros_like(x), where=norm > 0.0)


@njit(cache=True, error_model="numpy")
def traversal_stack():
    """Scratch for one BVH traversal: node ids and their squared box gaps (m^2)."""
    return np.empty(TRAVERSAL_STACK, dtype=np.int64), np.empty(TRAVERSAL_STACK)


@njit(cache=True, error_model="numpy")
def _gap2(lo0: float, hi0: float, lo1: float, hi1: float) -> float:
    """Squared gap (m^2) between intervals [lo0, hi0] and [lo1, hi1] (0 if they overlap)."""
    d = max(lo0 - hi1, lo1 - hi0, 0.0)
    return d * d


@njit(cache=True, error_model="numpy")
def _box_gap2(lo, hi, node, slo, shi) -> float:
    """Squared distance (m^2) between node's box and the box slo-shi; a lower bound."""
    return (_gap2(lo[node, 0], hi[node, 0], slo[0], shi[0])
            + _gap2(lo[node, 1], hi[node, 1], slo[1], shi[1])
            + _gap2(lo[node, 2], hi[node, 2], slo[2], shi[2]))


@njit(cache=True, error_model="numpy")
def _centre_dist2(lo, hi, node, x) -> float:
    """Squared distance (m^2) from node's box centre to point x."""
    d0 = 0.5 * (lo[node, 0] + hi[node, 0]) - x[0]
    d1 = 0.5 * (lo[node, 1] + hi[node, 1]) - x[1]
    d2 = 0.5 * (lo[node, 2] + hi[node, 2]) - x[2]
    return d0 * d0 + d1 * d1 + d2 * d2


@njit(cache=True, error_model="numpy")
def _nearer_first(lo, hi, a, b, slo, shi, mid):
    """Children a, b reordered nearer first, with their box gaps to the segment's box.

    Near the surface both gaps are often 0; the box centres then decide.
    """
    ga = _box_gap2(lo, hi, a, slo, shi)
    gb = _box_gap2(lo, hi, b, slo, shi)
    swap = ga > gb
    if ga == gb:
        swap = _centre_dist2(lo, hi, a, mid) > _centre_dist2(lo, hi, b, mid)
    if swap:
        return b, a, gb, ga
    return a, b, ga, gb


@njit(cache=True, error_model="numpy")
def _push_children(lo, hi, a, b, slo, shi, mid, limit2, stack, bound, sp) -> int:
    """Push children a, b whose box gap^2 to the segment's box is within ``limit2`` (m^2),
    the nearer one last so that it is searched first; returns the new stack size."""
    a, b, ga, gb = _nearer_first(lo, hi, a, b, slo, shi, mid)
    if gb <= limit2:
        stack[sp] = b
        bound[sp] = gb
        sp += 1
    if ga <= limit2:
        stack[sp] = a
        bound[sp] = ga
        sp += 1
    return sp


@njit(cache=True, error_model="numpy")
def _corners(vertices, faces, f):
    """The three corners (m) of triangle ``f`` as tuples."""
    return ((vertices[faces[f, 0], 0], vertices[faces[f, 0], 1], vertices[faces[f, 0], 2]),
            (vertices[faces[f, 1], 0], vertices[faces[f, 1], 1], vertices[faces[f, 1], 2]),
            (vertices[faces[f, 2], 0], vertices[faces[f, 2], 1], vertices[faces[f, 2], 2]))


@njit(cache=True, error_model="numpy")
def _beyond(va, vb, vc, p0, p1, slo, shi, reach2) -> bool:
    """True if triangle va-vb-vc is surely farther than sqrt(reach2) from segment p0p1.

    Cheap cuts before the exact test: the triangle's box against the segment's box, then the
    segment against a sphere around the triangle (tighter for segments running diagonally to
    the axes, whose box is large).
    """
    g = _gap2(min(va[0], vb[0], vc[0]), max(va[0], vb[0], vc[0]), slo[0], shi[0])
    g += _gap2(min(va[1], vb[1], vc[1]), max(va[1], vb[1], vc[1]), slo[1], shi[1])
    g += _gap2(min(va[2], vb[2], vc[2]), max(va[2], vb[2], vc[2]), slo[2], shi[2])
    if g > reach2:
        return True
    cen = bary_point(va, vb, vc, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0)
    rad = math.sqrt(max(dist2(cen, va), dist2(cen, vb), dist2(cen, vc)))
    gap = math.sqrt(dist2(lerp(p0, p1, closest_point_segment(cen, p0, p1)), cen)) - rad
    return gap > 0.0 and gap * gap > reach2


@njit(cache=True, error_model="numpy")
def bvh_closest_segment(lo, hi, left, right, start, count, order, vertices, faces, p0, p1,
                        max_dist, root=0):
    """Triangle nearest to segment p0p1 (tuples, m) among those within ``max_dist`` (m).

    Returns ``(tri, s, u, v, w, d2)``: the triangle (-1 if none is within ``max_dist``), the
    segment parameter and barycentrics of a closest pair, and its squared distance (m^2; inf
    when tri is -1). ``max_dist = np.inf`` searches the whole mesh. Depth-first, nearer child
    first, pruning boxes farther than the best so far from the segment's bounding box.
    ``root`` is the tree's root node (several trees may share the arrays, see ``pack``).
    """
    stack, bound = traversal_stack()
    return closest_segment_search(lo, hi, left, right, start, count, order, vertices, faces, p0,
                                  p1, max_dist, root, stack, bound)


@njit(cache=True, error_model="numpy")
def closest_segment_search(lo, hi, left, right, start, count, order, vertices, faces, p0, p1,
                           max_dist, root, stack, bound):
    """``bvh_closest_segment`` with its traversal scratch passed in (``traversal_stack``): it
    allocates nothing, so a caller compiled without reference counting can use it."""
    point = p0[0] == p1[0] and p0[1] == p1[1] and p0[2] == p1[2]
    slo = (min(p0[0], p1[0]), min(p0[1], p1[1]), min(p0[2], p1[2]))
    shi = (max(p0[0], p1[0]), max(p0[1], p1[1]), max(p0[2], p1[2]))
    mid = lerp(p0, p1, 0.5)
    best = max_dist * max_dist
    tri = -1
    rs = ru = rv = rw = 0.0
    g = _box_gap2(lo, hi, root, slo, shi)
    sp = 0
    if g <= best:
        stack[0] = root
        bound[0] = g
        sp = 1
    while sp > 0:
        sp -= 1
        node = stack[sp]
        if bound[sp] > best:
            continue  # the best improved since this node was pushed
        a = left[node]
        if a < 0:
            for i in range(start[node], start[node] + count[node]):
                f = order[i]
                va, vb, vc = _corners(vertices, faces, f)
                if _beyond(va, vb, vc, p0, p1, slo, shi, best):
                    continue
                s, u, v, w, d2 = segment_triangle_dist2(p0, p1, point, va, vb, vc)
                # <= for the first hit so that a triangle exactly at max_dist counts.
                if d2 < best or (tri < 0 and d2 <= best):
                    best = d2
                    tri = f
                    rs, ru, rv, rw = s, u, v, w
            if best <= 0.0 and tri >= 0:
                break  # touching: nothing can be nearer
            continue
        sp = _push_children(lo, hi, a, right[node], slo, shi, mid, best, stack, bound, sp)
    if tri < 0:
        return -1, 0.0, 0.0, 0.0, 0.0, np.inf
    return tri, rs, ru, rv, rw, best


@njit(cache=True, error_model="numpy")
def signed_side(face_n, edge_n, vertex_n, faces, tri, u, v, w, p, c) -> float:
    """+1.0 if point p (m) is outside the closed mesh, -1.0 if inside (+1.0 on the surface).

    ``c`` is the closest point to p on the mesh, on triangle ``tri`` at barycentrics (u, v, w).
    The sign of dot(p - c, n) with the angle-weighted pseudonormal n of the feature holding c
    (face interior, edge or vertex) is exact for closed meshes (Baerentzen and Aanaes 2005),
    where the face normal alone fails near edges and vertices.
    """
    tol = _FEATURE_TOL * (u + v + w)
    zu = u <= tol
    zv = v <= tol
    zw = w <= tol
    nz = zu + zv + zw
    if nz >= 2:  # a vertex: the corner whose coordinate is not ~0
        corner = 0 if not zu else (1 if not zv else 2)
        if zu and zv and zw:  # cannot happen for u + v + w > 0; keep the largest
            corner = 0 if u >= v and u >= w else (1 if v >= w else 2)
        k = faces[tri, corner]
        n0 = vertex_n[k, 0]
        n1 = vertex_n[k, 1]
        n2 = vertex_n[k, 2]
    elif nz == 1:  # an edge: edge i joins corners i and i + 1, so it is opposite corner i + 2
        e = 0 if zw else (1 if zu else 2)
        n0 = edge_n[tri, e, 0]
        n1 = edge_n[tri, e, 1]
        n2 = edge_n[tri, e, 2]
    else:
        n0 = face_n[tri, 0]
        n1 = face_n[tri, 1]
        n2 = face_n[tri, 2]
    d = (p[0] - c[0]) * n0 + (p[1] - c[1]) * n1 + (p[2] - c[2]) * n2
    return math.copysign(1.0, d) if d != 0.0 else 1.0


@njit(cache=True, error_model="numpy")
def bvh_nearest_k(lo, hi, left, right, start, count, order, vertices, faces, p0, p1, max_dist,
                  out_tri, out_dist, root=0):
    """The ``k = len(out_tri)`` triangles nearest to segment p0p1 (m) within ``max_dist`` (m).

    Writes their ids and exact distances (m, ascending) to ``out_tri`` and ``out_dist`` and
    returns ``(n, horizon)``: n triangles listed, and every triangle not listed is at least
    ``horizon`` (m) from the segment (``max_dist`` when fewer than k lie within it). A caller
    can keep the list while the segment moves by at most ``delta``: a listed triangle is then
    at least ``out_dist - delta`` away and any other at least ``horizon - delta``. ``root`` as
    in ``bvh_closest_segment``.
    """
    stack, bound = traversal_stack()
    return nearest_k_search(lo, hi, left, right, start, count, order, vertices, faces, p0, p1,
                            max_dist, out_tri, out_dist, root, stack, bound)


@njit(cache=True, error_model="numpy")
def nearest_k_search(lo, hi, left, right, start, count, order, vertices, faces, p0, p1, max_dist,
                     out_tri, out_dist, root, stack, bound):
    """``bvh_nearest_k`` with its traversal scratch passed in (see ``closest_segment_search``)."""
    point = p0[0] == p1[0] and p0[1] == p1[1] and p0[2] == p1[2]
    k = out_tri.shape[0]
    slo = (min(p0[0], p1[0]), min(p0[1], p1[1]), min(p0[2], p1[2]))
    shi = (max(p0[0], p1[0]), max(p0[1], p1[1]), max(p0[2], p1[2]))
    mid = lerp(p0, p1, 0.5)
    horizon = max_dist
    n = 0
    g = _box_gap2(lo, hi, root, slo, shi)
    sp = 0
    if g <= horizon * horizon:
        stack[0] = root
        bound[0] = g
        sp = 1
    while sp > 0:
        sp -= 1
        node = stack[sp]
        if bound[sp] > horizon * horizon:
            continue  # the horizon shrank since this node was pushed
        a = left[node]
        if a < 0:
            for i in range(start[node], start[node] + count[node]):
                f = order[i]
                va, vb, vc = _corners(vertices, faces, f)
                # Beyond the horizon a triangle can neither enter the list nor lower it.
                if _beyond(va, vb, vc, p0, p1, slo, shi, horizon * horizon):
                    continue
                d = math.sqrt(segment_triangle_dist2(p0, p1, point, va, vb, vc)[4])
                if d > horizon:
                    continue
                if n == k:
                    if d >= out_dist[k - 1]:
                        horizon = d  # not listed, and nearer than the horizon so far
                        continue
                    horizon = out_dist[k - 1]  # the farthest listed one drops out
                    n -= 1
                j = n  # insertion into the sorted list
                while j > 0 and out_dist[j - 1] > d:
                    out_tri[j] = out_tri[j - 1]
                    out_dist[j] = out_dist[j - 1]
                    j -= 1
                out_tri[j] = f
                out_dist[j] = d
                n += 1
            continue
        sp = _push_children(lo, hi, a, right[node], slo, shi, mid, horizon * horizon, stack,
                            bound, sp)
    return n, horizon
