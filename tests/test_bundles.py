"""The kernels' bundles carve exactly the arrays Python sees (same memory, same shapes)."""

from __future__ import annotations

import numpy as np
import trimesh
from numba import literal_unroll, njit

import deformx as dx
from deformx.engine.kernels.bundles import GROUPS, carve_cols, carve_env, carve_rods


@njit
def _addresses(RF, RI, RF3, EF, EI, CF, CI):
    """(data address, size) of every carved field, in bundle order."""
    out = []
    st, md, ct, wk = carve_rods(RF, RI, RF3)
    for a in literal_unroll(st):
        out.append((a.ctypes.data, a.size))
    for a in literal_unroll(md):
        out.append((a.ctypes.data, a.size))
    for a in literal_unroll(ct):
        out.append((a.ctypes.data, a.size))
    for a in literal_unroll(wk):
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
    want = [(p[name].ctypes.data, p[name].size) for p, group in zip(packs, ("rods", "env", "cols"))
            for name, _, _ in GROUPS[group]]
    assert len(got) == len(want)
    for (name, _, _), g, w in zip([f for grp in ("rods", "env", "cols") for f in GROUPS[grp]],
                                  got, want):
        assert g == w, name
    # Field shapes follow the spec (a wrong dimension count would not compile above).
    assert world.arrays["Q"].shape == (world.arrays["elem0"][-1] + 8, 3, 3)
    assert np.shares_memory(world.rods[0].positions, world._rods_p.F3)
