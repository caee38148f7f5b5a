"""Standard errors and the simulation band (blockid.evaluation.uncertainty): shapes,
fixed entries, JSON, and calibration on simulated plants with white output noise."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from blockid.blocks import PiecewiseLinear, TwoSegmentPolynomial
from blockid.data import Dataset
from blockid.errors import ParameterError
from blockid.evaluation.uncertainty import (
    ParameterCovariance,
    named_standard_errors,
    parameter_covariance,
    simulation_band,
    standard_errors,
    with_standard_errors,
)
from blockid.fitting import fit_model
from blockid.models import ARX, Hammerstein, OutputError, model_document
from plants_for_options import PLANTS, record

LIN = {"na": 2, "nb": 2, "nk": 1, "a": [-1.2, 0.35], "b": [1.0, 0.4]}


def _shape(tree):
    if isinstance(tree, dict):
        return {k: _shape(v) for k, v in tree.items()}
    if isinstance(tree, list):
        return [_shape(v) for v in tree]
    return type(tree) in (float, int, type(None))


@pytest.mark.slow
def test_standard_errors_are_calibrated_on_a_hammerstein_wiener_plant():
    """Issue 11: at 40 dB white output noise, over 20 noise seeds, the true parameters
    lie within two reported standard errors in 85-99 % of the cases."""
    plant = PLANTS["hammerstein-wiener"]()
    truth = plant.free_parameters()
    names = plant.free_parameter_names()
    inside = []
    for seed in range(20):
        data = record(plant, 1000, snr_db=40.0, seed=seed)
        fit = with_standard_errors(
            fit_model(data, "hammerstein-wiener", na=2, nb=2, nk=1, r1=2, r2=2), data
        )
        cov = fit.settings["covariance"]
        assert cov["names"] == names
        se = np.sqrt(np.diag(np.array(cov["matrix"], dtype=float)))
        inside.append(np.abs(fit.model.free_parameters() - truth) <= 2 * se)
    inside = np.array(inside)
    groups = {
        "input block": [n[0] in "fp" for n in names],
        "linear block": [n[0] in "ab" for n in names],
        "output block": [n[0] == "q" for n in names],
    }
    shares = {g: float(inside[:, np.array(m)].mean()) for g, m in groups.items()}
    assert 0.85 <= inside.mean() <= 0.99, (inside.mean(), shares)
    assert min(shares.values()) >= 0.8, shares


def test_named_standard_errors_have_the_shape_of_the_parameters_and_fixed_entries_zero():
    plant = PLANTS["hammerstein-wiener"]()
    data = record(plant, 400, snr_db=40.0, seed=1)
    se = standard_errors(plant, data)
    assert _shape(se) == _shape(plant.parameters)
    assert se["b"][0] == 0.0 and se["q"][0] == 0.0  # b_0 = 1 and q_1 = 1 are fixed
    cov = parameter_covariance(plant, data)
    flat = dict(zip(cov.names, cov.standard_errors, strict=True))
    assert se["f"][1] == flat["f_1"] and se["p"][2] == flat["p_2"]
    assert se["a"][1] == flat["a_2"] and se["b"][1] == flat["b_1"] and se["q"][1] == flat["q_2"]
    assert all(v > 0 for v in cov.standard_errors)


def test_breakpoints_are_not_parameters():
    model = Hammerstein(
        "u", "y", input_block=PiecewiseLinear([-1.0, 0.0, 1.0], [-0.5, 0.0, 0.8]), **LIN
    )
    data = record(model, 400, snr_db=40.0, seed=2)
    se = standard_errors(model, data)
    assert se["breakpoints"] == [0.0, 0.0, 0.0]
    assert all(v > 0 for v in se["values"]) and se["b"][0] == 0.0


def test_arx_standard_errors_are_the_least_squares_ones():
    plant = PLANTS["arx"]()
    rng = np.random.default_rng(3)
    u, e = rng.uniform(-1, 1, 800), 0.05 * rng.standard_normal(800)
    y = np.zeros(800)
    for k in range(2, 800):  # ARX plant with white equation error
        y[k] = 1.2 * y[k - 1] - 0.35 * y[k - 2] + u[k - 1] + 0.4 * u[k - 2] + e[k]
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    fit = fit_model(data, "arx", na=2, nb=2, nk=1)
    Phi, target = fit.model.regressors(u, y, 0)
    theta = fit.model.parameter_vector(0)
    r = target - Phi @ theta
    expected = np.sqrt(np.diag(r @ r / (r.size - 4) * np.linalg.inv(Phi.T @ Phi)))
    cov = parameter_covariance(fit.model, data, fit.method)
    np.testing.assert_allclose(cov.standard_errors, expected, rtol=1e-8)
    assert cov.names == plant.parameter_names(0)
    se = standard_errors(fit.model, data)
    assert se["y"]["a"]["y"] == pytest.approx(list(expected[:2]), rel=1e-8)
    rls = parameter_covariance(fit.model, data, "rls")
    assert "P is not kept" in rls.basis


def test_with_standard_errors_lands_in_the_model_file_as_json():
    plant = PLANTS["hammerstein"]()
    data = record(plant, 300, snr_db=40.0, seed=4, mean=0.2)
    fit = fit_model(data, "hammerstein", na=2, nb=2, nk=1, r1=2, max_nfev=10)
    out = with_standard_errors(fit, data)
    assert "standard_errors" not in fit.settings  # a new result, the old one unchanged
    doc = json.loads(
        json.dumps(model_document(out.model, out.estimation_record()), allow_nan=False)
    )
    se = doc["estimation"]["settings"]["standard_errors"]
    assert _shape(se) == _shape(doc["model"]["parameters"])
    cov = doc["estimation"]["settings"]["covariance"]
    assert cov["names"] == out.model.free_parameter_names()
    assert len(cov["matrix"]) == len(cov["names"]) and cov["degrees_of_freedom"] > 0
    assert set(cov["noise_variance"]) == {"y"}


def test_an_unidentifiable_parameter_has_no_standard_error():
    """With positive inputs only, the negative segment of B1 is never excited."""
    model = Hammerstein(
        "u",
        "y",
        input_block=TwoSegmentPolynomial.from_segments([0.0, 1.0, 0.2], [0.0, 0.5, 0.1]),
        **LIN,
    )
    rng = np.random.default_rng(5)
    u = rng.uniform(0.1, 1.0, 400)
    y = model.simulate(u)[:, 0] + 0.01 * rng.standard_normal(400)
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    se = standard_errors(model, data)
    assert se["p"] == [None, None, None]
    assert all(v is not None and v > 0 for v in se["a"])
    json.dumps(se, allow_nan=False)


def test_feedback_model_standard_errors():
    plant = PLANTS["feedback"]()
    data = record(plant, 400, snr_db=40.0, seed=6, amplitude=0.8)
    se = standard_errors(plant, data)
    assert _shape(se) == _shape(plant.parameters)
    assert all(v > 0 for v in se["a"] + se["b"] + se["c"][1:])


def test_a_covariance_of_the_wrong_size_is_refused():
    plant = PLANTS["hammerstein"]()
    with pytest.raises(ParameterError, match="does not fit"):
        named_standard_errors(plant, np.eye(3))
    with pytest.raises(ParameterError, match="level"):
        simulation_band(plant, np.eye(plant.free_parameters().size), np.zeros(10), level=1.5)


# ----------------------------------------------------------------------------- band
def _band_shares(center: bool, mean: float) -> tuple[float, float]:
    """Share of validation samples where the 95 % band holds the noise-free output of
    an output-error plant (30 dB, 400 samples, 12 seeds), with the covariance as fitted
    and with its offset terms left out."""
    plant = OutputError("u", "y", **LIN)
    rng = np.random.default_rng(8)
    u_val = mean + rng.uniform(-1, 1, 300)
    truth = plant.simulate(u_val)
    shares: dict[bool, list[float]] = {True: [], False: []}
    for seed in range(12):
        data = record(plant, 400, snr_db=30.0, seed=seed, mean=mean)
        fit = fit_model(
            data, "output-error", na=2, nb=2, nk=1, tail_fraction=0.0, center=center,
            standard_errors=True,
        )  # fmt: skip
        cov = ParameterCovariance.from_dict(fit.settings["covariance"])
        assert bool(cov.offsets) == center
        for with_offsets in (True, False):
            used = cov if with_offsets else replace(cov, offsets={})
            band = simulation_band(fit.model, used, u_val, level=0.95)
            assert band.lower.shape == band.upper.shape == truth.shape
            inside = (band.lower <= truth) & (truth <= band.upper)
            shares[with_offsets].append(float(inside[20:].mean()))
    return float(np.mean(shares[True])), float(np.mean(shares[False]))


@pytest.mark.parametrize(("center", "mean"), [(False, 0.0), (True, 0.0), (True, 0.5)])
def test_the_band_holds_the_noise_free_output_about_as_often_as_it_says(center, mean):
    """Measured: without centering 95.8 %; centred, 94.1 % (input mean 0) and 95.6 %
    (input mean 0.5), against 27 % and 0.7 % when the offsets' error is left out."""
    share, without_offsets = _band_shares(center, mean)
    assert 0.85 <= share <= 0.995, share
    if center:  # the offsets' noise and bias are what makes the difference
        assert without_offsets < 0.5, without_offsets


