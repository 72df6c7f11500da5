"""The fast renderer against analytic geometry: z-depth of a plane, a rod's mask against its
projected capsule, projection with K and the pose, instance order; the tube kernel against a
NumPy construction; the files a frame writes."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import deformx as dx
from deformx.visual.camera import Camera
from deformx.visual.fast import FastRenderer
from deformx.visual.tube import Tube


def test_depth_of_a_tilted_view_of_a_plane_is_the_analytic_z_depth():
    world = dx.World()
    world.add_rod(dx.Rod.straight(n_elements=4, start=(50, 50, 1), length=0.1))  # out of view
    world.add_plane(point=(0, 0, 0), normal=(0, 0, 1))
    cam = Camera(position=(0.1, -0.2, 1.0), look_at=(0.4, 0.5, 0.0), fov_y=50, width=160,
                 height=120)
    frame = FastRenderer(world, shadows=False).render(cam)
    rays = cam.rays() @ cam.rotation.T  # world directions with unit z-depth
    expected = (0.0 - cam.position[2]) / rays[..., 2]
    ok = (expected > 0) & (expected < 10.0)
    assert ok.mean() > 0.9
    np.testing.assert_allclose(frame.depth[ok], expected[ok], atol=1e-3)
    assert np.all(frame.instances[ok] == 2)  # the plane: after the one rod


def _capsule_mask(cam: Camera, a: np.ndarray, b: np.ndarray, r: float) -> np.ndarray:
    """Pixels whose ray (through the pixel centre) passes within r of segment ab."""
    d = cam.rays() @ cam.rotation.T
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    o = cam.position
    u = (b - a) / np.linalg.norm(b - a)
    L = np.linalg.norm(b - a)
    # closest points between the ray o + t d and the segment a + s u
    w0 = o - a
    bdot = d @ u
    dd, ee = np.sum(w0 * d, axis=-1), w0 @ u
    den = 1.0 - bdot ** 2
    s = np.clip((ee - bdot * dd) / np.where(den > 1e-12, den, 1.0), 0.0, L)
    t = np.maximum(s * bdot - dd, 0.0)
    gap = (o + t[..., None] * d) - (a + s[..., None] * u)
    return np.linalg.norm(gap, axis=-1) <= r


def test_rod_masks_match_their_projected_capsules_in_world_order():
    world = dx.World()
    r0 = world.add_rod(dx.Rod.straight(n_elements=20, start=(-0.3, -0.05, 0), direction=(1, 0, 0),
                                       length=0.6, radius=0.01))
    r1 = world.add_rod(dx.Rod.straight(n_elements=20, start=(-0.3, 0.1, 0.02), direction=(1, 0, 0),
                                       length=0.6, radius=0.004))
    cam = Camera(position=(0.0, 0.0, 1.0), look_at=(0.0, 0.0, 0.0), up=(0, 1, 0), fov_y=45,
                 width=320, height=240)
    frame = FastRenderer(world, sides=32, shadows=False).render(cam, amodal=True)
    for k, rod in enumerate((r0, r1)):
        a, b = rod.positions[0], rod.positions[-1]
        want = _capsule_mask(cam, a, b, rod.node_radius[0])
        got = frame.instances == k + 1
        width = want.sum() / (cam.focal * 0.6 / 1.0)  # mask pixels / length in pixels
        iou = (want & got).sum() / (want | got).sum()
        assert iou >= (0.9 if width >= 6 else 0.7), (k, width, iou)
        assert got.sum() > 0 and frame.amodal[k + 1].sum() >= got.sum()
    assert [e["kind"] for e in frame.ids[:2]] == ["rod", "rod"]
    assert frame.visible[0].all() and frame.visible[1].all()


def test_a_thin_wire_still_gets_a_mask():
    world = dx.World()
    world.add_rod(dx.Rod.straight(n_elements=10, start=(-0.2, 0, 0), direction=(1, 0, 0),
                                  length=0.4, radius=0.0005))  # 1 mm wide at 2 m: < 1 px
    world.add_plane(point=(0, 0, -0.01))
    cam = Camera(position=(0, -1.0, 1.8), look_at=(0, 0, 0), fov_y=40, width=320, height=240)
    frame = FastRenderer(world, shadows=False).render(cam)
    assert (frame.instances == 1).sum() >= 20


def test_projection_lands_where_the_renderer_draws_a_point():
    world = dx.World()
    world.add_rod(dx.Rod.straight(n_elements=4, start=(50, 50, 1), length=0.1))
    centre = np.array([0.12, -0.07, 0.05])
    world.add_sphere(0.008, center=centre)
    cam = Camera(position=(0.5, -0.6, 0.7), look_at=(0, 0, 0), fov_y=40, width=320, height=240)
    frame = FastRenderer(world, shadows=False).render(cam)
    ys, xs = np.nonzero(frame.instances == 2)
    uv, z = cam.project(centre)
    assert len(xs) > 20
    assert abs(xs.mean() + 0.5 - uv[0]) < 1.0 and abs(ys.mean() + 0.5 - uv[1]) < 1.0
    # K and the pose say the same as project()
    K, T = cam.intrinsics, np.linalg.inv(cam.pose)
    p = K @ (T[:3, :3] @ centre + T[:3, 3])
    np.testing.assert_allclose(p[:2] / p[2], uv, atol=1e-9)


def _tube_reference(pos, Q, radius, sides):
    """A NumPy construction of the tube vertices (open rod; rings of sides + 1 vertices, the
    last on the seam), for the kernel to match."""
    t = Q[:, 2]
    d1 = Q[:, 0]
    tn = np.vstack([t[:1], t[:-1] + t[1:], t[-1:]])
    un = np.vstack([d1[:1], d1[:-1] + d1[1:], d1[-1:]])
    tn /= np.linalg.norm(tn, axis=1, keepdims=True)
    un = un - np.sum(un * tn, axis=1, keepdims=True) * tn
    un /= np.linalg.norm(un, axis=1, keepdims=True)
    wn = np.cross(tn, un)
    ang = 2 * np.pi * np.arange(sides + 1) / sides
    ring = np.cos(ang)[None, :, None] * un[:, None] + np.sin(ang)[None, :, None] * wn[:, None]
    verts = pos[:, None] + radius[:, None, None] * ring
    return np.vstack([verts.reshape(-1, 3), pos[:1], pos[-1:]])


def test_tube_kernel_equals_a_numpy_construction_and_turns_with_twist():
    rng = np.random.default_rng(3)
    pts = np.cumsum(rng.normal(scale=0.05, size=(15, 3)), axis=0)
    rod = dx.Rod.from_points(pts, radius=0.01)
    world = dx.World()
    world.add_rod(rod)
    tube = Tube(rod, sides=10)
    ref = _tube_reference(rod.positions, rod.directors, rod.node_radius, 10)
    np.testing.assert_allclose(tube.vertices, ref, atol=1e-12)
    # twist the last element by 30 deg about its tangent: its end ring turns by 30 deg
    Q = rod.directors[-1]
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    rod.directors[-1] = np.array([c * Q[0] + s * Q[1], -s * Q[0] + c * Q[1], Q[2]])
    before = tube.vertices[14 * 11:15 * 11].copy()
    tube.update()
    after = tube.vertices[14 * 11:15 * 11]
    r0 = before[0] - rod.positions[-1]
    r1 = after[0] - rod.positions[-1]
    assert math.degrees(math.acos(np.clip(r0 @ r1 / (r0 @ r0), -1, 1))) == pytest.approx(30, abs=1e-6)


def test_frame_files(tmp_path):
    world = dx.World()
    world.add_rod(dx.Rod.straight(n_elements=10, start=(-0.2, 0, 0.05), length=0.4, radius=0.01))
    world.add_plane()
    cam = Camera(position=(0.3, -0.5, 0.4), look_at=(0, 0, 0), width=64, height=48)
    frame = FastRenderer(world).render(cam)
    paths = frame.save(tmp_path, "f0_")
    import imageio.v3 as iio

    assert iio.imread(paths["rgb"]).shape == (48, 64, 3)
    inst = iio.imread(paths["instances"])
    assert inst.dtype == np.uint16 and np.array_equal(inst, frame.instances)
    mm = iio.imread(paths["depth_mm"])
    assert mm.dtype == np.uint16
    np.testing.assert_allclose(mm[np.isfinite(frame.depth)],
                               np.round(frame.depth[np.isfinite(frame.depth)] * 1000), atol=0.5)
    meta = json.loads(paths["camera"].read_text())
    np.testing.assert_allclose(meta["K"], cam.intrinsics)
    assert meta["instances"][0] == {"id": 1, "kind": "rod", "name": "rod 0"}
    assert np.load(paths["depth"]).dtype == np.float32


def test_camera_checks_its_arguments():
    with pytest.raises(ValueError, match="look_at must differ"):
        Camera(position=(0, 0, 1), look_at=(0, 0, 1))
    with pytest.raises(ValueError, match="up must not be parallel"):
        Camera(position=(0, 0, 1), look_at=(0, 0, 0), up=(0, 0, 1))
    with pytest.raises(ValueError, match="fov_y"):
        Camera(position=(0, 0, 1), look_at=(1, 0, 0), fov_y=180)
    K = Camera(position=(0, 0, 1), look_at=(1, 0, 0), fov_y=60).intrinsics
    assert Camera(position=(0, 0, 1), look_at=(1, 0, 0), K=K).fov_y == pytest.approx(60)


def test_renders_a_cosimulation_with_an_id_per_mujoco_body():
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
    for _ in range(5):
        sim.step()
    cam = Camera(position=(1.2, -1.2, 1.0), look_at=tuple(tip - [0, 0, 0.2]), width=160,
                 height=120)
    frame = FastRenderer(sim).render(cam)
    kinds = {e["name"]: e["id"] for e in frame.ids}
    assert frame.ids[0]["kind"] == "rod" and "plane" not in [e["kind"] for e in frame.ids]
    seen = set(np.unique(frame.instances).tolist())
    assert {1, kinds["world"], kinds["upper_arm_link"]} <= seen


def _twist(rod, angle: float) -> None:
    """Turn the material frames about their tangents, linearly from 0 to ``angle``."""
    E = rod.n_elements
    for e in range(E):
        th = angle * (e + 0.5) / E
        Q = rod.directors[e].copy()
        c, s = math.cos(th), math.sin(th)
        rod.directors[e] = np.array([c * Q[0] + s * Q[1], -s * Q[0] + c * Q[1], Q[2]])


def striped_wire_scene():
    """A straight wire with a yellow stripe on its d1 side, d1 facing a camera above it."""
    from deformx.visual.materials import Material

    world = dx.World()
    rod = world.add_rod(dx.Rod.straight(n_elements=40, start=(-0.3, 0, 0.1), length=0.6,
                                        radius=0.01, normal=(0, 0, 1)))
    look = Material((0.1, 0.2, 0.8), texture="stripe", texture_color=(1.0, 1.0, 0.0))
    cam = Camera(position=(0, 0, 1.0), look_at=(0, 0, 0.1), up=(0, 1, 0), fov_y=45, width=320,
                 height=240)
    return world, rod, look, cam


def stripe_columns(frame, cam, rod):
    """Position along the wire (0..1) of each image column over it, and whether the stripe's
    yellow shows there."""
    x0, x1 = cam.project(rod.positions[[0, -1]])[0][:, 0]
    rgb = frame.rgb.astype(int)
    yellow = (rgb[..., 0] > rgb[..., 2] + 60) & (rgb[..., 1] > rgb[..., 2] + 60) & (
        frame.instances == 1)
    cols = np.arange(int(x0) + 2, int(x1) - 2)
    return (cols - x0) / (x1 - x0), yellow[:, cols].any(axis=0)


def test_a_striped_texture_winds_round_a_twisted_wire():
    world, rod, look, cam = striped_wire_scene()
    r = FastRenderer(world, materials={0: look}, shadows=False)
    _, seen = stripe_columns(r.render(cam), cam, rod)
    assert seen.mean() > 0.97  # along the whole wire, also across the texture's seam (on d1)
    _twist(rod, math.pi)  # d1 turns from facing the camera to facing away
    s, seen = stripe_columns(r.render(cam), cam, rod)
    assert seen[s < 0.25].mean() > 0.95
    assert seen[s > 0.75].mean() < 0.02


def test_an_image_texture_is_laid_out_rows_round_from_d1_columns_along():
    from deformx.visual.materials import Material

    img = np.zeros((64, 64, 3), np.uint8)
    img[..., 2] = 200
    img[13:19] = (255, 255, 0)  # rows at t = 0.2-0.3 of the circumference: round d2
    world = dx.World()
    rod = world.add_rod(dx.Rod.straight(n_elements=40, start=(-0.3, 0, 0.1), length=0.6,
                                        radius=0.01, normal=(0, 1, 0)))  # d2 = +z
    cam = Camera(position=(0, 0, 1.0), look_at=(0, 0, 0.1), up=(0, 1, 0), fov_y=45, width=320,
                 height=240)
    r = FastRenderer(world, materials={0: Material(texture=img)}, shadows=False)

    def yellow_fraction():
        f = r.render(cam)
        rgb = f.rgb.astype(int)
        wire = f.instances == 1
        return np.sum((rgb[..., 0] > rgb[..., 2] + 60) & wire) / wire.sum()

    assert 0.15 < yellow_fraction() < 0.4  # the band faces the camera
    rod.directors[:] = rod.directors[:, [1, 0, 2]] * np.array([-1.0, 1.0, 1.0])[:, None]
    assert yellow_fraction() < 0.01  # d1 -> d2 = -d1 before: the band now faces away


def test_material_errors_name_the_parameter():
    from deformx.visual.materials import Material

    with pytest.raises(ValueError, match="roughness"):
        Material(roughness=2.0)
    with pytest.raises(ValueError, match="color"):
        Material(color=(1.0, 0.0))
    with pytest.raises(ValueError, match="texture_scale"):
        Material(texture="bands", texture_scale=0.0)
    with pytest.raises(ValueError, match="texture must be"):
        Material(texture="no-such-pattern")
    world = dx.World()
    world.add_rod(dx.Rod.straight(n_elements=4))
    with pytest.raises(ValueError, match="materials\\[0\\]"):
        FastRenderer(world, materials={0: "red"})
