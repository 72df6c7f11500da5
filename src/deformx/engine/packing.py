"""Allocation of the flat buffers that hold a world's arrays (see ``kernels/bundles.py``)."""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from .kernels.bundles import GROUPS, STATE_FIELDS

_HEAD = 5  # layout row: offset, then up to four dimensions


class Packed:
    """One group's float and int buffers and a numpy view per field (``packed["pos"]``).

    Fields are laid out in their spec order, so the first ``STATE_FIELDS[group]`` of them (the
    state) are a prefix of each buffer: :meth:`state` copies exactly those.
    """

    def __init__(self, group: str, dims: Mapping[str, int]) -> None:
        spec = GROUPS[group]
        self.group = group
        shapes = [tuple(int(dims[d]) if isinstance(d, str) else d for d in shape)
                  for _, _, shape in spec]
        header = 1 + _HEAD * len(spec)
        layout = np.zeros((len(spec), _HEAD), dtype=np.int64)
        n_f, n_i = 0, header
        self._state_end = [0, header]
        for k, ((name, kind, _), shape) in enumerate(zip(spec, shapes)):
            size = int(np.prod(shape))
            layout[k, 1:1 + len(shape)] = shape
            if kind == "f":
                layout[k, 0] = n_f
                n_f += size
            else:
                layout[k, 0] = n_i
                n_i += size
            if k + 1 == STATE_FIELDS[group]:
                self._state_end = [n_f, n_i]
        self.F = np.zeros(n_f)
        self.I = np.zeros(n_i, dtype=np.int64)
        self.I[0] = len(spec)
        self.I[1:header] = layout.ravel()
        self.fields: dict[str, np.ndarray] = {}
        for k, ((name, kind, _), shape) in enumerate(zip(spec, shapes)):
            buf = self.F if kind == "f" else self.I
            o = int(layout[k, 0])
            self.fields[name] = buf[o:o + int(np.prod(shape))].reshape(shape)
        self.shapes = dict(zip((s[0] for s in spec), shapes))

    def __getitem__(self, name: str) -> np.ndarray:
        return self.fields[name]

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """Copies of the state prefix of the float and int buffers."""
        f, i = self._state_end
        return self.F[:f].copy(), self.I[1 + _HEAD * len(GROUPS[self.group]):i].copy()

    def set_state(self, state: Sequence[np.ndarray]) -> None:
        f, i = self._state_end
        head = 1 + _HEAD * len(GROUPS[self.group])
        sf, si = state
        if sf.shape != (f,) or si.shape != (i - head,):
            raise ValueError("state: it was taken from a world of another size (rods, "
                             "colliders or clamps differ)")
        self.F[:f] = sf
        self.I[head:i] = si

    def state_names(self) -> list[str]:
        return [s[0] for s in GROUPS[self.group][:STATE_FIELDS[self.group]]]
