"""Friction's slope along the slip in the stable integrator's Newton matrix (the secant method).

The friction force saturates as mu N tanh(|s| / delta) along the slip s; its stiffness along
the slip is taken as the chord between the last iterate's slip and this one's, which tends to
the exact tangent as the iterates converge, bounded by the secant |f_t| / |s| above and a
fraction of it below. These check the slope against the closed forms of tanh.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from deformx.engine.contact.speculative import (
    SLIP_COS, SLIP_LINEAR, SLOPE_FLOOR, SP_COLS_F, SP_KP, SP_SP, _slip_slope,
)

KT, DELTA = 2.0e4, 1.0e-6  # N/m at zero slip, m


def _fresh():
    sp_f = np.zeros((1, 2, SP_COLS_F))
    sp_f[0, 0, SP_KP] = -1.0  # as at a step's start
    return sp_f


def _slope(sp_f, s, chord=True):
    s = np.asarray(s, float)
    smag = float(np.linalg.norm(s))
    y = smag / DELTA
    th = math.tanh(y)
    kb = KT * th / y
    return _slip_slope(sp_f, 0, 0, s[0], s[1], s[2], smag, DELTA, th, KT, kb, chord), kb


def test_first_evaluation_of_a_step_takes_the_secant_and_keeps_the_slip():
    sp_f = _fresh()
    ka, kb = _slope(sp_f, (1.5e-6, 0.0, 0.0))
    assert ka == kb
    assert sp_f[0, 0, SP_KP] == ka
    np.testing.assert_array_equal(sp_f[0, 0, SP_SP:SP_SP + 3], (1.5e-6, 0.0, 0.0))


@pytest.mark.parametrize("y_prev, y", [(2.5, 2.0), (1.0, 1.2), (0.5, 0.8)])
def test_chord_between_two_iterates_is_that_of_tanh(y_prev, y):
    sp_f = _fresh()
    _slope(sp_f, (y_prev * DELTA, 0.0, 0.0))
    ka, kb = _slope(sp_f, (y * DELTA, 0.0, 0.0))
    chord = KT * (math.tanh(y) - math.tanh(y_prev)) / (y - y_prev)
    tangent = KT * (1.0 - math.tanh(y) ** 2)
    assert ka == pytest.approx(min(kb, max(chord, tangent, SLOPE_FLOOR * kb)), rel=1e-12)
    assert tangent <= ka <= kb


def test_chord_tends_to_the_tangent_as_the_iterates_converge():
    y = 1.5
    tangent = KT * (1.0 - math.tanh(y) ** 2)
    errors = []
    for gap in (1e-2, 1e-3, 1e-4):
        sp_f = _fresh()
        _slope(sp_f, ((y - gap) * DELTA, 0.0, 0.0))  # from below: the chord is steeper
        ka, _ = _slope(sp_f, (y * DELTA, 0.0, 0.0))
        errors.append(abs(ka - tangent))
    # first order in the gap: tanh'' / 2 times it
    for coarse, fine in zip(errors, errors[1:]):
        assert fine / coarse == pytest.approx(0.1, rel=0.05)


def test_the_same_iterate_again_keeps_its_slope():
    sp_f = _fresh()
    _slope(sp_f, (2.5e-6, 0.0, 0.0))
    first, _ = _slope(sp_f, (2.0e-6, 1e-8, 0.0))
    again, kb = _slope(sp_f, (2.0e-6, 1e-8, 0.0))
    assert again == first < kb


def test_secant_where_the_slip_turns_or_the_chord_is_off_and_floor_when_saturated():
    sp_f = _fresh()
    _slope(sp_f, (2.0e-6, 0.0, 0.0))
    turned = (2.0e-6, 0.5e-6, 0.0)  # 14 degrees away
    assert 2.0 / math.hypot(2.0, 0.5) < SLIP_COS
    ka, kb = _slope(sp_f, turned)
    assert ka == kb
    sp_f = _fresh()
    _slope(sp_f, (2.5e-6, 0.0, 0.0))
    ka, kb = _slope(sp_f, (2.0e-6, 0.0, 0.0), chord=False)
    assert ka == kb
    sp_f = _fresh()  # where tanh is still ~linear its slopes differ by little: the secant
    _slope(sp_f, (0.8 * SLIP_LINEAR * DELTA, 0.0, 0.0))
    ka, kb = _slope(sp_f, (0.6 * SLIP_LINEAR * DELTA, 0.0, 0.0))
    assert ka == kb
    sp_f = _fresh()  # deep in saturation the chord is ~0: the floor holds Newton back
    _slope(sp_f, (6.0e-6, 0.0, 0.0))
    ka, kb = _slope(sp_f, (5.0e-6, 0.0, 0.0))
    assert ka == pytest.approx(SLOPE_FLOOR * kb, rel=1e-12)
