"""Snapshots of a world's state: everything the next step depends on, as plain numpy arrays.

A :class:`WorldState` holds the state prefixes of the world's buffers (see ``packing.py``:
positions, velocities, frames, angular velocities, the stable integrator's memory, friction
anchors and contact sets, mesh query caches, the rod-rod pair list), the driver table and the
time. It pickles, and restoring it makes the continuation bit-identical.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np



@dataclass
class WorldState:
    """A copy of a world's state (see :meth:`deformx.World.get_state`)."""

    time: float
    rods: tuple[np.ndarray, np.ndarray]
    cols: tuple[np.ndarray, np.ndarray] | None
    drivers: np.ndarray
    pairs: np.ndarray


# Symbolic dimensions that run over query slots (see kernels/bundles.py); an array sized 0
# along one (unused in that world) slices to empty pieces.
SLOT_AXES = ("Q", "QM", "QA")


def rod_slices(packed_rods, r: int, rod) -> dict[str, slice]:
    """Index ranges of rod ``r`` along each symbolic dimension of the state fields."""
    n0 = int(packed_rods["node0"][r])
    e0 = int(packed_rods["elem0"][r])
    n_nodes = packed_rods["pos"].shape[0]
    return {"N": slice(n0, n0 + rod.n_nodes), "E": slice(e0, e0 + rod.n_elements),
            "R": slice(r, r + 1), "Qn": slice(n0, n0 + rod.n_nodes),
            "Qe": slice(n_nodes + e0, n_nodes + e0 + rod.n_elements)}


def take_rod(packed, sl: dict[str, slice]) -> dict[str, np.ndarray]:
    """Copies of one rod's rows of a group's state fields (whole-world fields, such as the
    rod-rod pair list, are left out)."""
    out = {}
    for name in packed.state_fields():
        axis, arr = packed.axes[name], packed[name]
        if axis in SLOT_AXES:  # query slots: the rod's nodes, then its elements
            out[name] = np.concatenate([arr[sl["Qn"]], arr[sl["Qe"]]])
        elif axis in sl:
            out[name] = arr[sl[axis]].copy()
    return out


def put_rod(packed, sl: dict[str, slice], values: dict[str, np.ndarray]) -> None:
    for name in packed.state_fields():
        if name not in values:
            continue
        axis, arr = packed.axes[name], packed[name]
        if axis in SLOT_AXES:
            nq = sl["Qn"].stop - sl["Qn"].start
            arr[sl["Qn"]] = values[name][:nq]
            arr[sl["Qe"]] = values[name][nq:]
        else:
            arr[sl[axis]] = values[name]
