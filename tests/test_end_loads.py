"""Axial stretch and pure torsion under end loads against linear elasticity."""

from __future__ import annotations

import numpy as np
import pytest

import deformx as dx

E, G, R, RHO, L, N = 1e6, 4e5, 0.01, 1000.0, 1.0, 50


def _clamped_rod():
    rod = dx.Rod.straight(n_elements=N, start=(0, 0, 0), direction=(1, 0, 0), normal=(0, 0, 1),
                          length=L, radius=R, density=RHO, youngs_modulus=E, shear_modulus=G,
                          damping=30.0)
    world = dx.World(gravity=(0, 0, 0), dt=0.3 * rod.stable_dt() * 4)
    world.add_rod(rod)
    rod.fix_start()
    return world, rod


def test_axial_stretch_matches_FL_over_EA():
    world, rod = _clamped_rod()
    area = np.pi * R**2
    force = 1e-4 * E * area  # 0.01 % strain: linear regime
    rod.external_forces[-1] = (force, 0.0, 0.0)
    world.run(1.5)
    assert np.abs(rod.velocities).max() < 1e-9
    elongation = rod.positions[-1, 0] - L
    assert abs(elongation / (force * L / (E * area)) - 1.0) < 1e-3


def test_pure_torsion_matches_TL_over_GJ():
    world, rod = _clamped_rod()
    polar = np.pi * R**4 / 2
    torque = 0.5 * G * polar  # 0.5 rad/m of twist
    rod.external_torques[-1] = (0.0, 0.0, torque)  # material frame: about d3, the rod axis
    world.run(1.5)
    assert np.abs(rod.angular_velocities).max() < 1e-7
    d1_first, d1_last = rod.directors[0, 0], rod.directors[-1, 0]
    angle = np.arctan2(np.dot(np.cross(d1_first, d1_last), rod.directors[-1, 2]),
                       np.dot(d1_first, d1_last))
    # The clamp holds the first element; the twisted span runs between element centres.
    span = L - L / N
    assert abs(angle / (torque * span / (G * polar)) - 1.0) < 1e-3
    # No bending or stretching from a pure torque.
    assert np.abs(rod.positions[:, 1:]).max() < 1e-9


def test_stretch_modulus_sets_the_axial_stiffness_and_leaves_bending_alone():
    """A rope-like rod (stretch_modulus = 20 E): an end force stretches it by F L / (E_s A);
    under a transverse tip load it bends exactly as the rod without it (E I)."""
    Es = 20.0 * E
    area = np.pi * R**2

    def clamped(**kw):
        rod = dx.Rod.straight(n_elements=N, start=(0, 0, 0), direction=(1, 0, 0),
                              normal=(0, 0, 1), length=L, radius=R, density=RHO,
                              youngs_modulus=E, shear_modulus=G, damping=30.0, **kw)
        world = dx.World(gravity=(0, 0, 0), dt=0.3 * 0.25 * rod.stable_dt() * 4)
        world.add_rod(rod)
        rod.fix_start()
        return world, rod

    world, rod = clamped(stretch_modulus=Es)
    # the explicit step follows the faster axial waves
    assert rod.stable_dt() == pytest.approx(0.3 * (L / N) * np.sqrt(RHO / Es), rel=1e-9)
    force = 1e-4 * Es * area
    rod.external_forces[-1] = (force, 0.0, 0.0)
    world.run(0.5)
    assert abs((rod.positions[-1, 0] - L) / (force * L / (Es * area)) - 1.0) < 1e-3
    tips = []
    for kw in ({"stretch_modulus": Es}, {}):
        world, rod = clamped(**kw)
        world.dt = 2e-5
        rod.external_forces[-1] = (0.0, 0.0, -1e-3)
        world.run(0.3)
        tips.append(rod.positions[-1, 2])
    assert tips[0] < -1e-4 and tips[0] == pytest.approx(tips[1], rel=1e-3)
    with pytest.raises(ValueError, match="stretch_modulus"):
        dx.Rod.straight(stretch_modulus=-1.0)


def test_twist_modulus_sets_the_torsional_stiffness_and_leaves_shear_alone():
    """A rope-like rod (twist_modulus = G / 20): an end torque twists it by T L / (G_t J);
    under a transverse tip load (shear and bending) it deflects exactly as the rod without it."""
    Gt = G / 20.0
    polar = np.pi * R**4 / 2

    def clamped(damping=30.0, **kw):
        rod = dx.Rod.straight(n_elements=N, start=(0, 0, 0), direction=(1, 0, 0),
                              normal=(0, 0, 1), length=L, radius=R, density=RHO,
                              youngs_modulus=E, shear_modulus=G, damping=damping, **kw)
        world = dx.World(gravity=(0, 0, 0), dt=0.3 * rod.stable_dt() * 4)
        world.add_rod(rod)
        rod.fix_start()
        return world, rod

    # (the softer twist's slowest mode, ~7 rad/s, critically damped)
    world, rod = clamped(damping=14.0, twist_modulus=Gt)
    assert rod.twist_modulus == Gt and rod.shear_modulus == G
    torque = 0.5 * Gt * polar  # 0.5 rad/m of twist
    rod.external_torques[-1] = (0.0, 0.0, torque)
    world.run(3.0)
    assert np.abs(rod.angular_velocities).max() < 1e-7
    d1_first, d1_last = rod.directors[0, 0], rod.directors[-1, 0]
    angle = np.arctan2(np.dot(np.cross(d1_first, d1_last), rod.directors[-1, 2]),
                       np.dot(d1_first, d1_last))
    assert abs(angle / (torque * (L - L / N) / (Gt * polar)) - 1.0) < 1e-3
    tips = []
    for kw in ({"twist_modulus": Gt}, {}):
        world, rod = clamped(**kw)
        rod.external_forces[-1] = (0.0, 0.0, -1e-3)
        world.run(0.3)
        tips.append(rod.positions[-1, 2])
    assert tips[0] < -1e-4 and tips[0] == pytest.approx(tips[1], rel=1e-9)
    with pytest.raises(ValueError, match="twist_modulus"):
        dx.Rod.straight(twist_modulus=0.0)
