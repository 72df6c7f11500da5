"""Contact at the robot's time step (stable integrator, dt = 1e-2 s): no tunnelling, no step
halvings, safe starts; and clear errors for bad mesh files.

Depths are measured with analytic signed distances of the colliders written here (not the
engine's queries), at five points along every segment, after every step.
"""

from __future__ import annotations

import logging

import numpy as np
import pytest
import trimesh

import deformx as dx

DT = 1e-2
HEIGHT = 1.0  # m: impact at ~4.4 m/s


def _box_sdf(Q, c, he):
    q = np.abs(Q - c) - he
    return np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0)


def _segment_points(P, m=5):
    s = np.linspace(0.0, 1.0, m)[:, None, None]
    return (P[:-1][None] * (1.0 - s) + P[1:][None] * s).reshape(-1, 3)


def _scene(kind: str, r: float, E: float, integrator: str = "stable", dt: float = DT,
           z0: float = HEIGHT):
    """A 0.4 m rope (40 elements) above a collider, the floor 0.3 m below it; returns the
    world, the rope and the collider's signed distance (m, negative inside)."""
    world = dx.World(dt=dt, integrator=integrator, rod_contact=False)
    if kind == "plane":
        world.add_plane()

        def sdf(Q):
            return Q[:, 2]
    elif kind == "sheet":  # an open mesh of two triangles: no inside, either side holds
        V = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float)
        world.add_mesh((V, np.array([[0, 1, 2], [0, 2, 3]])))

        def sdf(Q):
            return np.abs(Q[:, 2])
    elif kind in ("plate", "box", "slab"):
        ext = {"plate": (1.0, 1.0, 0.002), "box": (0.3, 0.3, 0.1), "slab": (1.0, 1.0, 0.1)}[kind]
        mesh = trimesh.creation.box(extents=ext)
        mesh.apply_translation((0.0, 0.0, -ext[2] / 2))
        world.add_mesh(mesh)
        c, he = np.array([0.0, 0.0, -ext[2] / 2]), np.array(ext) / 2

        def sdf(Q):
            return _box_sdf(Q, c, he)
    elif kind == "cylinder":  # radius 5 cm, axis along y, top at z = 0
        R = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])
        world.add_cylinder(radius=0.05, length=0.6, pose=((0.0, 0.0, -0.05), R))

        def sdf(Q):
            radial = np.hypot(Q[:, 0], Q[:, 2] + 0.05) - 0.05
            axial = np.abs(Q[:, 1]) - 0.3
            return (np.hypot(np.maximum(radial, 0), np.maximum(axial, 0))
                    + np.minimum(np.maximum(radial, axial), 0))
    else:
        raise ValueError(kind)
    world.add_plane(point=(0.0, 0.0, -0.3))
    rope = world.add_rod(dx.Rod.straight(n_elements=40, start=(-0.2, 0.0, z0 + r),
                                         direction=(1, 0, 0), length=0.4, radius=r,
                                         density=1000.0, youngs_modulus=E, damping=1.0))
    return world, rope, sdf


CASES = [pytest.param(kind, r, E, id=f"{kind}-r{r * 1e3:g}mm-E{E:.0e}")
    for kind in ("plane", "sheet", "plate", "box", "cylinder")
    for r in (1e-3, 5e-3) for E in (1e5, 2e11)] + [
    # the rope whips round the box's edge at impact: the edge node and the segments turning
    # round it (planes added at the converged iterate) carry it
    pytest.param("box", 1e-3, 1e7, id="box-r1mm-E1e+07")]


@pytest.mark.parametrize("kind, r, E", CASES)
def test_rope_dropped_at_large_steps_stays_outside(kind, r, E, caplog):
    _drop_stays_outside(kind, r, E, HEIGHT, caplog)


@pytest.mark.parametrize("z0", [1.0002, 1.0008])
def test_thin_soft_rope_whipped_round_a_cylinder_stays_outside_from_other_heights(z0, caplog):
    """The hardest drop (1 mm, E = 1e5 Pa: the rope whips round the cylinder, its steps take
    up to 40 iterations and release planes near convergence) from 0.2 and 0.8 mm higher: these
    heights went 44 % and 39 % of the radius deep while a released plane still counted as
    holding a segment where it cut into the shape."""
    _drop_stays_outside("cylinder", 1e-3, 1e5, z0, caplog)


