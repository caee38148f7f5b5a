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


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
# Standard errors and the band on small models whose every number is known: an
# output-error model y(t) = 0.5 y(t-1) + u(t-1) and the same as an ARX model (gaps found
# by mutation testing, see docs/testing.md). The offsets are 0, so none of these models
# counts as centred on its data.
_U = np.array([1.0, 0.0, 2.0, -1.0, 0.5, 0.0, 1.0, 3.0, -2.0, 1.0,
               0.0, -1.0, 2.0, 1.0, -0.5, 0.0, 1.5, -1.0, 0.5, 2.0])  # fmt: skip


_D = np.array([0.0, 0.1, -0.2, 0.05, 0.3, -0.1, 0.0, 0.2, -0.3, 0.1,
               0.15, -0.05, 0.25, -0.2, 0.1, 0.0, -0.1, 0.2, 0.05, -0.15])  # fmt: skip


def _oe(a=-0.5, b=1.0):
    from blockid.models import OutputError

    return OutputError("u", "y", na=1, nb=1, nk=1, a=[a], b=[b])


def _oe_data():
    # the model's free run from y(0) = 2 plus a known disturbance (0 at the start)
    return Dataset.from_arrays(_U, _oe().simulate(_U, [2.0])[:, 0] + _D, ["u"], ["y"])


def _oe_jacobian(stop):
    # d y_hat / d (a_1, b_0) on rows 1 .. stop - 1 by central differences, from y(0) = 2
    cols = []
    for da, db in ((1e-6, 0.0), (0.0, 1e-6)):
        up = _oe(-0.5 + da, 1.0 + db).simulate(_U[:stop], [2.0])[1:stop, 0]
        down = _oe(-0.5 - da, 1.0 - db).simulate(_U[:stop], [2.0])[1:stop, 0]
        cols.append((up - down) / 2e-6)
    return np.column_stack(cols)


def test_output_error_covariance_is_sigma2_times_the_inverse_gram_matrix():
    from blockid.evaluation.uncertainty import parameter_covariance

    cov = parameter_covariance(_oe(), _oe_data())
    sigma2 = float(_D[1:] @ _D[1:]) / 17  # 19 residuals (y(0) starts the run), 2 parameters
    J = _oe_jacobian(20)
    assert cov.names == ["a_1", "b_0"]
    np.testing.assert_array_equal(cov.estimate, [-0.5, 1.0])
    assert cov.degrees_of_freedom == 17
    assert cov.noise_variance == {"y": pytest.approx(sigma2, rel=1e-12)}
    np.testing.assert_allclose(cov.matrix, sigma2 * np.linalg.inv(J.T @ J), rtol=1e-6)
    assert cov.basis == "free-run simulation Jacobian (output-error noise model)"


def test_the_held_out_tail_is_left_out_unless_too_little_would_remain():
    from blockid.evaluation.uncertainty import parameter_covariance

    # a quarter of 20 samples held out: rows 1..14 remain, 14 - 2 degrees of freedom
    cov = parameter_covariance(_oe(), _oe_data(), tail_fraction=0.25)
    assert cov.degrees_of_freedom == 12
    assert cov.noise_variance["y"] == pytest.approx(float(_D[1:15] @ _D[1:15]) / 12, rel=1e-12)
    J = _oe_jacobian(15)
    np.testing.assert_allclose(
        cov.matrix, cov.noise_variance["y"] * np.linalg.inv(J.T @ J), rtol=1e-6
    )
    # 10 samples, 8 held out would leave 1 row for 2 parameters: nothing is held out
    short = Dataset.from_arrays(_U[:10], _oe_data().experiments[0].y[:10, 0], ["u"], ["y"])
    cov = parameter_covariance(_oe(), short, tail_fraction=0.8)
    assert cov.degrees_of_freedom == 7
    assert cov.noise_variance["y"] == pytest.approx(float(_D[1:10] @ _D[1:10]) / 7, rel=1e-12)


@pytest.mark.parametrize(
    ("method", "suffix"),
    [
        (None, ""),
        ("simulation-error", ""),
        ("key-term-rls+refine", ""),
        ("key-term-rls", ", at the key-term-rls estimate"),
    ],
)
def test_the_basis_names_the_estimate_a_covariance_is_taken_at(method, suffix):
    from blockid.evaluation.uncertainty import parameter_covariance

    cov = parameter_covariance(_oe(), _oe_data(), method)
    assert cov.basis == "free-run simulation Jacobian (output-error noise model)" + suffix


