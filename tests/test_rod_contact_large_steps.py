"""Rod-rod contact at the robot's time step (stable integrator, dt = 1e-2 s): ropes dropped on
ropes and a pile of eight keep their surfaces apart at every step, end on the side they fell
from, converge without halving the step, conserve momentum, and rods placed inside each other
come apart without being launched.

Surface gaps are exact segment-segment distances computed here in numpy (not the engine's
closest-point routine) after every step.
"""

from __future__ import annotations

import logging

import numpy as np
import pytest

import deformx as dx

DT = 1e-2


def segment_distances(P: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """(len(P) - 1, len(Q) - 1) exact distances between the segments of two polylines."""
    p0, d1 = P[:-1, None, :], (P[1:] - P[:-1])[:, None, :]
    q0, d2 = Q[None, :-1, :], (Q[1:] - Q[:-1])[None, :, :]
    r = p0 - q0
    a = np.sum(d1 * d1, axis=2)
    e = np.sum(d2 * d2, axis=2)
    f = np.sum(d2 * r, axis=2)
    c = np.sum(d1 * r, axis=2)
    b = np.sum(d1 * d2, axis=2)
    denom = a * e - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(denom > 1e-20 * a * e, np.clip((b * f - c * e) / denom, 0, 1), 0.0)
        t = (b * s + f) / e
        s = np.where(t < 0, np.clip(-c / a, 0, 1), np.where(t > 1, np.clip((b - c) / a, 0, 1), s))
        t = np.clip(t, 0, 1)
    diff = p0 + s[..., None] * d1 - q0 - t[..., None] * d2
    return np.linalg.norm(diff, axis=2)


def _rope(start, direction, radius, E, length=0.4, n=40, damping=2.0):
    return dx.Rod.straight(n_elements=n, start=start, direction=direction, length=length,
                           radius=radius, youngs_modulus=E, density=1000.0, damping=damping)


def _worst_gap(rods, radius):
    worst = np.inf
    for i in range(len(rods)):
        for j in range(i + 1, len(rods)):
            d = segment_distances(rods[i].positions, rods[j].positions).min() - 2 * radius
            worst = min(worst, d)
    return worst


def _crossing_heights(lower: np.ndarray, upper: np.ndarray):
    """Heights of the two ropes' axes where they cross in the xy-plane (None if they do not)."""
    d = segment_distances(lower[:, :2], upper[:, :2])  # distances in the xy-plane
    i, j = np.unravel_index(np.argmin(d), d.shape)
    if d[i, j] > 1e-3:
        return None
    return 0.5 * (lower[i, 2] + lower[i + 1, 2]), 0.5 * (upper[j, 2] + upper[j + 1, 2])


ACROSS = [(0.005, 1e6, 0.1), (0.005, 1e6, 1.0), (0.002, 5e7, 0.1), (0.001, 2e11, 1.0)]


@pytest.mark.parametrize("radius, E, height", ACROSS)
def test_rope_dropped_across_a_rope_stays_on_top_at_large_steps(radius, E, height):
    _dropped_across_stays_on_top(radius, E, height)


@pytest.mark.slow
@pytest.mark.parametrize("radius, E, height", ACROSS)
def test_rope_dropped_across_a_rope_from_nearby_heights_stays_on_top(radius, E, height):
    """The same drops from 0.1-0.6 mm higher (a requirement met at one start only is luck)."""
    for dz in (1e-4, 2e-4, 3e-4, 4e-4, 5e-4, 6e-4):
        _dropped_across_stays_on_top(radius, E, height + dz)


def _dropped_across_stays_on_top(radius, E, height):
    world = dx.World(dt=DT, integrator="stable")
    world.add_plane(friction=0.5)
    lower = world.add_rod(_rope((-0.2, 0.0, radius), (1, 0, 0), radius, E))
    upper = world.add_rod(_rope((0.0, -0.2, radius + height), (0, 1, 0), radius, E))
    worst = np.inf
    steps = int(round((np.sqrt(2 * height / 9.81) + 0.4) / DT))  # fall, impact, settling
    for _ in range(steps):
        world.step()
        worst = min(worst, _worst_gap([lower, upper], radius))
    assert worst >= -0.2 * radius, f"surfaces overlapped by {-worst / radius:.0%} of r"
    z_low, z_up = _crossing_heights(lower.positions, upper.positions)
    assert z_up - z_low == pytest.approx(2 * radius, abs=0.2 * radius)  # on top, touching
    stats = world.solver_stats()
    assert stats["halvings"] < steps / 100
    assert np.abs(upper.velocities).max() < 1.0  # it came to rest on top, no bounce away


# (seed 2: the ropes dropped elsewhere overlapped by 24 % of r while a pair's plane kept the
# closest points of the step start, 23 % while it could lag by 10 % of r and the pairs' penalty
# was not stiffened; see ``pairplanes.refind_pairs`` and ``stiffen_pairs``; seed 4: a step
# halved while a stiffened pair had four iterations to settle again, not eight, as did 0, 5, 7
# and 9; the slow tier drops the pile from fourteen seeds)
@pytest.mark.parametrize("seed", [3, 2, 4] + [pytest.param(s, marks=pytest.mark.slow)
                                              for s in (0, 1, 5, 6, 7, 8, 9, 10, 11, 12, 13)])
def test_pile_of_eight_ropes_keeps_every_gap_and_the_order_they_fell_in(seed, caplog):
    world, rods = _pile(seed, 2.0, caplog)
    assert world.solver_stats()["halvings"] < 1


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(14))
def test_pile_of_less_damped_ropes_keeps_every_gap_and_the_order_they_fell_in(seed, caplog):
    """The benchmark's ropes (damping 1): seed 11 ended a step 23 % of r inside another rope
    while a pair's penalty could be doubled twice a step (three times now). (Seeds 1 and 5
    halve one step in 100 here: not asserted.)"""
    _pile(seed, 1.0, caplog)


