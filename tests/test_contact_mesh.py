"""Mesh contact: thin plates, floors, slopes, reactions; both integrators.

References: statics (the contact force carries the weight), Coulomb's law on a slope
(hold below the friction angle, slide with a = g (sin t - mu_k cos t) above it), Newton's third
law (the mesh's reaction is minus the rods' contact force) and geometry (segment-to-plate
distances from the box's exact distance function, sampled densely along each segment).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

import deformx as dx
from deformx.engine.contact.segments import Q_FLAT
from deformx.engine.geometry.shapes import grid_mesh

G = 9.81
SETUPS = {"verlet": 2e-5, "stable": 1e-3}  # integrator: dt (s)


def rope(n: int, start, direction=(1.0, 0.0, 0.0), dl: float = 0.01, radius: float = 0.002,
         E: float = 1e6, damping: float = 2.0) -> dx.Rod:
    return dx.Rod.straight(n_elements=n, start=start, direction=direction, length=n * dl,
                           radius=radius, youngs_modulus=E, density=1000.0, damping=damping)


def grid_floor(size: float = 1.0, n: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """An open square grid mesh at z = 0 (2 n^2 triangles)."""
    return grid_mesh(size, n)


def segment_box_distances(half: np.ndarray, pos: np.ndarray, samples: int = 41) -> np.ndarray:
    """Signed distance (m) of each segment axis to a centred box of half extents ``half``,
    by dense sampling along the segment and the box's exact distance function (independent
    of DeformX's mesh geometry)."""
    t = np.linspace(0.0, 1.0, samples)[None, :, None]
    pts = pos[:-1, None, :] * (1 - t) + pos[1:, None, :] * t
    q = np.abs(pts) - half
    d = np.linalg.norm(np.maximum(q, 0.0), axis=2) + np.minimum(q.max(axis=2), 0.0)
    return d.min(axis=1)


@pytest.mark.parametrize("integrator", sorted(SETUPS))
def test_rope_drapes_over_thin_plate_and_never_passes_through(integrator):
    """1 cm elements, 2 mm radius, a 2 mm thick plate: node spheres alone would straddle it."""
    plate = trimesh.creation.box(extents=(0.002, 0.4, 0.2))  # top edge at z = 0.1
    world = dx.World(dt=SETUPS[integrator], integrator=integrator)
    # Nodes at x = +-0.005, ... : the plate (|x| <= 1 mm) lies between two nodes.
    rod = world.add_rod(rope(30, start=(-0.15, 0.0, 0.108), damping=5.0))
    mesh = world.add_mesh(plate, friction=0.3)
    worst = np.inf
    for _ in range(40):
        world.run(0.025)
        d = segment_box_distances(np.array([0.001, 0.2, 0.1]), rod.positions)
        worst = min(worst, d.min())
    r = 0.002
    # Capsules may sink into the plate by the penalty's small elastic compression only.
    assert worst >= 0.9 * r, f"a segment came {worst * 1e3:.3f} mm from the plate (r = 2 mm)"
    x = rod.positions
    mid = np.argmin(np.abs(x[:, 0]))
    assert x[mid, 2] > 0.1, "the rope's middle fell below the top edge"
    assert x[0, 2] < 0.06 and x[-1, 2] < 0.06, "the rope did not drape down both sides"
    assert np.sign(x[0, 0]) != np.sign(x[-1, 0]), "the rope slid off to one side"
    # Hanging at rest: the plate carries the whole weight.
    world.run(1.0)
    assert mesh.force[2] == pytest.approx(-rod.mass * G, rel=0.01)


@pytest.mark.parametrize("integrator", sorted(SETUPS))
def test_rope_on_mesh_floor_weight_is_carried(integrator):
    V, F = grid_floor(1.0, 40)  # 3200 triangles, open: two-sided
    world = dx.World(dt=SETUPS[integrator], integrator=integrator)
    rod = world.add_rod(rope(40, start=(-0.2, 0.013, 0.01)))
    floor = world.add_mesh((V, F), friction=0.5)
    world.run(0.6)
    W = rod.mass * G
    total = world.contact_forces(rod).sum(axis=0)
    assert total[2] == pytest.approx(W, rel=0.01)
    assert np.abs(total[:2]).max() < 1e-3 * W
    assert rod.positions[:, 2] == pytest.approx(0.002, abs=0.1 * 0.002)
    # Reaction: the floor feels minus what the rod feels (Newton's third law).
    np.testing.assert_allclose(floor.force, -total, rtol=1e-9, atol=1e-12 * W)


