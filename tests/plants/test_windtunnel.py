"""Simulated wind tunnel of paper A: exact S1/S2 equations, flow field, experiments."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import brentq

from blockid.blocks.backlash import Backlash
from blockid.errors import DataError, ParameterError
from blockid.plants.windtunnel import (
    CONDITIONS,
    WindTunnelParameters,
    _mach_per_log_pressure_ratio,
    _throat_mach_sensitivity,
    flow_field_arx,
    operating_point_commands,
    simulate_windtunnel,
    windtunnel_experiment,
)

COLUMNS = ["t", "u1", "u2", "v1", "v2", "y1", "y2", "x_true"]


@pytest.fixture(scope="module")
def clean_110():
    return windtunnel_experiment("110kPa", seed=3, noise=False)


def lagged(signal, lag, start):
    return signal[start - lag : signal.size - lag]


def test_frame_layout(clean_110):
    assert list(clean_110.columns) == COLUMNS
    assert len(clean_110) == 1200
    np.testing.assert_allclose(np.diff(clean_110["t"]), 0.05)
    attrs = clean_110.attrs
    assert (attrs["condition"], attrs["kind"], attrs["seed"]) == ("110kPa", "estimation", 3)
    assert (attrs["p0_op"], attrs["mach_op"], attrs["dt"]) == (110.0, 0.578, 0.05)


def test_exhaust_valve_follows_a1_exactly(clean_110):
    u1, v1 = clean_110["u1"].to_numpy(), clean_110["v1"].to_numpy()
    # Least-squares refit of v1(t) = b1 u1(t-1) - a1 v1(t-1), no intercept.
    regressors = np.column_stack([lagged(u1, 1, 1), -lagged(v1, 1, 1)])
    (b1, a1), *_ = np.linalg.lstsq(regressors, v1[1:], rcond=None)
    assert b1 == pytest.approx(0.39, abs=1e-8)
    assert a1 == pytest.approx(-0.62, abs=1e-8)
    # The record starts at rest: v1(0) is the steady state of u1(0).
    assert v1[0] == pytest.approx(0.39 / 0.38 * u1[0], rel=1e-12)


def test_choke_finger_is_backlash_then_a5_exactly(clean_110):
    u2 = clean_110["u2"].to_numpy()
    x = clean_110["x_true"].to_numpy()
    v2 = clean_110["v2"].to_numpy()
    # x is the paper's backlash driven by u2, from the middle of the dead band.
    x_rest = 0.5 * (0.9 * (u2[0] + 0.8) + 0.9 * (u2[0] - 0.85))
    np.testing.assert_array_equal(x, Backlash(0.9, 0.8, 0.9, 0.85).simulate(u2, x0=x_rest))
    # v2(t) = x(t-1) + 1.0 v2(t-1) - 0.17 v2(t-2)                            (A5)
    regressors = np.column_stack([lagged(x, 1, 2), -lagged(v2, 1, 2), -lagged(v2, 2, 2)])
    coef, *_ = np.linalg.lstsq(regressors, v2[2:], rcond=None)
    np.testing.assert_allclose(coef, [1.0, -1.0, 0.17], rtol=0, atol=1e-8)
    residual = v2[2:] - regressors @ np.array([1.0, -1.0, 0.17])
    assert np.abs(residual).max() < 1e-9


def test_dead_band_visible_in_a_reversal():
    p = WindTunnelParameters()
    u1_op, u2_op = operating_point_commands(p)
    hold = 120  # 6 s: v2 settles (slowest pole 0.78) to well below 1e-9 mm
    # Drive the finger up by 3, reverse by 1.5 (< cL + cR = 1.65), then by 1.8 (> 1.65),
    # then ramp up again by 0.3.
    levels = [u2_op, u2_op + 3.0, u2_op + 1.5, u2_op + 1.2]
    u2 = np.concatenate([np.full(hold, lv) for lv in levels])
    u2 = np.concatenate([u2, np.linspace(u2_op + 1.2, u2_op + 1.5, 20)])
    df = simulate_windtunnel(np.full(u2.size, u1_op), u2, params=p, noise=False)
    x, v2 = df["x_true"].to_numpy(), df["v2"].to_numpy()
    end = [hold * k - 1 for k in (1, 2, 3, 4)]  # last sample of each hold
    x_top = 0.9 * (u2_op + 3.0 - 0.85)
    assert x[end[1]] == pytest.approx(x_top)
    np.testing.assert_array_equal(x[end[1] + 1 : end[2] + 1], x_top)  # nothing moves
    assert v2[end[2]] == pytest.approx(v2[end[1]], abs=1e-9)
    np.testing.assert_allclose(x[end[2] + 1 : end[3] + 1], 0.9 * (u2_op + 1.2 + 0.8))
    # The position follows the 0.15 that went beyond the dead band, times the gain 0.9/0.17.
    assert v2[end[3]] - v2[end[2]] == pytest.approx(-0.15 * 0.9 / 0.17, rel=1e-6)
    np.testing.assert_array_equal(x[end[3] + 1 :], x[end[3]])  # rising again: held


def test_dead_band_visible_in_experiment(clean_110):
    du2 = np.diff(clean_110["u2"].to_numpy())
    dx = np.diff(clean_110["x_true"].to_numpy())
    assert np.all(du2 != 0.0)  # the dithered command moves at every sample ...
    assert np.mean(dx == 0.0) > 0.5  # ... but the backlash output mostly holds
    # Large reversals get through: x moves in both directions during the record.
    assert (dx > 0.1).sum() > 5 and (dx < -0.1).sum() > 5


@pytest.mark.parametrize("condition", CONDITIONS)
def test_steady_state_is_the_operating_point(condition):
    p = WindTunnelParameters.for_condition(condition)
    u1_op, u2_op = operating_point_commands(p)
    n = 400
    df = simulate_windtunnel(np.full(n, u1_op), np.full(n, u2_op), params=p, seed=1, noise=False)
    np.testing.assert_allclose(df["v1"], p.v1_op, rtol=1e-13)
    np.testing.assert_allclose(df["v2"], p.v2_op, rtol=1e-13)
    np.testing.assert_allclose(df["y1"], p.p0_op, rtol=0, atol=1e-10)
    np.testing.assert_allclose(df["y2"], p.mach_op, rtol=0, atol=1e-12)
    assert (
        p.p0_op == float(condition[:3]) and p.mach_op == {"110": 0.578, "130": 0.822}[condition[:3]]
    )


@pytest.mark.parametrize("condition", CONDITIONS)
def test_static_gains_of_the_flow_field(condition):
    p = dataclasses.replace(WindTunnelParameters.for_condition(condition), drift_amplitude=0.0)
    u1_op, u2_op = operating_point_commands(p)
    n = 2000  # 100 s: many times the slowest time constant (1.5 s)
    step = 5.0  # mm of valve position
    df = simulate_windtunnel(
        np.full(n, u1_op + step / p.valve_gain), np.full(n, u2_op), params=p, noise=False
    )
    assert df["v1"].iloc[-1] == pytest.approx(p.v1_op + step)
    assert df["y1"].iloc[-1] - p.p0_op == pytest.approx(p.gain_p0_v1 * step, rel=1e-9)
    assert df["y2"].iloc[-1] - p.mach_op == pytest.approx(p.gain_mach_v1 * step, rel=1e-9)


@pytest.mark.parametrize("condition", CONDITIONS)
def test_flow_field_is_an_exact_tito_arx_without_drift(condition):
    p = dataclasses.replace(WindTunnelParameters.for_condition(condition), drift_amplitude=0.0)
    df = windtunnel_experiment(params=p, seed=5, noise=False)
    dy = df[["y1", "y2"]].to_numpy() - [p.p0_op, p.mach_op]
    dv = df[["v1", "v2"]].to_numpy() - [p.v1_op, p.v2_op]
    arx = flow_field_arx(p)
    assert (arx["na"], arx["nb"], arx["nk"]) == (2, 2, 1)
    # Regressors [-y1(t-1), -y1(t-2), -y2(t-1), -y2(t-2), v1(t-1), v1(t-2), v2(t-1), v2(t-2)]
    cols = [-lagged(dy[:, j], k, 2) for j in range(2) for k in (1, 2)]
    cols += [lagged(dv[:, j], k, 2) for j in range(2) for k in (1, 2)]
    regressors = np.column_stack(cols)
    for i, out in enumerate(("y1", "y2")):
        theta = np.concatenate(
            [*arx["a"][out].values(), *arx["b"][out].values()]  # y1, y2 then v1, v2
        )
        residual = dy[2:, i] - regressors @ theta
        assert np.abs(residual).max() < 1e-10 * np.abs(dy[:, i]).max()
        refit, *_ = np.linalg.lstsq(regressors, dy[2:, i], rcond=None)
        np.testing.assert_allclose(refit, theta, rtol=1e-5, atol=1e-12)
    # Stable, and the own-pressure lag polynomial carries the slow circuit pole.
    assert arx["a"]["y1"]["y1"][0] < -1.5


def test_drift_changes_the_gains_by_a_few_percent():
    p = WindTunnelParameters()
    u1_op, u2_op = operating_point_commands(p)
    n = 1200
    df = simulate_windtunnel(
        np.full(n, u1_op + 5.0 / p.valve_gain), np.full(n, u2_op), params=p, seed=2, noise=False
    )
    settled = (df["y1"].to_numpy()[200:] - p.p0_op) / (p.gain_p0_v1 * 5.0)
    assert settled.max() <= 1.0 + p.drift_amplitude + 1e-3
    assert settled.min() >= 1.0 - p.drift_amplitude - 1e-3
    assert settled.max() - settled.min() > 0.01  # it does drift within 50 s


@pytest.mark.parametrize("condition", CONDITIONS)
def test_measurement_noise_levels(condition):
    noisy = windtunnel_experiment(condition, seed=11)
    clean = windtunnel_experiment(condition, seed=11, noise=False)
    pd.testing.assert_series_equal(noisy["x_true"], clean["x_true"])
    e1 = (noisy["y1"] - clean["y1"]).to_numpy()
    e2 = (noisy["y2"] - clean["y2"]).to_numpy()
    p = WindTunnelParameters.for_condition(condition)
    s1, s2 = p.noise_std
    assert np.std(e1) == pytest.approx(s1, rel=0.08)
    assert np.std(e2) == pytest.approx(s2, rel=0.08)
    # Both come from the stagnation-pressure transducer: correlation 1/sqrt(2).
    assert np.corrcoef(e1, e2)[0, 1] == pytest.approx(2**-0.5, abs=0.06)
    assert np.std((noisy["v1"] - clean["v1"]).to_numpy()) == pytest.approx(0.02, rel=0.08)


def test_signal_ranges_near_paper_figure_4():
    df = windtunnel_experiment("110kPa", seed=0)
    v1, v2, y1, y2 = (df[c].to_numpy() for c in ("v1", "v2", "y1", "y2"))
    assert 408 < v1.min() < 414 and 421 < v1.max() < 427  # paper: [410, 425] mm
    assert 336 < v2.min() < 347 and 363 < v2.max() < 374  # paper: [340, 370] mm
    assert 109.75 < y1.min() and y1.max() < 110.25  # paper: [109.8, 110.0] kPa
    assert 0.12 < np.ptp(y1) < 0.35
    assert 0.572 < y2.min() and y2.max() < 0.584  # paper: [0.575, 0.580]
    assert 0.003 < np.ptp(y2) < 0.008


def test_ranges_at_130kpa():
    df = windtunnel_experiment("130kPa", seed=0)
    assert abs(df["y1"].mean() - 130.0) < 0.05
    assert abs(df["y2"].mean() - 0.822) < 0.002
    # A choked throat makes the Mach number more sensitive to the finger near Ma 1.
    ptp_130 = np.ptp(df["y2"].to_numpy())
    ptp_110 = np.ptp(windtunnel_experiment("110kPa", seed=0)["y2"].to_numpy())
    assert ptp_130 > 1.5 * ptp_110


def test_seeds_reproduce_and_records_differ():
    a = windtunnel_experiment("110kPa", seed=7)
    pd.testing.assert_frame_equal(a, windtunnel_experiment("110kPa", seed=7))
    for other in (
        windtunnel_experiment("110kPa", seed=8),
        windtunnel_experiment("110kPa", seed=7, kind="validation"),
    ):
        assert not np.allclose(a["u1"], other["u1"])
        assert not np.allclose(a["u2"], other["u2"])
    u1, u2 = a["u1"].to_numpy(), a["u2"].to_numpy()
    pd.testing.assert_frame_equal(
        simulate_windtunnel(u1, u2, seed=4), simulate_windtunnel(u1, u2, seed=4)
    )
    assert not np.allclose(
        simulate_windtunnel(u1, u2, seed=4)["y1"], simulate_windtunnel(u1, u2, seed=5)["y1"]
    )


def test_isentropic_helpers_against_finite_differences():
    def pressure_ratio(mach):  # P0/ps
        return (1 + 0.2 * mach**2) ** 3.5

    def area_ratio(mach):  # A/A*
        return (1 / mach) * ((1 + 0.2 * mach**2) / 1.2) ** 3

    for mach in (0.578, 0.822):
        h = 1e-6
        dlog = np.log(pressure_ratio(mach + h)) - np.log(pressure_ratio(mach - h))
        assert _mach_per_log_pressure_ratio(mach) == pytest.approx(2 * h / dlog, rel=1e-6)

        def mach_of(throat):  # subsonic Mach with A_test/A_t = A/A*(M), A_test = 1
            return brentq(lambda m, r=1 / throat: area_ratio(m) - r, 0.05, 1.0, xtol=1e-14)

        throat = 1 / area_ratio(mach)
        dm = mach_of(throat + 1e-7) - mach_of(throat - 1e-7)
        assert _throat_mach_sensitivity(mach) == pytest.approx(dm / 2e-7, rel=1e-5)


def test_bad_arguments():
    with pytest.raises(ParameterError, match="unknown wind-tunnel condition"):
        windtunnel_experiment("120kPa")
    with pytest.raises(ParameterError, match="kind"):
        windtunnel_experiment(kind="training")
    with pytest.raises(ParameterError, match="n_samples"):
        windtunnel_experiment(n_samples=2)
    with pytest.raises(ParameterError, match="seed"):
        windtunnel_experiment(seed=-1)
    with pytest.raises(DataError, match="same length"):
        simulate_windtunnel(np.ones(5), np.ones(4))
    with pytest.raises(DataError, match="u2 has a non-finite value at sample 1"):
        simulate_windtunnel(np.ones(3), np.array([1.0, np.nan, 1.0]))
    with pytest.raises(DataError, match="one-dimensional"):
        simulate_windtunnel(np.ones((3, 2)), np.ones(3))
