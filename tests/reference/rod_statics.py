"""Reference static solutions for planar Cosserat (Simo-Reissner) rods.

Everything here is independent of the DeformX engine; tests compare the
simulator's converged static states against these curves.

Conventions (shared by all functions)
-------------------------------------
* The rod lies in the x-z plane, clamped at the origin with its rest tangent
  along +x; gravity acts along -z.
* ``s`` is the *rest* arc length (m), 0 at the clamp, L at the free end.
* ``theta`` (rad) is the rotation of the cross-section, measured from +x
  towards +z, i.e. the director ``d3 = (cos theta, sin theta)`` in (x, z).
  The in-plane shear director is ``d1 = (-sin theta, cos theta)``.  For a
  shearable rod the centreline tangent is *not* d3; theta is the angle of
  the director, which in the engine is ``atan2(d3_z, d3_x)``.  A sagging
  rod has theta < 0.  At theta = 0, d1 = +z: a DeformX rod built with
  ``direction=(1, 0, 0), normal=(0, 0, 1)``.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import solve_bvp, solve_ivp
from scipy.optimize import brentq

#: Timoshenko shear correction factor used by PyElastica (Kaneko 1975, nu = 0.5).
ALPHA_C: float = 27.0 / 28.0

_RTOL = 1e-12  # solve_ivp tolerances for the shooting (brief asks <= 1e-10)
_ATOL = 1e-14
_BRANCH_TOL = 1e-6  # rad; shooting vs collocation agreement to accept shooting


def _strains(
    theta: ArrayLike,
    nx: ArrayLike,
    nz: ArrayLike,
    axial_stiffness: float,
    shear_stiffness: float,
    pyelastica_dilatation: bool,
) -> tuple[Any, Any, Any]:
    """Invert the constitutive law: lab-frame internal force -> (nu1, nu3, e).

    ``nu1`` is the shear strain, ``nu3`` the stretch (1 at rest) and
    ``e = |r'|`` the dilatation.  Infinite stiffnesses give the unshearable
    / inextensible limits (x / inf == 0 in IEEE arithmetic).  Vectorised.
    """
    c, sn = np.cos(theta), np.sin(theta)
    a = (-nx * sn + nz * c) / shear_stiffness  # n . d1 / (alpha_c G A)
    b = (nx * c + nz * sn) / axial_stiffness  # n . d3 / (E A)
    if not pyelastica_dilatation:
        return a, 1.0 + b, np.hypot(a, 1.0 + b)
    # PyElastica transmits n = S sigma / e with e = |nu|.  Writing nu1 = a e,
    # nu3 = 1 + b e and e^2 = nu1^2 + nu3^2 gives a quadratic in e whose
    # positive root is:
    e = (b + np.sqrt(1.0 - a * a)) / (1.0 - a * a - b * b)
    return a * e, 1.0 + b * e, e


def planar_rod_statics(
    length: float,
    bending_stiffness: float,
    axial_stiffness: float,
    shear_stiffness: float,
    weight_per_length: float = 0.0,
    end_force: Sequence[float] = (0.0, 0.0),
    n_eval: int = 201,
    pyelastica_dilatation: bool = False,
) -> dict[str, Any]:
    """Equilibrium of a planar clamped-free Cosserat rod under dead loads.

    Section stiffnesses: ``bending_stiffness`` EI (N m^2), ``axial_stiffness``
    EA (N), ``shear_stiffness`` alpha_c G A (N); EA and alpha_c G A may be
    ``np.inf`` (inextensible / unshearable).  ``weight_per_length`` w (N/m,
    per REST length, acting along -z), ``end_force`` (Fx, Fz) in N at s = L.

    Equations (rest arc length s, ' = d/ds; see module docstring)::

        n(s)   = (Fx, Fz - w (L - s))        force across s, lab frame (known)
        n1     = n . d1,  n3 = n . d3        material components
        nu1    = n1 / (alpha_c G A)          shear strain
        nu3    = 1 + n3 / (E A)              stretch
        r'     = nu1 d1 + nu3 d3
        M      = E I theta'                  bending moment
        M'     = -(r' x n) = -(x' n_z - z' n_x)
        theta(0) = 0, r(0) = 0, M(L) = 0

    With ``pyelastica_dilatation=True`` the law of PyElastica's
    discretisation is used instead: n1 = alpha_c G A nu1 / e,
    n3 = E A (nu3 - 1) / e and M = E I theta' / e^3 with e = |r'|.  The two
    differ at order strain.

    Solution: (theta, M) do not depend on r.  The tip angle theta(L) is the
    one unknown: integrating (theta, M) from the free end (M = 0) back to
    the clamp must give theta(0) = 0, solved with brentq (solve_ivp DOP853,
    rtol 1e-12).  For floppy rods this map is exponentially sensitive and
    has many roots (looped equilibria), so the root is first located by
    collocation (solve_bvp) with continuation in the load from the straight
    rod, which follows the quasi-static loading path; shooting then
    polishes it.  The returned curve is re-integrated from the clamp with
    the recovered clamp moment, so it meets the clamp conditions exactly
    and ``residual_moment`` = M(L) measures the shooting error.  If the
    shooting is too ill-conditioned (w L^3 / EI above a few hundred) the
    collocation result is returned and ``method`` says so.  Not meant for
    loads past a buckling bifurcation.

    Returns a dict: ``s, x, z, theta`` (m, m, m, rad), ``moment`` (N m),
    ``nu1``, ``nu3`` (strains), ``tip`` = array (x, z) at s = L (m),
    ``clamp_moment`` (N m), ``residual_moment`` (N m; for "collocation"
    only the BVP's boundary residual), ``method`` ("shooting" or
    "collocation").
    """
    length = float(length)
    ei, ka, ks = float(bending_stiffness), float(axial_stiffness), float(shear_stiffness)
    w = float(weight_per_length)
    fx, fz = (float(v) for v in end_force)

    def rhs(s: Any, y: Any, load: float = 1.0) -> Any:
        """d/ds [theta, M, x, z] (rows beyond y[:2] optional); vectorised."""
        theta, moment = y[0], y[1]
        # Statically determinate: the force carried across section s (exerted
        # by (s, L] on [0, s]) is the end load plus the weight beyond s.
        nx = load * fx + 0.0 * s  # + 0 * s broadcasts for solve_bvp
        nz = load * (fz - w * (length - s))
        nu1, nu3, e = _strains(theta, nx, nz, ka, ks, pyelastica_dilatation)
        c, sn = np.cos(theta), np.sin(theta)
        dx = -nu1 * sn + nu3 * c  # r' = nu1 d1 + nu3 d3
        dz = nu1 * c + nu3 * sn
        # PyElastica's couple is B kappa / e^3 with kappa per rest length.
        kappa = moment / ei * (e**3 if pyelastica_dilatation else 1.0)
        dmoment = -(dx * nz - dz * nx)  # M' + r' x n = 0
        return np.array([kappa, dmoment, dx, dz][: len(y)])

    # 1) Collocation with continuation in the load factor (geometric steps,
    #    halved on failure) to land on the loading-path branch.
    load_scale = (abs(w) * length**3 + np.hypot(fx, fz) * length**2) / ei
    mesh = np.linspace(0.0, length, 101)
    guess = np.zeros((2, mesh.size))

    def bc(ya: Any, yb: Any) -> Any:
        return np.array([ya[0], yb[1]])  # theta(0) = 0, M(L) = 0

    lam, step = 0.0, min(1.0, 1.0 / max(load_scale, 1e-300))
    bvp = None
    while lam < 1.0:
        target = min(1.0, lam + step)
        last = target == 1.0
        trial = solve_bvp(
            lambda s, y: rhs(s, y, target),
            bc,
            mesh,
            guess,
            tol=1e-9 if last else 1e-5,
            max_nodes=200_000,
        )
        if trial.status != 0:
            step /= 2.0
            if step < 1e-8:
                raise RuntimeError(f"continuation failed at load factor {lam:g}")
            continue
        lam, bvp = target, trial
        mesh, guess = trial.x, trial.y
        step *= 2.0
    assert bvp is not None

    # 2) Shooting polish around the collocation tip angle.
    def from_tip(tip_angle: float) -> tuple[float, float]:
        """(theta(0), M(0)) integrating from the free end, where M = 0."""
        sol = solve_ivp(
            rhs, (length, 0.0), [tip_angle, 0.0], method="DOP853", rtol=_RTOL, atol=_ATOL
        )
        return (float(sol.y[0, -1]), float(sol.y[1, -1])) if sol.success else (np.nan, np.nan)

    s_eval = np.linspace(0.0, length, n_eval)
    tip0 = float(bvp.y[0, -1])
    g0 = from_tip(tip0)[0]
    root = tip0 if g0 == 0.0 else None
    delta = 1e-10
    while root is None and delta < 1e-3 and np.isfinite(g0):
        for other in (tip0 - delta, tip0 + delta):
            g1 = from_tip(other)[0]
            if g0 * g1 < 0.0:
                lo, hi = sorted((tip0, other))
                root = brentq(lambda p: from_tip(p)[0], lo, hi, xtol=1e-16, rtol=1e-15)
                break
        delta *= 10.0
    method = "collocation"
    if root is not None:
        sol = solve_ivp(
            rhs,
            (0.0, length),
            [0.0, from_tip(root)[1], 0.0, 0.0],
            method="DOP853",
            t_eval=s_eval,
            rtol=_RTOL,
            atol=_ATOL,
        )
        # Accept only if the re-integration from the clamp stayed on the
        # collocation branch (it diverges when the problem is too stiff).
        if sol.success and np.max(np.abs(sol.y[0] - bvp.sol(s_eval)[0])) < _BRANCH_TOL:
            method = "shooting"
            theta, moment, x, z = sol.y
    if method == "collocation":
        # Positions by quadrature along the collocation solution.
        theta, moment = bvp.sol(s_eval)
        pos = solve_ivp(
            lambda s, r: rhs(s, np.r_[bvp.sol(s), r])[2:],
            (0.0, length),
            [0.0, 0.0],
            t_eval=s_eval,
            rtol=1e-10,
            atol=_ATOL,
        )
        x, z = pos.y

    nu1, nu3, _ = _strains(
        theta, fx + 0.0 * s_eval, fz - w * (length - s_eval), ka, ks, pyelastica_dilatation
    )
    return {
        "s": s_eval,
        "x": x,
        "z": z,
        "theta": theta,
        "moment": moment,
        "nu1": nu1,
        "nu3": nu3,
        "tip": np.array([x[-1], z[-1]]),
        "clamp_moment": float(moment[0]),
        "residual_moment": float(moment[-1]),
        "method": method,
    }


def clamped_rod_sag(
    length: float,
    radius: float,
    density: float,
    youngs_modulus: float,
    shear_modulus: float,
    gravity: float = 9.81,
    alpha_c: float = ALPHA_C,
    n_eval: int = 201,
    end_force: Sequence[float] = (0.0, 0.0),
    pyelastica_dilatation: bool = False,
) -> dict[str, Any]:
    """Horizontal cantilever of circular section sagging under its own weight.

    SI units: length, radius (m), density (kg/m^3), moduli (Pa), gravity
    (m/s^2, magnitude, acting along -z), end_force (Fx, Fz) dead load at the
    tip (N).  Weight per rest length w = density * pi r^2 * gravity;
    EA = E pi r^2, alpha_c G A, EI = E pi r^4 / 4 (PyElastica's choices).
    Pass ``density=0`` for a pure end-load case.  See
    :func:`planar_rod_statics` for the equations and the returned dict.
    """
    area = np.pi * radius**2
    inertia = np.pi * radius**4 / 4.0
    return planar_rod_statics(
        length=length,
        bending_stiffness=youngs_modulus * inertia,
        axial_stiffness=youngs_modulus * area,
        shear_stiffness=alpha_c * shear_modulus * area,
        weight_per_length=density * area * gravity,
        end_force=end_force,
        n_eval=n_eval,
        pyelastica_dilatation=pyelastica_dilatation,
    )


def timoshenko_cantilever_deflection(
    s: ArrayLike,
    length: float,
    end_force: float | Sequence[float],
    youngs_modulus: float,
    shear_modulus: float,
    radius: float,
    alpha_c: float = ALPHA_C,
) -> NDArray[np.float64]:
    """Small-deflection Timoshenko cantilever under a transverse tip load.

    y(s) = F s / (alpha_c G A) + F L s^2 / (2 E I) - F s^3 / (6 E I), the
    analytical curve of PyElastica's Timoshenko-beam example (shear term plus
    Euler-Bernoulli term).  ``s`` rest arc length (m); ``end_force`` is the
    transverse load in N (a vector is reduced to its norm).  Returns the
    deflection magnitude (m, >= 0) at each s.
    """
    s = np.asarray(s, dtype=float)
    force = float(np.linalg.norm(np.atleast_1d(np.asarray(end_force, dtype=float))))
    area = np.pi * radius**2
    ei = youngs_modulus * np.pi * radius**4 / 4.0
    return (
        force * s / (alpha_c * shear_modulus * area)
        + force * length * s**2 / (2.0 * ei)
        - force * s**3 / (6.0 * ei)
    )
