"""Skinning any cable mesh to a rod: CAD cables (OBJ/STL/PLY/GLB through trimesh) follow the
rod's centreline and material frames.

Binding (once, with the rod in the pose the mesh was modelled in): each vertex gets the arc
length ``s`` of its nearest point on the centreline and its coordinates in the material frame
there. Deforming (each frame, numba): the frame at ``s`` is interpolated between the
neighbouring elements' frames by quaternion slerp (node frames halfway between elements), the
centreline point linearly between nodes, and the vertex is put back at its coordinates: twist
rotates each section by the rod's twist there (no candy-wrapper collapse, as linear blend
skinning gives), a rigid motion of the rod moves the mesh rigidly, and at the bind pose the
mesh is unchanged. Rigid parts (connectors, plugs) follow the frame of the end they belong to
without bending.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit


@njit(cache=True)
def _quat_from_directors(Q, out) -> None:
    """Quaternions (w, x, y, z) of world-from-material rotations R = Q[e]^T."""
    for e in range(Q.shape[0]):
        # R[i, j] = Q[e, j, i]
        r00, r01, r02 = Q[e, 0, 0], Q[e, 1, 0], Q[e, 2, 0]
        r10, r11, r12 = Q[e, 0, 1], Q[e, 1, 1], Q[e, 2, 1]
        r20, r21, r22 = Q[e, 0, 2], Q[e, 1, 2], Q[e, 2, 2]
        tr = r00 + r11 + r22
        if tr > 0.0:
            s = math.sqrt(tr + 1.0) * 2.0
            w, x, y, z = 0.25 * s, (r21 - r12) / s, (r02 - r20) / s, (r10 - r01) / s
        elif r00 > r11 and r00 > r22:
            s = math.sqrt(1.0 + r00 - r11 - r22) * 2.0
            w, x, y, z = (r21 - r12) / s, 0.25 * s, (r01 + r10) / s, (r02 + r20) / s
        elif r11 > r22:
            s = math.sqrt(1.0 + r11 - r00 - r22) * 2.0
            w, x, y, z = (r02 - r20) / s, (r01 + r10) / s, 0.25 * s, (r12 + r21) / s
        else:
            s = math.sqrt(1.0 + r22 - r00 - r11) * 2.0
            w, x, y, z = (r10 - r01) / s, (r02 + r20) / s, (r12 + r21) / s, 0.25 * s
        if e > 0 and w * out[e - 1, 0] + x * out[e - 1, 1] + y * out[e - 1, 2] + z * out[e - 1, 3] < 0:
            w, x, y, z = -w, -x, -y, -z  # same hemisphere as the neighbour: short slerps
        out[e, 0], out[e, 1], out[e, 2], out[e, 3] = w, x, y, z


@njit(cache=True, inline="always")
def _slerp(q, a, b, t):
    aw, ax, ay, az = q[a, 0], q[a, 1], q[a, 2], q[a, 3]
    bw, bx, by, bz = q[b, 0], q[b, 1], q[b, 2], q[b, 3]
    d = aw * bw + ax * bx + ay * by + az * bz
    if d < 0.0:
        bw, bx, by, bz, d = -bw, -bx, -by, -bz, -d
    if d > 0.9995:
        ka, kb = 1.0 - t, t
    else:
        th = math.acos(d)
        sn = math.sin(th)
        ka, kb = math.sin((1.0 - t) * th) / sn, math.sin(t * th) / sn
    w, x, y, z = ka * aw + kb * bw, ka * ax + kb * bx, ka * ay + kb * by, ka * az + kb * bz
    n = math.sqrt(w * w + x * x + y * y + z * z)
    return w / n, x / n, y / n, z / n


@njit(cache=True, inline="always")
def _rotate(w, x, y, z, v0, v1, v2):
    # v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z)
    c0, c1, c2 = y * v2 - z * v1, z * v0 - x * v2, x * v1 - y * v0
    return (v0 + 2.0 * (w * c0 + y * c2 - z * c1), v1 + 2.0 * (w * c1 + z * c0 - x * c2),
            v2 + 2.0 * (w * c2 + x * c1 - y * c0))


@njit(cache=True)
def frame_at(q, e, t, ne):
    """Material frame (quaternion) at fraction t of element e: halfway between elements at the
    nodes, the element's own at its middle."""
    if t < 0.5:
        a = max(e - 1, 0)
        return _slerp(q, a, e, t + 0.5) if a != e else (q[e, 0], q[e, 1], q[e, 2], q[e, 3])
    b = min(e + 1, ne - 1)
    return _slerp(q, e, b, t - 0.5) if b != e else (q[e, 0], q[e, 1], q[e, 2], q[e, 3])