def test_the_offset_terms_of_a_centred_output_error_fit():
    plant = OutputError("u", "y", **LIN)
    data = record(plant, 400, snr_db=30.0, seed=3, mean=0.5)
    fit = fit_model(data, "output-error", na=2, nb=2, nk=1, tail_fraction=0.0)
    assert fit.model.output_offset != 0.0  # centred by default
    cov = parameter_covariance(fit.model, data)  # detected: the offsets are the means
    assert cov.to_dict() == parameter_covariance(fit.model, data, centered=True).to_dict()
    assert parameter_covariance(fit.model, data, centered=False).offsets == {}
    entry = cov.offsets["y"]
    sigma2 = cov.noise_variance["y"]
    # white residuals: N_eff is about N
    assert sigma2 / 400 <= entry["variance"] <= 1.3 * sigma2 / 400
    u, y = data.experiments[0].u, data.experiments[0].y
    residual = y[2:, 0] - fit.model.simulate(u, y[:2])[2:, 0]
    assert entry["bias"] == pytest.approx(-residual.mean(), rel=1e-9)
    # no parameter of a linear block makes a constant: m is small and the offset's
    # noise variance adds to every sample
    band = simulation_band(fit.model, replace(cov, offsets={"y": {**entry, "bias": 0.0}}), u)
    plain = simulation_band(fit.model, replace(cov, offsets={}), u)
    added = band.std[20:, 0] ** 2 - plain.std[20:, 0] ** 2
    assert np.all(added > 0.9 * entry["variance"]) and np.all(added <= entry["variance"])
    # the bias widens the band, not its centre
    biased = simulation_band(fit.model, cov, u)
    np.testing.assert_allclose(biased.upper + biased.lower, 2 * biased.simulated, atol=1e-12)
    assert np.all(biased.upper - biased.simulated >= band.upper - band.simulated)
    assert biased.bias.tolist() == [entry["bias"]]
    # and survives the model file
    again = ParameterCovariance.from_dict(json.loads(json.dumps(cov.to_dict(), allow_nan=False)))
    assert again.offsets["y"]["variance"] == entry["variance"]
    np.testing.assert_array_equal(again.offsets["y"]["direction"], entry["direction"])