def slope_world(angle_deg: float, integrator: str, mu: float = 0.5):
    """A rope lying along the fall line of a tilted box mesh."""
    th = math.radians(angle_deg)
    R = np.array([[math.cos(th), 0.0, math.sin(th)], [0.0, 1.0, 0.0],
                  [-math.sin(th), 0.0, math.cos(th)]])  # about y: local +x points downhill
    down = R @ np.array([1.0, 0.0, 0.0])
    normal = R @ np.array([0.0, 0.0, 1.0])
    box = trimesh.creation.box(extents=(2.0, 0.5, 0.1))  # top face through the origin
    world = dx.World(dt=SETUPS[integrator], integrator=integrator)
    slope = world.add_mesh(box, pose=(-0.05 * normal, R), friction=mu)
    start = -0.1 * down + 0.002 * normal
    rod = world.add_rod(rope(20, start=start, direction=down, E=1e6, damping=0.0))
    return world, rod, slope, down, normal


@pytest.mark.parametrize("integrator", sorted(SETUPS))
def test_static_friction_holds_on_mesh_slope_below_the_limit(integrator):
    world, rod, _, down, _ = slope_world(20.0, integrator)  # tan 20 deg = 0.36 < 0.5
    world.run(0.2)
    x0 = rod.positions.copy()
    world.run(0.5)
    drift = np.abs((rod.positions - x0) @ down).max()
    assert drift < 1e-5, f"the rope crept {drift:.2e} m down a slope below the friction angle"


@pytest.mark.parametrize("integrator", sorted(SETUPS))
def test_rope_slides_on_mesh_slope_above_the_limit(integrator):
    angle, mu = 40.0, 0.5  # tan 40 deg = 0.84 > 0.5
    world, rod, _, down, _ = slope_world(angle, integrator, mu)
    world.run(0.1)
    s0, t0 = rod.positions.mean(axis=0) @ down, world.time
    v0 = rod.velocities.mean(axis=0) @ down
    world.run(0.2)
    s1, t1 = rod.positions.mean(axis=0) @ down, world.time
    th = math.radians(angle)
    a = G * (math.sin(th) - mu * math.cos(th))
    expected = v0 * (t1 - t0) + 0.5 * a * (t1 - t0) ** 2
    assert s1 - s0 == pytest.approx(expected, rel=0.03)


@pytest.mark.parametrize("integrator", sorted(SETUPS))
def test_reaction_wrench_is_minus_the_contact_force_on_the_rods(integrator):
    """Two ropes draped over a sphere-like mesh: force and torque balance."""
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=0.05)
    world = dx.World(dt=SETUPS[integrator], integrator=integrator)
    a = world.add_rod(rope(20, start=(-0.1, 0.012, 0.053)))
    b = world.add_rod(rope(20, start=(-0.09, -0.015, 0.06), direction=(1.0, 0.1, 0.0)))
    center = np.array([0.003, -0.002, 0.0])
    ball = world.add_mesh(sphere, pose=center, friction=0.4)
    world.run(0.15)
    for _ in range(3):
        world.run(0.01)
        f_rods = sum(world.contact_forces(r).sum(axis=0) for r in (a, b))
        assert np.linalg.norm(f_rods) > 0.1 * (a.mass + b.mass) * G  # they are touching
        np.testing.assert_allclose(ball.force, -f_rods, rtol=1e-9, atol=1e-12)
        # Torque about the mesh origin: forces act at the surface points, within a rod
        # radius of the nodes.
        tau_nodes = sum(np.cross(r.positions - center, world.contact_forces(r)).sum(axis=0)
                        for r in (a, b))
        bound = 0.002 * sum(np.abs(world.contact_forces(r)).sum() for r in (a, b))
        assert np.linalg.norm(ball.torque + tau_nodes) <= bound


def test_mesh_input_validation(tmp_path):
    world = dx.World()
    with pytest.raises(ValueError, match="mesh"):
        world.add_mesh("no/such/file.obj")
    with pytest.raises(ValueError, match="mesh"):
        world.add_mesh((np.zeros((3, 2)), np.array([[0, 1, 2]])))
    with pytest.raises(ValueError, match="mesh"):
        world.add_mesh(42)
    with pytest.raises(ValueError, match="two_sided"):
        V, F = grid_floor(1.0, 2)
        world.add_mesh((V, F), two_sided=False)
    with pytest.raises(ValueError, match="pose"):
        world.add_mesh(trimesh.creation.box(), pose=np.ones((3, 3)))
    with pytest.raises(ValueError, match="kinetic_friction"):
        world.add_mesh(trimesh.creation.box(), static_friction=0.2, kinetic_friction=0.3)
    # A mesh file round trip (STL through trimesh).
    path = tmp_path / "box.stl"
    trimesh.creation.box(extents=(0.1, 0.1, 0.1)).export(path)
    c = world.add_mesh(path)
    assert c.faces.shape == (12, 3) and c.kind == "mesh"


