"""Procedural meshes: the bunny-like blob and the grid floor (geometry only, no simulation)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from deformx.engine.geometry.shapes import blob_mesh, grid_mesh


@pytest.mark.parametrize("subdivisions", [0, 2, 4])
def test_blob_is_watertight_with_the_icosphere_face_count(subdivisions):
    mesh = blob_mesh(subdivisions=subdivisions)
    assert mesh.is_watertight
    assert mesh.faces.shape == (20 * 4**subdivisions, 3)
    assert mesh.vertices.shape == (10 * 4**subdivisions + 2, 3)


@pytest.mark.parametrize("ears", [True, False])
def test_blob_stands_on_z0_with_a_plausible_volume(ears):
    r = 0.08
    mesh = blob_mesh(radius=r, subdivisions=4, ears=ears)
    assert mesh.vertices[:, 2].min() == pytest.approx(0.0, abs=1e-12)
    sphere = 4.0 / 3.0 * math.pi * r**3
    assert 0.6 * sphere < mesh.volume < 1.6 * sphere  # positive: outward-facing triangles
    # Star-shaped about its centre: every vertex's radial factor stays above 0.5.
    d = np.linalg.norm(mesh.vertices - mesh.metadata["center"], axis=1)
    assert d.min() > 0.5 * 0.85 * r
    # The ears add height on top, nothing else changes (same seed).
    other = blob_mesh(radius=r, subdivisions=4, ears=not ears)
    taller = np.ptp(mesh.vertices[:, 2]) > np.ptp(other.vertices[:, 2]) + 0.2 * r
    assert taller if ears else not taller


def test_blob_scales_with_radius():
    a, b = blob_mesh(radius=0.08, subdivisions=2), blob_mesh(radius=0.16, subdivisions=2)
    np.testing.assert_allclose(b.vertices, 2.0 * a.vertices, rtol=1e-12, atol=1e-15)


def test_blob_is_deterministic_for_a_seed_and_differs_between_seeds():
    a = blob_mesh(subdivisions=3, seed=7)
    b = blob_mesh(subdivisions=3, seed=7)
    c = blob_mesh(subdivisions=3, seed=8)
    np.testing.assert_array_equal(a.vertices, b.vertices)
    np.testing.assert_array_equal(a.faces, c.faces)  # same connectivity
    assert np.abs(a.vertices - c.vertices).max() > 1e-3  # m, different shape


@pytest.mark.parametrize("kwargs, name", [
    (dict(radius=0.0), "radius"),
    (dict(radius=-1.0), "radius"),
    (dict(radius=float("nan")), "radius"),
    (dict(radius="big"), "radius"),
    (dict(subdivisions=-1), "subdivisions"),
    (dict(subdivisions=9), "subdivisions"),
    (dict(subdivisions=2.0), "subdivisions"),
    (dict(seed=-3), "seed"),
    (dict(seed=1.5), "seed"),
    (dict(ears="yes"), "ears"),
])
def test_blob_rejects_bad_arguments(kwargs, name):
    with pytest.raises(ValueError, match=name):
        blob_mesh(**kwargs)


def test_grid_counts_bounds_and_orientation():
    V, F = grid_mesh(1.5, 10)
    assert V.shape == (121, 3) and F.shape == (200, 3)
    assert F.min() == 0 and F.max() == 120
    np.testing.assert_allclose(V.min(axis=0), (-0.75, -0.75, 0.0))
    np.testing.assert_allclose(V.max(axis=0), (0.75, 0.75, 0.0))
    # Every triangle has positive area and faces +z; together they tile the square.
    e1, e2 = V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]
    n = np.cross(e1, e2)
    assert np.all(n[:, 2] > 0.0)
    assert 0.5 * n[:, 2].sum() == pytest.approx(1.5**2)


@pytest.mark.parametrize("args, name", [
    ((0.0, 4), "size"), ((-1.0, 4), "size"), ((1.0, 0), "n"), ((1.0, 2.5), "n"),
    ((1.0, True), "n"),
])
def test_grid_rejects_bad_arguments(args, name):
    with pytest.raises(ValueError, match=name):
        grid_mesh(*args)