def test_a_constant_parameter_absorbs_the_offset_error():
    """A polynomial input block with a constant term can make any offset: the fit moves
    it instead of the offset, its error is already in the covariance (m = 1)."""
    plant = PLANTS["hammerstein"]()
    data = record(plant, 400, snr_db=30.0, seed=4, mean=0.3)
    fit = fit_model(
        data, "hammerstein", na=2, nb=2, nk=1, input_block="polynomial:degree=3",
        center=True, standard_errors=True, max_nfev=20,
    )  # fmt: skip
    cov = ParameterCovariance.from_dict(fit.settings["covariance"])
    entry = cov.offsets["y"]
    u = data.experiments[0].u
    without_bias = replace(cov, offsets={"y": {**entry, "bias": 0.0}})
    band = simulation_band(fit.model, without_bias, u)
    plain = simulation_band(fit.model, replace(cov, offsets={}), u)
    np.testing.assert_allclose(band.std[20:], plain.std[20:], rtol=0.05)
    assert abs(entry["bias"]) < 0.1 * np.sqrt(cov.noise_variance["y"])


def test_centred_arx_offsets_follow_its_noise_model():
    """ARX noise is e/A: the output offset's variance is sigma^2 / (N A(1)^2)."""
    rng = np.random.default_rng(11)
    u, e = 0.5 + rng.uniform(-1, 1, 800), 0.05 * rng.standard_normal(800)
    y = np.zeros(800)
    for k in range(2, 800):
        y[k] = 1.2 * y[k - 1] - 0.35 * y[k - 2] + u[k - 1] + 0.4 * u[k - 2] + e[k]
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    fit = with_standard_errors(fit_model(data, "arx", na=2, nb=2, nk=1, center=True), data)
    cov = ParameterCovariance.from_dict(fit.settings["covariance"])
    a1 = 1.0 + fit.model.a["y"]["y"].sum()
    entry = cov.offsets["y"]
    assert entry["variance"] == pytest.approx(cov.noise_variance["y"] / (800 * a1**2))
    assert "direction" not in entry and "estimation means" in cov.basis
    plain = fit_model(data, "arx", na=2, nb=2, nk=1, standard_errors=True)
    assert "offsets" not in plain.settings["covariance"]
    band = simulation_band(fit.model, cov, u[:200], y[:2])
    bare = simulation_band(fit.model, replace(cov, offsets={}), u[:200], y[:2])
    assert np.all(band.upper - band.lower > bare.upper - bare.lower)