# Every drop again from 0.1-0.8 mm higher: a requirement met at one start only is luck (three
# tests once passed at their own start and failed 0.2-0.6 mm higher; docs/contact.md).
NEARBY = tuple(1e-4 * k for k in range(1, 9))


@pytest.mark.slow
@pytest.mark.parametrize("kind, r, E", CASES)
def test_rope_dropped_from_nearby_heights_stays_outside(kind, r, E, caplog):
    for dz in NEARBY:
        _drop_stays_outside(kind, r, E, HEIGHT + dz, caplog)


def _drop_stays_outside(kind, r, E, z0, caplog):
    world, rope, sdf = _scene(kind, r, E, z0=z0)
    worst = 0.0
    with caplog.at_level(logging.WARNING, logger="deformx"):
        for _ in range(200):  # impact at ~0.45 s, then 1.5 s to settle
            world.step()
            P = rope.positions
            assert np.all(np.isfinite(P))
            worst = max(worst, float((r - sdf(_segment_points(P))).max()))
            assert P[:, 2].min() > -0.3, "passed through to the floor"
    # never inside by more than a step resolves, so no start-penetration warning (a node behind
    # only the plane where it was headed, past a box edge, once gave a false one)
    assert not [rec for rec in caplog.records if "inside a collider" in rec.message]
    stats = world.solver_stats()
    print(f"{kind} r={r} E={E:g}: depth {worst * 1e3:.3f} mm, {stats}")
    assert worst <= 0.2 * r, f"{worst * 1e3:.3f} mm deep ({worst / r:.0%} of the radius)"
    assert stats["halvings"] < 2, stats  # fewer than one per 100 steps
    if kind != "cylinder":  # on the cylinder a rope may slide off (without passing through)
        assert np.abs(rope.velocities).max() < 0.05 and rope.positions[20, 2] > 0.0


@pytest.mark.parametrize("kind, depth", [("plane", 0.0025), ("plane", 0.005),
                                         ("plane", 0.0075), ("slab", 0.003), ("box", 0.003)])
def test_rope_starting_inside_is_pushed_out_gently(kind, depth, caplog):
    """A rope placed ``depth`` into a collider (half its radius, centred on the surface, its
    centreline below it) comes out at well under 0.5 m/s, and the world says so once."""
    r = 0.005
    world, rope, sdf = _scene(kind, r, 1e6, z0=-depth)
    speed = 0.0
    with caplog.at_level(logging.WARNING, logger="deformx"):
        for _ in range(100):
            world.step()
            speed = max(speed, float(np.linalg.norm(rope.velocities, axis=1).max()))
    warnings = [rec for rec in caplog.records if "inside a collider or plane" in rec.message]
    assert len(warnings) == 1 and "rod 0" in warnings[0].message
    assert speed < 0.5, f"launched at {speed:.3g} m/s"
    assert sdf(rope.positions).min() > 0.8 * r  # out, resting on top


@pytest.mark.parametrize("kind, depth", [("plane", 0.0025), ("plane", 0.005), ("slab", 0.003),
                                         ("box", 0.002), ("box", 0.003)])
def test_explicit_rope_starting_inside_is_not_launched(kind, depth, caplog):
    """The same with the explicit integrator (dt = 2e-5 s): before, 2.5 mm into the ground
    sent the rope 0.94 m up; 2 and 3 mm into the box, whose edges the rope crosses (a segment
    over an edge, its outer node touching nothing, kept no offset), 3.7 and 5.5 m/s."""
    r = 0.005
    world, rope, sdf = _scene(kind, r, 1e6, integrator="verlet", dt=2e-5, z0=-depth)
    speed = 0.0
    with caplog.at_level(logging.WARNING, logger="deformx"):
        for _ in range(100):
            world.step(100)
            speed = max(speed, float(np.linalg.norm(rope.velocities, axis=1).max()))
    warnings = [rec for rec in caplog.records if "inside a collider or plane" in rec.message]
    assert len(warnings) == 1 and "rod 0" in warnings[0].message
    assert speed < 0.5, f"launched at {speed:.3g} m/s"
    assert sdf(rope.positions).min() > 0.8 * r  # out, resting on top


