"""Rod.set_material: a material changed in place (no rebuild) is the material built in."""

from __future__ import annotations

import numpy as np
import pytest

import deformx as dx

NEW = dict(density=900.0, youngs_modulus=3e6, shear_modulus=1.1e6, stretch_modulus=5e6,
           twist_modulus=2e5)


def _world(integrator: str, dt: float, **material) -> tuple[dx.World, dx.Rod]:
    """A rope clamped at one end, swinging down onto a plane (contact stiffness floors
    depend on the stretch modulus, contact damping on the masses)."""
    world = dx.World(dt=dt, integrator=integrator, rod_contact=False)
    world.add_plane(point=(0, 0, -0.06), friction=0.3)
    params = dict(density=1200.0, youngs_modulus=1e6, shear_modulus=4e5,
                  stretch_modulus=2e6) | material
    rod = world.add_rod(dx.Rod.straight(25, start=(0, 0, 0), direction=(1, 0, 0), length=0.5,
                                        radius=0.005, damping=0.5, **params))
    rod.set_point_mass(-1, 0.01)
    rod.fix_start()
    return world, rod


@pytest.mark.parametrize("integrator,dt,n", [("verlet", 2e-5, 4000), ("stable", 2e-3, 60)])
def test_a_material_set_in_place_runs_like_one_built_with_it(integrator, dt, n):
    built, a = _world(integrator, dt, **NEW)
    changed, b = _world(integrator, dt)
    changed.step(n)  # packed and stepped with the old material ...
    b.set_material(**NEW)  # ... then changed in place,
    built.step(n)  # and the built one brought to the same state:
    a.set_state(b.get_state())
    built.time = changed.time
    built.step(n)
    changed.step(n)
    for name in ("positions", "velocities", "directors", "angular_velocities"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    np.testing.assert_array_equal(a.masses, b.masses)
    assert b.density == 900.0 and b.mass == pytest.approx(a.mass, rel=1e-15)


def test_a_new_youngs_modulus_carries_shear_and_stretch_along():
    rod = dx.Rod.straight(10, radius=0.01, youngs_modulus=1e6, poisson_ratio=0.25)
    rod.set_material(youngs_modulus=4e6)
    assert rod.shear_modulus == pytest.approx(4e6 / 2.5, rel=1e-14)
    assert rod.stretch_modulus == 4e6
    rod.set_material(poisson_ratio=0.5)
    assert rod.shear_modulus == pytest.approx(4e6 / 3.0, rel=1e-14)
    assert rod.twist_modulus == rod.shear_modulus  # the default twist follows the shear
    rope = dx.Rod.straight(10, youngs_modulus=1e6, shear_modulus=4e5, twist_modulus=1e5)
    rope.set_material(youngs_modulus=2e6)  # a twist modulus of its own scales with E
    assert (rope.shear_modulus, rope.twist_modulus) == (8e5, 2e5)
    rope.set_material(twist_modulus=3e5)
    assert (rope.shear_modulus, rope.twist_modulus) == (8e5, 3e5)


def test_a_lighter_rope_sags_less_after_the_change():
    """Static check: a clamped cantilever's tip deflection scales as rho / E (w L^4 / 8EI)."""
    def tip_sag(**material):
        world = dx.World(dt=2e-3, integrator="stable", rod_contact=False)
        rod = world.add_rod(dx.Rod.straight(40, direction=(1, 0, 0), length=0.5,
                                            radius=0.005, density=1000.0,
                                            youngs_modulus=2e9, damping=20.0))
        rod.fix_start()
        world.step(5)
        if material:
            rod.set_material(**material)  # packed and stepped: changed in place
        world.step(1500)
        return -rod.positions[-1, 2]

    base = tip_sag()
    assert tip_sag(density=500.0) == pytest.approx(0.5 * base, rel=0.02)
    assert tip_sag(youngs_modulus=4e9) == pytest.approx(0.5 * base, rel=0.02)


def test_bad_material_is_refused_with_the_parameter_named():
    rod = dx.Rod.straight(10)
    with pytest.raises(ValueError, match="density"):
        rod.set_material(density=-1.0)
    with pytest.raises(ValueError, match="shear_modulus or poisson_ratio"):
        rod.set_material(shear_modulus=1e5, poisson_ratio=0.3)