def test_a_simulation_that_blows_up_has_no_standard_errors():
    from blockid.errors import DataError
    from blockid.evaluation.uncertainty import parameter_covariance

    data = Dataset.from_arrays(np.ones(2000), np.ones(2000), ["u"], ["y"])
    with pytest.raises(DataError) as info:
        parameter_covariance(_oe(a=-2.0), data)  # pole at 2: overflows
    assert str(info.value) == "the model's simulation on the data is not finite: no standard errors"


def test_data_with_other_signals_are_refused_by_name():
    from blockid.errors import DataError
    from blockid.evaluation.uncertainty import parameter_covariance

    data = Dataset.from_arrays(_U, _U, ["u"], ["z"])
    with pytest.raises(DataError) as info:
        parameter_covariance(_oe(), data)
    assert str(info.value) == (
        "the model maps ['u'] to ['y'] but the data have inputs ['u'] and outputs ['z']"
    )


def _arx():
    return ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [-0.5]}}, b={"y": {"u": [1.0]}})


def test_arx_covariance_records_estimate_basis_and_degrees_of_freedom():
    from blockid.evaluation.uncertainty import parameter_covariance

    # equation error _D: y(t) = 0.5 y(t-1) + u(t-1) + d(t)
    y = np.zeros(20)
    y[0] = 2.0
    for k in range(1, 20):
        y[k] = 0.5 * y[k - 1] + _U[k - 1] + _D[k]
    data = Dataset.from_arrays(_U, y, ["u"], ["y"])
    cov = parameter_covariance(_arx(), data)
    np.testing.assert_array_equal(cov.estimate, [-0.5, 1.0])
    assert cov.degrees_of_freedom == 17
    assert cov.noise_variance == {"y": pytest.approx(float(_D[1:] @ _D[1:]) / 17, rel=1e-12)}
    phi = np.column_stack([-y[:-1], _U[:-1]])
    np.testing.assert_allclose(
        cov.matrix, cov.noise_variance["y"] * np.linalg.inv(phi.T @ phi), rtol=1e-9
    )
    assert cov.basis == "least squares, sigma^2 (Phi^T Phi)^-1"
    assert parameter_covariance(_arx(), data, "rls").basis == (
        "least squares, sigma^2 (Phi^T Phi)^-1 at the final rls estimate "
        "(the recursion's P is not kept)"
    )


def test_too_few_residuals_for_the_parameters_are_refused_with_the_counts():
    from blockid.errors import DataError
    from blockid.evaluation.uncertainty import parameter_covariance

    data = Dataset.from_arrays(_U[:3], _U[:3], ["u"], ["y"])  # 2 regression rows
    with pytest.raises(DataError) as info:
        parameter_covariance(_arx(), data)
    assert str(info.value) == (
        "2 residual sample(s) for 2 parameter(s): too few to estimate the noise variance "
        "and the parameters' standard errors"
    )


def test_an_arx_model_without_parameters_has_an_empty_covariance_and_a_zero_band():
    from blockid.evaluation.uncertainty import parameter_covariance, simulation_band

    model = ARX(["u"], ["y"], 0, 0, 1)  # y = 0
    cov = parameter_covariance(model, Dataset.from_arrays(_U, _U, ["u"], ["y"]))
    assert cov.names == [] and cov.matrix.shape == (0, 0) and cov.noise_variance == {}
    assert cov.degrees_of_freedom == 0
    assert cov.to_dict()["degrees_of_freedom"] == 0
    band = simulation_band(model, cov, _U)
    np.testing.assert_array_equal(band.simulated, np.zeros((20, 1)))
    np.testing.assert_array_equal(band.std, np.zeros((20, 1)))
    np.testing.assert_array_equal(band.upper, np.zeros((20, 1)))


