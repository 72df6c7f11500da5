"""Internal forces and torques of discrete Cosserat rods (Gazzola et al. 2018).

Same discretisation and operation order as PyElastica 1.0 ``CosseratRod``: element strains
``sigma = e Q t - d3``, Voronoi curvature from the rotation log map, stresses divided by the
dilatation (forces) and by the cubed Voronoi dilatation (couples). Arrays are node-major:
positions (N, 3), directors (E, 3, 3), Voronoi quantities (V, 3). Closed rods wrap around.
"""

from __future__ import annotations

import math

from numba import njit

from .so3 import relative_rotation_vector
from .bundles import (
    E_DIL,
    E_J,
    E_OMEGA,
    E_Q,
    E_REST_LEN,
    E_REST_SIGMA,
    E_S,
    E_SCR_EDOT,
    E_STRESS,
    E_TORQUE,
    N_FORCE,
    N_POS,
    N_VEL,
    R_CLOSED,
    R_ELEM0,
    R_NE,
    R_NODE0,
    R_VOR0,
    V_B,
    V_COUPLE,
    V_KAPPA,
    V_REST_KAPPA,
    V_REST_VOR,
    V_SCR_C,
    V_SCR_X,
)
from .refcount import NO_REFCOUNT


@njit(cache=True, inline="always", error_model="numpy")
def rod_extent(r, rod_node0, rod_elem0, rod_vor0, rod_ne, rod_closed):
    """First node, element and Voronoi index of rod ``r`` in the packed arrays, and its
    element, node and Voronoi counts (a closed rod has as many nodes as elements)."""
    ne = rod_ne[r]
    closed = rod_closed[r] != 0
    nn = ne if closed else ne + 1
    nv = ne if closed else ne - 1
    return rod_node0[r], rod_elem0[r], rod_vor0[r], ne, nn, nv, closed


