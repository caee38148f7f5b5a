"""Tests of the electrohydraulic excavator-arm plant (paper B simulator).

The numba right-hand side and integrator are checked against a plain-Python twin
written from the equations in ``docs/plants/electrohydraulic.md`` and integrated by
``scipy.integrate.solve_ivp``; the physics is checked against hand-derived steady states.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.optimize import fsolve

from blockid._kernels.electrohydraulic import (
    electrohydraulic_geometry,
    electrohydraulic_integrate,
)
from blockid.errors import ParameterError
from blockid.plants.electrohydraulic import (
    PHASE_TRIALS,
    ElectrohydraulicParameters,
    _trim_experiment,
    electrohydraulic_equilibrium,
    electrohydraulic_experiment,
    electrohydraulic_static_spool,
    electrohydraulic_static_velocity,
    general_trajectory_current,
    multisine_current,
    simulate_electrohydraulic,
)

from reference import ref_geometry, ref_pilot_setpoint, ref_rhs

P = ElectrohydraulicParameters()
TS = 0.05


# ----------------------------------------------------------------------------------
# Steady states from the twin of the documented equations (tests/reference.py)
# ----------------------------------------------------------------------------------


def steady_speed(current, h, par=P):
    """Steady velocity at position h from the full balance (leakage, regularised roots)."""
    xv = float(electrohydraulic_static_spool(current, par))
    pp = ref_pilot_setpoint(current, par)
    guess = float(electrohydraulic_static_velocity(current, h, par))
    p_mid = 0.5 * (par.supply_pressure + par.return_pressure)

    def equations(z):
        v, p1, p2 = z[0], z[1] * 1e6, z[2] * 1e6
        d = ref_rhs([h, v, p1, p2, xv, pp], current, par)
        return [d[1] * 1e-2, d[2] * 1e-6, d[3] * 1e-6]

    sol, info, ier, msg = fsolve(equations, [guess, p_mid / 1e6, p_mid / 1e6], full_output=True)
    assert ier == 1, msg
    return sol[0]


def trimmed(raw, par=P):
    """Offset and start position so a noise-free run stays inside the stroke."""
    current, _, run_par = _trim_experiment(raw, par)
    return current, run_par


# ----------------------------------------------------------------------------------
# The plant's responses
# ----------------------------------------------------------------------------------


def test_input_delay_pilot_lag_and_spool_response():
    current = np.zeros(60)
    current[20:] = 0.6  # step at t = 1 s
    df = simulate_electrohydraulic(current, noise=False, substeps=200)
    onset = 20 + int(round(P.input_delay / TS))
    assert np.all(df["pilot"].to_numpy()[: onset + 1] == 0.0)
    # First-order pilot lag towards kp (I - Id), exact at the samples.
    target = P.pilot_gain * (0.6 - P.deadband_current)
    s = (np.arange(onset, 60) - onset) * TS
    np.testing.assert_allclose(
        df["pilot"].to_numpy()[onset:], target * (1 - np.exp(-s / P.pilot_time_constant)), rtol=1e-8
    )
    # The spool waits for the pilot force to reach the preload, then follows
    # cs xv' = As pp - F0 - ks xv, solved in closed form for the exponential pilot.
    a = P.spool_end_area * target / P.spool_stiffness
    b = P.spool_preload / P.spool_stiffness
    tau_p, tau_s = P.pilot_time_constant, P.spool_time_constant
    crack = -tau_p * math.log(1 - b / a)
    e = math.exp(-crack / tau_p)
    c = -a * e * tau_p / (tau_p - tau_s)
    xv = df["xv"].to_numpy()[onset:]
    before = s < crack
    assert np.all(xv[before] == 0.0)
    r = s[~before] - crack
    expected = a * e + c * np.exp(-r / tau_p) - (a * e + c) * np.exp(-r / tau_s)
    np.testing.assert_allclose(xv[~before], expected, rtol=1e-5, atol=1e-9)
    assert xv[-1] == pytest.approx(float(electrohydraulic_static_spool(0.6)), rel=1e-4)


def test_spool_returns_to_neutral_and_stays():
    current = np.zeros(80)
    current[5:30] = -0.7
    df = simulate_electrohydraulic(current, noise=False)
    xv = df["xv"].to_numpy()
    assert xv.min() < -0.8 * abs(float(electrohydraulic_static_spool(-0.7)))
    # The preload pushes the spool onto its seat in finite time: exactly zero afterwards.
    back = 30 + int(round(P.input_delay / TS)) + 20
    assert np.all(xv[back:] == 0.0)
    assert np.all(np.abs(df["pilot"].to_numpy()[back:]) * P.spool_end_area < P.spool_preload)


# ----------------------------------------------------------------------------------
# Physics
# ----------------------------------------------------------------------------------


def test_zero_current_holds_the_arm():
    x0 = electrohydraulic_equilibrium()
    # (A1 - A2) p_eq balances gravity through the linkage and the spring.
    theta, dth, _ = ref_geometry(P.initial_position)
    load = P.arm_mass * P.gravity * P.arm_com_distance * math.cos(theta) * dth
    load += P.spring_stiffness * (P.initial_position - P.spring_free_position)
    assert x0[2] == x0[3] == pytest.approx(load / (P.area_head - P.area_rod), rel=1e-12)
    df = simulate_electrohydraulic(np.zeros(1100), noise=False)
    assert np.abs(df["h"] - x0[0]).max() < 5e-4  # < 0.5 mm in 55 s (external leakage)
    assert np.abs(df["velocity"]).max() < 1e-4
    assert np.abs(df["p1"] / x0[2] - 1).max() < 0.01
    assert np.all(df["xv"] == 0.0)
    assert np.all(df["pilot"] == 0.0)


def test_pressures_settle_to_equilibrium():
    # Start force-balanced but with p1 != p2: internal leakage equalises them.
    x0 = electrohydraulic_equilibrium()
    force = (P.area_head - P.area_rod) * x0[2]
    p2 = 3e6
    p1 = (force + P.area_rod * p2) / P.area_head
    start = np.array([x0[0], 0.0, p1, p2, 0.0, 0.0])
    sealed = dataclasses.replace(P, external_leakage=0.0)
    states = electrohydraulic_integrate(start, sealed.to_array(), np.zeros(8000), TS / 25, 25)
    h_end = states[-1, 0]
    assert 0.005 < x0[0] - h_end < 0.05  # the arm sinks while oil crosses the piston
    expected = electrohydraulic_equilibrium(h_end, sealed)[2]
    np.testing.assert_allclose(states[-1, 2:4], expected, rtol=0.005)
    assert abs(states[-1, 1]) < 1e-6
    # External leakage alone lets the held arm sink at Ce (p1 + p2) / (A1 - A2).
    # (after the ~70 s leakage transient that sets up the small p1 - p2 it needs).
    states = electrohydraulic_integrate(x0, P.to_array(), np.zeros(8000), TS / 25, 25)
    sink = (states[-1, 0] - states[4000, 0]) / (4000 * TS)
    rate = P.external_leakage * (states[-1, 2] + states[-1, 3]) / (P.area_head - P.area_rod)
    assert sink == pytest.approx(-rate, rel=0.05)
    assert abs(x0[0] - states[1100, 0]) < 3e-4  # < 0.3 mm in a 55 s experiment


def test_dead_band():
    total = P.deadband_total
    crack = P.deadband_current + P.spool_preload / (P.spool_end_area * P.pilot_gain)
    land = P.spool_stiffness * P.spool_overlap / (P.spool_end_area * P.pilot_gain)
    assert total == pytest.approx(crack + land)
    # The static spool position is zero up to the crack current, the overlap's end at
    # the total dead band.
    assert float(electrohydraulic_static_spool(0.999 * crack)) == 0.0
    assert float(electrohydraulic_static_spool(-total)) == pytest.approx(-P.spool_overlap)
    assert float(electrohydraulic_static_velocity(0.999 * total)) == 0.0
    delay = int(round(P.input_delay / TS))
    ramp = np.concatenate([np.linspace(0, 0.95 * total, 200), np.full(100, 0.95 * total)])
    for sign in (1.0, -1.0):
        df = simulate_electrohydraulic(sign * ramp, noise=False)
        assert np.abs(df["h"] - df["h"].iloc[0]).max() < 2e-4  # no flow inside the band
        assert np.abs(df["velocity"]).max() < 1e-3
        assert np.abs(df["xv"]).max() < P.spool_overlap  # inside the overlap
        # Pilot threshold: no pilot pressure while |I| <= Id (delayed) ...
        delayed = np.r_[np.zeros(delay), ramp[:-delay]]
        assert np.all(df["pilot"].to_numpy()[1:][np.abs(delayed[:-1]) <= P.deadband_current] == 0)
        # ... and the spool stays on its seat while the pilot force is below the preload.
        held = np.abs(df["pilot"].to_numpy()) * P.spool_end_area <= P.spool_preload
        assert np.all(df["xv"].to_numpy()[held] == 0.0)
        assert not np.all(held)  # the ramp did crack the spool
        above = np.concatenate([np.zeros(20), np.full(80, sign * 1.25 * total)])
        df = simulate_electrohydraulic(above, noise=False)
        assert sign * (df["h"].iloc[-1] - df["h"].iloc[0]) > 0.02  # it moves, that way


def test_static_spool_matches_spring_balance():
    currents = np.array([0.0, 0.25, 0.4, 0.6, 0.85, 0.95, 1.2])
    for sign in (1.0, -1.0):
        spool = electrohydraulic_static_spool(sign * currents)
        for current, xv in zip(sign * currents, spool, strict=True):
            force = P.spool_end_area * abs(ref_pilot_setpoint(current))
            travel = min(max(force - P.spool_preload, 0.0) / P.spool_stiffness, P.spool_max)
            assert xv == pytest.approx(math.copysign(travel, current) if travel else 0.0)
    # Full stroke near 0.9 A: the end caps saturate the valve.
    assert float(electrohydraulic_static_spool(0.9)) == pytest.approx(P.spool_max, rel=0.01)
    assert float(electrohydraulic_static_spool(1.0)) == P.spool_max


def test_direction_asymmetry_matches_force_and_flow_balance():
    speeds = {}
    for current, start in ((0.6, 0.35), (-0.6, 0.85)):
        par = dataclasses.replace(P, initial_position=start)
        df = simulate_electrohydraulic(np.full(45, current), params=par, noise=False)
        h, v = df["h"].iloc[-1], df["hdot"].iloc[-1]
        assert 0.45 < h < 0.75  # near mid-stroke, still moving
        assert v == pytest.approx(steady_speed(current, h, par), rel=0.01)
        speeds[current] = steady_speed(current, 0.6, par)
    ratio = speeds[0.6] / -speeds[-0.6]
    # Leakage-free closed form: (v_ext / v_ret)^2 = drive_ext / drive_ret minus friction.
    p = P.to_array()
    theta, dth, _ = electrohydraulic_geometry(0.6, p)
    load = P.arm_mass * P.gravity * P.arm_com_distance * math.cos(theta) * dth
    a1, a2, ps, pr = P.area_head, P.area_rod, P.supply_pressure, P.return_pressure
    fric_ext = P.coulomb_friction + P.viscous_friction * speeds[0.6]
    fric_ret = P.coulomb_friction - P.viscous_friction * speeds[-0.6]
    closed = math.sqrt(
        (a1 * ps - a2 * pr - load - fric_ext) / (a2 * ps - a1 * pr + load - fric_ret)
    )
    assert ratio == pytest.approx(closed, rel=0.01)
    assert ratio < 0.95  # gravity makes lowering faster despite A1 > A2
    # Without the arm's weight the area ratio dominates: extension is faster.
    light = dataclasses.replace(P, arm_mass=1.0, spring_stiffness=0.0)
    up = electrohydraulic_static_velocity(0.6, 0.6, light)
    down = electrohydraulic_static_velocity(-0.6, 0.6, light)
    assert up / -down == pytest.approx(math.sqrt(a1 / a2), rel=0.03)


def test_static_velocity_matches_simulation():
    # (Below about 0.05 m/s internal leakage, which the static characteristic
    # neglects, takes a few per cent of the flow; these speeds are 0.07-0.22 m/s.)
    for current in (0.6, 0.8, -0.6, -0.8):
        start = 0.35 if current > 0 else 0.85
        par = dataclasses.replace(P, initial_position=start)
        df = simulate_electrohydraulic(np.full(50, current), params=par, noise=False)
        # Averaged over the last 0.5 s, across the ringing of the hydraulic resonance.
        h, v = df["h"].iloc[-10:].mean(), df["hdot"].iloc[-10:].mean()
        assert v == pytest.approx(electrohydraulic_static_velocity(current, h, par), rel=0.02)


def test_end_stops_are_inelastic():
    df = simulate_electrohydraulic(np.full(200, 1.0), noise=False)
    assert df["h"].max() == P.stroke
    at_stop = df["h"] == P.stroke
    assert at_stop.sum() > 50
    assert np.all(df["hdot"][at_stop] == 0.0)
    assert df["p1"].max() <= 1.1 * P.supply_pressure


@pytest.mark.parametrize("generator", [multisine_current, general_trajectory_current])
def test_step_halving_changes_outputs_below_0p1_percent(generator):
    current, par = trimmed(generator(seed=3))  # the multisine reaches the spool's end caps
    coarse = simulate_electrohydraulic(current, params=par, noise=False)
    fine = simulate_electrohydraulic(current, params=par, noise=False, substeps=100)
    assert 0.0 < coarse["h"].min() and coarse["h"].max() < P.stroke
    for column in ("velocity", "angle"):
        change = np.abs(coarse[column] - fine[column]).max() / np.ptp(fine[column])
        assert change < 1e-3, column


def test_noise_free_velocity_is_derivative_of_angle():
    current, par = trimmed(multisine_current(seed=1))
    df = simulate_electrohydraulic(current, params=par, noise=False)
    assert np.array_equal(df["angle"], df["angle_measured"])
    _, dth, _ = np.vectorize(lambda h: ref_geometry(h, par))(df["h"].to_numpy())
    true_rate = dth * df["hdot"].to_numpy()
    error = np.abs(df["velocity"].to_numpy() - true_rate)[1:-1]
    assert error.max() < 0.05 * np.ptp(true_rate)
    assert np.sqrt(np.mean(error**2)) < 0.01 * np.ptp(true_rate)


def test_measurement_noise_level():
    current = multisine_current(seed=2)
    df = simulate_electrohydraulic(current, seed=5)
    noise = df["angle_measured"] - df["angle"]
    assert noise.std() == pytest.approx(P.angle_noise_std, rel=0.1)
    clean = simulate_electrohydraulic(current, noise=False)
    velocity_noise = (df["velocity"] - clean["velocity"])[1:-1]
    # Central difference of white noise: sigma / (sqrt(2) Ts).
    assert velocity_noise.std() == pytest.approx(P.angle_noise_std / (math.sqrt(2) * TS), rel=0.1)


def test_seeds_reproduce():
    current = multisine_current(duration=10.0, seed=4)
    np.testing.assert_array_equal(current, multisine_current(duration=10.0, seed=4))
    assert not np.array_equal(current, multisine_current(duration=10.0, seed=5))
    a = simulate_electrohydraulic(current, seed=7)
    b = simulate_electrohydraulic(current, seed=7)
    c = simulate_electrohydraulic(current, seed=8)
    np.testing.assert_array_equal(a["velocity"], b["velocity"])
    assert not np.array_equal(a["velocity"], c["velocity"])
    np.testing.assert_array_equal(a["h"], c["h"])  # noise is only in the measurement
    np.testing.assert_array_equal(
        general_trajectory_current(seed=3), general_trajectory_current(seed=3)
    )


def test_multisine_spectrum_and_range():
    freqs = (0.05, 0.1, 0.2, 0.4, 0.5)
    u = multisine_current(duration=100.0, frequencies=freqs, amplitude=0.7, offset=0.1, seed=0)
    assert u.max() - 0.1 == pytest.approx(0.7) or 0.1 - u.min() == pytest.approx(0.7)
    assert np.abs(u - 0.1).max() == pytest.approx(0.7)
    assert u.mean() == pytest.approx(0.1, abs=0.01)
    spectrum = np.abs(np.fft.rfft(u - u.mean()))
    grid = np.fft.rfftfreq(u.size, TS)
    peaks = np.sort(grid[np.argsort(spectrum)[-5:]])
    np.testing.assert_allclose(peaks, freqs, atol=1e-9)


def test_multisine_phase_search_lowers_the_crest_factor():
    def crest(u):
        return np.abs(u).max() / np.sqrt(np.mean(u**2))

    single = [crest(multisine_current(seed=s)) for s in range(20)]
    searched = [crest(multisine_current(seed=s, phase_trials=PHASE_TRIALS)) for s in range(20)]
    # The search keeps the best of its draws; its first draw is the single-trial signal.
    assert all(b <= a + 1e-12 for a, b in zip(single, searched, strict=True))
    assert np.median(searched) < 0.85 * np.median(single)
    u = multisine_current(seed=3, phase_trials=PHASE_TRIALS)
    assert np.abs(u).max() == pytest.approx(0.9)


def test_experiment_records():
    data = electrohydraulic_experiment(seed=11, n_repeats=4)
    est, val = data["estimation"], data["validation"]
    for frame in (est, val):
        assert list(frame.columns) == ["t", "current", "velocity"]
        assert len(frame) == 1100
        assert frame["t"].iloc[-1] == pytest.approx(54.95)
        # The command crosses the dead band both ways and stays within +-1 A.
        assert frame["current"].max() > 1.5 * P.deadband_total
        assert frame["current"].min() < -1.5 * P.deadband_total
        assert np.abs(frame["current"]).max() <= 1.0
        par = dataclasses.replace(P, initial_position=frame.attrs["initial_position"])
        clean = simulate_electrohydraulic(frame["current"].to_numpy(), params=par, noise=False)
        assert 0.02 < clean["h"].min() and clean["h"].max() < P.stroke - 0.02
        assert np.ptp(clean["h"]) > 0.3  # large motion: the geometry matters
        residual = (frame["velocity"] - clean["velocity"])[1:-1]
        n = 4 if frame is est else 1
        sigma = P.angle_noise_std / (math.sqrt(2) * TS) / math.sqrt(n)
        assert residual.std() == pytest.approx(sigma, rel=0.15)
    # Validation stays within the current range the estimation record covers.
    assert est["current"].min() <= val["current"].min()
    assert val["current"].max() <= est["current"].max()
    again = electrohydraulic_experiment(seed=11, n_repeats=4)
    np.testing.assert_array_equal(again["estimation"]["velocity"], est["velocity"])


def test_validation_command_stays_in_the_identified_band():
    def above(u, f0=0.55):
        power = np.abs(np.fft.rfft(u - u.mean())) ** 2
        return power[np.fft.rfftfreq(u.size, TS) > f0].sum() / power.sum()

    for seed in range(3):
        banded = general_trajectory_current(seed=seed)
        steps = general_trajectory_current(seed=seed, bandwidth=None)
        assert above(banded) < 0.01 and above(steps) > 0.015
        assert above(banded) < 0.3 * above(steps)
        assert np.std(banded) > 0.8 * np.std(steps)  # the moves survive the filter


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"current": [0.0, np.nan, 0.1]}, "current"),
        ({"current": np.zeros((3, 2))}, "current"),
        ({"current": np.zeros(10), "sample_time": 0.0}, "sample_time"),
        ({"current": np.zeros(10), "substeps": 0}, "substeps"),
        ({"current": np.zeros(10), "params": {"stroke": 1.0}}, "params"),
        (
            {"current": np.zeros(10), "params": ElectrohydraulicParameters(rod_diameter=0.2)},
            "rod_diameter",
        ),
        (
            {"current": np.zeros(10), "params": ElectrohydraulicParameters(bulk_modulus=-1.0)},
            "bulk_modulus",
        ),
        (
            {"current": np.zeros(10), "params": ElectrohydraulicParameters(stroke=3.0)},
            "linkage",
        ),
    ],
)
def test_bad_input_raises(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        simulate_electrohydraulic(**kwargs)


def test_bad_signal_options_raise():
    with pytest.raises(ParameterError, match="frequencies"):
        multisine_current(frequencies=(0.05, 12.0))
    with pytest.raises(ParameterError, match="amplitude"):
        multisine_current(amplitude=0.0)
    with pytest.raises(ParameterError, match="phase_trials"):
        multisine_current(phase_trials=0)
    with pytest.raises(ParameterError, match="duration"):
        general_trajectory_current(duration=0.01)
    with pytest.raises(ParameterError, match="duration must be at least 10 s"):
        general_trajectory_current(duration=5.0)  # short records used to come back NaN
    for bad in (0.0, 1e-9, 0.03, 10.0, float("nan")):
        with pytest.raises(ParameterError, match="bandwidth must be a frequency from 0.0364 Hz"):
            general_trajectory_current(bandwidth=bad)
    for bad in ("0.5", True, [0.5]):
        with pytest.raises(ParameterError, match="bandwidth must be a number"):
            general_trajectory_current(bandwidth=bad)
    with pytest.raises(ParameterError, match="n_repeats"):
        electrohydraulic_experiment(n_repeats=0)