def test_the_half_width_holds_a_biased_error_with_the_level():
    from scipy.special import ndtr

    from blockid.evaluation.uncertainty import _half_width

    std = np.array([[0.0, 1.0], [1.0, 2.0], [3.0, np.inf]])
    bias = np.array([0.5, -2.0])
    w = _half_width(bias, std, 0.95)
    assert w[0, 0] == 0.5 and np.isinf(w[2, 1])
    for k, j in ((1, 0), (2, 0), (0, 1), (1, 1)):
        b, s = bias[j], std[k, j]
        assert ndtr((w[k, j] - b) / s) - ndtr((-w[k, j] - b) / s) == pytest.approx(0.95)
        assert 1.959963 * s < w[k, j] < abs(b) + 1.959964 * s
    np.testing.assert_allclose(_half_width(np.zeros(2), std, 0.95), 1.959963985 * std)
    assert np.all(np.isinf(_half_width(np.array([np.inf, np.nan]), std, 0.95)))


def test_the_arx_band_by_differences_equals_the_analytic_one():
    arx = ARX(["u"], ["y"], 2, 2, 1, a={"y": {"y": LIN["a"]}}, b={"y": {"u": LIN["b"]}})
    oe = OutputError("u", "y", **LIN)
    cov = np.diag([1e-4, 2e-4, 3e-4, 4e-4]) + 1e-5
    u = np.random.default_rng(9).uniform(-1, 1, 200)
    a = simulation_band(arx, cov, u, level=0.9)
    b = simulation_band(oe, cov, u, level=0.9)
    np.testing.assert_allclose(a.std, b.std, rtol=1e-5, atol=1e-9)
    np.testing.assert_allclose(a.simulated, b.simulated, atol=1e-12)


def test_the_noise_band_adds_the_noise_variance():
    plant = OutputError("u", "y", na=1, nb=1, nk=1, a=[-0.5], b=[1.0])
    cov = ParameterCovariance(["a_1", "b_0"], np.array([-0.5, 1.0]), np.zeros((2, 2)),
                              {"y": 0.04}, 100, "test")  # fmt: skip
    band = simulation_band(plant, cov, np.ones(5), noise=True, level=0.95)
    np.testing.assert_allclose(band.upper - band.simulated, 1.959964 * 0.2, rtol=1e-6)


