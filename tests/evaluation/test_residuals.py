"""Residual analysis against known truth: a model of the right orders leaves a white,
independent residual; a model missing a pole or a delay does not; feedback in the data
shows at negative lags; the correlations are those of a direct formula."""

from __future__ import annotations

import numpy as np
import pytest

from blockid.data import Dataset
from blockid.errors import DataError, ParameterError
from blockid.evaluation.residuals import _lagged_sums, residual_analysis
from blockid.fitting import fit_model

A = (-1.5, 0.7)  # y(t) = 1.5 y(t-1) - 0.7 y(t-2) + u(t-1) + 0.5 u(t-2) + e(t)
B = (1.0, 0.5)


def _arx_record(n=3000, seed=0, noise=0.3, feedback=0.0, colour=0.0):
    """An ARX(2, 2, 1) plant with white equation noise; with ``feedback``, the input
    carries ``-feedback * y(t-1)`` (a closed loop); with ``colour``, the reference is
    white noise through ``1 / (1 - colour q^-1)`` (a slow input)."""
    rng = np.random.default_rng(seed)
    r = rng.standard_normal(n)
    for t in range(1, n):
        r[t] += colour * r[t - 1]
    e = noise * rng.standard_normal(n)
    u, y = np.zeros(n), np.zeros(n)
    for t in range(n):
        u[t] = r[t] - (feedback * y[t - 1] if t else 0.0)
        y[t] = e[t]
        if t >= 1:
            y[t] += -A[0] * y[t - 1] + B[0] * u[t - 1]
        if t >= 2:
            y[t] += -A[1] * y[t - 2] + B[1] * u[t - 2]
    return Dataset.from_arrays(u, y, ["u"], ["y"])


def test_the_right_model_leaves_a_white_residual_independent_of_the_input():
    train, fresh = _arx_record(seed=0), _arx_record(seed=1)
    model = fit_model(train, "arx", na=2, nb=2, nk=1).model
    out = residual_analysis(model, fresh)
    assert out.whiteness["y"]["white"] and out.independence[("u", "y")]["independent"]
    assert out.whiteness["y"]["p_value"] > 0.01 and out.autocorrelation["y"][0] == 1.0
    assert out.n_samples == 3000 - model.max_lag
    assert out.auto_bound == pytest.approx(2.5758 / np.sqrt(out.n_samples), rel=1e-4)


def test_a_missing_pole_colours_the_residual_and_a_missing_delay_shows_in_the_input():
    train, fresh = _arx_record(seed=0), _arx_record(seed=1)
    short = fit_model(train, "arx", na=1, nb=2, nk=1).model
    out = residual_analysis(short, fresh)
    assert not out.whiteness["y"]["white"] and out.whiteness["y"]["outside"] >= 3
    late = fit_model(train, "arx", na=2, nb=1, nk=2).model  # misses u(t-1)
    out = residual_analysis(late, fresh)
    pair = out.independence[("u", "y")]
    assert not pair["independent"] and pair["outside"] >= 1
    one = out.cross_correlation[("u", "y")][out.cross_lags == 1][0]
    assert abs(one) > 5 * out.cross_bound[("u", "y")]  # the lag the model lacks


def test_feedback_in_the_data_shows_at_negative_lags():
    loop = dict(noise=1.0, feedback=0.1)
    train, fresh = _arx_record(seed=0, **loop), _arx_record(seed=1, **loop)
    model = fit_model(train, "arx", na=2, nb=2, nk=1).model
    out = residual_analysis(model, fresh)
    pair = out.independence[("u", "y")]
    assert pair["outside_negative"] >= 1  # u(t+1) holds -0.1 y(t), hence e(t)
    assert pair["feedback"] and pair["feedback_p_value"] < 1e-6
    lags = out.cross_lags
    r = out.cross_correlation[("u", "y")]
    assert abs(r[lags == -1][0]) > abs(r[lags >= 0]).max()  # the loop's lag stands out


def test_a_wrong_model_on_a_slow_open_loop_input_is_not_called_feedback():
    """With a coloured input, a model that misses a lag leaves a residual correlated
    with the input at negative lags too (raw correlation outside its bound): that is
    the model's error, not a loop; the prewhitened test over negative lags says so,
    and still finds the loop of a closed-loop record with the same slow input."""
    slow = dict(colour=0.9)
    train, fresh = _arx_record(seed=0, **slow), _arx_record(seed=1, **slow)
    late = fit_model(train, "arx", na=2, nb=1, nk=2).model  # misses u(t-1)
    pair = residual_analysis(late, fresh).independence[("u", "y")]
    assert not pair["independent"] and pair["outside_negative"] >= 3
    assert not pair["feedback"] and pair["feedback_p_value"] > 0.01
    loop = dict(colour=0.9, noise=1.0, feedback=0.1)
    train, fresh = _arx_record(seed=0, **loop), _arx_record(seed=1, **loop)
    model = fit_model(train, "arx", na=2, nb=2, nk=1).model
    assert residual_analysis(model, fresh).independence[("u", "y")]["feedback"]


