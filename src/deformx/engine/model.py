"""Packing all rods of a world into one ``rods`` buffer group (PyElastica's memory block).

Rods are laid end to end with ghost entries between them (one node, two elements, three Voronoi
domains), so node, element and Voronoi arrays are plain blocks that flat loops can sweep. Ghost
nodes have unit mass and ghost elements unit inertia, so whole-block updates leave them at rest.
The model part (parameters, rest shape, segment tables) is written once here; the rods' state
and loads move in, and each rod's arrays become views of the buffers.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from .packing import Packed

GHOST_NODES, GHOST_ELEMENTS, GHOST_VORONOI = 1, 2, 3
CONTACT_STIFFNESS_FLOOR = 1e-3  # automatic plane stiffness >= this times EA / dl


def pack_rods(rods: Sequence, dt: float, stable: bool = True) -> Packed:
    """The ``rods`` group of ``rods``; their state arrays become views of it. ``stable``:
    room for the stable integrator's Newton system (none for explicit worlds)."""
    R = len(rods)
    nn = [r.n_nodes for r in rods]
    ne = [r.n_elements for r in rods]
    nv = [r.rest_voronoi_lengths.shape[0] for r in rods]
    N = sum(nn) + GHOST_NODES * max(R - 1, 0)
    E = sum(ne) + GHOST_ELEMENTS * max(R - 1, 0)
    V = sum(nv) + GHOST_VORONOI * max(R - 1, 0)
    b = Packed("rods", dict(R=R, N=N, E=E, V=V, S=sum(ne), M=sum(nn), Q=N + E,
                            B=N + E if stable else 0))
    b["node0"][:] = [sum(nn[:i]) + GHOST_NODES * i for i in range(R)]
    b["elem0"][:] = [sum(ne[:i]) + GHOST_ELEMENTS * i for i in range(R)]
    b["vor0"][:] = [sum(nv[:i]) + GHOST_VORONOI * i for i in range(R)]
    b["ne"][:] = ne
    b["closed"][:] = [int(r.closed) for r in rods]
    b["group"][:] = [r.contact_group for r in rods]
    set_damping(b, rods, dt)
    b["mass"][:] = 1.0
    b["Q"][:] = np.eye(3)
    b["Qn"][:] = np.eye(3)
    b["J"][:] = 1.0
    b["inv_J"][:] = 1.0
    b["rest_len"][:] = 1.0
    b["rest_vor"][:] = 1.0
    b["dil"][:] = 1.0
    b["rate"][:] = 1.0
    b["sp_i"][..., 0] = -1  # no contact planes yet
    b["pair_off"][:] = -1.0  # and no rod-rod contact
    b["pen_off"][:] = -1.0  # nor any contact of the explicit integrator
    b["seg_off"][:] = -1.0
    b["seg_rod"][:] = -1
    b["excluded"][:] = 1
    segs, nodes = [], []
    for i, rod in enumerate(rods):
        n0, e0, v0 = int(b["node0"][i]), int(b["elem0"][i]), int(b["vor0"][i])
        n = slice(n0, n0 + nn[i])
        e = slice(e0, e0 + ne[i])
        v = slice(v0, v0 + nv[i])
        write_material(b, rod, i)
        b["node_radius"][n] = rod.node_radius
        b["rest_len"][e] = rod.rest_lengths
        b["rest_sigma"][e] = rod.rest_sigma
        b["rest_vor"][v] = rod.rest_voronoi_lengths
        b["rest_kappa"][v] = rod.rest_kappa
        _segments(b, rod, i, n0, e0)
        segs.extend(range(e0, e0 + ne[i]))
        nodes.extend(range(n0, n0 + nn[i]))
        # Move the state in, then make the rod's arrays views of the buffers.
        for name, field, sl in _rod_views(n, e):
            b[field][sl] = getattr(rod, name)
        bind_rod(b, rod, i)
    b["segs"][:] = segs
    b["nodes"][:] = nodes
    return b


