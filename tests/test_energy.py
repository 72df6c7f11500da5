"""Energy bookkeeping and conservation of the undamped explicit integrator."""

from __future__ import annotations

import numpy as np

import deformx as dx


def _swinging_rod(n: int = 40, dt: float = 5e-5):
    rod = dx.Rod.straight(n_elements=n, start=(0, 0, 0), direction=(1, 0, 0), normal=(0, 0, 1),
                          length=0.5, radius=0.01, density=1000.0, youngs_modulus=1e6)
    world = dx.World(gravity=(0, 0, -9.81), dt=dt)
    world.add_rod(rod)
    rod.pin(0)  # a pendulum: the first node is held, the rod swings and bends freely
    return world, rod


def test_undamped_swinging_rod_conserves_energy():
    world, rod = _swinging_rod()
    e0 = world.energy()["total"]
    scale = rod.mass * 9.81 * rod.length  # energy exchanged in the swing
    totals, kinetic = [], []
    for _ in range(100):  # 1 s
        world.run(0.01)
        e = world.energy()
        totals.append(e["total"])
        kinetic.append(e["kinetic"])
    drift = np.max(np.abs(np.array(totals) - e0)) / scale
    assert max(kinetic) > 0.3 * scale  # it really swings
    assert drift < 1e-3


def test_energy_split_matches_imposed_deformation():
    """Pure twist, pure bend and pure stretch put energy only in their own bucket."""
    n, L, r, E, G = 20, 1.0, 0.01, 1e6, 4e5
    area, inertia = np.pi * r**2, np.pi * r**4 / 4
    twist = dx.Rod.straight(n_elements=n, length=L, radius=r, youngs_modulus=E, shear_modulus=G,
                            rest_curvature=(0.0, 0.0, 0.5))
    e = twist.elastic_energy()
    # Rest twist 0.5 rad/m with a straight untwisted rod: (1/2) G J k^2 over the Voronoi length.
    expected = 0.5 * G * 2 * inertia * 0.5**2 * (L - L / n)
    assert np.isclose(e["twist"], expected, rtol=1e-9)
    assert e["bend"] == e["stretch"] == e["shear"] == 0.0

    bend = dx.Rod.straight(n_elements=n, length=L, radius=r, youngs_modulus=E, shear_modulus=G,
                           rest_curvature=(0.3, 0.0, 0.0))
    assert np.isclose(bend.elastic_energy()["bend"], 0.5 * E * inertia * 0.09 * (L - L / n), rtol=1e-9)

    stretch = dx.Rod.straight(n_elements=n, length=L, radius=r, youngs_modulus=E, shear_modulus=G)
    stretch.positions[:] *= 1.01  # 1 % axial strain, start node at the origin
    es = stretch.elastic_energy()
    assert np.isclose(es["stretch"], 0.5 * E * area * 0.01**2 * L, rtol=1e-9)
    assert es["shear"] < 1e-20 and es["bend"] == 0.0


def test_kinetic_energy_of_rigid_translation_and_spin():
    rod = dx.Rod.straight(n_elements=10, length=1.0, radius=0.02, density=500.0, youngs_modulus=1e6)
    rod.velocities[:] = (0.0, 2.0, 0.0)
    assert np.isclose(rod.kinetic_energy(), 0.5 * rod.mass * 4.0)
    rod.velocities[:] = 0.0
    rod.angular_velocities[:] = (0.0, 0.0, 3.0)  # spin about the axis
    polar = rod.mass * 0.02**2 / 2
    assert np.isclose(rod.kinetic_energy(), 0.5 * polar * 9.0)
