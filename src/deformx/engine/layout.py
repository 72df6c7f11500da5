"""Packing of all rods of a world into contiguous arrays (PyElastica's memory block layout).

Rods are laid end to end with ghost entries between them (one node, two elements, three Voronoi
domains), so node, element and Voronoi arrays are plain blocks that flat loops can sweep. Ghost
nodes have unit mass and ghost elements unit inertia, so whole-block updates leave them at rest.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

GHOST_NODES, GHOST_ELEMENTS, GHOST_VORONOI = 1, 2, 3
CONTACT_STIFFNESS_FLOOR = 1e-3  # automatic plane stiffness >= this times EA / dl


class Block:
    """Packed parameters, state and scratch arrays of every rod in a world."""

    def __init__(self, rods: Sequence) -> None:
        R = len(rods)
        nn = [r.n_nodes for r in rods]
        ne = [r.n_elements for r in rods]
        nv = [r.rest_voronoi_lengths.shape[0] for r in rods]
        self.rod_node0 = np.array([sum(nn[:i]) + GHOST_NODES * i for i in range(R)], dtype=np.int64)
        self.rod_elem0 = np.array([sum(ne[:i]) + GHOST_ELEMENTS * i for i in range(R)], dtype=np.int64)
        self.rod_vor0 = np.array([sum(nv[:i]) + GHOST_VORONOI * i for i in range(R)], dtype=np.int64)
        self.rod_ne = np.array(ne, dtype=np.int64)
        self.rod_closed = np.array([int(r.closed) for r in rods], dtype=np.int64)
        N = sum(nn) + GHOST_NODES * max(R - 1, 0)
        E = sum(ne) + GHOST_ELEMENTS * max(R - 1, 0)
        V = sum(nv) + GHOST_VORONOI * max(R - 1, 0)

        self.node_rod = np.full(N, -1, dtype=np.int64)
        self.pos = np.zeros((N, 3))
        self.vel = np.zeros((N, 3))
        self.mass = np.ones(N)
        self.node_radius = np.zeros(N)
        # Floor of the automatic contact stiffness (N/m): a fraction of the adjacent elements' axial
        # stiffness, so a stiff rod pressing on a plane does not sink into it.
        self.node_kmin = np.zeros(N)
        self.fext = np.zeros((N, 3))
        self.force = np.zeros((N, 3))
        self.contact_force = np.zeros((N, 3))

        self.elem_rod = np.full(E, -1, dtype=np.int64)
        self.Q = np.tile(np.eye(3), (E, 1, 1))
        self.omega = np.zeros((E, 3))
        self.J = np.ones((E, 3))
        self.inv_J = np.ones((E, 3))
        self.S = np.zeros((E, 3))
        self.rest_len = np.ones(E)
        self.rest_sigma = np.zeros((E, 3))
        self.text = np.zeros((E, 3))
        self.torque = np.zeros((E, 3))
        self.dil = np.ones(E)
        self.stress = np.zeros((E, 3))
        self.scr_edot = np.zeros(E)

        # Stable integrator: state at the step start, friction anchors, Newton statistics.
        self.xn = np.zeros((N, 3))
        self.vn = np.zeros((N, 3))
        self.Qn = np.tile(np.eye(3), (E, 1, 1))
        self.wn = np.zeros((E, 3))
        self.fn_el = np.zeros((N, 3))
        self.tn_el = np.zeros((E, 3))
        self.anchor = np.zeros((N, 3))
        self.anchor_on = np.zeros(N, dtype=np.int64)
        self.c_plane = np.full(N, -1, dtype=np.int64)
        self.c_stick = np.zeros(N, dtype=np.int64)
        self.c_dir = np.zeros((N, 3))
        self.stats = np.zeros((R, 5))
        self.h_prev = np.zeros(R)  # last accepted (sub-)step per rod: the predictor's memory
        self.rate = np.ones(R)  # Newton contraction rate per rod, for the convergence test

        self.B = np.zeros((V, 3))
        self.rest_vor = np.ones(V)
        self.rest_kappa = np.zeros((V, 3))
        self.kappa = np.zeros((V, 3))
        self.couple = np.zeros((V, 3))
        self.scr_C = np.zeros((V, 3))
        self.scr_X = np.zeros((V, 3))

        for i, rod in enumerate(rods):
            n = slice(self.rod_node0[i], self.rod_node0[i] + nn[i])
            e = slice(self.rod_elem0[i], self.rod_elem0[i] + ne[i])
            v = slice(self.rod_vor0[i], self.rod_vor0[i] + nv[i])
            self.node_rod[n] = i
            self.elem_rod[e] = i
            self.mass[n] = rod.masses
            self.node_radius[n] = rod.node_radius
            axial = rod._shear_matrix[:, 2] / rod.rest_lengths
            kmin = np.zeros(nn[i])
            kmin[: rod.n_elements] = axial
            kmin[1:] = np.maximum(kmin[1:], axial[: nn[i] - 1])
            self.node_kmin[n] = CONTACT_STIFFNESS_FLOOR * kmin
            self.J[e] = rod._inertia
            self.inv_J[e] = 1.0 / rod._inertia
            self.S[e] = rod._shear_matrix
            self.rest_len[e] = rod.rest_lengths
            self.rest_sigma[e] = rod.rest_sigma
            self.B[v] = rod._bend_matrix
            self.rest_vor[v] = rod.rest_voronoi_lengths
            self.rest_kappa[v] = rod.rest_kappa
            # Move the state in, then make the rod's arrays views of the block.
            for name, block, sl in (("_positions", self.pos, n), ("_velocities", self.vel, n),
                                    ("_external_forces", self.fext, n),
                                    ("_directors", self.Q, e), ("_angular_velocities", self.omega, e),
                                    ("_external_torques", self.text, e)):
                block[sl] = getattr(rod, name)
                setattr(rod, name, block[sl])
            # Parameters stay shared too, so edits of rest shape after packing take effect.
            rod.rest_kappa = self.rest_kappa[v]
            rod.rest_sigma = self.rest_sigma[e]

    def node_slice(self, i: int, rod) -> slice:
        return slice(self.rod_node0[i], self.rod_node0[i] + rod.n_nodes)