@pytest.mark.parametrize("depth", [0.001, 0.003])
def test_explicit_rope_starting_inside_a_cylinder_is_not_kicked(depth):
    """Placed across the cylinder's top, the rope drapes round it under gravity; placed 1 or
    3 mm inside, it must not gain more (before, 1.8 m/s within 2 ms and 0.7 m/s within 12 ms:
    a segment next to the top node took that node's depth again once its other neighbour
    lifted off)."""
    r = 0.005
    world, rope, _ = _scene("cylinder", r, 1e6, integrator="verlet", dt=2e-5, z0=-depth)
    speed = 0.0
    for _ in range(10):  # 20 ms: resting on the cylinder, the rope gains ~0.15 m/s
        world.step(100)
        speed = max(speed, float(np.linalg.norm(rope.velocities, axis=1).max()))
    assert speed < 0.5, f"kicked to {speed:.3g} m/s"


@pytest.mark.slow
@pytest.mark.parametrize("shift", [0.0005, 0.002, 0.005])
def test_explicit_rope_starting_inside_a_box_elsewhere_is_not_launched(shift):
    """The box case from 0.5-5 mm further along (before, 2-7.5 m/s; 1.0 and 0.7 m/s at 0.5
    and 2 mm while a segment's excess over its nodes was offset on its own, not its depth)."""
    r = 0.005
    world = dx.World(dt=2e-5, integrator="verlet", rod_contact=False)
    mesh = trimesh.creation.box(extents=(0.3, 0.3, 0.1))
    mesh.apply_translation((0.0, 0.0, -0.05))
    world.add_mesh(mesh)
    rope = world.add_rod(dx.Rod.straight(n_elements=40, start=(-0.2 + shift, 0.0, r - 0.003),
                                         direction=(1, 0, 0), length=0.4, radius=r,
                                         density=1000.0, youngs_modulus=1e6, damping=1.0))
    speed = 0.0
    for _ in range(100):
        world.step(100)
        speed = max(speed, float(np.linalg.norm(rope.velocities, axis=1).max()))
    assert speed < 0.5, f"launched at {speed:.3g} m/s"


def _dragged(kind: str):
    """A clamp drags a 0.4 m rope (r = 5 mm) at 1 m/s over a 4 cm mesh kerb (lifting the end
    over it) or past a 2 cm mesh post and round it; returns the world, the rope, the clamp's
    velocity as a function of time, and the obstacle's analytic signed distance."""
    r = 0.005
    world = dx.World(dt=DT, integrator="stable", rod_contact=False)
    world.add_plane(friction=0.5)
    rope = world.add_rod(dx.Rod.straight(n_elements=40, start=(0.0, 0, r), direction=(-1, 0, 0),
                                         length=0.4, radius=r, density=1000.0,
                                         youngs_modulus=1e6, damping=1.0))
    if kind == "kerb":
        ext, c = np.array([0.1, 1.0, 0.04]), np.array([0.25, 0.0, 0.02])
        mesh = trimesh.creation.box(extents=ext)
        mesh.apply_translation(c)

        def sdf(Q):
            return _box_sdf(Q, c, ext / 2)

        def velocity(t):
            return (1.0, 0.0, 0.3 if t < 0.2 else 0.0)
    else:
        pc = np.array([0.15, 0.03])
        mesh = trimesh.creation.cylinder(radius=0.02, height=0.3, sections=48)
        mesh.apply_translation((pc[0], pc[1], 0.15))

        def sdf(Q):
            return np.linalg.norm(Q[:, :2] - pc, axis=1) - 0.02

        def velocity(t):
            return (1.0, 0.0, 0.0) if t < 0.3 else (0.0, 1.0, 0.0)
    world.add_mesh(mesh, friction=0.5)
    return world, rope, velocity, sdf


def _drag(kind: str, speed: float = 1.0):
    """Runs the drag (the clamp's horizontal velocity times ``speed``, the kerb's lift as it
    is); returns the world, the rope and the deepest point of any segment inside the obstacle
    over the run (m)."""
    world, rope, velocity, sdf = _dragged(kind)
    clamp = rope.fix_start()
    worst = -np.inf
    for s in range(70):
        v = velocity(s * DT)
        clamp.set_velocity((speed * v[0], speed * v[1], v[2]))
        world.step()
        worst = max(worst, float((rope.radius - sdf(_segment_points(rope.positions))).max()))
    return world, rope, worst


def _assert_dragged_past_without_tunnelling(rope, worst):
    assert worst <= 0.2 * rope.radius, f"{worst * 1e3:.3f} mm deep"
    assert rope.positions[-1, 0] > 0.25  # dragged past the obstacle, not held behind