def test_a_direction_below_the_relative_rank_tolerance_is_unidentifiable():
    from blockid.evaluation.uncertainty import _least_squares_covariance

    # unit columns at an angle of sqrt(2) 1e-10: singular values sqrt(2) and 1e-10, the
    # smaller one below 1e-10 times the larger (it would pass 1e-10 / sqrt(2))
    J = np.array([[1.0, 1.0], [0.0, np.sqrt(2.0) * 1e-10], [0.0, 0.0]])
    cov, sigma2, dof = _least_squares_covariance(J, np.array([1.0, 2.0, 2.0]))
    assert (sigma2, dof) == (9.0, 1)
    assert np.all(np.isinf(cov))


def test_an_unexcited_parameter_has_infinite_rows_and_columns():
    from blockid.evaluation.uncertainty import _least_squares_covariance

    J = np.array([[1.0, 0.0], [2.0, 0.0], [2.0, 0.0]])  # the second parameter does nothing
    cov, sigma2, dof = _least_squares_covariance(J, np.array([1.0, 2.0, 2.0]))
    assert (sigma2, dof) == (9.0, 1)  # both columns count as parameters
    assert cov[0, 0] == pytest.approx(9.0 / 9.0)
    assert np.isposinf(cov[0, 1]) and np.isposinf(cov[1, 0]) and np.isposinf(cov[1, 1])


def test_arx_sensitivities_by_differences_are_the_derivatives():
    from blockid.fitting.simulation_error import simulate_with_sensitivities

    # the ARX model's central differences equal the output-error model's analytic
    # derivatives with respect to the same (a_1, b_0), sign included
    y, dy = _arx().output_sensitivities(_U, [2.0])
    y_oe, dy_oe = simulate_with_sensitivities(_oe(), _U, [2.0])
    assert dy.shape == (20, 1, 2)
    np.testing.assert_allclose(y[:, 0], y_oe, atol=1e-12)
    np.testing.assert_allclose(dy[:, 0, :], dy_oe, rtol=1e-6, atol=1e-9)


def test_the_arx_band_starts_from_the_measured_outputs():
    from blockid.evaluation.uncertainty import simulation_band

    band = simulation_band(_arx(), np.diag([1e-4, 2e-4]), _U[:8], [2.0])
    np.testing.assert_allclose(
        band.simulated[:, 0], [2.0, 2.0, 1.0, 2.5, 0.25, 0.625, 0.3125, 1.15625]
    )


def test_a_band_level_of_0_is_refused():
    from blockid.errors import ParameterError
    from blockid.evaluation.uncertainty import simulation_band

    with pytest.raises(ParameterError) as info:
        simulation_band(_oe(), np.eye(2), _U, level=0.0)
    assert str(info.value).startswith("level must be between 0 and 1, got 0.0")


def test_a_matrix_as_json_stores_it_gives_an_infinite_band_for_null_entries():
    from blockid.evaluation.uncertainty import simulation_band

    band = simulation_band(_oe(), [[None, 0.0], [0.0, 1e-4]], _U)  # null: infinite
    assert np.all(np.isposinf(band.std)) and np.all(np.isneginf(band.lower))
    band = simulation_band(_oe(), [[0, 0], [0, 0]], _U)  # integers are numbers
    np.testing.assert_array_equal(band.std, np.zeros((20, 1)))


def test_band_columns_use_the_level_given():
    from blockid.evaluation.uncertainty import band_columns, simulation_band

    cov = np.array([[1e-3, 2e-4], [2e-4, 4e-3]])
    columns = band_columns(_oe(), cov, _oe_data(), level=0.5)
    band = simulation_band(_oe(), cov, _U, [2.0], level=0.5)
    z = 0.6744897501960817  # the 75 % quantile of N(0, 1)
    np.testing.assert_allclose(columns["y_upper"], band.simulated[:, 0] + z * band.std[:, 0])
    np.testing.assert_allclose(columns["y_lower"], band.simulated[:, 0] - z * band.std[:, 0])


def test_a_covariance_read_back_without_an_estimate_has_one_nan_per_parameter():
    from blockid.evaluation.uncertainty import ParameterCovariance, parameter_covariance

    doc = parameter_covariance(_oe(), _oe_data()).to_dict()
    back = ParameterCovariance.from_dict(doc)
    assert back.estimate.shape == (2,) and np.all(np.isnan(back.estimate))
    np.testing.assert_array_equal(ParameterCovariance.from_dict(doc, [1.0, 2.0]).estimate, [1, 2])


