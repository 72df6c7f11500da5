"""The photoreal renderer (Blender Cycles through bpy, extra [photoreal]): analytic z-depth,
and masks and depth that agree with the fast renderer's on the same scene. CI runs these in
its environment with the extra (numpy 1.x, bpy 5.0.1); without bpy they are skipped."""

from __future__ import annotations

import numpy as np
import pytest

import deformx as dx
from deformx.visual.camera import Camera

pytest.importorskip("bpy")
pytest.importorskip("OpenEXR")

from deformx.visual.fast import FastRenderer  # noqa: E402
from deformx.visual.photoreal import PhotorealRenderer  # noqa: E402


def test_depth_of_a_tilted_view_of_a_plane_is_the_analytic_z_depth():
    world = dx.World()
    world.add_rod(dx.Rod.straight(n_elements=4, start=(50, 50, 1), length=0.1))
    world.add_plane()
    cam = Camera(position=(0.1, -0.2, 1.0), look_at=(0.4, 0.5, 0.0), fov_y=50, width=64,
                 height=48)
    frame = PhotorealRenderer(world, samples=2, denoise=False).render(cam)
    rays = cam.rays() @ cam.rotation.T
    expected = (0.0 - cam.position[2]) / rays[..., 2]
    ok = (expected > 0) & (expected < 9.0)  # the plane is 20 m wide
    assert ok.mean() > 0.9
    np.testing.assert_allclose(frame.depth[ok], expected[ok], atol=1e-3)
    assert np.all(frame.instances[ok] == 2)


def test_masks_and_depth_agree_with_the_fast_renderer(tmp_path):
    world = dx.World()
    world.add_rod(dx.Rod.straight(n_elements=20, start=(-0.3, 0, 0.1), direction=(1, 0, 0),
                                  length=0.6, radius=0.01))
    world.add_rod(dx.Rod.straight(n_elements=20, start=(0, -0.3, 0.15), direction=(0, 1, 0),
                                  length=0.6, radius=0.008))
    world.add_plane()
    world.add_box((0.05, 0.05, 0.05), pose=(0.2, 0.2, 0.05))
    cam = Camera(position=(0.8, -0.8, 0.6), look_at=(0, 0, 0.05), width=160, height=120)
    photo = PhotorealRenderer(world, samples=4)
    a = photo.render(cam, amodal=True)
    b = FastRenderer(world, sides=16).render(cam, amodal=True)
    assert a.ids == b.ids
    for i in (1, 2):
        ma, mb = a.instances == i, b.instances == i
        assert (ma & mb).sum() / (ma | mb).sum() >= 0.9
        aa, ab = a.amodal[i], b.amodal[i]
        assert (aa & ab).sum() / (aa | ab).sum() >= 0.9
    both = np.isfinite(a.depth) & np.isfinite(b.depth) & (a.instances == b.instances)
    assert np.median(np.abs(a.depth[both] - b.depth[both])) < 1e-3
    assert a.rgb.shape == (120, 160, 3) and a.rgb.std() > 5
    path = photo.save_blend(tmp_path / "scene.blend")
    assert path.stat().st_size > 10000


def test_demo_photoreal_key_frames(tmp_path):
    from typer.testing import CliRunner

    from deformx.cli import app

    out = tmp_path / "demo"
    res = CliRunner().invoke(app, ["demo", "--duration", "0.1", "--out", str(out), "--no-video",
                                   "--no-progress", "--photoreal", "--samples", "1"])
    assert res.exit_code == 0, res.output
    rgb = sorted((out / "photoreal").glob("*_rgb.png"))
    assert len(rgb) == 3
    import imageio.v3 as iio

    ids = iio.imread(sorted((out / "photoreal").glob("*_instances.png"))[-1])
    assert set(range(1, 6)) <= set(np.unique(ids).tolist())  # the five cables


def test_cosimulation_ids_agree_with_the_fast_renderer():
    from deformx import cosim, robots

    xml = robots.ur5e(tool_length=0.3, floor=True, q0=(0.0, -1.2, 1.5, -1.87, -1.57, 0.0))
    backend = cosim.MujocoBackend(xml, keyframe="home")
    tip = backend.motion("tool_tip").position
    world = dx.World(dt=backend.dt, integrator="stable")
    rope = world.add_rod(dx.Rod.straight(n_elements=10, start=tip, direction=(0, 0, -1),
                                         length=0.3, radius=0.008))
    sim = cosim.CoSimulation(world, backend)
    sim.add_colliders("world")
    sim.attach(rope, "start", body="tool_tip")
    sim.step()
    cam = Camera(position=tuple(tip + [0.7, -0.7, 0.3]), look_at=tuple(tip - [0, 0, 0.15]),
                 width=200, height=150)
    a = PhotorealRenderer(sim, samples=2, denoise=False).render(cam)
    b = FastRenderer(sim).render(cam)
    assert a.ids == b.ids
    assert (a.instances == 1).sum() >= 10 and (b.instances == 1).sum() >= 10  # the rope
    seen = [e for e in b.ids if (b.instances == e["id"]).sum() >= 50]
    assert any(e["kind"] == "body" and e["name"] != "world" for e in seen)
    for e in seen:  # the rope and every robot link in view
        ma, mb = a.instances == e["id"], b.instances == e["id"]
        assert (ma & mb).sum() / (ma | mb).sum() >= 0.85, e


def test_a_skinned_cable_asset_keeps_its_part_materials():
    from deformx.visual import assets

    world = dx.World()
    rod = world.add_rod(dx.Rod.straight(n_elements=12, start=(-0.2, 0, 0.02), direction=(1, 0, 0),
                                        length=0.4, radius=0.003))
    world.add_plane()
    cable = assets.usb_c_cable(length=0.4, radius=0.003)
    renderer = PhotorealRenderer(world, samples=2, denoise=False, skins={0: cable.skin(rod)})
    mesh = renderer.bpy.data.objects["rod_0"].data
    assert [m.name for m in mesh.materials] == ["rod_0_part0", "rod_0_part1", "rod_0_part2"]
    index = np.zeros(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("material_index", index)
    np.testing.assert_array_equal(index, cable.part)
    shell = mesh.materials[2].node_tree.nodes["Principled BSDF"].inputs["Metallic"]
    assert shell.default_value == 1.0
    frame = renderer.render(Camera(position=(0, -0.5, 0.4), look_at=(0, 0, 0), width=80,
                                   height=60))
    assert (frame.instances == 1).sum() > 20


def test_a_striped_texture_turns_with_twist_as_in_the_fast_renderer():
    import math

    from .test_visual_fast import _twist, stripe_columns, striped_wire_scene

    world, rod, look, cam = striped_wire_scene()
    world.add_plane(point=(0, 0, -0.5))  # something to bounce light from
    _twist(rod, math.pi)
    fast = FastRenderer(world, materials={0: look}, shadows=False).render(cam)
    real = PhotorealRenderer(world, samples=8, materials={0: look}).render(cam)
    s, seen_fast = stripe_columns(fast, cam, rod)
    _, seen_real = stripe_columns(real, cam, rod)
    assert seen_real[s < 0.25].mean() > 0.95 and seen_real[s > 0.75].mean() < 0.02
    assert np.mean(seen_fast != seen_real) < 0.05