@pytest.mark.parametrize("kind", ["kerb", "post"])
def test_rope_dragged_over_a_kerb_and_round_a_post_does_not_tunnel(kind):
    _, rope, worst = _drag(kind)
    _assert_dragged_past_without_tunnelling(rope, worst)
    # it did touch the obstacle (over the kerb the rope mostly flies, its end whipped up: at
    # 0.99 or 1.01 times the speed it passes 0.3 mm above the edge)
    assert worst >= -0.05 * rope.radius


@pytest.mark.parametrize("kind", ["kerb", "post"])
def test_rope_dragged_over_a_kerb_and_round_a_post_without_halving(kind):
    world, _, _ = _drag(kind)
    assert world.solver_stats()["halvings"] < 1


@pytest.mark.slow
@pytest.mark.parametrize("speed", [0.95, 0.97, 0.99, 1.01, 1.03, 1.05])
@pytest.mark.parametrize("kind", ["kerb", "post"])
def test_rope_dragged_a_little_slower_or_faster_neither_tunnels_nor_halves(kind, speed):
    world, rope, worst = _drag(kind, speed)
    _assert_dragged_past_without_tunnelling(rope, worst)
    assert world.solver_stats()["halvings"] < 1


def _pushed_along_the_floor(shape: str, speed: float, r: float = 0.005, E: float = 1e6):
    """A rope (radius ``r``, Young's modulus ``E``) lying on the floor along y, a 3 cm shape
    lying beside it driven into it along x at ``speed`` (m/s) for 0.3 s; asserts it never went
    deeper than 20 % of its radius into either (analytic distances) and was carried ahead of
    the shape at its speed; returns the world."""
    world = dx.World(dt=DT, integrator="stable", rod_contact=False)
    world.add_plane(friction=0.5)
    rope = world.add_rod(dx.Rod.straight(n_elements=40, start=(0.0, -0.2, r), direction=(0, 1, 0),
                                         length=0.4, radius=r, density=1000.0,
                                         youngs_modulus=E, damping=1.0))
    R = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])  # axis along y
    if shape == "cylinder":
        body = world.add_cylinder(radius=0.03, length=0.6, pose=((-0.065, 0.0, 0.03), R),
                                  friction=0.5)
    else:
        body = world.add_capsule(radius=0.03, length=0.6, pose=((-0.065, 0.0, 0.03), R),
                                 friction=0.5)
    body.set_velocity((speed, 0.0, 0.0))
    floor = shape_depth = -np.inf
    for _ in range(30):
        world.step()
        Q = _segment_points(rope.positions)
        c = body.position
        floor = max(floor, r - Q[:, 2].min())  # (both shapes are 0.6 m long: no end reached)
        shape_depth = max(shape_depth, r - (np.hypot(Q[:, 0] - c[0], Q[:, 2] - c[2]) - 0.03).min())
    assert floor <= 0.2 * r, f"{floor / r:.0%} of the radius into the floor"
    assert shape_depth <= 0.2 * r, f"{shape_depth / r:.0%} of the radius into the {shape}"
    assert rope.positions[:, 0].min() > body.position[0]  # carried ahead of it
    assert np.abs(rope.velocities[:, 0].mean() - speed) < 0.1 * speed
    return world


@pytest.mark.parametrize("speed", [1.0, 2.0])
@pytest.mark.parametrize("shape", ["cylinder", "capsule"])
def test_shape_pushing_a_rope_along_the_floor_keeps_it_out_of_both(shape, speed):
    """A robot link's case: a shape sweeping a rope along the table. For a fast node a shape
    gives two planes (the nearest, and the one where it is headed); they crowded the floor's
    plane out of the node's two, and the rope sank 24 % (1 m/s) and 75 % (2 m/s) of its radius
    into the floor in one step."""
    world = _pushed_along_the_floor(shape, speed)
    assert world.solver_stats()["halvings"] < 1


@pytest.mark.parametrize("speed", [0.5, 1.0])
@pytest.mark.parametrize("shape", ["cylinder", "capsule"])
def test_shape_pushing_a_thin_rope_along_the_floor_keeps_it_out_of_both(shape, speed):
    """The same with a 1 mm rope (E = 1e5 Pa): it sank 23 % (0.5 m/s) and 49 % (1 m/s) of its
    radius into the floor under the planes where its nodes were headed (their flight in the
    world, not relative to the cylinder), and at 1 m/s was then carried along half its radius
    inside the floor by a plane where it was not. The capsule at 0.5 m/s then wedged it in 75 %
    deep: the friction bounds fixed in the step it was met kept the normal forces of before
    its contacts were stiffened (0.016 against 7 N)."""
    world = _pushed_along_the_floor(shape, speed, 0.001, 1e5)
    assert world.solver_stats()["halvings"] < 1


