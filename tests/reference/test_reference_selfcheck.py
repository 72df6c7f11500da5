"""Self-checks of the reference solutions against closed forms and an
independent formulation, so that simulator tests can trust them."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_bvp, trapezoid

from tests.reference.rod_statics import (
    ALPHA_C,
    clamped_rod_sag,
    planar_rod_statics,
    timoshenko_cantilever_deflection,
)

G_ACC = 9.81


def _section(radius: float) -> tuple[float, float]:
    """(A, I) of a circular section, m^2 and m^4."""
    return np.pi * radius**2, np.pi * radius**4 / 4.0


def _inextensible_elastica_tip(load: float, end_force_z: float = 0.0) -> np.ndarray:
    """Independent 2nd-order form of the classical elastica (EI = L = 1).

    theta'' = (w (1 - s) - Fz) cos(theta), theta(0) = 0, theta'(1) = 0, with
    w = ``load``; solved by collocation, positions by trapezoid quadrature.
    """
    s = np.linspace(0.0, 1.0, 2001)

    def fun(s, y):
        return np.vstack([y[1], (load * (1.0 - s) - end_force_z) * np.cos(y[0])])

    def bc(ya, yb):
        return np.array([ya[0], yb[1]])

    sol = solve_bvp(fun, bc, s, np.zeros((2, s.size)), tol=1e-10, max_nodes=100_000)
    assert sol.status == 0
    theta = sol.sol(s)[0]
    return np.array([trapezoid(np.cos(theta), s), trapezoid(np.sin(theta), s)])


def test_stiff_rod_sag_matches_euler_bernoulli():
    """(a) Small sag: tip deflection -> w L^4 / (8 E I) (+ Timoshenko shear)."""
    length, radius, density, e_mod = 1.0, 0.01, 1000.0, 1e11
    area, inertia = _section(radius)
    w = density * area * G_ACC
    res = clamped_rod_sag(length, radius, density, e_mod, e_mod / 3.0)
    eb = w * length**4 / (8.0 * e_mod * inertia)
    assert res["tip"][1] < 0.0  # sags downwards, along gravity
    assert -res["tip"][1] == pytest.approx(eb, rel=5e-3)
    # Tighter with the linear shear term w L^2 / (2 alpha_c G A) included.
    timo = eb + w * length**2 / (2.0 * ALPHA_C * e_mod / 3.0 * area)
    assert -res["tip"][1] == pytest.approx(timo, rel=1e-6)


def test_approaches_inextensible_unshearable_limit():
    """(b) Stretch/shear stiffness -> inf at fixed EI: converges like 1/k to
    the classical elastica, which also matches an independent formulation."""
    load = 3.0  # w L^3 / EI: large deflection
    exact = _inextensible_elastica_tip(load)
    limit = planar_rod_statics(1.0, 1.0, np.inf, np.inf, weight_per_length=load)["tip"]
    assert np.allclose(limit, exact, rtol=0.0, atol=1e-7)  # quadrature-limited

    errors = []
    for k in (1e2, 1e4, 1e6):  # EA = alpha_c G A = k EI / L^2
        tip = planar_rod_statics(1.0, 1.0, k, k, weight_per_length=load)["tip"]
        errors.append(np.abs(tip - limit).max())
    assert errors[0] > 1e-4  # extensibility is visible at k = 100 ...
    assert errors[-1] < 1e-5  # ... and vanishes as k grows,
    assert errors[0] / errors[1] == pytest.approx(100.0, rel=0.1)  # at O(1/k).


def test_large_end_load_is_geometrically_nonlinear():
    """(c) P L^2 / EI = 1 and 10: the tip deflection is well below linear
    theory and equals the Bisshopp & Drucker (1945) elastica values."""
    tip1 = planar_rod_statics(1.0, 1.0, np.inf, np.inf, end_force=(0.0, -1.0))["tip"]
    # Bisshopp & Drucker, Q. Appl. Math. 3 (1945): delta_v = 0.30172 L,
    # delta_h = 0.05643 L for P L^2 / EI = 1.
    assert -tip1[1] == pytest.approx(0.30172, abs=1e-5)
    assert 1.0 - tip1[0] == pytest.approx(0.05643, abs=1e-5)
    assert np.allclose(tip1, _inextensible_elastica_tip(0.0, -1.0), rtol=0.0, atol=1e-7)

    # Same for a real (extensible, shearable) rod: linear theory predicts a
    # tip deflection of 3.33 L here; the exact one is ~0.81 L.
    length, radius, e_mod = 1.0, 0.01, 1e7
    _, inertia = _section(radius)
    force = 10.0 * e_mod * inertia / length**2
    res = clamped_rod_sag(length, radius, 0.0, e_mod, e_mod / 3.0, end_force=(0.0, -force))
    linear = timoshenko_cantilever_deflection(length, length, force, e_mod, e_mod / 3.0, radius)
    assert -res["tip"][1] < 0.3 * linear
    assert -res["tip"][1] == pytest.approx(0.8106, abs=2e-3)
    assert res["tip"][0] < 0.5 * length  # tip pulled well back towards the clamp


@pytest.mark.parametrize(
    "length, radius, e_mod, g_mod",
    [
        (3.0, 0.25, 1e6, 1e6 / 1.99),  # PyElastica Timoshenko example rod
        (1.0, 0.2, 1e6, 1e6 / 3.0),  # stubby rod: shear ~9% of deflection
    ],
)
def test_small_end_force_matches_timoshenko(length, radius, e_mod, g_mod):
    """(d) Tiny transverse tip force: F L^3/(3EI) + F L/(alpha_c G A)."""
    area, inertia = _section(radius)
    force = 1e-6 * e_mod * inertia / length**2
    res = clamped_rod_sag(length, radius, 0.0, e_mod, g_mod, end_force=(0.0, -force))
    bending = force * length**3 / (3.0 * e_mod * inertia)
    shear = force * length / (ALPHA_C * g_mod * area)
    assert -res["tip"][1] == pytest.approx(bending + shear, rel=5e-3)
    # The whole curve, via the helper, and the shear term is really resolved.
    curve = timoshenko_cantilever_deflection(res["s"], length, force, e_mod, g_mod, radius)
    assert np.allclose(-res["z"], curve, rtol=0, atol=1e-4 * curve[-1])
    assert abs(-res["tip"][1] - bending) > 5.0 * abs(-res["tip"][1] - bending - shear)


def test_shooting_residual_vanishes():
    """(e) Moment at the free end after re-integrating from the clamp."""
    length, radius, density, e_mod = 1.0, 0.01, 1000.0, 1e7  # w L^3 / EI ~ 39
    area, _ = _section(radius)
    res = clamped_rod_sag(length, radius, density, e_mod, e_mod / 3.0)
    assert res["method"] == "shooting"
    w = density * area * G_ACC
    assert abs(res["residual_moment"]) < 1e-9 * w * length**2 / 2.0
    assert res["theta"][0] == 0.0 and np.all(res["tip"] != 0.0)
    # Large sag: the clamp moment is well below the rigid value w L^2 / 2.
    assert 0.0 < -res["clamp_moment"] < 0.5 * w * length**2 / 2.0


def test_floppy_rod_hangs_down():
    """Very floppy rod (w L^3 / EI ~ 400, single shooting ill-conditioned):
    the loading-path branch hangs almost vertically, no loops."""
    res = clamped_rod_sag(1.0, 0.01, 1000.0, 1e6, 1e6 / 3.0)
    assert res["theta"][-1] == pytest.approx(-np.pi / 2, abs=1e-4)
    assert np.all(np.diff(res["theta"]) <= 1e-12)  # monotone: no loops
    assert 0.0 < res["tip"][0] < 0.1 and res["tip"][1] < -0.95


@pytest.mark.parametrize("pyelastica_dilatation", [False, True])
def test_pure_tension_stretch(pyelastica_dilatation):
    """Axial tip pull: uniform stretch, closed form for both laws."""
    ea, force = 100.0, 10.0
    res = planar_rod_statics(
        2.0, 1.0, ea, 50.0, end_force=(force, 0.0), pyelastica_dilatation=pyelastica_dilatation
    )
    # Linear law: nu3 = 1 + F/EA.  PyElastica: F = EA (e - 1) / e.
    stretch = 1.0 / (1.0 - force / ea) if pyelastica_dilatation else 1.0 + force / ea
    assert res["tip"] == pytest.approx([2.0 * stretch, 0.0], abs=1e-12)
    assert np.allclose(res["nu3"], stretch) and np.allclose(res["theta"], 0.0)