def _inverse_rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate rows of v by the inverse of quaternions q (rows)."""
    qi = q * np.array([1.0, -1.0, -1.0, -1.0])
    out = np.empty_like(v)
    for k in range(len(v)):
        out[k] = _rotate(*qi[k], *v[k])
    return out


class Skin:
    """A triangle mesh bound to ``rod`` (open rods), deformed with it.

    ``mesh``: a path, ``trimesh.Trimesh`` or ``(vertices, faces)``, in world coordinates with
    the rod in its current pose (bind it while the rod is where the mesh was modelled);
    ``rigid``: optional per-vertex labels, 0 skinned, 1 rigid with the start, 2 rigid with the
    end (connectors, plugs); with ``rigid="auto"`` vertices beyond the rod's ends are rigid with
    the nearer end. ``vertices`` / ``normals`` / ``faces`` after :meth:`update`.
    """

    def __init__(self, rod, mesh: Any, rigid: Any = "auto") -> None:
        import trimesh

        from ..engine.contact.colliders import load_mesh

        if rod.closed:
            raise ValueError("Skin: closed rods are not supported (bind to an open rod)")
        V, F, _ = load_mesh(mesh)
        self.rod = rod
        self.faces = np.asarray(F, dtype=np.int64)
        self.rest_vertices = np.asarray(V, dtype=np.float64).copy()
        tm = trimesh.Trimesh(self.rest_vertices, self.faces, process=False)
        rest_normals = np.asarray(tm.vertex_normals, dtype=np.float64).copy()
        pos = rod.positions.copy()
        ne = rod.n_elements
        seg = pos[1:] - pos[:-1]
        seg_len2 = np.einsum("ij,ij->i", seg, seg)
        # nearest point on the centreline: per vertex, over all elements (binding is once)
        rel = self.rest_vertices[:, None, :] - pos[None, :-1, :]
        t = np.clip(np.einsum("vej,ej->ve", rel, seg) / seg_len2, 0.0, 1.0)
        gap = rel - t[..., None] * seg[None]
        e = np.argmin(np.einsum("vej,vej->ve", gap, gap), axis=1)
        tt = t[np.arange(len(e)), e]
        # unclamped position along the end elements, to find what lies beyond the ends
        t_raw = np.einsum("vj,vj->v", rel[np.arange(len(e)), e], seg[e]) / seg_len2[e]
        if isinstance(rigid, str) and rigid == "auto":
            # a connected part reaching beyond an end is rigid with that end (a plug)
            tol = 1e-6 * float(np.sqrt(seg_len2.max()))
            beyond0 = (e == 0) & (t_raw * np.sqrt(seg_len2[0]) < -tol)
            beyond1 = (e == ne - 1) & ((t_raw - 1.0) * np.sqrt(seg_len2[-1]) > tol)
            part = trimesh.graph.connected_component_labels(tm.edges_unique,
                                                            node_count=len(e))
            labels = np.zeros(len(e), dtype=np.int64)
            labels[np.isin(part, np.unique(part[beyond0]))] = 1
            labels[np.isin(part, np.unique(part[beyond1]))] = 2
        elif rigid is None:
            labels = np.zeros(len(e), dtype=np.int64)
        else:
            labels = np.asarray(rigid, dtype=np.int64).reshape(-1)
            if labels.shape != (len(e),) or not np.isin(labels, (0, 1, 2)).all():
                raise ValueError("rigid must be 'auto', None or one label (0, 1, 2) per vertex")
        # rigid parts ride on their end element's own frame (its middle: no slerp)
        e = np.where(labels == 1, 0, np.where(labels == 2, ne - 1, e))
        tt = np.where(labels == 1, 0.0, np.where(labels == 2, 1.0, tt))
        self.labels = labels
        self.elem = e.astype(np.int64)
        self.frac = tt.astype(np.float64)
        self._quats = np.zeros((ne, 4))
        _quat_from_directors(rod.directors, self._quats)
        q = np.array([frame_at(self._quats, int(ei), float(ti), ne)
                      for ei, ti in zip(self.elem, self._frame_frac())])
        centre = pos[self.elem] + self.frac[:, None] * seg[self.elem]
        self.local = _inverse_rotate(q, self.rest_vertices - centre)
        self.local_normals = _inverse_rotate(q, rest_normals)
        self._frac_frame = self._frame_frac()
        self.vertices = self.rest_vertices.copy()
        self.normals = rest_normals.copy()

    def _frame_frac(self) -> np.ndarray:
        """Where each vertex reads its frame: rigid parts at their end element's middle."""
        return np.where(self.labels == 0, self.frac, 0.5)

    def update(self) -> np.ndarray:
        """Deform to the rod's current nodes and frames; returns the vertices."""
        _quat_from_directors(self.rod.directors, self._quats)
        _skin(self.rod.positions, self._quats, self.elem, self.frac, self._frac_frame,
              self.local, self.local_normals, self.vertices, self.normals)
        return self.vertices


@njit(cache=True)
def _skin(pos, quats, elem, frac, frac_frame, local, local_normals, verts, normals) -> None:
    ne = quats.shape[0]
    for k in range(elem.shape[0]):
        e, t = elem[k], frac[k]
        w, x, y, z = frame_at(quats, e, frac_frame[k], ne)
        p0 = pos[e, 0] + t * (pos[e + 1, 0] - pos[e, 0])
        p1 = pos[e, 1] + t * (pos[e + 1, 1] - pos[e, 1])
        p2 = pos[e, 2] + t * (pos[e + 1, 2] - pos[e, 2])
        r = _rotate(w, x, y, z, local[k, 0], local[k, 1], local[k, 2])
        verts[k, 0], verts[k, 1], verts[k, 2] = p0 + r[0], p1 + r[1], p2 + r[2]
        n = _rotate(w, x, y, z, local_normals[k, 0], local_normals[k, 1], local_normals[k, 2])
        normals[k, 0], normals[k, 1], normals[k, 2] = n[0], n[1], n[2]
