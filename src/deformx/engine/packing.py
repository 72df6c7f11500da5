"""Allocation of the flat buffers that hold a world's arrays (see ``kernels/bundles.py``)."""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from .kernels.bundles import GROUPS, STATE_FIELDS

_HEAD = 5  # layout row: offset, then up to four dimensions


class Packed:
    """One group's buffers and a numpy view per field (``packed["pos"]``).

    Each group has a float and an int buffer holding its fields one after another (the int
    buffer starts with the layout: per field its offset and up to four dimensions); the
    ``rods`` group also keeps its (n, 3) float fields as rows of a third, (rows, 3) buffer, so
    that the kernels get them by slicing rather than reshaping (~7x cheaper on every call).
    Fields are laid out in spec order, so the first ``STATE_FIELDS[group]`` of them (the state)
    are a prefix of every buffer: :meth:`state` copies exactly those.
    """

    def __init__(self, group: str, dims: Mapping[str, int]) -> None:
        spec = GROUPS[group]
        self.group = group
        shapes = [tuple(int(dims[d]) if isinstance(d, str) else d for d in shape)
                  for _, _, shape in spec]
        rows3 = group == "rods"
        self._head = [0, 1 + _HEAD * len(spec), 0]
        layout = np.zeros((len(spec), _HEAD), dtype=np.int64)
        where, size = [], list(self._head)
        self._state_end = list(self._head)
        for k, ((name, kind, _), shape) in enumerate(zip(spec, shapes)):
            b = 2 if (rows3 and kind == "f" and shape[1:] == (3,)) else (0 if kind == "f" else 1)
            n = shape[0] if b == 2 else int(np.prod(shape))
            layout[k, 0] = size[b]
            layout[k, 1:1 + len(shape)] = shape
            where.append((b, size[b], n))
            size[b] += n
            if k + 1 == STATE_FIELDS[group]:
                self._state_end = list(size)
        self.buffers = (np.zeros(size[0]), np.zeros(size[1], dtype=np.int64),
                        np.zeros((size[2], 3)))
        self.buffers[1][0] = len(spec)
        self.buffers[1][1:self._head[1]] = layout.ravel()
        self.fields: dict[str, np.ndarray] = {}
        for (name, _, _), shape, (b, o, n) in zip(spec, shapes, where):
            self.fields[name] = self.buffers[b][o:o + n].reshape(shape)
        self.shapes = dict(zip((s[0] for s in spec), shapes))

    @property
    def F(self) -> np.ndarray:
        """The float buffer."""
        return self.buffers[0]

    @property
    def I(self) -> np.ndarray:  # noqa: E743 (the int buffer)
        """The int buffer (layout first)."""
        return self.buffers[1]

    @property
    def F3(self) -> np.ndarray:
        """The (rows, 3) float buffer (rods group; empty for the others)."""
        return self.buffers[2]

    def __getitem__(self, name: str) -> np.ndarray:
        return self.fields[name]

    def state(self) -> tuple[np.ndarray, ...]:
        """Copies of the state prefix of every buffer."""
        return tuple(buf[h:e].copy() for buf, h, e in zip(self.buffers, self._head,
                                                          self._state_end))

    def set_state(self, state: Sequence[np.ndarray]) -> None:
        parts = list(zip(self.buffers, self._head, self._state_end))
        if len(state) != len(parts) or any(
                np.shape(s) != buf[h:e].shape for s, (buf, h, e) in zip(state, parts)):
            raise ValueError("state: it was taken from a world of another size (rods, "
                             "colliders or clamps differ)")
        for s, (buf, h, e) in zip(state, parts):
            buf[h:e] = s
