"""The environment and collider buffer groups of a world, and the kernels' run options."""

from __future__ import annotations

from typing import Sequence

import numpy as np

from .contact import colliders as col
from .kernels.bundles import OPT_ITER, OPT_LEN, OPT_LOAD, OPT_R0, OPT_R1, OPT_STORE
from .packing import Packed


def env_group(rods: Sequence, rods_p: Packed, planes: Sequence[np.ndarray],
              n_drivers: int) -> Packed:
    """Clamp tables (node / element and driver of each, per rod), planes and the drivers'
    per-rod copies and reactions."""
    pn, fe, off, rel = [], [], [], []
    rod_pcon, rod_fcon = [0], [0]
    for i, rod in enumerate(rods):
        n0, e0 = int(rods_p["node0"][i]), int(rods_p["elem0"][i])
        for c in rod.clamps:
            if c.holds_position:
                pn.append((n0 + c.node, c._driver))
                off.append(c.offset)
            if c.element is not None:
                fe.append((e0 + c.element, c._driver))
                rel.append(c.relative)
        rod_pcon.append(len(pn))
        rod_fcon.append(len(fe))
    R = len(rods)
    env = Packed("env", dict(R=R, R1=R + 1, P=len(pn), F=len(fe), L=len(planes), D=n_drivers))
    env["rod_pcon"][:] = rod_pcon
    env["rod_fcon"][:] = rod_fcon
    if pn:
        env["pcon_node"][:], env["pcon_drv"][:] = np.array(pn).T
        env["pcon_off"][:] = np.array(off)
    if fe:
        env["fcon_elem"][:], env["fcon_drv"][:] = np.array(fe).T
        env["fcon_rel"][:] = np.array(rel)
    if planes:
        env["planes"][:] = np.array(planes)
    return env


def cols_group(colliders: Sequence, ignored: set[tuple[int, int]], rods_p: Packed,
               old: Packed | None, empty: bool = False) -> Packed | None:
    """The colliders' tables (without colliders: None, or empty tables if ``empty``);
    friction anchors and query caches carry over from ``old`` when rods and colliders are the
    same."""
    if not colliders and not empty:
        return None
    R = rods_p["node0"].shape[0]
    N, E = rods_p["pos"].shape[0], rods_p["Q"].shape[0]
    allowed = np.ones((R, len(colliders)), dtype=np.int64)
    for r, c in ignored:
        allowed[r, c] = 0
    packed = col.pack(colliders, R, N, N + E, allowed)
    packed["drv"][:] = [c._driver for c in colliders]
    if old is not None:  # fields of another size (rods, or the first mesh, added) start afresh
        for name in packed.state_fields():
            if old[name].shape == packed[name].shape:
                packed[name][...] = old[name]
    return packed


def run_options(groups: Sequence[tuple[int, int]], iterations: int) -> list[np.ndarray]:
    """One ``opts`` array per range of rods a call advances (see ``kernels/bundles.py``)."""
    out = []
    for r0, r1 in groups:
        opts = np.zeros(OPT_LEN, dtype=np.int64)
        opts[OPT_ITER] = iterations
        opts[OPT_LOAD] = 1
        opts[OPT_STORE] = int(len(groups) == 1)
        opts[OPT_R0], opts[OPT_R1] = r0, r1
        out.append(opts)
    return out