@pytest.mark.parametrize("speed", [0.5, 1.0])
@pytest.mark.parametrize("shape", ["cylinder", "capsule"])
def test_shape_pushing_a_steel_wire_along_the_floor_keeps_it_out_of_both(shape, speed):
    """A 1 mm steel wire (E = 2e11 Pa) pushed so: under the cylinder at 1 m/s it ended a step
    97 % of its radius in the floor, the floor's plane released near convergence (it had
    pulled) and the release rounds spent; a plane released deep behind acts again now. (One
    or two steps in 30 still halve: not asserted.)"""
    _pushed_along_the_floor(shape, speed, 0.001, 2e11)


def _rotz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@pytest.mark.parametrize("kind, r, E, spin", [
    ("box", 5e-3, 1e6, 10.0), ("box", 1e-3, 2e11, 10.0), ("box", 1e-3, 2e11, 20.0),
    ("box", 1e-3, 1e5, 10.0), ("mesh", 5e-3, 1e6, 10.0), ("mesh", 1e-3, 1e5, 10.0)])
def test_paddle_swung_through_a_rope_on_the_floor_does_not_cut_it(kind, r, E, spin):
    """A robot link's sweep: a 0.3 x 0.02 x 0.04 m paddle (box primitive or mesh), 0.5 mm above
    the floor, pivoting about a vertical axis at one end at ``spin`` rad/s (tip 3.1 / 6.2 m/s)
    through a rope lying across its path. The box's plane where a node was headed, taken
    nearest the end of the node's own flight (none for a node at rest), let the 1 mm steel wire
    be cut 144 % (10 rad/s) and 183 % (20 rad/s) of its radius deep; nearest the end of its
    flight relative to the paddle, past the tip, it put the 5 mm rope 2.4 radii behind a plane
    of the far corner (49 % deep)."""
    world = dx.World(dt=DT, integrator="stable", rod_contact=False)
    world.add_plane(friction=0.5)
    rope = world.add_rod(dx.Rod.straight(n_elements=40, start=(0.1, 0.05, r), direction=(1, 0, 0),
                                         length=0.4, radius=r, density=1000.0, youngs_modulus=E,
                                         damping=1.0))
    he = np.array([0.15, 0.01, 0.02])
    a0 = -np.pi / 2

    def centre(a):  # the pivot at the origin, the paddle along its local x
        return _rotz(a) @ np.array([he[0] + 0.01, 0.0, he[2] + 0.0005])

    pose = (centre(a0), _rotz(a0))
    paddle = (world.add_box(he, pose=pose, friction=0.5) if kind == "box" else
              world.add_mesh(trimesh.creation.box(extents=2 * he), pose=pose, friction=0.5))
    worst = -np.inf
    for k in range(int(round((np.pi / 2 + 0.6) / spin / DT))):
        c = centre(a0 + spin * k * DT)
        paddle.set_velocity((-spin * c[1], spin * c[0], 0.0), (0.0, 0.0, spin))
        world.step()
        Q = _segment_points(rope.positions)
        inside = r - _box_sdf((Q - paddle.position) @ paddle.rotation, np.zeros(3), he)
        worst = max(worst, inside.max(), r - Q[:, 2].min())
    assert worst <= 0.2 * r, f"{worst / r:.0%} of the radius deep"
    assert np.abs(rope.velocities).max() < 2.0 * spin * 0.31  # swept along, not flung
    assert world.solver_stats()["halvings"] < 1


# ------------------------------------------------------------------ bad inputs
def _write(path, data: bytes):
    path.write_bytes(data)
    return path