@pytest.mark.parametrize("integrator", sorted(SETUPS))
def test_moving_mesh_carries_a_rope_by_friction(integrator):
    """A platform driven between steps (pose and velocity) carries the rope lying on it."""
    box = trimesh.creation.box(extents=(0.6, 0.3, 0.02))  # top face at z = 0.01
    world = dx.World(dt=SETUPS[integrator], integrator=integrator)
    rod = world.add_rod(rope(20, start=(-0.1, 0.0, 0.012)))
    platform = world.add_mesh(box, friction=0.8)
    world.run(0.1)  # settle
    x0 = rod.positions.mean(axis=0)
    v = np.array([0.2, 0.1, 0.0])  # m/s, the platform's velocity
    platform.set_velocity(linear=v)
    # As a co-simulation does: pose and velocity set before every step (the world does not
    # move colliders itself).
    chunk = world.dt
    n = int(round(0.2 / chunk))
    for k in range(n):
        platform.set_pose(position=v * chunk * (k + 1))
        world.step()
    moved = rod.positions.mean(axis=0) - x0
    # It lags by the distance friction needs to accelerate it: v^2 / (2 mu g) = 3 mm.
    lag = v[:2] * np.linalg.norm(v) / (2 * 0.8 * G)
    np.testing.assert_allclose(moved[:2], v[:2] * chunk * n - lag, atol=5e-4)
    assert abs(moved[2]) < 1e-3
    # The rope pulls back on the platform while it accelerates, not at constant velocity.
    assert np.linalg.norm(platform.force[:2]) < 0.05 * rod.mass * G


def test_penetrated_rope_is_pushed_out_of_a_closed_mesh_the_nearest_way():
    """A rope placed 3 mm deep inside a closed 4 cm slab leaves through the nearest face
    (the top), not onward through the slab."""
    box = trimesh.creation.box(extents=(0.4, 0.4, 0.04))  # top face at z = 0.02
    world = dx.World(dt=SETUPS["verlet"], gravity=(0, 0, 0))
    rod = world.add_rod(rope(10, start=(-0.05, 0.0, 0.017)))  # axis 3 mm below the top
    world.add_mesh(box, friction=0.0)
    world.run(0.05)
    assert np.all(rod.positions[:, 2] > 0.02 + 0.9 * 0.002), "not pushed out through the top"


def test_open_mesh_pushes_a_rope_back_to_its_own_side():
    """An open sheet is two-sided: a rope just under it is pushed down, one just over it up."""
    V, F = grid_floor(0.4, 8)
    world = dx.World(dt=SETUPS["verlet"], gravity=(0, 0, 0))
    below = world.add_rod(rope(10, start=(-0.05, 0.0, -0.001)))
    above = world.add_rod(rope(10, start=(-0.05, 0.1, 0.001)))
    world.add_mesh((V, F), friction=0.0)
    world.run(0.05)
    assert np.all(below.positions[:, 2] < -0.9 * 0.002)
    assert np.all(above.positions[:, 2] > 0.9 * 0.002)


def test_flat_patch_shortcut_agrees_with_the_exact_search():
    """Nodes and segments over a flat patch skip the triangle tests (the nodes' heights above
    the plane are their distances; segments add nothing to their ends). The same floor
    roughened by 1e-7 m, beyond the coplanarity tolerance, takes the exact search: the
    contact forces of a wavy, partly penetrating rope on a tilted floor agree."""
    V, F = grid_mesh(0.6, 30)
    angle = math.radians(10.0)
    R = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(angle), -math.sin(angle)],
                  [0.0, math.sin(angle), math.cos(angle)]])
    origin = np.array([0.1, -0.2, 0.3])
    radius = 0.002
    x = np.linspace(-0.2, 0.2, 41)
    local = np.column_stack([x, 0.013 + 0.01 * np.sin(20 * x),
                             radius * (0.8 + 0.15 * np.sin(37 * x))])  # 0.1-0.7 r deep
    forces, flat = [], []
    for roughness in (0.0, 1e-7):
        Vr = V.copy()
        Vr[:, 2] += roughness * np.random.default_rng(0).standard_normal(len(V))
        world = dx.World(dt=1e-7, gravity=(0.0, 0.0, 0.0), rod_contact=False)
        rod = world.add_rod(dx.Rod.from_points(local @ R.T + origin, radius=radius,
                                               youngs_modulus=1e6, density=1000.0))
        world.add_mesh((Vr, F), pose=(origin, R), friction=0.0)
        world.step(2)  # the first step fills the query caches, the second uses them
        forces.append(world.contact_forces(rod))
        flat.append(world.arrays["qc_meta"][:, Q_FLAT].copy())  # per query: the flat patch's face, or -1
    # Both paths ran (on the rough floor only queries over a single triangle stay "flat").
    assert np.all(flat[0] >= 0) and np.mean(flat[1] < 0) > 0.5
    scale = np.abs(forces[1]).max()
    assert scale > 0.0
    np.testing.assert_allclose(forces[0], forces[1], rtol=0.0, atol=1e-3 * scale)