def _pile(seed, damping, caplog):
    """Eight ropes dropped from 3-31 cm onto each other and the floor, 100 steps; asserts the
    gaps, the order and no start warnings; returns the world and the ropes."""
    radius = 0.004
    world = dx.World(dt=DT, integrator="stable")
    world.add_plane(friction=0.5)
    rng = np.random.default_rng(seed)
    rods = []
    for k in range(8):
        a = rng.uniform(0.0, np.pi)
        d = np.array([np.cos(a), np.sin(a), 0.0])
        c = rng.uniform(-0.03, 0.03, 3) * [1, 1, 0]
        rods.append(world.add_rod(_rope(c - 0.2 * d + [0, 0, 0.03 + 0.04 * k], d, radius, 1e6,
                                        damping=damping)))
    worst = np.inf
    with caplog.at_level(logging.WARNING, logger="deformx"):
        for _ in range(100):
            world.step()
            worst = min(worst, _worst_gap(rods, radius))
    assert not caplog.records  # ropes landing on ropes were not placed inside them
    assert worst >= -0.2 * radius, f"surfaces overlapped by {-worst / radius:.0%} of r"
    # Wherever two ropes cross, the one dropped from higher lies above.
    checked = 0
    for i in range(8):
        for j in range(i + 1, 8):
            z = _crossing_heights(rods[i].positions, rods[j].positions)
            if z is not None:
                checked += 1
                assert z[1] > z[0] + radius, f"rope {j} ended below rope {i}"
    assert checked >= 10
    assert min(r.positions[:, 2].min() for r in rods) > 0.8 * radius
    return world, rods


def _loops(radius: float, E: float, dz: float = 0.0) -> dx.Rod:
    """A 1 m rope laid as two loops of a trochoid (4 r elements), rising from 5 to 20 cm
    (``dz`` higher): dropped, it lands across itself twice, the later part on top."""
    u = np.linspace(-2.5, 2 * np.pi + 2.5, 10000)
    P = np.column_stack([0.012 * u - 0.04 * np.sin(u), 0.04 * np.cos(u), np.zeros_like(u)])
    P[:, 0] -= P[:, 0].mean()
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])
    P[:, 2] = 0.05 + dz + 0.15 * s / s[-1]
    at = np.linspace(0.0, s[-1], int(round(s[-1] / (4 * radius))) + 1)
    P = np.column_stack([np.interp(at, s, P[:, i]) for i in range(3)])
    return dx.Rod.from_points(P, radius=radius, density=1000.0, youngs_modulus=E, damping=1.0)


@pytest.mark.parametrize("dt", [1e-2, 1e-3])
@pytest.mark.parametrize("E", [1e5, 1e7])
def test_rope_dropped_in_loops_onto_itself_keeps_its_gaps(E, dt):
    """Self-contact of a falling rope (r = 1 mm): at 1e-3 (E = 1e7) a segment near its top
    landing on one near its end at ~1.6 m/s overlapped 24 % of r (20 % from 1 mm higher)
    while a pair's penalty could be doubled twice a step; 15-16 % now (12-19 % over the four
    cases). (At 1e-2 with E = 1e5 drops from 0.1 and 0.3 mm higher halve one step in 60:
    not asserted.)"""
    radius = 0.001
    world = dx.World(dt=dt, integrator="stable")
    world.add_plane(friction=0.5)
    rope = world.add_rod(_loops(radius, E))
    far = np.abs(np.subtract.outer(np.arange(rope.n_elements), np.arange(rope.n_elements))) > 2
    worst = np.inf
    for _ in range(int(round(0.3 / dt))):
        world.step()
        X = rope.positions
        worst = min(worst, segment_distances(X, X)[far].min() - 2 * radius)
    assert worst >= -0.2 * radius, f"surfaces overlapped by {-worst / radius:.0%} of r"
    # where it lies across itself, the part dropped from higher (later along it) is on top
    X = rope.positions
    d = segment_distances(X[:, :2], X[:, :2])
    d[~far] = np.inf
    crossings = [(i, j) for i, j in zip(*np.nonzero(d < 1e-4)) if i < j]
    assert crossings
    for i, j in crossings:
        assert X[j:j + 2, 2].mean() > X[i:i + 2, 2].mean() + radius, f"segment {j} under {i}"


