"""world.run(duration, callbacks=...) calls each callback at its simulated times."""

from __future__ import annotations

import numpy as np
import pytest

import deformx as dx


class Probe:
    def __init__(self, every: float) -> None:
        self.every = every
        self.times: list[float] = []

    def __call__(self, world: dx.World) -> None:
        self.times.append(world.time)


def _world():
    world = dx.World(dt=1e-3, integrator="stable")
    world.add_rod(dx.Rod.straight(10, start=(0, 0, 0.5), length=0.3, radius=0.005))
    return world


def test_callbacks_fire_at_the_requested_simulated_times():
    world = _world()
    a, b = Probe(0.013), Probe(0.05)
    world.run(0.2, callbacks=[a, b])
    assert world.time == pytest.approx(0.2, abs=1e-12)
    assert np.allclose(a.times, 0.013 * np.arange(16), atol=1e-12)  # 0 .. 0.195
    assert np.allclose(b.times, 0.05 * np.arange(5), atol=1e-12)  # 0 .. 0.2


def test_a_recorder_is_a_callback_and_recorder_keyword_still_works():
    world = _world()
    rec = dx.Recorder(world, every=0.02)
    world.run(0.1, callbacks=[rec])
    world.run(0.1, recorder=rec)  # continues without repeating the sample at t = 0.1
    assert np.allclose(rec.times, 0.02 * np.arange(11), atol=1e-12)
    assert rec.arrays()["rod0_positions"].shape == (11, 11, 3)


def test_a_callback_without_every_is_refused():
    with pytest.raises(ValueError, match="every"):
        _world().run(0.1, callbacks=[lambda w: None])
