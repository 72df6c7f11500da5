"""Allocation of the flat buffers that hold a world's arrays (see ``kernels/bundles.py``)."""

from __future__ import annotations

import math
from typing import Mapping, Sequence

import numpy as np

from .kernels.bundles import GROUPS

_HEAD = 5  # layout row: offset, then up to four dimensions


# A world packs its groups on the first step after any change (a new world: every group):
# the layouts and carving plans are kept per group and size, which halves that cost.
_LAYOUTS: dict[tuple, tuple[np.ndarray, int, int]] = {}
_CARVINGS: dict[tuple, tuple] = {}
_CACHE_SIZE = 256


def _layout(group: str, dims: Mapping[str, int]) -> tuple[np.ndarray, int, int]:
    """(head of ``I``: count and per array offset and dimensions; float and int buffer sizes)
    of ``group`` at the sizes ``dims``."""
    key = (group, tuple(sorted((k, int(v)) for k, v in dims.items())))
    got = _LAYOUTS.get(key)
    if got is None:
        spec = GROUPS[group]
        header = 1 + _HEAD * len(spec)
        layout = np.zeros((len(spec), _HEAD), dtype=np.int64)
        size = {"f": 0, "i": header}
        for k, (_, kind, shape, _, _) in enumerate(spec):
            shape = tuple(int(dims[d]) if isinstance(d, str) else d for d in shape)
            layout[k, 0] = size[kind]
            layout[k, 1:1 + len(shape)] = shape
            size[kind] += math.prod(shape)
        head = np.concatenate(([len(spec)], layout.ravel())).astype(np.int64)
        if len(_LAYOUTS) >= _CACHE_SIZE:
            _LAYOUTS.clear()
        got = _LAYOUTS[key] = (head, size["f"], size["i"])
    return got


def _carving(group: str, I: np.ndarray) -> tuple:
    """Per array of ``group``: (name, kind, symbols, rows, state rows, offset, shape, size), from
    the layout at the head of ``I``."""
    spec = GROUPS[group]
    head = I[:1 + _HEAD * len(spec)]
    key = (group, head.tobytes())
    got = _CARVINGS.get(key)
    if got is None:
        layout = head[1:].reshape(len(spec), _HEAD)
        plan = []
        for k, (name, kind, sym, rows, n_state) in enumerate(spec):
            shape = tuple(int(d) for d in layout[k, 1:1 + len(sym)])
            plan.append((name, kind, sym, rows, n_state, int(layout[k, 0]), shape,
                         math.prod(shape)))
        if len(_CARVINGS) >= _CACHE_SIZE:
            _CARVINGS.clear()
        got = _CARVINGS[key] = tuple(plan)
    return got


class Packed:
    """One group's float and int buffers, a numpy view per array (``packed.arrays``) and per
    named field (``packed["pos"]``: a row of a stacked array, or a whole array).

    The int buffer starts with the layout (per array: offset, then up to four dimensions),
    which the kernels read to carve the buffers. The state of a group (see ``GROUPS``) is the
    first rows of its stacked arrays and the whole of its state arrays: :meth:`state` copies
    exactly those.
    """

    def __init__(self, group: str, dims: Mapping[str, int]) -> None:
        self.group = group
        head, n_f, n_i = _layout(group, dims)
        self.F = np.zeros(n_f)
        self.I = np.zeros(n_i, dtype=np.int64)
        self.I[:head.shape[0]] = head
        self._carve()

    def _carve(self) -> None:
        """The views of every array and field, from the layout at the head of ``I``."""
        self.arrays: dict[str, np.ndarray] = {}
        self.fields: dict[str, np.ndarray] = {}
        self.axes: dict[str, str | int] = {}  # a field's first (per-item) dimension
        self._state: list[np.ndarray] = []
        self._state_names: list[str] = []
        for name, kind, sym, rows, n_state, o, shape, size in _carving(self.group, self.I):
            arr = (self.F if kind == "f" else self.I)[o:o + size].reshape(shape)
            self.arrays[name] = arr
            if rows is None:
                self.fields[name] = arr
                self.axes[name] = sym[0]
                if n_state:
                    self._state.append(arr)
                    self._state_names.append(name)
            else:
                for j, row in enumerate(rows):
                    self.fields[row] = arr[j]
                    self.axes[row] = sym[1]
                    if j < n_state:
                        self._state.append(self.fields[row])
                        self._state_names.append(row)

    # Copies and pickles hold the two buffers only; the views are carved again from them
    # (a deep copy of the views would give arrays no longer backed by the buffers).
    def __getstate__(self) -> dict:
        return {"group": self.group, "F": self.F, "I": self.I}

    def __setstate__(self, state: dict) -> None:
        self.group, self.F, self.I = state["group"], state["F"], state["I"]
        self._carve()

    def __getitem__(self, name: str) -> np.ndarray:
        return self.fields[name]

    def state_fields(self) -> list[str]:
        """Names of the state fields, in snapshot order."""
        return list(self._state_names)

    def state(self) -> tuple[np.ndarray, ...]:
        """Copies of the group's state."""
        return tuple(a.copy() for a in self._state)

    def set_state(self, state: Sequence[np.ndarray]) -> None:
        if len(state) != len(self._state) or any(
                np.shape(s) != a.shape for s, a in zip(state, self._state)):
            raise ValueError("state: it was taken from a world of another size (rods, "
                             "colliders or clamps differ)")
        for s, a in zip(state, self._state):
            a[...] = s