@pytest.fixture
def mesh_files(tmp_path):
    box = trimesh.creation.box()
    files = {}
    for ext in ("obj", "stl", "ply", "glb"):
        good = tmp_path / f"good.{ext}"
        box.export(good)
        data = good.read_bytes()
        files[f"truncated {ext}"] = _write(tmp_path / f"truncated.{ext}", data[: len(data) // 3])
        files[f"garbage {ext}"] = _write(tmp_path / f"garbage.{ext}", b"\x00\x13 not a mesh" * 5)
        files[f"empty {ext}"] = _write(tmp_path / f"empty.{ext}", b"")
    files["face index"] = _write(tmp_path / "index.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    files["nan"] = _write(tmp_path / "nan.obj", b"v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n")
    files["inf"] = _write(tmp_path / "inf.obj", b"v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n")
    files["format"] = _write(tmp_path / "mesh.xyz", b"0 0 0\n")
    return files


def test_bad_mesh_files_give_a_value_error_naming_the_file(mesh_files):
    world = dx.World()
    for what, path in mesh_files.items():
        with pytest.raises(ValueError) as err:
            world.add_mesh(path)
        assert path.name in str(err.value), what
    assert not world.colliders


def test_bad_mesh_arrays_are_refused():
    world = dx.World()
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    with pytest.raises(ValueError, match="face indices"):
        world.add_mesh((V, np.array([[0, 1, 3]])))
    with pytest.raises(ValueError, match="NaN or infinite"):
        world.add_mesh((np.array([[0.0, 0, 0], [1, 0, 0], [0, np.nan, 0]]),
                        np.array([[0, 1, 2]])))
    with pytest.raises(ValueError, match="integer"):
        world.add_mesh((V, np.array([[0.0, 1.0, 2.0]])))


def test_short_elements_and_short_runs_are_flagged():
    world = dx.World(dt=1e-3)
    with pytest.warns(UserWarning, match="tenth of the rod's radius"):
        world.add_rod(dx.Rod.straight(n_elements=100, length=0.04, radius=0.005))
    with pytest.warns(UserWarning, match="shorter than half a step"):
        world.run(1e-4)
    assert world.time == 0.0


@pytest.mark.parametrize("kind", ["plane", "box"])
def test_small_steps_keep_their_stiffness(kind):
    """At dt = 1e-3 an impact is resolved over several steps: its penetration must not be
    mistaken for a rope placed inside (whose push-out is slowed), which once let a rope sink
    to 42 % of its radius into the box's edges."""
    r = 0.005
    world, rope, sdf = _scene(kind, r, 1e6, dt=1e-3, z0=0.5)
    worst = 0.0
    for _ in range(100):
        world.step(8)
        worst = max(worst, float((r - sdf(_segment_points(rope.positions))).max()))
    assert worst <= 0.2 * r, f"{worst * 1e3:.3f} mm deep"


def test_elements_wrapping_a_cylinder_keep_their_middles_out():
    """A 1 mm rope of 2 cm elements falling round a 5 cm cylinder at dt = 1e-2 s: a chord
    between two nodes on the cylinder passes 1 mm (its radius) inside, and while the rope wraps
    a segment is often deepest at an end at the step start; its middle gets a plane of its own.
    Exact segment-to-cylinder depths at nine points per segment, every step (before: 67 %)."""
    r, R = 0.001, 0.05
    world = dx.World(dt=DT, integrator="stable", rod_contact=False)
    Ry = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])  # local z along world y
    world.add_cylinder(radius=R, length=0.2, pose=((0.0, 0.0, -R), Ry), friction=0.8)
    rope = world.add_rod(dx.Rod.straight(n_elements=15, start=(-0.15, 0.0, r + 0.002),
                                         direction=(1, 0, 0), length=0.3, radius=r,
                                         density=1000.0, youngs_modulus=1e5, damping=1.0))
    worst = -np.inf
    for _ in range(60):
        world.step()
        Q = _segment_points(rope.positions, 9)
        worst = max(worst, float((r - (np.hypot(Q[:, 0], Q[:, 2] + R) - R)).max()))
    P = rope.positions
    assert P[0, 2] < -R and P[-1, 2] < -R, "the rope did not drape over the cylinder"
    assert (np.hypot(P[:, 0], P[:, 2] + R) < R + 2.5 * r).sum() >= 6
    assert worst <= 0.2 * r, f"{worst * 1e3:.3f} mm deep ({worst / r:.0%} of the radius)"
    assert world.solver_stats()["halvings"] == 0


@pytest.mark.parametrize("kind", ["plane", "box", "cylinder"])
def test_thin_rope_at_small_steps_stays_as_far_out_as_at_large_ones(kind):
    """A 1 mm rope dropped 1 m at dt = 1e-3 s: the penalty stops a 5 m/s impact within a tenth
    of the radius in one step (before, chosen from the node's mass alone, it let the rope sink
    40 % of its radius into the ground and 54-63 % into the box and the cylinder: deeper than
    at dt = 1e-2). Every step checked."""
    r = 0.001
    world, rope, sdf = _scene(kind, r, 1e6, dt=1e-3)
    worst = 0.0
    for _ in range(700):  # impact at ~0.45 s
        world.step()
        worst = max(worst, float((r - sdf(_segment_points(rope.positions))).max()))
    assert worst <= 0.2 * r, f"{worst * 1e3:.3f} mm deep ({worst / r:.0%} of the radius)"
    assert world.solver_stats()["halvings"] == 0


EDGE_BOX = np.array([0.3, 0.3, 0.1])  # extents (m) of the box whose edge the rope lies over


def _rope_over_box_edge(collider: str, n_elements: int, lift: float = 0.0):
    """Half of a 0.3 m, 1 mm rope (E = 1e5) laid over the edge of a box (top at z = 0) as a mesh
    or a primitive, ``lift`` (m) higher than 2 mm above it, at dt = 1e-2 s; returns the world,
    the box (primitive, else None), the rope and its depth (m) into a box centred at c: nine
    points per segment."""
    r = 0.001
    world = dx.World(dt=DT, integrator="stable", rod_contact=False)
    c = np.array([0.0, 0.0, -0.05])
    box = None
    if collider == "mesh":
        mesh = trimesh.creation.box(extents=EDGE_BOX)
        mesh.apply_translation(c)
        world.add_mesh(mesh)
    else:
        box = world.add_box(half_extents=EDGE_BOX / 2, pose=(c, np.eye(3)))
    rope = world.add_rod(dx.Rod.straight(n_elements=n_elements, start=(0.0, 0.0, r + 0.002 + lift),
                                         direction=(1, 0, 0), length=0.3, radius=r,
                                         density=1000.0, youngs_modulus=1e5, damping=1.0))

    def depth(c=c):
        return float((r - _box_sdf(_segment_points(rope.positions, 9), c, EDGE_BOX / 2)).max())
    return world, box, rope, depth


@pytest.mark.parametrize("n_elements, lift", [(15, 0.0), (30, 0.0), (15, 0.0006)])
@pytest.mark.parametrize("collider", ["mesh", "primitive"])
def test_rope_sliding_off_a_box_edge_keeps_its_segments_out(collider, n_elements, lift):
    """The rope swings down round the edge; exact depths every step. With 2 cm elements the
    segment on the edge is level over the top face at a step's start (deepest at an end, which
    its node carries) and its other node out of reach; in the step it turns round the edge and
    cut the corner 145 % of the radius deep (140 % off the box primitive) before segments were
    checked at the converged iterate. Dropped 0.6 mm higher onto the mesh, the segment across
    the edge cut in again after two rounds of such planes in a step (29 %); four now."""
    world, _, rope, depth = _rope_over_box_edge(collider, n_elements, lift)
    worst = 0.0
    for _ in range(60):
        world.step()
        worst = max(worst, depth())
    r = rope.radius
    assert rope.positions[-1, 2] < -0.1  # the free half hangs down the side
    assert worst <= 0.2 * r, f"{worst * 1e3:.3f} mm deep ({worst / r:.0%} of the radius)"
    assert world.solver_stats()["halvings"] < 2


@pytest.mark.parametrize("n_elements", [15, 30])
def test_rope_over_a_moving_box_edge_keeps_its_segments_out(n_elements):
    """The same rope over the box primitive's edge, the box then driven back and up under it at
    (-0.5, 0, 0.3) m/s: the edge sweeps along the rope, whose segments turn round it within a
    step (85 % and 23 % of the radius deep before segments were checked at the converged
    iterate)."""
    world, box, rope, depth = _rope_over_box_edge("primitive", n_elements)
    worst = 0.0
    for k in range(60):
        if k == 20:
            box.set_velocity((-0.5, 0.0, 0.3))
        world.step()
        worst = max(worst, depth(box.pose[:3, 3]))
    r = rope.radius
    assert box.pose[0, 3] == pytest.approx(-0.2)  # it moved 0.2 m under the rope
    assert worst <= 0.2 * r, f"{worst * 1e3:.3f} mm deep ({worst / r:.0%} of the radius)"
    assert world.solver_stats()["halvings"] < 2
