"""The electrohydraulic plant's end stops: the lower one, and leaving a stop again.

``_constrain`` (docstring of :mod:`blockid._kernels.electrohydraulic`) clips the piston
to ``[0, stroke]`` and zeroes a velocity that pushes into a stop (inelastic stops).
The upper stop is tested in ``test_electrohydraulic.py``; here the arm is retracted
into the lower stop (h = 0) and then driven out of it.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from blockid.plants.electrohydraulic import ElectrohydraulicParameters, simulate_electrohydraulic

P = ElectrohydraulicParameters()


@pytest.fixture(scope="module")
def retract_then_extend():
    """-1 A for 10 s (retracting into the lower stop), then +1 A for 3 s; noise-free."""
    current = np.concatenate([np.full(200, -1.0), np.full(60, 1.0)])
    par = dataclasses.replace(P, initial_position=0.3)
    return simulate_electrohydraulic(current, params=par, noise=False)


def test_position_stays_exactly_at_the_lower_stop(retract_then_extend):
    df = retract_then_extend
    h = df["h"].to_numpy()
    assert h.min() == 0.0  # never below the stop
    at_stop = np.flatnonzero(h == 0.0)
    assert at_stop.size > 100  # it arrives within the first 2 s and stays
    # once there it stays, sample after sample, until the current reverses
    assert np.array_equal(at_stop, np.arange(at_stop[0], at_stop[-1] + 1))
    assert at_stop[0] < 60 and at_stop[-1] >= 200


def test_velocity_is_zero_at_the_lower_stop(retract_then_extend):
    df = retract_then_extend
    at_stop = df["h"].to_numpy() == 0.0
    assert np.all(df["hdot"].to_numpy()[at_stop] == 0.0)
    # the measured (noise-free) angular velocity is the central difference of equal
    # angles inside the run at the stop: exactly zero
    inside = np.flatnonzero(at_stop)[1:-1]
    assert np.all(df["velocity"].to_numpy()[inside] == 0.0)
    assert np.all(df["angle"].to_numpy()[at_stop] == df["angle"].to_numpy()[inside[0]])
    # it was moving down before it got there
    first = np.flatnonzero(at_stop)[0]
    assert df["hdot"].iloc[first - 1] < -0.01


def test_the_stop_is_not_sticky_and_pressures_stay_in_range(retract_then_extend):
    df = retract_then_extend
    h = df["h"].to_numpy()
    assert h[-1] > 0.3  # extended out of the stop after the current reversed
    assert np.all(np.diff(h[-40:]) > 0.0)
    for col in ("p1", "p2"):
        assert df[col].min() >= P.min_pressure
        assert df[col].max() <= 1.1 * P.supply_pressure
