"""The explicit integrator reproduces PyElastica 1.0 trajectories to round-off."""

from __future__ import annotations

import numpy as np
import pytest

import deformx as dx

ea = pytest.importorskip("elastica")


class _PESim(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.Damping):
    pass


def _pe_rod(n, start, direction, normal, length, radius, density, E, G):
    return ea.CosseratRod.straight_rod(n, np.asarray(start, float), np.asarray(direction, float),
                                       np.asarray(normal, float), length, radius, density,
                                       youngs_modulus=E, shear_modulus=G)


def _run_pe(sim, n_steps, dt):
    sim.finalize()
    stepper = ea.PositionVerlet()
    t = np.float64(0.0)
    for _ in range(n_steps):
        t = stepper.step(sim, t, dt)
    return t


def test_clamped_cantilever_under_gravity_with_damping_matches_pyelastica():
    n, dt, steps, nu = 100, 1e-4, 2000, 0.5
    E, G, r, rho = 1e6, 1e6 / 3.0, 0.01, 1000.0
    rod = dx.Rod.straight(n_elements=n, start=(0, 0, 0), direction=(1, 0, 0), normal=(0, 0, 1),
                          length=1.0, radius=r, density=rho, youngs_modulus=E,
                          shear_modulus=G, damping=nu)
    world = dx.World(gravity=(0, 0, -9.81), dt=dt)
    world.add_rod(rod)
    rod.fix_start()
    world.step(steps)

    sim = _PESim()
    pe = _pe_rod(n, (0, 0, 0), (1, 0, 0), (0, 0, 1), 1.0, r, rho, E, G)
    sim.append(pe)
    sim.constrain(pe).using(ea.OneEndFixedBC, constrained_position_idx=(0,),
                            constrained_director_idx=(0,))
    sim.add_forcing_to(pe).using(ea.GravityForces, acc_gravity=np.array([0.0, 0.0, -9.81]))
    sim.dampen(pe).using(ea.AnalyticalLinearDamper, uniform_damping_constant=nu, time_step=dt)
    t = _run_pe(sim, steps, dt)

    assert world.time == pytest.approx(float(t), abs=1e-12)
    # The rod really moved (sagged by centimetres), so agreement is not trivial.
    assert rod.positions[-1, 2] < -0.05
    assert np.abs(pe.position_collection.T - rod.positions).max() < 1e-8
    assert np.abs(np.moveaxis(pe.director_collection, 2, 0) - rod.directors).max() < 1e-8
    assert np.abs(pe.velocity_collection.T - rod.velocities).max() < 1e-6


def test_several_rods_in_one_world_match_pyelastica_block():
    """Different sizes and materials packed with ghosts, end loads, a free rod in flight."""
    dt, steps = 5e-5, 1500
    specs = [  # n, start, direction, normal, length, radius, density, E, G
        (30, (0, 0, 0), (1, 0, 0), (0, 0, 1), 0.6, 0.008, 1200.0, 2e6, 7e5),
        (17, (0, 0.5, 0), (0, 0, 1), (1, 0, 0), 0.4, 0.01, 800.0, 5e5, 2e5),
        (45, (0.2, -0.3, 0.1), (0, 0.6, 0.8), (1, 0, 0), 0.9, 0.006, 1500.0, 3e6, 1e6),
    ]
    end_force = np.array([0.05, -0.2, 0.1])
    world = dx.World(gravity=(0, 0, -9.81), dt=dt)
    sim = _PESim()
    ours, theirs = [], []
    for i, (n, s, d, nrm, L, r, rho, E, G) in enumerate(specs):
        rod = world.add_rod(dx.Rod.straight(n_elements=n, start=s, direction=d, normal=nrm, length=L,
                                            radius=r, density=rho, youngs_modulus=E, shear_modulus=G))
        pe = _pe_rod(n, s, d, nrm, L, r, rho, E, G)
        sim.append(pe)
        sim.add_forcing_to(pe).using(ea.GravityForces, acc_gravity=np.array([0.0, 0.0, -9.81]))
        ours.append(rod)
        theirs.append(pe)
    ours[0].fix_start()
    theirs_bc = sim.constrain(theirs[0])
    theirs_bc.using(ea.OneEndFixedBC, constrained_position_idx=(0,), constrained_director_idx=(0,))
    ours[2].external_forces[-1] = end_force
    sim.add_forcing_to(theirs[2]).using(ea.EndpointForces, start_force=np.zeros(3),
                                        end_force=end_force, ramp_up_time=1e-300)
    # The middle rod flies free with an initial spin and velocity.
    ours[1].velocities[:] = (0.3, 0.0, 1.0)
    ours[1].angular_velocities[:] = (0.0, 0.5, 5.0)
    theirs[1].velocity_collection[:] = np.array([0.3, 0.0, 1.0])[:, None]
    theirs[1].omega_collection[:] = np.array([0.0, 0.5, 5.0])[:, None]

    d1_before = ours[1].directors[:, 0].copy()
    world.step(steps)
    _run_pe(sim, steps, dt)
    for rod, pe in zip(ours, theirs):
        assert np.abs(pe.position_collection.T - rod.positions).max() < 1e-8
        assert np.abs(np.moveaxis(pe.director_collection, 2, 0) - rod.directors).max() < 1e-8
    # The spinning rod turned by a visible angle, so frame agreement is not trivial.
    assert np.min(np.einsum("ki,ki->k", d1_before, ours[1].directors[:, 0])) < np.cos(0.1)