@njit(cache=True, error_model="numpy", **NO_REFCOUNT)
def rod_internal_loads(r: int, rd) -> None:
    """Write internal forces (lab, N) and torques (material, N m) of rod ``r`` (bundles:
    the rods' arrays ``rd``, see :mod:`.bundles`).

    ``force``/``torque`` are overwritten on the rod's nodes/elements. ``dil`` (element
    dilatation), ``kappa`` (Voronoi curvature), ``stress`` and ``couple`` (material-frame
    resultants) are left for diagnostics and divergence checks.
    """
    pos, vel, Q, omega = rd.n3[N_POS], rd.n3[N_VEL], rd.e33[E_Q], rd.e3[E_OMEGA]
    J, S, rest_len, rest_sigma, B = rd.e3[E_J], rd.e3[E_S], rd.e1[E_REST_LEN], rd.e3[E_REST_SIGMA], rd.v3[V_B]
    rest_vor, rest_kappa = rd.v1[V_REST_VOR], rd.v3[V_REST_KAPPA]
    force, torque, dil, kappa, stress = rd.n3[N_FORCE], rd.e3[E_TORQUE], rd.e1[E_DIL], rd.v3[V_KAPPA], rd.e3[E_STRESS]
    couple, scr_C, scr_X, scr_edot = rd.v3[V_COUPLE], rd.v3[V_SCR_C], rd.v3[V_SCR_X], rd.e1[E_SCR_EDOT]
    n0, e0, v0, ne, nn, nv, closed = rod_extent(r, rd.ri[R_NODE0], rd.ri[R_ELEM0], rd.ri[R_VOR0], rd.ri[R_NE], rd.ri[R_CLOSED])

    # Stretch / shear: element strain, stress, and the lab-frame stress Q^T n / e.
    p0 = p1 = p2 = 0.0  # lab-frame stress of the element before
    for k in range(ne):
        a = n0 + k
        b = a + 1 if k + 1 < nn else n0  # wraps only on a closed rod (no integer modulo)
        e = e0 + k
        dx0 = pos[b, 0] - pos[a, 0]
        dx1 = pos[b, 1] - pos[a, 1]
        dx2 = pos[b, 2] - pos[a, 2]
        length = math.sqrt(dx0 * dx0 + dx1 * dx1 + dx2 * dx2) + 1e-14
        inv_len = 1.0 / length
        t0 = dx0 * inv_len
        t1 = dx1 * inv_len
        t2 = dx2 * inv_len
        inv_l0 = 1.0 / rest_len[e]
        d = length * inv_l0
        inv_d = rest_len[e] * inv_len
        dil[e] = d
        # Tangent in the material frame, kept for the shear-stretch couple below.
        qt0 = Q[e, 0, 0] * t0 + Q[e, 0, 1] * t1 + Q[e, 0, 2] * t2
        qt1 = Q[e, 1, 0] * t0 + Q[e, 1, 1] * t1 + Q[e, 1, 2] * t2
        qt2 = Q[e, 2, 0] * t0 + Q[e, 2, 1] * t1 + Q[e, 2, 2] * t2
        n_0 = S[e, 0] * (d * qt0 - 0.0 - rest_sigma[e, 0])
        n_1 = S[e, 1] * (d * qt1 - 0.0 - rest_sigma[e, 1])
        n_2 = S[e, 2] * (d * qt2 - 1.0 - rest_sigma[e, 2])
        stress[e, 0] = n_0
        stress[e, 1] = n_1
        stress[e, 2] = n_2
        # Nodal forces: difference of the element stresses (free ends carry none), each node
        # written once: its left element's stress is carried along.
        f0 = (Q[e, 0, 0] * n_0 + Q[e, 1, 0] * n_1 + Q[e, 2, 0] * n_2) * inv_d
        f1 = (Q[e, 0, 1] * n_0 + Q[e, 1, 1] * n_1 + Q[e, 2, 1] * n_2) * inv_d
        f2 = (Q[e, 0, 2] * n_0 + Q[e, 1, 2] * n_1 + Q[e, 2, 2] * n_2) * inv_d
        if k == 0:
            force[a, 0], force[a, 1], force[a, 2] = f0, f1, f2
        else:
            force[a, 0], force[a, 1], force[a, 2] = f0 - p0, f1 - p1, f2 - p2
        p0, p1, p2 = f0, f1, f2
        # (Q t x n) l0
        torque[e, 0] = (qt1 * n_2 - qt2 * n_1) * rest_len[e]
        torque[e, 1] = (qt2 * n_0 - qt0 * n_2) * rest_len[e]
        torque[e, 2] = (qt0 * n_1 - qt1 * n_0) * rest_len[e]
        # Dilatation rate (1/s): d|dx|/dt / l0 = (dx . dv) / (l l0)
        dv0 = vel[b, 0] - vel[a, 0]
        dv1 = vel[b, 1] - vel[a, 1]
        dv2 = vel[b, 2] - vel[a, 2]
        scr_edot[e] = (dx0 * dv0 + dx1 * dv1 + dx2 * dv2) * inv_len * inv_l0

    if closed:
        force[n0, 0] -= p0
        force[n0, 1] -= p1
        force[n0, 2] -= p2
    else:
        force[n0 + ne, 0], force[n0 + ne, 1], force[n0 + ne, 2] = -p0, -p1, -p2

    # Bend / twist at the Voronoi domains.
    for j in range(nv):
        ea = e0 + j
        eb = ea + 1 if j + 1 < ne else e0
        vj = v0 + j
        inv_v0 = 1.0 / rest_vor[vj]
        vd = 0.5 * (rest_len[ea] * dil[ea] + rest_len[eb] * dil[eb]) * inv_v0
        r0, r1, r2 = relative_rotation_vector(Q, ea, Q, eb)
        inv3 = 1.0 / (vd * vd * vd)
        kappa[vj, 0] = r0 * inv_v0
        kappa[vj, 1] = r1 * inv_v0
        kappa[vj, 2] = r2 * inv_v0
        for i in range(3):
            couple[vj, i] = B[vj, i] * (kappa[vj, i] - rest_kappa[vj, i])
        for i in range(3):
            scr_C[vj, i] = couple[vj, i] * inv3
        k0 = kappa[vj, 0]
        k1 = kappa[vj, 1]
        k2 = kappa[vj, 2]
        c0 = couple[vj, 0]
        c1 = couple[vj, 1]
        c2 = couple[vj, 2]
        w = rest_vor[vj] * inv3
        scr_X[vj, 0] = (k1 * c2 - k2 * c1) * w
        scr_X[vj, 1] = (k2 * c0 - k0 * c2) * w
        scr_X[vj, 2] = (k0 * c1 - k1 * c0) * w

    # Element torques: couple difference + couple quadrature + inertial terms.
    for k in range(ne):
        e = e0 + k
        has_right = closed or k < ne - 1
        has_left = closed or k > 0
        jr = v0 + k
        jl = jr - 1 if k > 0 else v0 + ne - 1
        for i in range(3):
            c = 0.0
            x = 0.0
            if has_right:
                c += scr_C[jr, i]
                x += scr_X[jr, i]
            if has_left:
                c -= scr_C[jl, i]
                x += scr_X[jl, i]
            torque[e, i] += c + 0.5 * x
        inv_d = 1.0 / dil[e]
        jw0 = J[e, 0] * omega[e, 0] * inv_d
        jw1 = J[e, 1] * omega[e, 1] * inv_d
        jw2 = J[e, 2] * omega[e, 2] * inv_d
        w0 = omega[e, 0]
        w1 = omega[e, 1]
        w2 = omega[e, 2]
        rate = scr_edot[e] * inv_d
        torque[e, 0] += (jw1 * w2 - jw2 * w1) + jw0 * rate
        torque[e, 1] += (jw2 * w0 - jw0 * w2) + jw1 * rate
        torque[e, 2] += (jw0 * w1 - jw1 * w0) + jw2 * rate