def test_fast_queries_search_directly_and_find_what_the_exact_search_finds():
    """A query slot moving faster than its cache's skin per step (a rope dragged round a post
    at a 10 ms step) stops refilling its cache of a curved patch and searches the mesh's BVH
    directly (``Q_COL`` = -2 - collider) until it slows down; every answer along the way, cached
    or direct, is the exact nearest triangle (a fresh search without any cache), and a segment
    over a single flat face adds nothing beyond its ends, as a flat patch's shortcut says."""
    from deformx.engine.contact.segments import Q_COL, _mesh_closest
    from deformx.engine.geometry.bvh import bvh_closest_segment

    post = trimesh.creation.cylinder(radius=0.02, height=0.3, sections=48)
    world = dx.World(dt=1e-2, gravity=(0.0, 0.0, 0.0))
    world.add_rod(rope(4, (0.5, 0.5, 0.5)))
    world.add_mesh((post.vertices, post.faces))
    world.step(1)  # (packs the tables; the rope is far from the post)
    a = world.arrays
    args = (0, a["rng"][0, 4], a["pose"][0], a["par"], a["MV"], a["MF"], a["Blo"], a["Bhi"],
            a["Bleft"], a["Bright"], a["Bstart"], a["Bcount"], a["Border"], a["Fn"], a["En"],
            a["Vn"], a["Fg"], a["qc_meta"], a["qc_geo"], a["qc_tris"], a["qc_dist"],
            a["tr_stack"][0], a["tr_bound"][0])
    reach = 0.0275  # a 5 mm rope's reach at 1 m/s and 10 ms
    a["qc_meta"][:3, Q_COL] = -1  # slots 0-2 as new (the step queried them far away)
    modes = []
    for k in range(40):  # an element circling the post 1 cm per call, then 1 mm per call
        step = 0.01 if k < 25 else 0.001
        phi = (step * k if k < 25 else 0.25 + step * (k - 25)) / 0.0245
        pa = (0.0245 * math.cos(phi), 0.0245 * math.sin(phi), 0.05)
        pb = (0.0245 * math.cos(phi + 0.4), 0.0245 * math.sin(phi + 0.4), 0.052)
        for slot, (p, q) in enumerate(((pa, pa), (pa, pb))):
            hit, s, sd, n, c = _mesh_closest(*args, slot, p, q, reach, 1 if step < 0.005 else 0)
            tri, s_ref, *_, d2 = bvh_closest_segment(
                a["Blo"], a["Bhi"], a["Bleft"], a["Bright"], a["Bstart"], a["Bcount"],
                a["Border"], a["MV"], a["MF"], p, q, reach, a["rng"][0, 4])
            assert hit and tri >= 0
            assert sd == pytest.approx(math.sqrt(d2), abs=1e-12)
            x = np.add(np.multiply(1.0 - s, p), np.multiply(s, q))
            assert np.linalg.norm(x - np.asarray(c)) == pytest.approx(sd, abs=1e-12)
        modes.append(a["qc_meta"][1, Q_COL])
    assert modes[0] == 0 and -2 in modes[1:25] and modes[-1] == 0  # cached, direct, cached
    # over the post's flat top face from end to end: nothing beyond the ends, directly too
    top = int(np.argmax(post.face_normals[:, 2]))
    corners = post.vertices[post.faces[top]]
    mid = corners.mean(axis=0)
    ends = [tuple(mid + 0.3 * (corners[i] - mid) + (0.0, 0.0, 0.002 + 0.001 * i)) for i in (0, 1)]
    a["qc_meta"][2, Q_COL] = -2
    assert not _mesh_closest(*args, 2, *ends, reach, 0)[0]
    assert a["qc_meta"][2, Q_COL] == -2
