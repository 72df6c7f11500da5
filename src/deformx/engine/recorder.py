"""Recorder: samples rod positions and directors at a fixed rate and writes them to ``.npz``."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from . import validation as check

if TYPE_CHECKING:
    from .world import World


class Recorder:
    """Stores ``time``, ``rod{i}_positions`` (T, n+1, 3) and ``rod{i}_directors`` (T, n, 3, 3)
    every ``every`` seconds of simulated time while ``world.run(..., recorder=rec)`` (or
    ``callbacks=[rec]``) runs: a callback like any other."""

    def __init__(self, world: "World", every: float = 0.01, directors: bool = True) -> None:
        self.world = world
        self.every = check.positive("every", every, "s")
        self.directors = directors
        self.times: list[float] = []
        self._positions: list[list[np.ndarray]] = []
        self._directors: list[list[np.ndarray]] = []

    def due(self) -> bool:
        """True when at least ``every`` s have passed since the last sample."""
        return not self.times or self.world.time - self.times[-1] >= self.every - 0.5 * self.world.dt

    def __call__(self, world: "World") -> None:
        self.sample()

    def sample(self) -> None:
        """Store the current state now."""
        self.times.append(self.world.time)
        self._positions.append([r.positions.copy() for r in self.world.rods])
        if self.directors:
            self._directors.append([r.directors.copy() for r in self.world.rods])

    def arrays(self) -> dict[str, np.ndarray]:
        """The recording as arrays keyed like the ``.npz`` file."""
        out = {"time": np.array(self.times)}
        for i in range(len(self.world.rods)):
            out[f"rod{i}_positions"] = np.array([p[i] for p in self._positions])
            if self.directors:
                out[f"rod{i}_directors"] = np.array([d[i] for d in self._directors])
        return out

    def save(self, path: str | Path) -> Path:
        """Write the recording to ``path`` (.npz, compressed); returns the path."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(path, **self.arrays())
        return path
