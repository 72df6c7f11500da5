"""Bad input is rejected with a message naming the parameter; divergence raises, never NaNs."""

from __future__ import annotations

import numpy as np
import pytest

import deformx as dx

GOOD = dict(n_elements=10, length=1.0, radius=0.01, density=1000.0, youngs_modulus=1e6)


@pytest.mark.parametrize("name, value", [
    ("n_elements", 1), ("n_elements", 2.5), ("length", 0.0), ("length", -1.0),
    ("radius", 0.0), ("radius", float("nan")), ("density", -5.0), ("youngs_modulus", 0.0),
    ("shear_modulus", -1.0), ("poisson_ratio", 0.7), ("poisson_ratio", -1.0), ("damping", -0.1),
    ("direction", (0, 0, 0)), ("start", (0, 0)), ("normal", (1, 0, 0)),
    ("rest_curvature", np.zeros((4, 3))),
])
def test_invalid_rod_parameter_is_named(name, value):
    kwargs = dict(GOOD, **{name: value})
    with pytest.raises(ValueError, match=name):
        dx.Rod.straight(**kwargs)


def test_shear_modulus_and_poisson_ratio_are_exclusive():
    with pytest.raises(ValueError, match="shear_modulus or poisson_ratio"):
        dx.Rod.straight(**GOOD, shear_modulus=1e5, poisson_ratio=0.3)


@pytest.mark.parametrize("points, kwargs, name", [
    (np.zeros((5, 2)), {}, "points"),
    ([[0, 0, 0], [1, 0, 0]], {}, "points"),
    ([[0, 0, 0], [0, 0, 0], [1, 0, 0]], {}, "points"),
    ([[0, 0, 0], [1, 0, 0], [2, 0, 0]], {"rest_shape": "curly"}, "rest_shape"),
])
def test_invalid_points_are_named(points, kwargs, name):
    with pytest.raises(ValueError, match=name):
        dx.Rod.from_points(points, radius=0.01, density=1000.0, youngs_modulus=1e6, **kwargs)


@pytest.mark.parametrize("kwargs, name", [
    ({"dt": 0.0}, "dt"), ({"dt": -1e-4}, "dt"), ({"gravity": (0, 9.81)}, "gravity"),
    ({"integrator": "euler"}, "integrator"), ({"max_strain": 0.0}, "max_strain"),
])
def test_invalid_world_parameter_is_named(kwargs, name):
    with pytest.raises(ValueError, match=name):
        dx.World(**kwargs)


@pytest.mark.parametrize("kwargs, name", [
    ({"normal": (0, 0, 0)}, "normal"), ({"stiffness": -1.0}, "stiffness"),
    ({"damping": -1.0}, "damping"), ({"friction": -0.2}, "friction"),
    ({"static_friction": 0.2, "kinetic_friction": 0.5}, "kinetic_friction"),
])
def test_invalid_plane_parameter_is_named(kwargs, name):
    with pytest.raises(ValueError, match=name):
        dx.World().add_plane(**kwargs)


def test_invalid_clamp_and_run_arguments_are_named():
    world = dx.World()
    rod = world.add_rod(dx.Rod.straight(**GOOD))
    with pytest.raises(ValueError, match="node"):
        rod.pin(11)
    with pytest.raises(ValueError, match="directors"):
        rod.fix_start().set_pose(directors=np.ones((3, 3)))
    with pytest.raises(ValueError, match="duration"):
        world.run(-1.0)
    with pytest.raises(ValueError, match="n_steps"):
        world.step(-3)
    with pytest.raises(ValueError, match="already belongs"):
        world.add_rod(rod)


def test_too_large_time_step_raises_simulation_diverged():
    rod = dx.Rod.straight(n_elements=50, start=(0, 0, 0), direction=(1, 0, 0), length=1.0,
                          radius=0.01, density=1000.0, youngs_modulus=1e7)
    world = dx.World(dt=20 * rod.stable_dt())
    world.add_rod(rod)
    rod.fix_start()
    with pytest.raises(dx.SimulationDiverged) as info:
        world.run(0.5)
    err = info.value
    assert err.rod == 0 and 0 <= err.element < rod.n_elements
    assert 0.0 < err.time <= 0.5
    assert 0.0 < err.suggested_dt < world.dt
    assert "dt" in str(err) and "rod 0" in str(err)
    # The suggested step runs the same case cleanly.
    rod2 = dx.Rod.straight(n_elements=50, start=(0, 0, 0), direction=(1, 0, 0), length=1.0,
                           radius=0.01, density=1000.0, youngs_modulus=1e7)
    world2 = dx.World(dt=err.suggested_dt)
    world2.add_rod(rod2)
    rod2.fix_start()
    world2.run(0.05)
    assert np.all(np.isfinite(rod2.positions))


def test_divergence_is_caught_within_one_step_of_a_nan():
    world = dx.World(dt=1e-5)
    rod = world.add_rod(dx.Rod.straight(**GOOD))
    world.step(3)
    rod.velocities[4, 1] = np.nan
    with pytest.raises(dx.SimulationDiverged, match="NaN"):
        world.step(1)
