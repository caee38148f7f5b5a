"""ModelOutput.to_dict, the JSON summary every command prints, key by key; the warnings
of a network's subsystems and of a single model; data one sample too short; standard
errors and the simulation band on small models with known numbers (gaps found by mutation
testing, see docs/testing.md)."""

import numpy as np
import pytest

from blockid.blocks import Polynomial
from blockid.data import Dataset
from blockid.errors import OrderError
from blockid.evaluation import evaluate
from blockid.models import ARX, Hammerstein, Network


def test_to_dict_is_the_documented_summary():
    # y(t) = u(t-1) exactly: every error is zero and the fit is 100 %
    u = np.array([1.0, -1.0, 2.0, 0.0, 3.0])
    y = np.concatenate([[0.0], u[:-1]])
    data = Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"])
    model = ARX(["u"], ["y"], 0, 1, 1, b={"y": {"u": [1.0]}})
    out = evaluate(model, data).to_dict()
    assert list(out) == [
        "mode",
        "n_samples",
        "initial_samples_per_experiment",
        "metrics",
        "warnings",
    ]
    assert out["mode"] == "simulation"
    assert out["n_samples"] == 5
    assert out["initial_samples_per_experiment"] == model.max_lag
    assert out["metrics"]["mse"] == {"y": 0.0}
    assert out["metrics"]["fit_percent"] == {"y": 100.0}
    assert out["warnings"] == []
    assert evaluate(model, data, "one-step").to_dict()["mode"] == "one-step"


_LEAVES = (
    "input 'u1' leaves the range seen in estimation [-1, 1] in 1 of 6 samples (by up to "
    "100 % of that range): the model extrapolates there (along the block's tangent at the "
    "range's end) (experiment 'experiment 1')"
)


def _two_subsystems():
    # S1: w = u + 0.5 u^2 (polynomial, fitted on u in [-1, 1]), v1(t) = 0.5 v1(t-1) + w(t-1)
    # S2: y(t) = 0.3 y(t-1) + 2 v1(t-1), fed by S1 only
    s1 = Hammerstein(
        "u1", "v1", input_block=Polynomial([0.0, 1.0, 0.5]), na=1, nb=1, nk=1, a=[-0.5]
    ).replace(ranges={"u": [-1.0, 1.0]})
    s2 = ARX(["v1"], ["y"], 1, 1, 1, a={"y": {"y": [-0.3]}}, b={"y": {"v1": [2.0]}})
    return s1, s2


U1 = np.array([0.0, 0.5, 3.0, 0.0, -0.5, 0.0])  # 3 lies beyond [-1, 1] by its width


def test_network_warnings_name_the_subsystem_that_extrapolates():
    s1, s2 = _two_subsystems()
    net = Network([("S1", s1), ("S2", s2)])
    y = net.simulate(U1)
    # beyond u = 1 the polynomial continues along its tangent: w(3) = 1.5 + 2 * 2 = 5.5
    np.testing.assert_allclose(y[:, 0], [0.0, 0.0, 0.625, 5.8125, 2.90625, 1.078125])
    data = Dataset.from_arrays(U1, y, inputs=["u1"], outputs=["v1", "y"])
    out = evaluate(net, data)
    assert out.warnings == [f"S1: {_LEAVES}"]
    assert out.metrics["fit_percent"] == {"v1": 100.0, "y": 100.0}


def test_single_model_warnings_have_no_subsystem_prefix():
    s1, _ = _two_subsystems()
    data = Dataset.from_arrays(U1, s1.simulate(U1), inputs=["u1"], outputs=["v1"])
    assert evaluate(s1, data).warnings == [_LEAVES]


def test_too_short_data_name_the_model_and_the_shortest_length_passes():
    # y(t) = 0.5 y(t-1) - 0.25 y(t-2) + u(t-1): looks back 2 samples
    model = ARX(["u"], ["y"], 2, 1, 1, a={"y": {"y": [-0.5, 0.25]}}, b={"y": {"u": [1.0]}})
    u, y = np.array([1.0, 2.0, 0.0]), np.array([0.5, -1.0, 1.625])
    too_short = Dataset.from_arrays(u[:2], y[:2], inputs=["u"], outputs=["y"])
    with pytest.raises(OrderError) as info:
        evaluate(model, too_short)
    assert str(info.value).startswith(
        "the arx model looks back 2 samples, so it needs more than 2 samples in every "
        "experiment, but experiment 'experiment 1' has only 2"
    )
    # three samples leave one to score: y(2) = 0.5 (-1) - 0.25 (0.5) + 2 = 1.375
    out = evaluate(model, Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"]))
    assert out.skip == 2
    np.testing.assert_allclose(out.outputs[0][:, 0], [0.5, -1.0, 1.375])
    assert out.metrics["mse"] == {"y": pytest.approx(0.0625)}


# ---------------------------------------------------------------- uncertainty
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
    from blockid.evaluation.uncertainty import _output_sensitivities
    from blockid.fitting.simulation_error import simulate_with_sensitivities

    # the ARX model's central differences equal the output-error model's analytic
    # derivatives with respect to the same (a_1, b_0), sign included
    y, dy = _output_sensitivities(_arx(), _U, [2.0], ["a_1", "b_0"])
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


# ----------------------------------------------------------------- second mutation round
def test_undefined_notes_say_why_for_every_metric():
    from blockid.evaluation.metrics import undefined_notes

    notes = undefined_notes({"mse": {"y": float("nan")}, "fit_percent": {"y": 5.0}})
    assert notes == ["mse of output 'y' is undefined (null): not defined on these samples"]


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
    from blockid.evaluation.uncertainty import _output_sensitivities

    # y(t) = 0.999 y(t-1) + u(t-1): dy/da follows s(t) = -y(t-1) - a s(t-1) exactly; the
    # central difference (step 1e-6 for |a| < 1) is off by its O(h^2) term, 4e-7 relative
    # here (a step of 2e-6 would be 1.6e-6)
    a, n = -0.999, 3000
    u = np.random.default_rng(0).uniform(-1, 1, n)
    model = ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [a]}}, b={"y": {"u": [1.0]}})
    y, dy = _output_sensitivities(model, u, [0.0], [])
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
