"""Procedural test meshes: a bunny-like blob and a flat grid floor.

Both are deterministic and need no files, so examples and tests can use a non-trivial
collider without shipping mesh assets. Lengths are in metres.
"""

from __future__ import annotations

import math

import numpy as np

from .. import validation as check

__all__ = ["blob_mesh", "grid_mesh"]

_MAX_SUBDIVISIONS = 8  # 20 * 4**8 = 1.3 million triangles


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def _tangent_basis(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors perpendicular to ``axis`` and to each other."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t1 = _unit(np.cross(axis, helper))
    return t1, np.cross(axis, t1)


def _bump(u: np.ndarray, axis, width_1: float, width_2: float,
          t1: np.ndarray | None = None) -> np.ndarray:
    """A smooth bump over unit directions ``u`` (V, 3), 1 at ``axis``: a Gaussian in the
    tangent-plane coordinates with angular widths ``width_1`` (along ``t1``) and ``width_2``
    (radians), fading to 0 on the far hemisphere."""
    axis = _unit(axis)
    if t1 is None:
        t1, t2 = _tangent_basis(axis)
    else:
        t1 = _unit(t1 - np.dot(t1, axis) * axis)
        t2 = np.cross(axis, t1)
    c = u @ axis
    a, b = u @ t1, u @ t2
    g = np.exp(-0.5 * ((a / width_1) ** 2 + (b / width_2) ** 2))
    return g * np.clip(c, 0.0, 1.0) ** 2


def blob_mesh(radius: float = 0.08, subdivisions: int = 4, seed: int = 0,
              ears: bool = True) -> "trimesh.Trimesh":  # noqa: F821
    """A watertight, bunny-like blob (m) standing with its lowest point at z = 0.

    An icosphere of ``radius`` (m) with ``subdivisions`` (0-8; 20 * 4**subdivisions
    triangles: 4 gives 5120, 7 about 327k) whose vertices move radially only, by a smooth
    function of direction: a head lobe forward (+x) and up, a few random low-frequency lobes
    drawn from ``np.random.default_rng(seed)``, a slight vertical squash and, with ``ears``,
    two tall narrow bumps on the head. The radial factor stays above 0.6, so the blob stays
    star-shaped about its centre and never self-intersects. The same arguments give the same
    mesh. Returns a ``trimesh.Trimesh``; ``mesh.metadata["center"]`` is the centre the
    vertices were displaced from (m, on the z axis).
    """
    import trimesh

    radius = check.in_range("radius", radius, 0.0, math.inf, low_open=True, high_open=True)
    if (isinstance(subdivisions, bool) or not isinstance(subdivisions, (int, np.integer))
            or not 0 <= subdivisions <= _MAX_SUBDIVISIONS):
        raise ValueError(f"subdivisions must be an integer in [0, {_MAX_SUBDIVISIONS}], "
                         f"got {subdivisions!r}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be an integer in [0, inf), got {seed!r}")
    if not isinstance(ears, (bool, np.bool_)):
        raise ValueError(f"ears must be True or False, got {ears!r}")

    sphere = trimesh.creation.icosphere(subdivisions=int(subdivisions), radius=1.0)
    u = sphere.vertices / np.linalg.norm(sphere.vertices, axis=1, keepdims=True)
    faces = np.asarray(sphere.faces, dtype=np.int64)

    # Radial factor 1 + f(u). Body: a head lobe forward and up over a shallow waist (the
    # neck) at about 45 degrees elevation.
    f = 0.4 * _bump(u, (0.3, 0.0, 1.0), 0.38, 0.38)
    f -= 0.08 * np.exp(-0.5 * ((u[:, 2] - 0.7) / 0.12) ** 2)
    # Random smooth lobes with bounded amplitudes: f > -0.08 - 5 * 0.06, factor > 0.6.
    rng = np.random.default_rng(int(seed))
    for _ in range(5):
        axis = rng.normal(size=3)
        width = rng.uniform(0.45, 0.8)
        f += rng.uniform(-0.06, 0.12) * _bump(u, axis, width, width)
    if ears:
        # Two ears on the head, leaning out; narrow across, longer front to back.
        for side in (-1.0, 1.0):
            axis = _unit((0.1, 0.42 * side, 1.0))
            f += 0.8 * _bump(u, axis, 0.09, 0.16, t1=np.array([0.0, 1.0, 0.0]))
    vertices = radius * (1.0 + f)[:, None] * u
    vertices[:, 2] *= 0.85  # squash a little vertically (a linear map keeps it star-shaped)
    z_min = vertices[:, 2].min()
    vertices[:, 2] -= z_min
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    mesh.metadata["center"] = np.array([0.0, 0.0, -z_min])
    return mesh


def grid_mesh(size: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """An open square grid in the plane z = 0, centred on the origin: ``size`` (m) on a
    side, ``n`` cells per side, ``2 n^2`` triangles (counter-clockwise seen from +z).
    Returns ``(vertices (V, 3), faces (2 n^2, 3))`` with ``V = (n + 1)^2``."""
    size = check.positive("size", size, "m")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n must be an integer in [1, inf), got {n!r}")
    n = int(n)
    xs = np.linspace(-size / 2, size / 2, n + 1)
    X, Y = np.meshgrid(xs, xs, indexing="ij")
    V = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    F = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return V, F.astype(np.int64)