def test_effective_samples_of_lag_one_correlated_residuals():
    from blockid.evaluation.uncertainty import _effective_samples

    # centre 0, power 6, lag-1 products 1 + 1 - 1 + 1 + 1 = 3: rho = 0.5, N (0.5 / 1.5)
    r = np.array([1.0, 1.0, 1.0, -1.0, -1.0, -1.0])
    assert _effective_samples([r], 6) == pytest.approx(2.0, rel=1e-12)
    assert _effective_samples([r], 9) == pytest.approx(3.0, rel=1e-12)


def test_fitted_rows_keep_the_tail_while_one_row_is_left_for_one_parameter():
    from blockid.evaluation.uncertainty import _fitted_rows

    assert _fitted_rows(10, 0, 1, 0.9) == 1  # 10 - 9 - 0 = 1 row >= 1 parameter
    assert _fitted_rows(10, 1, 1, 0.9) == 10  # no row left: the tail is fitted too
    assert _fitted_rows(10, 0, 0, 0.9) == 1


def _offset_arx_data():
    # y(t) = u(t-1) + 0.5: the simulation (no offsets) misses it by 0.5 at every sample
    u = np.array([1.0, -1.0, 2.0, 0.0, 3.0, -2.0])
    y = np.concatenate([[0.5], u[:-1] + 0.5])
    model = ARX(["u"], ["y"], 0, 1, 1, b={"y": {"u": [1.0]}})
    return model, Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"])


def test_arx_offsets_bias_is_minus_the_mean_simulation_error():
    from blockid.evaluation.uncertainty import _arx_offsets

    model, data = _offset_arx_data()
    out = _arx_offsets(model, data, {"y": 0.6})
    assert out == {"y": {"variance": pytest.approx(0.1, rel=1e-12), "bias": -0.5}}
    # an output without a noise variance has none
    assert _arx_offsets(model, data, {}) == {"y": {"variance": 0.0, "bias": -0.5}}


def test_arx_offsets_of_an_integrator_have_infinite_variance():
    from blockid.evaluation.uncertainty import _arx_offsets

    u = np.array([1.0, -1.0, 2.0, 0.0, 3.0, -2.0])
    y = np.zeros(6)
    for k in range(1, 6):  # y(t) = y(t-1) + u(t-1): A(1) = 0
        y[k] = y[k - 1] + u[k - 1]
    data = Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"])
    model = ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [-1.0]}}, b={"y": {"u": [1.0]}})
    out = _arx_offsets(model, data, {"y": 1.0})
    assert out["y"]["variance"] == np.inf
    assert out["y"]["bias"] == 0.0


def test_with_standard_errors_follows_the_fits_center_setting():
    from blockid.evaluation.uncertainty import with_standard_errors
    from blockid.fitting.result import FitResult

    model, data = _offset_arx_data()
    base = {"estimation_metrics": {}, "n_samples": 6}
    on = with_standard_errors(FitResult(model, "arx", {"center": True}, **base), data)
    # sigma^2 = 5 rows * 0.5^2 / (5 - 1) = 0.3125; its mean over N = 6 samples
    offsets = on.settings["covariance"]["offsets"]
    assert offsets == {"y": {"variance": pytest.approx(0.3125 / 6, rel=1e-12), "bias": -0.5}}
    off = with_standard_errors(FitResult(model, "arx", {"center": False}, **base), data)
    assert "offsets" not in off.settings["covariance"]


def test_free_positions_of_a_saturation_keep_its_knees_ordered():
    from blockid.blocks import Saturation
    from blockid.evaluation.uncertainty import _free_positions, named_standard_errors

    model = Hammerstein("u", "y", input_block=Saturation(-1.0, 1.0), na=1, nb=1, nk=1, a=[-0.5])
    assert _free_positions(model) == [0, 1, 2, 3]  # b_0 = 1 (index 4) is fixed
    se = named_standard_errors(model, np.diag([1.0, 4.0, 9.0, 16.0]))
    assert se == {"lower": 1.0, "upper": 2.0, "slope": 3.0, "a": [4.0], "b": [0.0]}


def test_load_covariance_without_one_names_the_file_and_the_remedy(tmp_path):
    from blockid.errors import ModelFileError
    from blockid.evaluation.uncertainty import load_covariance

    path = tmp_path / "none.json"
    path.write_text("{}", encoding="utf-8")
    with pytest.raises(ModelFileError) as info:
        load_covariance(path)
    assert str(info.value) == (
        f"{path} holds no parameter covariance: fit the model with standard errors "
        "to get a confidence band"
    )