def test_rods_in_contact_conserve_momentum():
    """Two ropes in free space, one thrown across the other: the pair forces are equal and
    opposite and both rods are solved together, so momentum is conserved to the solver's
    tolerance."""
    world = dx.World(dt=DT, integrator="stable", gravity=(0, 0, 0), tolerance=1e-8)
    a = world.add_rod(_rope((-0.2, 0.0, 0.0), (1, 0, 0), 0.004, 1e6, damping=0.0))
    b = world.add_rod(_rope((0.0, -0.2, 0.05), (0, 1, 0), 0.004, 1e6, damping=0.0))
    b.velocities[:] = (0.0, 0.0, -2.0)
    p0 = sum((r.masses[:, None] * r.velocities).sum(axis=0) for r in (a, b))
    touched = False
    for _ in range(40):
        world.step()
        touched |= np.abs(a.velocities).max() > 0.1
    p1 = sum((r.masses[:, None] * r.velocities).sum(axis=0) for r in (a, b))
    assert touched
    assert np.abs(p1 - p0).max() < 1e-4 * np.abs(p0).max()
    assert a.velocities[:, 2].mean() < -0.5  # the momentum went into the hit rope
    assert _worst_gap([a, b], 0.004) >= -0.2 * 0.004


@pytest.mark.parametrize("integrator, dt, substeps", [("stable", DT, 1), ("verlet", 2e-5, 500)])
@pytest.mark.parametrize("depth", [0.5, 1.0])
def test_ropes_placed_inside_each_other_come_apart_without_launch(depth, integrator, dt,
                                                                  substeps, caplog):
    """Crossing ropes whose axes start ``depth`` radii closer than touching are pushed apart
    at no more than the contact's push-out speed (no launch; the explicit integrator sent
    them apart at 5.8 and 10 m/s before its pairs kept a start offset), and the world says so
    once per rod."""
    radius = 0.004
    world = dx.World(dt=dt, integrator=integrator, gravity=(0, 0, 0))
    a = world.add_rod(_rope((-0.2, 0.0, 0.0), (1, 0, 0), radius, 1e6))
    b = world.add_rod(_rope((0.0, -0.2, (2 - depth) * radius), (0, 1, 0), radius, 1e6))
    top = 0.0
    with caplog.at_level(logging.WARNING, logger="deformx"):
        for _ in range(50):
            world.step(substeps)
            top = max(top, max(np.abs(r.velocities).max() for r in (a, b)))
    warnings = sorted(rec.message.split(" is ")[0] for rec in caplog.records
                      if "inside another rod" in rec.message)
    assert warnings == ["rod 0", "rod 1"]
    assert top <= 0.5
    assert _worst_gap([a, b], radius) >= -0.05 * radius  # apart by now


@pytest.mark.parametrize("integrator, dt, substeps", [("stable", DT, 1), ("verlet", 2e-5, 500)])
def test_rope_laid_through_itself_comes_apart_without_launch(integrator, dt, substeps, caplog):
    """A rope laid as a loop whose end crosses its start a whole radius too low (self-contact
    placed inside) comes apart at the push-out speed, and the world says so once."""
    radius = 0.004
    th = np.linspace(-np.pi / 2, 1.5 * np.pi, 60)
    loop = np.stack([0.06 * np.cos(th), 0.06 + 0.06 * np.sin(th), np.zeros_like(th)], 1)
    lead = np.stack([np.linspace(-0.2, 0.0, 21)[:-1], np.zeros(20), np.zeros(20)], 1)
    tail = np.stack([np.linspace(0.0, 0.2, 21)[1:], np.zeros(20), np.zeros(20)], 1)
    P = np.concatenate([lead, loop, tail])
    P[65:, 2] = radius  # the loop's end runs over the lead-in, axes one radius apart
    world = dx.World(dt=dt, integrator=integrator, gravity=(0, 0, 0))
    rod = world.add_rod(dx.Rod.from_points(P, radius=radius, youngs_modulus=1e6,
                                           density=1000.0, damping=2.0))
    top = 0.0
    with caplog.at_level(logging.WARNING, logger="deformx"):
        for _ in range(50):
            world.step(substeps)
            top = max(top, float(np.abs(rod.velocities).max()))
    assert [rec.message.split(" is ")[0] for rec in caplog.records
            if "inside another rod or itself" in rec.message] == ["rod 0"]
    assert top <= 0.5
    Q = rod.positions
    gaps = segment_distances(Q[:20], Q[66:]) - 2 * radius  # lead-in against the loop's end
    assert gaps.min() >= -0.05 * radius  # apart by now