def test_the_band_of_a_saved_model(tmp_path):
    from blockid.errors import ModelFileError
    from blockid.evaluation.uncertainty import band_columns, load_covariance
    from blockid.models import save_model

    plant = PLANTS["wiener"]()
    data = record(plant, 300, snr_db=40.0, seed=10)
    fit = with_standard_errors(fit_model(data, "wiener", na=2, nb=2, nk=1, r2=2, max_nfev=10), data)
    path = save_model(fit.model, tmp_path / "w.json", fit.estimation_record())
    cov = load_covariance(path)
    np.testing.assert_allclose(
        cov.matrix, parameter_covariance(fit.model, data, tail_fraction=0.2).matrix
    )
    columns = band_columns(fit.model, cov, data, 0.9)
    sim = fit.model.simulate(data.experiments[0].u, data.experiments[0].y[:2])[:, 0]
    assert np.all(columns["y_lower"] <= sim) and np.all(sim <= columns["y_upper"])
    assert len(columns["y_lower"]) == len(data.to_frame())
    with pytest.raises(ModelFileError, match="no parameter covariance"):
        load_covariance(save_model(plant, tmp_path / "plain.json"))


# ----------------------------------------------------------------------------- state space
SS = {
    "A": [[0.7, 0.2], [-0.2, 0.6]],
    "B": [[1.0], [0.5]],
    "C": [[1.0, 0.3]],
    "D": [[0.0]],
}


def _ss_record(seed, n=1000, noise=0.05):
    from blockid.models import StateSpace

    plant = StateSpace(["u"], ["y"], **SS)
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n)
    y = plant.simulate(u)[:, 0] + noise * rng.standard_normal(n)
    return plant, Dataset.from_arrays(u, y, ["u"], ["y"])


def test_state_space_standard_errors_leave_out_the_state_basis():
    """A linear state-space model is unique up to an invertible T (nx^2 = 4 directions):
    the covariance is the pseudo-inverse without them, finite, in the fitted basis,
    shaped like the matrices, and the held D (no feedthrough) has standard error 0."""
    _, data = _ss_record(0)
    fit = fit_model(data, "state-space", nx=2, feedthrough=False, standard_errors=True)
    cov = fit.settings["covariance"]
    assert "(4 left out)" in cov["basis"]
    se = fit.settings["standard_errors"]
    assert set(se) == {"A", "B", "C", "D"} and np.shape(se["A"]) == (2, 2)
    assert se["D"] == [[0.0]]
    values = np.array([v for k in "ABC" for row in se[k] for v in row])
    assert np.all(np.isfinite(values)) and np.all(values > 0)
    assert json.loads(json.dumps(model_document(fit.model, fit.estimation_record())))


@pytest.mark.slow
def test_the_state_space_band_is_calibrated():
    """30 records at 26 dB: the 95 % band of the simulated output on a new input holds
    the noise-free output in 95-96 % of the samples (measured 0.955); the band's width
    matches the spread of the simulations over the records within 10 %."""
    u = np.random.default_rng(100).standard_normal(320)
    errors, stds = [], []
    for seed in range(30):
        plant, data = _ss_record(seed)
        fit = fit_model(data, "state-space", nx=2, feedthrough=False, standard_errors=True)
        cov = ParameterCovariance.from_dict(fit.settings["covariance"], fit.model.free_parameters())
        band = simulation_band(fit.model, cov, u, None, 0.95)
        truth = plant.simulate(u)[:, 0]
        errors.append((band.simulated[:, 0] - truth)[20:])  # after the start from rest
        stds.append(((band.upper - band.simulated)[:, 0] / 1.959964)[20:])
    errors, stds = np.array(errors), np.array(stds)
    assert 0.92 <= np.mean(np.abs(errors) <= 1.959964 * stds) <= 0.98
    assert np.sqrt(np.mean(stds**2)) == pytest.approx(np.sqrt(np.mean(errors**2)), rel=0.1)
