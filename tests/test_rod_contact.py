"""Rod-rod and self-contact: no interpenetration, momentum conservation, broad phase.

Distances between capsule axes are recomputed here by dense sampling (independent of the
kernels' closest-point routine); the broad phase is checked against a brute-force pair scan.
"""

from __future__ import annotations

import numpy as np
import pytest

import deformx as dx

SETUPS = {"verlet": 2e-5, "stable": 1e-3}
R = 0.002


def axis_distances(xa: np.ndarray, xb: np.ndarray, samples: int = 11) -> np.ndarray:
    """(Sa, Sb) distances between segment axes of two polylines, by sampling both."""
    t = np.linspace(0.0, 1.0, samples)[None, :, None]
    pa = (xa[:-1, None] * (1 - t) + xa[1:, None] * t).reshape(-1, 3)
    pb = (xb[:-1, None] * (1 - t) + xb[1:, None] * t).reshape(-1, 3)
    d = np.linalg.norm(pa[:, None] - pb[None], axis=2)
    return d.reshape(xa.shape[0] - 1, samples, xb.shape[0] - 1, samples).min(axis=(1, 3))


def self_distance(x: np.ndarray, excluded: int) -> float:
    d = axis_distances(x, x)
    i, j = np.indices(d.shape)
    return float(d[np.abs(i - j) > excluded].min())


def rope(n, start, direction, length, damping=2.0, E=1e6):
    return dx.Rod.straight(n_elements=n, start=start, direction=direction, length=length,
                           radius=R, youngs_modulus=E, density=1000.0, damping=damping)


@pytest.mark.parametrize("integrator", sorted(SETUPS))
def test_two_ropes_fall_across_each_other_without_interpenetrating(integrator):
    world = dx.World(dt=SETUPS[integrator], integrator=integrator)
    a = world.add_rod(rope(30, (-0.15, 0.0, 0.01), (1, 0, 0), 0.3))
    b = world.add_rod(rope(30, (0.0, -0.15, 0.03), (0, 1, 0), 0.3))
    world.add_plane(friction=0.5)
    worst = np.inf
    for _ in range(60):
        world.run(0.01)
        worst = min(worst, axis_distances(a.positions, b.positions).min())
    assert worst >= 2 * R * 0.9, f"capsules overlapped: axis distance {worst * 1e3:.3f} mm"
    # b rests on a at the crossing: its middle two radii above a's axis.
    mid = b.positions[15]
    assert mid[2] == pytest.approx(a.positions[15, 2] + 2 * R, abs=0.2 * R)
    assert world.contact_stats()["candidate_pairs"] > 0


def alpha_loop(n: int = 90) -> np.ndarray:
    """A rope shaped like an alpha (nodal cubic) on the floor, one strand lying across the
    other at the crossing."""
    t = np.linspace(-1.45, 1.45, 400)
    # Lying on the floor (z = R) except where the strand t = 1 crosses over t = -1.
    z = R + 2.05 * R * np.exp(-(((t - 1.0) / 0.12) ** 2))
    pts = np.column_stack([0.1 * (t ** 2 - 1), 0.1 * t * (t ** 2 - 1), z])
    s = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    u = np.linspace(0, s[-1], n + 1)
    return np.column_stack([np.interp(u, s, pts[:, i]) for i in range(3)])


@pytest.mark.parametrize("integrator", sorted(SETUPS))
def test_rope_pulled_into_a_loop_does_not_pass_through_itself(integrator):
    world = dx.World(dt=SETUPS[integrator], integrator=integrator)
    world.add_plane(friction=0.3)
    rod = world.add_rod(dx.Rod.from_points(alpha_loop(), radius=R, youngs_modulus=1e6,
                                           density=1000.0, damping=2.0))
    x = rod.positions
    ends = (x[0] - x[3], x[-1] - x[-4])  # pull the tails outwards along themselves
    for node, d in zip((0, rod.n_nodes - 1), ends):
        clamp = rod.pin(node)
        clamp.set_velocity(0.25 * d / np.linalg.norm(d))
    excluded = 1
    worst = np.inf
    for _ in range(50):  # the loop shrinks; later (~0.6 s) it would flip and pull out
        world.run(0.01)
        worst = min(worst, self_distance(rod.positions, excluded))
    assert worst >= 2 * R * 0.9, f"the rope passed into itself: {worst * 1e3:.3f} mm"
    # The loop did tighten onto the crossing (the strands touch).
    assert worst < 2 * R * 1.05