def test_covariance_names_a_block_whose_parameters_are_not_all_in_its_vector():
    from blockid.blocks.base import StaticBlock
    from blockid.evaluation.uncertainty import parameter_covariance

    class _Tanh(StaticBlock):  # "width" is a parameter but not in the vector
        def __init__(self, limit: float = 1.0, width: float = 2.0) -> None:
            self.limit, self.width = float(limit), float(width)

        @property
        def parameters(self):
            return {"limit": self.limit, "width": self.width}

        def to_vector(self):
            return np.array([self.limit])

        def with_vector(self, theta):
            return type(self)(float(np.asarray(theta).reshape(-1)[0]), self.width)

        def __call__(self, x):
            return self.limit * np.tanh(np.asarray(x, dtype=float) / self.width)

    model = Hammerstein("u", "y", input_block=_Tanh(), na=1, nb=1, nk=1, a=[-0.5])
    rng = np.random.default_rng(0)
    u = rng.uniform(-2, 2, 60)
    y = model.simulate(u, [0.0])[:, 0] + 0.01 * rng.standard_normal(60)
    cov = parameter_covariance(model, Dataset.from_arrays(u, y, ["u"], ["y"]))
    assert cov.names == ["theta_0", "theta_1"]
    assert cov.matrix.shape == (2, 2) and np.all(np.isfinite(cov.matrix))


def test_arx_band_sensitivity_matches_the_exact_one_for_a_slow_pole():
    # y(t) = 0.999 y(t-1) + u(t-1): dy/da follows s(t) = -y(t-1) - a s(t-1) exactly; the
    # central difference (step 1e-6 for |a| < 1) is off by its O(h^2) term, 4e-7 relative
    # here (a step of 2e-6 would be 1.6e-6)
    a, n = -0.999, 3000
    u = np.random.default_rng(0).uniform(-1, 1, n)
    model = ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [a]}}, b={"y": {"u": [1.0]}})
    y, dy = model.output_sensitivities(u, [0.0])
    assert y.shape == (n, 1) and dy.shape == (n, 1, 2)
    s_a, s_b = np.zeros(n), np.zeros(n)
    for t in range(1, n):
        s_a[t] = -y[t - 1, 0] - a * s_a[t - 1]
        s_b[t] = u[t - 1] - a * s_b[t - 1]
    assert np.max(np.abs(dy[:, 0, 0] - s_a)) < 8e-7 * np.max(np.abs(s_a))
    np.testing.assert_allclose(dy[:, 0, 1], s_b, rtol=1e-6, atol=1e-9)


def test_free_positions_keep_close_knees_apart():
    from blockid.blocks import Saturation
    from blockid.evaluation.uncertainty import _free_positions, named_standard_errors

    # knees 1e-13 apart: the moves must be small enough to keep lower < upper
    model = Hammerstein("u", "y", input_block=Saturation(0.0, 1e-13), na=1, nb=1, nk=1, a=[-0.5])
    assert _free_positions(model) == [0, 1, 2, 3]
    se = named_standard_errors(model, np.diag([1.0, 4.0, 9.0, 16.0]))
    assert se == {"lower": 1.0, "upper": 2.0, "slope": 3.0, "a": [4.0], "b": [0.0]}


def test_a_band_of_a_model_without_sensitivities_is_refused_by_name():
    """simulation_band asks the model for its output sensitivities; a network of
    subsystems gives none, and gets a ParameterError naming it, not an AttributeError."""
    from blockid.evaluation.uncertainty import simulation_band
    from blockid.models import ARX, Network

    net = Network(
        [
            ("A", ARX(["u"], ["v"], 1, 1, 1, a={"v": {"v": [-0.5]}}, b={"v": {"u": [1.0]}})),
            ("B", ARX(["v"], ["y"], 1, 1, 1, a={"y": {"y": [-0.3]}}, b={"y": {"v": [2.0]}})),
        ]
    )
    with pytest.raises(ParameterError, match="Network gives no output sensitivities"):
        simulation_band(net, np.eye(4), np.zeros((50, 1)))