def test_an_input_that_repeats_exactly_reports_no_feedback():
    """A generated periodic input (a band-limited period, repeated) cannot carry the
    output's noise back: a wrong model's residual correlates with it at negative lags
    (an AR filter cannot whiten a band-limited line spectrum), and no loop is reported;
    the same input with noise added is tested as any other."""
    from scipy import signal

    rng = np.random.default_rng(4)
    b, a = signal.butter(4, 0.2)
    period = signal.lfilter(b, a, rng.standard_normal(512))
    u = np.tile(period, 6)
    x = signal.lfilter([0.0, 1.0, 0.5], [1.0, -1.5, 0.7], u)
    y = x + 0.3 * x**3 + 0.05 * rng.standard_normal(u.size)
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    wrong = fit_model(data, "arx", na=1, nb=1, nk=1).model
    pair = residual_analysis(wrong, data).independence[("u", "y")]
    assert not pair["independent"] and pair["outside_negative"] >= 1
    assert not pair["feedback"] and pair["feedback_statistic"] == 0.0


def test_the_correlations_are_the_direct_sums_over_each_experiment():
    rng = np.random.default_rng(3)
    a = [rng.standard_normal(40), rng.standard_normal(25)]
    b = [rng.standard_normal(40), rng.standard_normal(25)]
    got = _lagged_sums(a, b, 5)
    for i, tau in enumerate(range(-5, 6)):
        want = sum(
            sum(x[t] * z[t + tau] for t in range(len(x)) if 0 <= t + tau < len(z))
            for x, z in zip(a, b, strict=True)
        )
        assert got[i] == pytest.approx(want, abs=1e-12)


def test_bad_arguments_and_too_short_data_are_named():
    data = _arx_record(n=200)
    model = fit_model(data, "arx", na=2, nb=2, nk=1).model
    with pytest.raises(ParameterError, match="max_lag"):
        residual_analysis(model, data, max_lag=0)
    with pytest.raises(ParameterError, match="confidence"):
        residual_analysis(model, data, confidence=99)
    with pytest.raises(DataError, match="too few"):
        residual_analysis(model, data, max_lag=100)


def test_a_model_without_a_noise_model_is_told_apart():
    """An output-error fit has no noise model (its one-step residual is not made
    white): the analysis says so, and the ARX's does not."""
    train, fresh = _arx_record(seed=0), _arx_record(seed=1)
    arx = fit_model(train, "arx", na=2, nb=2, nk=1).model
    oe = fit_model(train, "output-error", na=2, nb=2, nk=1).model
    assert residual_analysis(arx, fresh).noise_model is True
    assert residual_analysis(oe, fresh).noise_model is False
    assert residual_analysis(oe, fresh, "simulation").noise_model is None


def test_the_verdict_names_the_test_that_decides():
    """Right orders pass; a missing pole fails both tests (an ARX has a noise model), a
    missing delay by the input; an output-error fit of the right orders passes (whiteness
    is not asked of it: see the next test for the wording)."""
    train, fresh = _arx_record(seed=0), _arx_record(seed=1)
    verdicts = {}
    for name, structure, orders in [
        ("right", "arx", (2, 2, 1)), ("pole", "arx", (1, 2, 1)),
        ("delay", "arx", (2, 1, 2)), ("oe", "output-error", (2, 2, 1)),
    ]:  # fmt: skip
        model = fit_model(
            train, structure, **dict(zip(("na", "nb", "nk"), orders, strict=True))
        ).model
        out = residual_analysis(model, fresh)
        verdicts[name] = (out.passed, out.verdict(), out.to_dict()["verdict"])
    assert verdicts["right"][:2] == (True, "passes: white and independent of the inputs at 99%")
    assert verdicts["pole"][0] is False and "nor is the residual white" in verdicts["pole"][1]
    assert verdicts["delay"][0] is False and "correlates with past u" in verdicts["delay"][1]
    assert verdicts["oe"][0] is True and verdicts["oe"][1].startswith("passes")
    assert all(v[1] == v[2] for v in verdicts.values())


def test_a_coloured_residual_without_a_noise_model_passes_and_says_why():
    """An output-error plant (white noise on the output): the output-error model's
    one-step residual is that noise through its A(q), coloured but independent of the
    input, which passes a model fitted without a noise model."""
    from scipy.signal import lfilter

    def record(seed):
        rng = np.random.default_rng(seed)
        u = rng.standard_normal(3000)
        y = lfilter([0.0, *B], [1.0, *A], u) + 0.3 * rng.standard_normal(3000)
        return Dataset.from_arrays(u, y, ["u"], ["y"])

    oe = fit_model(record(0), "output-error", na=2, nb=2, nk=1).model
    out = residual_analysis(oe, record(1))
    assert out.noise_model is False and not out.whiteness["y"]["white"]
    assert out.passed and out.verdict().startswith("passes: independent of the inputs; not white")
