"""Skinning cable meshes to rods: exact at the bind pose, rigid with the rod, sections turn
with the rod's twist, connectors stay rigid; the generated cable assets; drawing a skin."""

from __future__ import annotations

import math

import numpy as np
import pytest

import deformx as dx
from deformx.visual import assets
from deformx.visual.skin import Skin


def _rod(n=12, length=0.6):
    rod = dx.Rod.straight(n_elements=n, start=(0.1, -0.2, 0.3), direction=(0, 1, 0),
                          length=length, radius=0.003)
    dx.World().add_rod(rod)
    return rod


def _rotation(axis, angle):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


@pytest.mark.parametrize("name", sorted(assets.ASSETS))
def test_generated_cables_are_closed_outward_meshes_exact_at_the_bind_pose(name):
    cable = assets.ASSETS[name](length=0.6)
    assert cable.trimesh().volume > 0  # outward winding
    skin = cable.skin(_rod())
    np.testing.assert_allclose(skin.update(), skin.rest_vertices, atol=1e-9)


def test_a_rigid_motion_of_the_rod_moves_the_skin_rigidly():
    rod = _rod()
    skin = assets.usb_c_cable(length=0.6).skin(rod)
    R, t = _rotation((0.3, -0.5, 1.0), 0.8), np.array([0.2, 0.1, -0.4])
    rod.positions[:] = rod.positions @ R.T + t
    rod.directors[:] = rod.directors @ R.T
    np.testing.assert_allclose(skin.update(), skin.rest_vertices @ R.T + t, atol=1e-12)


def test_twist_turns_each_section_by_the_rods_twist_there_and_plugs_stay_rigid():
    rod = _rod(n=12)
    cable = assets.usb_c_cable(length=0.6)
    skin = cable.skin(rod)
    axis = rod.directors[0, 2]
    total = math.radians(90)
    ne = rod.n_elements
    for e in range(ne):  # twist grows linearly along the rod: element e turned by phi_e
        phi = total * (e + 0.5) / ne
        rod.directors[e] = rod.directors[e] @ _rotation(axis, phi).T
    V = skin.update()
    p0 = rod.positions[0]
    s = (skin.rest_vertices - p0) @ axis
    # every skinned vertex between the first and last element middles turns about the axis
    # by the twist interpolated there: total * s / L (slerp of frames about one axis)
    L = rod.length
    r0 = skin.rest_vertices - p0 - np.outer(s, axis)
    r1 = V - p0 - np.outer(s, axis)
    k = np.flatnonzero((skin.labels == 0) & (s > 0.5 * L / ne) & (s < L - 0.5 * L / ne)
                       & (np.linalg.norm(r0, axis=1) > 1e-6))
    assert len(k) > 1000
    cos = np.sum(r0[k] * r1[k], axis=1) / np.linalg.norm(r0[k], axis=1) ** 2
    np.testing.assert_allclose(np.arccos(np.clip(cos, -1, 1)), total * s[k] / L, atol=1e-6)
    # the plugs keep their shape (pairwise distances) and turn with their end element
    for label, e in ((1, 0), (2, ne - 1)):
        k = np.flatnonzero(skin.labels == label)
        d0 = np.linalg.norm(skin.rest_vertices[k, None] - skin.rest_vertices[None, k], axis=-1)
        d1 = np.linalg.norm(V[k, None] - V[None, k], axis=-1)
        np.testing.assert_allclose(d1, d0, atol=1e-12)


def test_auto_rigid_parts_and_bad_labels():
    import trimesh

    rod = _rod(n=6, length=0.3)
    jacket = assets.usb_c_cable(length=0.3)
    V = jacket.vertices @ np.column_stack([rod.directors[0, 2], rod.directors[0, 0],
                                           rod.directors[0, 1]]).T + rod.positions[0]
    auto = Skin(rod, (V, jacket.faces), rigid="auto")
    np.testing.assert_array_equal(auto.labels, jacket.labels)  # the plugs lie beyond the ends
    with pytest.raises(ValueError, match="rigid must be"):
        Skin(rod, (V, jacket.faces), rigid=np.full(len(V), 5))
    with pytest.raises(ValueError, match="long"):
        assets.usb_c_cable(length=0.5).skin(rod)
    assert isinstance(trimesh.Trimesh, type)


def test_fast_renderer_draws_a_skinned_cable():
    from deformx.visual.camera import Camera
    from deformx.visual.fast import FastRenderer

    world = dx.World()
    rod = world.add_rod(dx.Rod.straight(n_elements=12, start=(-0.2, 0, 0.02), direction=(1, 0, 0),
                                        length=0.4, radius=0.003))
    world.add_plane()
    skin = assets.usb_c_cable(length=0.4, radius=0.003).skin(rod)
    cam = Camera(position=(0, -0.5, 0.4), look_at=(0, 0, 0), width=160, height=120)
    frame = FastRenderer(world, skins={0: skin}).render(cam)
    ys, xs = np.nonzero(frame.instances == 1)
    # the plugs widen the silhouette beyond the rod's ends
    uv, _ = cam.project(rod.positions[[0, -1]])
    assert xs.min() < uv[0, 0] - 2 and xs.max() > uv[1, 0] + 2


def test_fast_renderer_gives_each_part_of_a_cable_asset_its_material():
    from deformx.visual.camera import Camera
    from deformx.visual.fast import FastRenderer

    world = dx.World()
    rod = world.add_rod(dx.Rod.straight(n_elements=12, start=(-0.2, 0, 0.02), direction=(1, 0, 0),
                                        length=0.4, radius=0.003))
    world.add_plane()
    asset = assets.usb_c_cable(length=0.4, radius=0.003, color=(0.9, 0.1, 0.1))
    r = FastRenderer(world, skins={0: asset.skin(rod)}, shadows=False)
    m = r.model
    rod_geoms = [g for g in range(m.ngeom) if m.geom(g).name.startswith("deformx_rod")]
    assert len(rod_geoms) == len(asset.materials)  # jacket, plug, shell
    colours = {tuple(np.round(m.mat_rgba[m.geom_matid[g], :3].astype(float), 3).tolist())
               for g in rod_geoms}
    assert colours == {tuple(np.round(mat.color, 3).tolist()) for mat in asset.materials.values()}
    # the parts hold every face once, and all of them are rod 1
    assert sum(m.mesh_facenum[m.geom_dataid[g]] for g in rod_geoms) == len(asset.faces)
    cam = Camera(position=(0, -0.5, 0.4), look_at=(0, 0, 0), width=160, height=120)
    frame = r.render(cam)
    ys, xs = np.nonzero(frame.instances == 1)
    uv, _ = cam.project(rod.positions[[0, -1]])
    assert xs.min() < uv[0, 0] - 2 and xs.max() > uv[1, 0] + 2
    # red jacket pixels between the rod's ends; the plugs beyond them are not red (a stray
    # pixel or two at their edges aside)
    rgb = frame.rgb.astype(int)
    red = (rgb[..., 0] > 2 * rgb[..., 1]) & (frame.instances == 1)
    rx = np.nonzero(red)[1]
    plugs = (xs < uv[0, 0] - 1) | (xs > uv[1, 0] + 1)
    assert len(rx) > 50 and plugs.sum() > 20
    assert np.sum((rx < uv[0, 0] - 1) | (rx > uv[1, 0] + 1)) <= 0.1 * plugs.sum()
