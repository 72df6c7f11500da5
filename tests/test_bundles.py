"""The kernels' bundles carve exactly the arrays Python sees (same memory, same shapes)."""

from __future__ import annotations

import numpy as np
import trimesh
from numba import literal_unroll, njit

import deformx as dx
from deformx.engine.kernels.bundles import GROUPS, carve_cols, carve_env, carve_rods


@njit
def _addresses(RF, RI, EF, EI, CF, CI):
    """(data address, size) of every carved array, in bundle order."""
    out = []
    for a in literal_unroll(carve_rods(RF, RI)):
        out.append((a.ctypes.data, a.size))
    for a in literal_unroll(carve_env(EF, EI)):
        out.append((a.ctypes.data, a.size))
    for a in literal_unroll(carve_cols(CF, CI)):
        out.append((a.ctypes.data, a.size))
    return out


def test_carved_fields_are_the_python_views():
    world = dx.World(dt=1e-3, integrator="stable")
    world.add_plane()
    world.add_mesh(trimesh.creation.box(extents=(0.1, 0.1, 0.1)))
    for k in range(2):
        rod = world.add_rod(dx.Rod.straight(7 + k, start=(0, 0.1 * k, 0.2), length=0.2))
        rod.fix_start()
    world.step()
    got = _addresses(*world._bufs)
    packs = (world._rods_p, world._env, world._cols_p)
    names = [spec[0] for grp in ("rods", "env", "cols") for spec in GROUPS[grp]]
    want = [(p.arrays[spec[0]].ctypes.data, p.arrays[spec[0]].size)
            for p, grp in zip(packs, ("rods", "env", "cols")) for spec in GROUPS[grp]]
    assert len(got) == len(want)
    for name, g, w in zip(names, got, want):
        assert g == w, name
    # Named fields are rows of the stacked arrays, and the rods' arrays views of them.
    assert world.arrays["Q"].shape == (world.arrays["elem0"][-1] + 8, 3, 3)
    assert np.shares_memory(world.rods[0].positions, world._rods_p.arrays["n3"])
    assert np.shares_memory(world.rods[1].directors, world._rods_p.arrays["e33"])
