"""get_state / set_state: running on after a restore is bit-identical to running on."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest
import trimesh

import deformx as dx


def _scene(integrator: str, dt: float) -> tuple[dx.World, list, object]:
    """Two ropes crossing over a box mesh on a frictional ground, one end dragged by a
    clamp that accelerates: mesh, rod contact, friction anchors and a moving driver."""
    world = dx.World(dt=dt, integrator=integrator)
    world.add_plane(friction=0.5)
    world.add_mesh(trimesh.creation.box(extents=(0.2, 0.2, 0.06)), pose=(0, 0, 0.03),
                   friction=0.4)
    a = world.add_rod(dx.Rod.straight(30, start=(-0.3, 0, 0.1), direction=(1, 0, 0),
                                      length=0.6, radius=0.005, density=1200.0,
                                      youngs_modulus=1e6, damping=1.0))
    b = world.add_rod(dx.Rod.straight(30, start=(0, -0.3, 0.125), direction=(0, 1, 0),
                                      length=0.6, radius=0.005, density=1200.0,
                                      youngs_modulus=1e6, damping=1.0))
    clamp = a.fix_start()
    clamp.set_velocity(velocity=(0.05, 0.0, 0.0))
    clamp.set_acceleration(linear=(0.2, 0.1, 0.0))
    return world, [a, b], clamp


def _snapshot(world):
    return [np.concatenate([r.positions.ravel(), r.velocities.ravel(), r.directors.ravel(),
                            r.angular_velocities.ravel()]) for r in world.rods]


@pytest.mark.parametrize("integrator,dt,n1,n2", [("verlet", 1e-4, 1500, 500),
                                                 ("stable", 2e-3, 100, 40)])
def test_restore_continues_bit_identically(integrator, dt, n1, n2):
    world, rods, clamp = _scene(integrator, dt)
    world.step(n1)
    assert np.abs(world.contact_forces(rods[1])).max() > 0.0  # touching something
    state = pickle.loads(pickle.dumps(world.get_state()))
    world.step(n2)
    after = _snapshot(world)
    time, clamp_at, impulse = world.time, clamp.position, clamp.impulse
    world.step(7)  # wander off, then come back
    world.set_state(state)
    world.step(n2)
    assert world.time == time
    for x, y in zip(_snapshot(world), after):
        assert np.array_equal(x, y)
    assert np.array_equal(clamp.position, clamp_at)
    # Impulses are not state: they keep accumulating across a restore.
    assert np.abs(clamp.impulse).sum() > np.abs(impulse).sum()


@pytest.mark.parametrize("integrator,dt,n1,n2", [("verlet", 1e-4, 1500, 300),
                                                 ("stable", 2e-3, 100, 30)])
@pytest.mark.parametrize("how", ["deepcopy", "pickle"])
def test_a_copied_world_runs_on_like_the_original(integrator, dt, n1, n2, how):
    world, rods, clamp = _scene(integrator, dt)
    world.step(n1)
    twin = copy.deepcopy(world) if how == "deepcopy" else pickle.loads(pickle.dumps(world))
    twin_rod, twin_clamp = twin.rods[1], twin.rods[0]._clamps[0]
    # The copy's handles are views of its own buffers, not of the original's.
    assert np.shares_memory(twin_rod.positions, twin.arrays["pos"])
    assert not np.shares_memory(twin_rod.positions, world.arrays["pos"])
    for w in (world, twin):
        w.step(n2)
    assert twin.time == world.time
    for x, y in zip(_snapshot(twin), _snapshot(world)):
        assert np.array_equal(x, y)
    assert np.array_equal(twin_clamp.impulse, clamp.impulse)
    # Driving the copy leaves the original alone.
    twin_clamp.set_velocity(velocity=(0.0, 0.0, 0.3))
    assert clamp.velocity[2] != 0.3
    for w in (world, twin):
        w.step(n2)
    rise = twin.rods[0].positions[0, 2] - rods[0].positions[0, 2]
    assert rise == pytest.approx(0.3 * n2 * dt, rel=1e-6)


def test_one_rod_of_a_batch_is_reset_alone():
    world = dx.World(dt=2e-3, integrator="stable")
    world.add_plane(friction=0.5)
    rods = []
    for k in range(2):
        rod = dx.Rod.straight(20, start=(0, k * 0.01, 0.05), direction=(1, 0, 0), length=0.4,
                              radius=0.005, youngs_modulus=1e6, damping=1.0)
        rod.contact_group = k  # environments of a batch: they overlap but never touch
        rods.append(world.add_rod(rod))
    world.step(50)
    saved = rods[0].get_state()
    world.step(30)
    end0 = rods[0].positions.copy()
    other = rods[1].positions.copy()
    rods[0].set_state(saved)
    assert not np.array_equal(rods[0].positions, end0)
    world.step(30)
    assert np.array_equal(rods[0].positions, end0)  # same steps from the same state
    assert not np.array_equal(rods[1].positions, other)  # the other rod ran on


def test_state_of_another_world_is_refused():
    w1, _, _ = _scene("stable", 2e-3)
    w2 = dx.World(dt=2e-3, integrator="stable")
    w2.add_rod(dx.Rod.straight(5, length=0.1))
    with pytest.raises(ValueError, match="state"):
        w2.set_state(w1.get_state())


@pytest.mark.parametrize("whole_world", [True, False])
def test_a_diverged_world_runs_on_after_a_restore(whole_world):
    """An RL reset after a divergence: restoring a snapshot (the world's, or each rod's)
    clears the divergence, and the run from it is the one that never diverged (bit for bit
    for the world's snapshot; per rod the rod-rod pair list is rebuilt, to round-off)."""
    world, rods, _ = _scene("verlet", 1e-4)
    world.step(50)
    t_saved = world.time
    saved = world.get_state() if whole_world else [r.get_state() for r in rods]

    def restore():
        if whole_world:
            world.set_state(saved)
        else:
            for r, s in zip(rods, saved):
                r.set_state(s)
            world.time = t_saved

    world.step(200)
    expected = _snapshot(world)
    restore()
    rods[0].velocities[5] = (1e5, 0.0, 0.0)  # blows up within a step
    with pytest.raises(dx.SimulationDiverged):
        world.step(5)
    restore()
    world.step(200)
    for g, e in zip(_snapshot(world), expected):
        if whole_world:
            np.testing.assert_array_equal(g, e)
        else:
            np.testing.assert_allclose(g, e, rtol=0, atol=1e-9)


@pytest.mark.parametrize("integrator,dt", [("verlet", 1e-4), ("stable", 2e-3)])
def test_a_diverged_rod_is_reported_and_the_others_step_on(integrator, dt):
    """on_diverged="report" in a world whose rods never touch: the other rods finish the
    step exactly as in a world where nothing diverged; the diverged one is named, its driver
    loads zeroed, and once restored it runs on as if it had never diverged."""
    def build():
        world = dx.World(dt=dt, integrator=integrator, rod_contact=False)
        world.add_plane(friction=0.5)
        rods = [world.add_rod(dx.Rod.straight(20, start=(0, 0.1 * k, 0.3), direction=(1, 0, 0),
                                              length=0.4, radius=0.005, youngs_modulus=1e6,
                                              damping=1.0)) for k in range(3)]
        clamps = [r.fix_start() for r in rods]
        return world, rods, clamps

    a, rods_a, clamps_a = build()
    b, rods_b, _ = build()
    assert not a.rods_coupled
    for w in (a, b):
        w.step(20)
    rods_a[1].velocities[5] = (1e5, 0.0, 0.0)  # blows up within the step
    failed = a.step(10, on_diverged="report")
    none = b.step(10, on_diverged="report")
    assert failed.tolist() == [1] and none.size == 0
    assert a.time == b.time
    for k in (0, 2):
        np.testing.assert_array_equal(rods_a[k].positions, rods_b[k].positions)
    np.testing.assert_array_equal(clamps_a[1].force, 0.0)
    # Restored (here to where the other world's copy is), it runs on with the others.
    rods_a[1].set_state(rods_b[1].get_state())
    for w in (a, b):
        w.step(10)
    for ra, rb in zip(rods_a, rods_b):
        np.testing.assert_array_equal(ra.positions, rb.positions)
    # Every rod diverging (a batch of one) is reported too, the time moved on by the step.
    for r in rods_a:
        r.velocities[5] = (1e5, 0.0, 0.0)
    t0 = a.time
    assert a.step(10, on_diverged="report").tolist() == [0, 1, 2]
    assert a.time == pytest.approx(t0 + 10 * dt, rel=1e-12)
    with pytest.raises(ValueError, match="on_diverged"):
        a.step(1, on_diverged="ignore")


def test_rods_that_touch_raise_even_when_reporting():
    world, rods, _ = _scene("verlet", 1e-4)
    assert world.rods_coupled
    world.step(10)
    rods[0].velocities[5] = (1e5, 0.0, 0.0)
    with pytest.raises(dx.SimulationDiverged):
        world.step(5, on_diverged="report")