def write_material(b: Packed, rod, i: int) -> None:
    """Rod ``i``'s masses, inertia and stiffness into ``b`` (at packing, and when
    :meth:`Rod.set_material` changes them in place)."""
    n0, e0, v0 = int(b["node0"][i]), int(b["elem0"][i]), int(b["vor0"][i])
    nn, ne = rod.masses.shape[0], rod.rest_lengths.shape[0]
    b["mass"][n0:n0 + nn] = rod.masses
    # Floor of the automatic contact stiffness (N/m): a fraction of the adjacent elements'
    # axial stiffness, so a stiff rod pressing on a plane does not sink into it.
    axial = rod._shear_matrix[:, 2] / rod.rest_lengths
    kmin = np.zeros(nn)
    kmin[:ne] = axial
    kmin[1:] = np.maximum(kmin[1:], axial[: nn - 1])
    b["node_kmin"][n0:n0 + nn] = CONTACT_STIFFNESS_FLOOR * kmin
    b["J"][e0:e0 + ne] = rod._inertia
    b["inv_J"][e0:e0 + ne] = 1.0 / rod._inertia
    b["S"][e0:e0 + ne] = rod._shear_matrix
    b["B"][v0:v0 + rod._bend_matrix.shape[0]] = rod._bend_matrix


def _rod_views(n: slice, e: slice) -> tuple:
    return (("_positions", "pos", n), ("_velocities", "vel", n), ("_external_forces", "fext", n),
            ("_directors", "Q", e), ("_angular_velocities", "omega", e),
            ("_external_torques", "text", e))


def bind_rod(b: Packed, rod, i: int) -> None:
    """Make rod ``i``'s state arrays (and rest curvature and stretch) views of ``b``."""
    n0, e0, v0 = int(b["node0"][i]), int(b["elem0"][i]), int(b["vor0"][i])
    for name, field, sl in _rod_views(slice(n0, n0 + rod.n_nodes), slice(e0, e0 + rod.n_elements)):
        setattr(rod, name, b[field][sl])
    # Parameters stay shared too, so edits of rest shape after packing take effect.
    rod.rest_kappa = b["rest_kappa"][v0:v0 + rod.rest_voronoi_lengths.shape[0]]
    rod.rest_sigma = b["rest_sigma"][e0:e0 + rod.n_elements]


def set_damping(b: Packed, rods: Sequence, dt: float) -> None:
    """Per-rod damping of every rod (see ``write_damping``)."""
    for i, rod in enumerate(rods):
        write_damping(b, rod, i, dt)


def write_damping(b: Packed, rod, i: int, dt: float) -> None:
    """Rod ``i``'s damping: the explicit step's decay factor, the rate and retardation time."""
    b["decay"][i] = math.exp(-rod.damping * dt)
    b["nu"][i] = rod.damping
    b["tau"][i] = rod.internal_damping


def _segments(b: Packed, rod, i: int, n0: int, e0: int) -> None:
    """Capsule segments of rod ``i`` for rod-rod contact."""
    ne = rod.n_elements
    k = np.arange(ne)
    e = e0 + k
    b["seg_a"][e] = n0 + k
    b["seg_b"][e] = np.where(k + 1 < rod.n_nodes, n0 + k + 1, n0)
    b["seg_rod"][e] = i
    b["seg_k"][e] = k
    b["seg_ne"][e] = ne
    b["seg_closed"][e] = int(rod.closed)
    radius = np.maximum(rod.node_radius[k], rod.node_radius[(k + 1) % rod.n_nodes])
    b["seg_radius"][e] = radius
    # Pairs closer along the rod than a half turn of the tightest fold are left out: they
    # overlap in the straight rest shape when the radius exceeds the element.
    b["excluded"][e] = 1 + int(math.floor(math.pi * radius.max() / rod.rest_lengths.min()))
