"""Stable integrator: Kelvin-Voigt internal damping against its damping ratio, and pinned nodes
and driven clamps behaving as with the explicit integrator."""

from __future__ import annotations

import numpy as np
import pytest

import deformx as dx

L, R, RHO, E = 0.3, 0.01, 1000.0, 1e7
AREA, INERTIA = np.pi * R**2, np.pi * R**4 / 4
OMEGA_1 = 1.8751**2 / L**2 * np.sqrt(E * INERTIA / (RHO * AREA))  # rad/s, first bending mode


def _free_vibration(internal_damping: float, dt: float = 1e-3) -> tuple[float, float]:
    """(measured damping ratio, period) of a cantilever released from a small tip deflection."""
    rod = dx.Rod.straight(n_elements=30, start=(0, 0, 0), direction=(1, 0, 0), normal=(0, 0, 1),
                          length=L, radius=R, density=RHO, youngs_modulus=E,
                          internal_damping=internal_damping)
    world = dx.World(gravity=(0, 0, 0), dt=1e-2, integrator="stable")
    world.add_rod(rod)
    rod.fix_start()
    rod.external_forces[-1] = (0.0, 0.0, -1e-4)
    rod.damping = 5.0
    world.run(20.0)  # static deflection
    rod.external_forces[-1] = 0.0
    rod.damping = 0.0
    world.dt = dt
    z, t = [], []
    for _ in range(3000):
        world.step(1)
        z.append(rod.positions[-1, 2])
        t.append(world.time)
    z, t = np.array(z), np.array(t)
    peaks = [i for i in range(1, len(z) - 1) if z[i] > z[i - 1] and z[i] >= z[i + 1] and z[i] > 0]
    amps = z[peaks]
    zeta = np.log(amps[0] / amps[-1]) / (2 * np.pi * (len(peaks) - 1))
    return float(zeta), float(np.mean(np.diff(t[peaks])))


def test_kelvin_voigt_damping_ratio_is_omega_tau_over_two():
    dt = 1e-3
    numerical = OMEGA_1 * dt / 2  # backward Euler's own damping ratio at this step
    zeta0, period0 = _free_vibration(0.0, dt)
    assert zeta0 == pytest.approx(numerical, rel=0.1)
    tau = 0.02
    zeta, period = _free_vibration(tau, dt)
    # Kelvin-Voigt adds w tau / 2; the measured ratio is the sum to within 10 %.
    assert zeta == pytest.approx(OMEGA_1 * tau / 2 + numerical, rel=0.1)
    assert period == pytest.approx(2 * np.pi / OMEGA_1, rel=0.05)
    assert period0 == pytest.approx(2 * np.pi / OMEGA_1, rel=0.05)


def test_internal_damping_needs_the_stable_integrator():
    world = dx.World(integrator="verlet")
    world.add_rod(dx.Rod.straight(n_elements=5, internal_damping=0.01))
    with pytest.raises(ValueError, match="internal_damping"):
        world.step(1)


def test_internal_damping_set_later_in_an_explicit_world_is_refused():
    world = dx.World(integrator="verlet")
    rods = [world.add_rod(dx.Rod.straight(n_elements=5, start=(0, k, 0))) for k in range(3)]
    world.step(1)
    with pytest.raises(ValueError, match="rod 1 sets it"):
        rods[1].internal_damping = 0.01


@pytest.mark.parametrize("integrator,dt", [("stable", 2e-3), ("verlet", 1e-4)])
def test_changing_one_rods_damping_matches_a_world_built_with_it(integrator, dt):
    """A rod's damping set in place (a batch redraws it at each reset of one environment)
    changes that rod alone, exactly as if the world had been built with it."""
    def world(dampings):
        w = dx.World(dt=dt, integrator=integrator, rod_contact=False)
        rods = [w.add_rod(dx.Rod.straight(n_elements=10, start=(0, 0.1 * k, 1), length=0.3,
                                          radius=0.005, density=1000.0, youngs_modulus=1e6,
                                          damping=d)) for k, d in enumerate(dampings)]
        for rod in rods:
            rod.fix_start()
        return w, rods

    changed, changed_rods = world([0.5, 0.5, 0.5])
    changed.run(0.05)
    changed_rods[1].damping = 4.0
    built, built_rods = world([0.5, 4.0, 0.5])
    built.step(1)  # packed, then given the other world's state
    built.set_state(changed.get_state())
    for w in (built, changed):
        w.run(0.05)
    for a, b in zip(built_rods, changed_rods):
        np.testing.assert_array_equal(a.positions, b.positions)
    shifted = changed_rods[1].positions - [0.0, 0.1, 0.0]
    assert np.abs(changed_rods[0].positions - shifted).max() > 1e-6  # the damping mattered


def _pendulum(integrator: str, dt: float):
    rod = dx.Rod.straight(n_elements=20, start=(0, 0, 1), direction=(1, 0, 0), normal=(0, 0, 1),
                          length=0.4, radius=0.005, density=1000.0, youngs_modulus=1e7,
                          damping=3.0)
    world = dx.World(dt=dt, integrator=integrator)
    world.add_rod(rod)
    rod.pin(0)
    return world, rod


def test_pinned_pendulum_matches_the_explicit_integrator():
    ws, rs = _pendulum("stable", 1e-3)
    we, re = _pendulum("verlet", 2e-5)
    for _ in range(10):
        ws.run(0.05)
        we.run(0.05)
        assert np.allclose(rs.positions[0], (0, 0, 1), atol=1e-12)
        assert np.abs(rs.positions - re.positions).max() < 0.01  # backward-Euler lag (measured 4 mm)
    ws.run(4.0)
    we.run(4.0)
    # At rest both hang straight down from the pin.
    assert np.abs(rs.positions - re.positions).max() < 1e-3
    assert rs.positions[-1, 2] == pytest.approx(1.0 - 0.4, abs=5e-3)


def test_driven_clamp_follows_its_trajectory_with_large_steps():
    rod = dx.Rod.straight(n_elements=20, start=(0, 0, 1), direction=(1, 0, 0), normal=(0, 0, 1),
                          length=0.4, radius=0.005, density=1000.0, youngs_modulus=1e9)
    world = dx.World(dt=1e-2, integrator="stable")
    world.add_rod(rod)
    clamp = rod.fix_start()
    v, w = np.array([0.1, 0.0, 0.2]), np.array([0.0, 0.0, 1.0])
    clamp.set_velocity(v, w)
    world.run(0.5)
    assert np.allclose(rod.positions[0], np.array([0, 0, 1]) + v * world.time, atol=1e-12)
    assert np.allclose(rod.directors[0], clamp.directors, atol=1e-10)
    assert np.allclose(rod.velocities[0], v)
