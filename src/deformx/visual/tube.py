"""Tube meshes around rods: a ring of vertices per node, oriented by the material frame (so
twist turns the rings), smooth normals, arc-length UVs, end caps. The topology is built once
(:class:`Tube`); :func:`tube_vertices` (numba) updates vertices and normals in place each frame.

Node frames: the element frame at the ends, between elements the mean of the two elements'
d1 made normal to the mean tangent (d3), d2 = d3 x d1. Ring vertex j of node i is
``x_i + r_i (cos t_j d1 + sin t_j d2)``, ``t_j = 2 pi j / sides``, j = 0..sides: the last vertex
repeats the first at texture coordinate t = 1 (a seam, so that a texture does not wrap backwards
across one face); caps add one centre vertex per open end.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def tube_vertices(pos, Q, radius, closed, cos_t, sin_t, verts, normals) -> None:
    """Ring vertices and normals of a tube around nodes ``pos`` (N, 3) with element frames
    ``Q`` (E, 3, 3), rows d1, d2, d3), node radii ``radius`` (N), ring angles given by their
    ``cos_t`` / ``sin_t`` (ring vertices); ``verts`` / ``normals`` ((N ring + caps), 3) are
    written in place (caps: the two end centres, open rods)."""
    sides = cos_t.shape[0]
    n = pos.shape[0]
    ne = Q.shape[0]
    for i in range(n):
        if closed:
            a, b = (i - 1) % ne, i % ne
        else:
            a, b = max(i - 1, 0), min(i, ne - 1)
        t0 = Q[a, 2, 0] + Q[b, 2, 0]
        t1 = Q[a, 2, 1] + Q[b, 2, 1]
        t2 = Q[a, 2, 2] + Q[b, 2, 2]
        tn = np.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
        t0, t1, t2 = t0 / tn, t1 / tn, t2 / tn
        u0 = Q[a, 0, 0] + Q[b, 0, 0]
        u1 = Q[a, 0, 1] + Q[b, 0, 1]
        u2 = Q[a, 0, 2] + Q[b, 0, 2]
        dot = u0 * t0 + u1 * t1 + u2 * t2
        u0, u1, u2 = u0 - dot * t0, u1 - dot * t1, u2 - dot * t2
        un = np.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
        u0, u1, u2 = u0 / un, u1 / un, u2 / un
        w0, w1, w2 = t1 * u2 - t2 * u1, t2 * u0 - t0 * u2, t0 * u1 - t1 * u0  # d2 = d3 x d1
        r = radius[i]
        for j in range(sides):
            c, s = cos_t[j], sin_t[j]
            k = i * sides + j
            n0, n1, n2 = c * u0 + s * w0, c * u1 + s * w1, c * u2 + s * w2
            normals[k, 0], normals[k, 1], normals[k, 2] = n0, n1, n2
            verts[k, 0] = pos[i, 0] + r * n0
            verts[k, 1] = pos[i, 1] + r * n1
            verts[k, 2] = pos[i, 2] + r * n2
    if not closed:
        k = n * sides
        for d in range(3):
            verts[k, d] = pos[0, d]
            verts[k + 1, d] = pos[n - 1, d]
            normals[k, d] = -Q[0, 2, d]
            normals[k + 1, d] = Q[ne - 1, 2, d]


def tube_faces(n_nodes: int, sides: int, closed: bool) -> np.ndarray:
    """Triangles (F, 3) of the tube (rings of ``sides + 1`` vertices, the last on the seam):
    two per quad between rings (outward, counter-clockwise seen from outside), a fan per cap."""
    rings = n_nodes if closed else n_nodes - 1
    ring = sides + 1
    faces = []
    j = np.arange(sides)
    jn = j + 1
    for i in range(rings):
        a = i * ring
        b = ((i + 1) % n_nodes) * ring
        faces.append(np.column_stack([a + j, a + jn, b + j]))
        faces.append(np.column_stack([a + jn, b + jn, b + j]))
    if not closed:
        c0, c1 = n_nodes * ring, n_nodes * ring + 1
        last = (n_nodes - 1) * ring
        # ring angles turn from d1 to d2, i.e. counter-clockwise about d3: the start cap faces -d3
        faces.append(np.column_stack([np.full(sides, c0), jn, j]))
        faces.append(np.column_stack([np.full(sides, c1), last + j, last + jn]))
    return np.vstack(faces).astype(np.int64)


class Tube:
    """The tube mesh of one rod: ``faces`` fixed, ``vertices`` / ``normals`` refreshed by
    :meth:`update` from the rod's current nodes and frames; ``uv``: u = rest arc length (m),
    v = angle from d1 / 2 pi (0..1, a seam vertex at 1); ``ring`` = sides + 1 vertices per
    node."""

    def __init__(self, rod, sides: int = 12, radius_scale: float = 1.0) -> None:
        if not isinstance(sides, (int, np.integer)) or sides < 3:
            raise ValueError(f"sides must be an integer >= 3, got {sides!r}")
        self.rod = rod
        self.sides = int(sides)
        self.closed = bool(rod.closed)
        n = rod.n_nodes
        self.radius = np.asarray(rod.node_radius, dtype=np.float64) * radius_scale
        self.ring = self.sides + 1
        self.faces = tube_faces(n, self.sides, self.closed)
        n_verts = n * self.ring + (0 if self.closed else 2)
        self.vertices = np.zeros((n_verts, 3))
        self.normals = np.zeros((n_verts, 3))
        s = np.concatenate([[0.0], np.cumsum(rod.rest_lengths)])[:n]
        uv = np.zeros((n_verts, 2))
        uv[: n * self.ring, 0] = np.repeat(s, self.ring)
        uv[: n * self.ring, 1] = np.tile(np.arange(self.ring) / self.sides, n)
        if not self.closed:
            uv[-1, 0] = s[-1]
            uv[-2:, 1] = 0.5
        self.uv = uv
        angle = 2.0 * np.pi * np.arange(self.ring) / self.sides
        self._cos, self._sin = np.cos(angle), np.sin(angle)
        self.update()

    def update(self, radius: np.ndarray | None = None) -> np.ndarray:
        """Refresh vertices and normals from the rod now (``radius`` per node overrides the
        rod's); returns the vertices."""
        tube_vertices(self.rod.positions, self.rod.directors,
                      self.radius if radius is None else radius, self.closed, self._cos,
                      self._sin, self.vertices, self.normals)
        return self.vertices