@pytest.mark.parametrize("friction", [0.0, 0.5])
def test_rod_contact_conserves_momentum(friction):
    """Explicit steps: equal and opposite pair forces at the same positions."""
    world = dx.World(dt=2e-5, gravity=(0, 0, 0), rod_friction=friction)
    a = world.add_rod(rope(20, (-0.1, 0.0, 0.0), (1, 0, 0), 0.2, damping=0.0))
    b = world.add_rod(rope(20, (0.03, -0.1, 0.003), (0, 1, 0), 0.2, damping=0.0))
    b.velocities[:] = (0.2, 0.3, -0.5)  # glancing blow with sliding along a
    def momentum():
        return sum((r.masses[:, None] * r.velocities).sum(axis=0) for r in (a, b))
    p0 = momentum()
    world.step(2000)
    p1 = momentum()
    np.testing.assert_allclose(p1, p0, atol=1e-12 * np.linalg.norm(p0))
    assert np.linalg.norm(a.velocities.mean(axis=0)) > 0.01  # a was pushed


def test_broad_phase_finds_every_touching_pair_and_prunes_distant_rods():
    rng = np.random.default_rng(3)
    world = dx.World(dt=1e-5, gravity=(0, 0, 0))
    rods = []
    for _ in range(12):  # a tangle in a 6 cm cube
        start = rng.uniform(-0.03, 0.03, 3)
        d = rng.normal(size=3)
        rods.append(world.add_rod(rope(10, start, d, 0.05)))
    far = [world.add_rod(rope(10, (1.0 + i, 0, 0), (0, 1, 0), 0.05)) for i in range(5)]
    world.step(1)
    pairs = world.arrays["pairs"][: world.contact_stats()["candidate_pairs"]]
    found = {(int(i), int(j)) for i, j in pairs}
    seg_rod = world.arrays["seg_rod"]
    e0 = world.arrays["elem0"]
    # Brute force: every pair of segments of different rods closer than 2 r.
    for ia, ra in enumerate(rods):
        for ib in range(ia + 1, len(rods)):
            d = axis_distances(ra.positions, rods[ib].positions)
            for i, j in zip(*np.nonzero(d < 2 * R)):
                key = (int(e0[ia] + i), int(e0[ib] + j))
                assert key in found, f"touching pair {key} missing from the broad phase"
    far_ids = {world.rods.index(r) for r in far}
    assert not any(seg_rod[i] in far_ids or seg_rod[j] in far_ids for i, j in found)


def test_rod_contact_can_be_turned_off_and_validates_input():
    world = dx.World(dt=2e-5, gravity=(0, 0, 0), rod_contact=False)
    a = world.add_rod(rope(10, (-0.05, 0, 0), (1, 0, 0), 0.1))
    b = world.add_rod(rope(10, (0.0, -0.05, 0.001), (0, 1, 0), 0.1))
    world.step(10)
    assert np.abs(world.contact_forces(a)).max() == 0.0
    assert np.abs(world.contact_forces(b)).max() == 0.0
    with pytest.raises(ValueError, match="rod_friction"):
        dx.World(rod_friction=-1)
    with pytest.raises(ValueError, match="rod_contact"):
        dx.World(rod_contact="yes")
    with pytest.raises(ValueError, match="rod_contact_stiffness"):
        dx.World(rod_contact_stiffness=0.0)
