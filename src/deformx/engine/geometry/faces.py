"""Per-face planes and barycentric maps, for constant-time point-in-face tests.

``face_frames(V, F)[f]`` is a 3 x 4 table of affine maps ``g . x - o`` (row ``(g, o)``): row 0
gives the height (m) of x above the face's plane (unit normal ``g``), rows 1 and 2 the
barycentrics ``v`` and ``w`` of x's projection onto the plane (``u = 1 - v - w``). The
projection lies in the face iff ``u, v, w >= 0``. Degenerate faces get NaN maps, so no point
is ever found inside them.
"""

from __future__ import annotations

import numpy as np


def face_frames(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(F, 3, 4) planes and barycentric maps of the faces of a mesh (vertices in m)."""
    tri = vertices[faces]
    a = tri[:, 0]
    e1 = tri[:, 1] - a
    e2 = tri[:, 2] - a
    n = np.cross(e1, e2)
    norm = np.linalg.norm(n, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        n = n / norm
        # Dual basis of (e1, e2) in the face's plane: x - a = v e1 + w e2 + h n.
        r1 = np.cross(e2, n)
        r1 /= np.einsum("ij,ij->i", e1, r1)[:, None]
        r2 = np.cross(n, e1)
        r2 /= np.einsum("ij,ij->i", e2, r2)[:, None]
    out = np.full((faces.shape[0], 3, 4), np.nan)
    good = norm[:, 0] > 0.0
    for row, vec in enumerate((n, r1, r2)):
        out[good, row, :3] = vec[good]
        out[good, row, 3] = np.einsum("ij,ij->i", vec[good], a[good])
    return out
