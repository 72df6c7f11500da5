"""USD export re-read with pxr gives the recorded points at every time sample; PLY per frame."""

from __future__ import annotations

import numpy as np
import pytest

import deformx as dx

pxr = pytest.importorskip("pxr")


def test_usd_export_round_trips_every_time_sample(tmp_path):
    from pxr import Usd, UsdGeom

    from deformx.visual.export import UsdWriter

    world = dx.World(dt=1e-4)
    world.add_rod(dx.Rod.straight(n_elements=10, start=(0, 0, 0.2), length=0.3, radius=0.005,
                                  youngs_modulus=1e5)).fix_start()
    world.add_plane()
    box = world.add_box((0.05, 0.05, 0.05), pose=(0.4, 0, 0.05))
    box.set_velocity(linear=(0.1, 0, 0))
    writer = UsdWriter(world, tmp_path / "run.usda", fps=50)
    world.run(0.1, callbacks=[writer])
    path = writer.save()
    stage = Usd.Stage.Open(str(path))
    assert UsdGeom.GetStageUpAxis(stage) == "Z" and UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    points = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Rods/rod_0")).GetPointsAttr()
    assert len(writer.times) == 6
    for t, frame in zip(writer.times, writer.points):
        got = np.array(points.Get(t * 50))
        np.testing.assert_allclose(got, frame[0], atol=1e-6)  # float32 in USD
    assert not np.allclose(writer.points[0][0], writer.points[-1][0])  # the rod moved
    xf = UsdGeom.Xformable(stage.GetPrimAtPath("/World/Colliders/collider_0"))
    m0 = np.array(xf.ComputeLocalToWorldTransform(0.0))
    m5 = np.array(xf.ComputeLocalToWorldTransform(5.0))
    np.testing.assert_allclose(m5[3, :3] - m0[3, :3], [0.01, 0, 0], atol=1e-9)  # 0.1 s x 0.1 m/s


def test_ply_per_frame(tmp_path):
    import trimesh

    from deformx.visual.export import export_meshes

    world = dx.World()
    world.add_rod(dx.Rod.straight(n_elements=8, length=0.2, radius=0.004))
    (path,) = export_meshes(world, tmp_path, stem="t0_")
    mesh = trimesh.load(path, process=False)
    assert len(mesh.vertices) == 9 * (12 + 1) + 2  # rings carry a texture-seam vertex
    mesh.merge_vertices()
    assert mesh.is_watertight and len(mesh.vertices) == 9 * 12 + 2
