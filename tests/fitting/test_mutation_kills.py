"""Fitting paths the other fitting tests leave out (found by mutation testing, see
docs/testing.md): ARX through fit_model, what the settings record, explicit options
that override a structure's default, the scikit-learn estimators' score and names."""

import numpy as np
import pytest

from blockid.data import Dataset
from blockid.errors import DataError, ParameterError
from blockid.evaluation import evaluate
from blockid.fitting import fit_model
from blockid.fitting.arx import fit_arx
from blockid.fitting.estimator import ESTIMATORS


def _arx_data(n=200, seed=0):
    # y(t) = 0.5 y(t-1) + u(t-1), noise free
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n)
    y = np.zeros(n)
    for t in range(1, n):
        y[t] = 0.5 * y[t - 1] + u[t - 1]
    return u, y


def _dataset():
    u, y = _arx_data()
    return Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"])


def test_fit_model_fits_arx_through_the_registry():
    result = fit_model(_dataset(), "arx", na=1, nb=1, nk=1)
    np.testing.assert_allclose(
        result.model.simulate(np.ones(5))[:, 0], [0.0, 1.0, 1.5, 1.75, 1.875], atol=1e-10
    )


def test_fit_arx_settings_record_orders_and_the_covariance_only_when_given():
    data = _dataset()
    batch = fit_arx(data, na=1, nb=1, nk=1)
    assert (
        batch.settings["na"] == [[1]]
        and batch.settings["nb"] == [[1]]
        and batch.settings["nk"] == [[1]]
    )
    assert "initial_covariance" not in fit_arx(data, na=1, nb=1, nk=1, method="rls").settings
    given = fit_arx(data, na=1, nb=1, nk=1, method="rls", initial_covariance=1e4)
    assert given.settings["initial_covariance"] == 1e4


def test_fit_arx_unknown_method_lists_the_methods():
    with pytest.raises(ParameterError, match="choose one of batch, rls, aw-rls, hierarchical-rls"):
        fit_arx(_dataset(), na=1, nb=1, nk=1, method="nope")


def test_explicit_center_false_overrides_the_wiener_default():
    u, y = _arx_data()
    data = Dataset.from_arrays(u + 3.0, y + 6.0, inputs=["u"], outputs=["y"])
    kwargs = dict(na=1, nb=1, nk=1, r2=1, max_nfev=5)
    centred = fit_model(data, "wiener", **kwargs)  # the Wiener default: centre
    plain = fit_model(data, "wiener", center=False, **kwargs)
    assert centred.model.input_offset == pytest.approx(np.mean(u + 3.0))
    assert plain.model.input_offset == 0.0 and plain.model.output_offset == 0.0


def test_recursive_fitters_refuse_what_is_not_a_dataset():
    u, y = _arx_data(20)
    with pytest.raises(DataError, match="key-term RLS needs a blockid Dataset, got ndarray"):
        fit_model(u, "hammerstein", method="key-term-rls")


def test_estimator_names_and_score():
    assert {cls.__name__ for cls in ESTIMATORS.values()} >= {
        "ARXEstimator",
        "HammersteinEstimator",
        "WienerEstimator",
        "HammersteinWienerEstimator",
        "BacklashEstimator",
    }
    u, y = _arx_data()
    est = ESTIMATORS["arx"](na=1, nb=1, nk=1).fit(u, y)
    assert est.model_.inputs == ("u",) or list(est.model_.inputs) == ["u"]
    data = Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"])
    expected = evaluate(est.model_, data).metrics["fit_percent"]["y"]
    assert est.score(u, y) == pytest.approx(expected)
    assert est.score(u, y) == pytest.approx(100.0, abs=1e-6)
    named = ESTIMATORS["arx"](na=1, nb=1, nk=1).fit(u, y, inputs=["v"], outputs=["w"])
    assert list(named.model_.inputs) == ["v"] and list(named.model_.outputs) == ["w"]


def test_key_term_rls_names_a_bad_nb():
    from blockid.fitting.key_term import fit_key_term_rls

    with pytest.raises(ParameterError, match=r"^nb=0 must be a whole number >= 1"):
        fit_key_term_rls(_dataset(), structure="hammerstein", na=1, nb=0, nk=1)


def _backlash_model(a=-0.5):
    # backlash (unit slopes, c = 0.3) then x(t) = -a x(t-1) + w(t-1)
    from blockid.blocks import Backlash
    from blockid.models import BacklashModel

    return BacklashModel(
        "u", "y", input_block=Backlash(1.0, 0.3, 1.0, 0.3), na=1, nb=1, nk=1, a=[a]
    )


def _backlash_data(scale=1.0):
    # the backlash model's output, noise free, times `scale`
    truth = _backlash_model()
    rng = np.random.default_rng(0)
    u = 2.0 * np.sin(np.linspace(0.0, 12.0 * np.pi, 400)) + 0.3 * rng.standard_normal(400)
    return truth, Dataset.from_arrays(u, scale * truth.simulate(u)[:, 0], ["u"], ["y"])


def test_initial_backlash_estimate_of_a_plant_with_a_tiny_gain_is_the_scaled_one():
    # measured in units where the gain is 1e-13: every grid shape's b_0 is about 1e-13,
    # below 1e-12 in absolute terms but far from zero relative to b itself
    from blockid.fitting import initial_estimate

    truth, data = _backlash_data()
    _, tiny = _backlash_data(scale=1e-13)
    plain = initial_estimate(data, "backlash", na=1, nb=1, nk=1).parameters
    small = initial_estimate(tiny, "backlash", na=1, nb=1, nk=1).parameters
    assert plain["c_left"] == pytest.approx(0.3, abs=0.02)
    assert plain["m_left"] == pytest.approx(1.0, abs=0.03)
    for key in ("c_left", "c_right", "a"):
        np.testing.assert_allclose(small[key], plain[key], rtol=1e-9)
    for key in ("m_left", "m_right"):
        assert small[key] == pytest.approx(1e-13 * plain[key], rel=1e-9)


def test_start_score_runs_from_the_measured_initial_outputs():
    from blockid.fitting.initial import _sse

    truth, data = _backlash_data()
    u = data.experiments[0].u[:, 0]
    z = truth.simulate(u, [2.0])[:, 0]  # started away from rest: x(0) = 2
    assert _sse(truth, [u], [z]) == 0.0
    other = _backlash_model(a=-0.4)
    expected = np.sum((z[1:] - other.simulate(u, [2.0])[1:, 0]) ** 2)
    assert _sse(other, [u], [z]) == pytest.approx(expected, rel=1e-12)
    assert _sse(None, [u], [z]) == np.inf


def test_recursive_fit_settings_keep_tol_and_normalize():
    from blockid.fitting.key_term import fit_key_term_rls

    data = _dataset()
    kwargs = dict(na=1, nb=1, nk=1, passes=5, tol=1e-3, forgetting=1)
    raw = fit_key_term_rls(data, "arx", normalize=False, **kwargs)
    np.testing.assert_allclose(raw.model.parameter_vector(0), [-0.5, 1.0], atol=1e-6)
    assert raw.settings["tol"] == 1e-3
    assert raw.settings["normalize"] is False
    assert raw.settings["converged"] is True
    assert fit_key_term_rls(data, "arx", **kwargs).settings["normalize"] is True


def test_backlash_aw_rls_settings_keep_tol_only_with_several_passes():
    from blockid.fitting.backlash import fit_backlash_aw_rls

    _, data = _backlash_data()
    several = fit_backlash_aw_rls(data, na=1, nb=1, nk=1, passes=3, tol=1e-2)
    assert several.settings["tol"] == 1e-2
    assert several.settings["passes"] == 3 and several.settings["converged"] is True
    assert several.settings["normalize"] is True
    one = fit_backlash_aw_rls(data, na=1, nb=1, nk=1, passes=1, tol=1e-2)
    assert "tol" not in one.settings  # not used in one pass
    assert (
        fit_backlash_aw_rls(data, na=1, nb=1, nk=1, normalize=False).settings["normalize"] is False
    )


def test_refined_recursive_fit_keeps_the_recursion_trajectory():
    _, data = _backlash_data()
    opts = dict(method="aw-rls", na=1, nb=1, nk=1, record_history=True)
    plain = fit_model(data, "backlash", **opts)
    refined = fit_model(data, "backlash", refine=True, **opts)
    assert refined.method == "aw-rls+refine"
    for key in ("theta", "update"):
        np.testing.assert_array_equal(refined.history[key], plain.history[key])
    assert refined.history["names"] == plain.history["names"]
    assert plain.history["theta"].shape == (len(plain.history["update"]), 5)


# ----------------------------------------------------------------------------- second round
def test_rank_deficiency_from_a_constant_output_names_it_an_output():
    rng = np.random.default_rng(0)
    data = Dataset.from_arrays(rng.standard_normal(50), np.full(50, 3.0), ["u"], ["y"])
    from blockid.errors import EstimationError

    with pytest.raises(EstimationError) as info:
        fit_arx(data, na=2, nb=1, nk=1)
    assert str(info.value) == (
        "output 'y': least squares is rank deficient: the regressors y at lag 2 are (nearly) "
        "linear combinations of the others; output 'y' is constant over the estimation data "
        "(3 at every sample): a constant signal tells nothing about the dynamics and its "
        "lags repeat one another; use data in which it varies"
    )


def test_estimator_classes_carry_their_structure_and_a_docstring():
    from blockid.fitting.registry import STRUCTURES

    for name, cls in ESTIMATORS.items():
        assert cls.structure == name
        assert cls.__doc__.startswith(f"Estimator of {STRUCTURES[name].help} models")
        assert f"(structure ``{name}``)" in cls.__doc__
    doc = ESTIMATORS["hammerstein"].__doc__
    assert "Methods: simulation-error, key-term-rls (default simulation-error)." in doc


def _duffing_data(n=600):
    # noise free: y from A y = z^-1 B [u - 0.2 y^2 - y^3], nb = 2
    from blockid.blocks import Polynomial
    from blockid.blocks.linear import LinearBlock
    from blockid.models.feedback import LinearFeedback

    plant = LinearFeedback(
        "u",
        "y",
        linear=LinearBlock(2, 2, 1, a=[-1.5, 0.7], b=[0.2, 0.1]),
        feedback=Polynomial([0.0, 0.2, 1.0], constant=False),
    )
    u = np.random.default_rng(4).normal(0.0, 0.5, n)
    return plant, Dataset.from_arrays(u, plant.simulate(u), ["u"], ["y"])


def test_feedback_rank_one_candidate_recovers_b_and_c_on_noise_free_data():
    from blockid.fitting.feedback import _candidates
    from blockid.models.feedback import LinearFeedback

    plant, data = _duffing_data()
    template = LinearFeedback.template("u", "y", na=2, nb=2, nk=1, r=3)
    a, b, c = _candidates(template, data, 3)["equation error, rank one"]
    np.testing.assert_allclose(a, [-1.5, 0.7], atol=1e-8)
    np.testing.assert_allclose(b, [0.2, 0.1], atol=1e-8)
    np.testing.assert_allclose(c, [0.2, 1.0], atol=1e-7)


def test_feedback_start_counts_the_parameters_of_degree_r():
    # r = 5: a_1, b_0, c_2..c_5 = 6 parameters; 6 samples give 5 rows
    from blockid.errors import OrderError
    from blockid.fitting.feedback import initial_feedback

    _, data = _duffing_data()
    short = data.select(0, 6)
    with pytest.raises(OrderError, match=r"^feedback model r=5 has 6 parameters and needs at"):
        initial_feedback(short, na=1, nb=1, nk=1, r=5)


def test_feedback_start_that_explodes_for_every_candidate_is_reported(monkeypatch):
    import blockid.fitting.feedback as feedback
    from blockid.errors import EstimationError

    _, data = _duffing_data()
    monkeypatch.setattr(feedback, "simulation_mse", lambda model, data: float("inf"))
    with pytest.raises(EstimationError) as info:
        feedback.initial_feedback(data, na=2, nb=2, nk=1, r=3)
    assert str(info.value) == (
        "the feedback model's initial estimate explodes in free-run simulation for every "
        "candidate; try other orders (na, nb, nk) or a lower degree r"
    )


def _network_data(n=200):
    rng = np.random.default_rng(7)
    u = rng.standard_normal(n)
    v = np.zeros(n)
    for t in range(1, n):
        v[t] = 0.6 * v[t - 1] + 0.4 * u[t - 1]
    return Dataset.from_arrays(u, v, ["u"], ["v"])


def test_network_fit_records_methods_and_scores_by_simulation():
    from blockid.fitting.network import SubsystemSpec, fit_network

    spec = SubsystemSpec("S1", ["u"], ["v"], "arx", "batch", {"na": 1, "nb": 1, "nk": 1})
    fit = fit_network(_network_data(), [spec])
    assert fit.metrics_mode == "simulation"
    assert fit.settings["subsystems"]["S1"]["method"] == "batch"
    assert fit.settings["subsystems"]["S1"]["structure"] == "arx"


def test_network_option_that_does_not_fit_is_named_with_the_subsystem_options():
    # method given among the options as well as the spec's method: fit_model's TypeError
    from blockid.fitting.network import SubsystemSpec, fit_network

    opts = {"na": 1, "nb": 1, "nk": 1, "method": "rls"}
    with pytest.raises(
        ParameterError,
        match=r"^subsystem S1: an option value does not fit \(na=1 nb=1 nk=1 method=rls\): ",
    ):
        fit_network(_network_data(), [SubsystemSpec("S1", ["u"], ["v"], "arx", None, opts)])


def test_online_backlash_predicts_nothing_before_its_first_update():
    # orders na=2, nb=1, nk=1: the first update is at sample 2, as offline
    from blockid.fitting.online import online_estimator

    _, data = _backlash_data()
    u, y = data.experiments[0].u[:40], data.experiments[0].y[:40]
    whole = online_estimator("backlash", "aw-rls", {"na": 2}, "u", "y").partial_fit(u, y)
    assert np.all(np.isnan(whole.predictions_[:2])) and np.all(np.isfinite(whole.predictions_[2:]))
    single = online_estimator("backlash", "aw-rls", {"na": 2}, "u", "y")
    steps = np.array([single.update(u[k], y[k]) for k in range(len(u))])
    assert np.all(np.isnan(steps[:2])) and np.all(np.isfinite(steps[2:]))
    np.testing.assert_array_equal(steps, whole.predictions_)


def test_false_nearest_neighbour_shares_with_the_noise_allowance_by_brute_force():
    from blockid.fitting.orders import false_nearest_neighbours

    rng = np.random.default_rng(5)
    n = 90
    u = rng.standard_normal(n)
    y = np.convolve(u, [0.0, 1.0, 0.5])[:n] + 0.3 * rng.standard_normal(n)
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    r_tol, a_tol, noise = 2.0, 10.0, 0.1
    ev = false_nearest_neighbours(
        data, max_na=1, max_nb=2, max_nk=1, r_tol=r_tol, a_tol=a_tol, noise=noise,
        max_points=None, exclude=0,
    )  # fmt: skip
    us, ys = (u - u.mean()) / u.std(), (y - y.mean()) / y.std()
    lag = 2  # max(max_na, max_nk + max_nb - 1)
    for i, na in enumerate(ev.na):
        for j, nb in enumerate(ev.nb):
            for m, nk in enumerate(ev.nk):
                cols = [ys[lag - k : n - k] for k in range(1, na + 1)]
                cols += [us[lag - d : n - d] for d in range(nk, nk + nb)]
                x, out = np.column_stack(cols), ys[lag:]
                dist = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=2)
                np.fill_diagonal(dist, np.inf)
                nearest = dist.argmin(axis=1)
                dy = np.abs(out - out[nearest])
                slack = 2 * r_tol * np.sqrt(na * noise**2 + nb * noise**2) + 2 * noise
                false = (dy > r_tol * dist.min(axis=1) + slack) | (dy > a_tol)
                assert ev.percent[i, j, m] == pytest.approx(100.0 * false.mean(), abs=1e-9)
    assert ev.percent.max() > 50.0  # (0, 1, 0): a wrong order, mostly false neighbours


def test_bla_arx_start_skips_the_first_sample_even_for_a_static_gain():
    # na = 0, nb = 1, nk = 0: y(k) = b u(k); the regression still starts at k = 1
    from blockid.fitting.wiener_hammerstein import _arx

    rng = np.random.default_rng(1)
    u, y = rng.standard_normal(20), rng.standard_normal(20)
    a, b = _arx([u], [y], 0, 1, 0)
    assert a.size == 0
    assert b[0] == pytest.approx(np.dot(u[1:], y[1:]) / np.dot(u[1:], u[1:]), rel=1e-12)


def test_roots_with_a_tiny_imaginary_part_are_a_conjugate_pair():
    from blockid.fitting.wiener_hammerstein import _units

    # |imag| = 1.5e-9 > 1e-9 * max(1, |r|) for |r| = 0.5: a pair, not two real roots
    roots = np.array([0.5 + 1.5e-9j, 0.3, 0.5 - 1.5e-9j])
    units = _units(roots)
    assert [u.size for u in units] == [2, 1]
    np.testing.assert_array_equal(units[0], [0.5 + 1.5e-9j, 0.5 - 1.5e-9j])
    # within the tolerance: real
    assert [u.size for u in _units(np.array([0.5 + 0.5e-9j, 0.5 - 0.5e-9j]))] == [1, 1]
    # the tolerance grows with |r| beyond 1
    assert [u.size for u in _units(np.array([3.0 + 2e-9j, 3.0 - 2e-9j]))] == [1, 1]


def test_wiener_hammerstein_passes_gtol_to_the_refinement():
    from blockid.blocks import LinearBlock, Polynomial
    from blockid.fitting.wiener_hammerstein import fit_wiener_hammerstein
    from blockid.models import WienerHammerstein

    truth = WienerHammerstein(
        "u",
        "y",
        first=LinearBlock(1, 1, 1, a=[-0.5], b=[0.4]),
        static=Polynomial([0.0, 1.0, 0.2]),
        second=LinearBlock(1, 1, 0, a=[-0.3], b=[1.0]),
    )
    u = np.random.default_rng(0).standard_normal(400)
    data = Dataset.from_arrays(u, truth.simulate(u)[:, 0] + 0.01, ["u"], ["y"])
    kwargs = dict(na=2, nb=1, nk=1, r2=2, starts=1, tail_fraction=0.0, max_nfev=20)
    loose = fit_wiener_hammerstein(data, gtol=1e6, **kwargs)
    assert loose.settings["stop_reason"] == "`gtol` termination condition is satisfied."
    assert loose.settings["iterations"] == 0
    tight = fit_wiener_hammerstein(data, **kwargs)
    assert tight.settings["iterations"] > 0  # the default gtol lets it iterate


# ----------------------------------------------------------------------------- third round
def test_arx_with_nb_zero_for_every_input_names_the_inputs():
    from blockid.errors import OrderError

    with pytest.raises(OrderError) as info:
        fit_arx(_dataset(), na=1, nb=0, nk=1)
    assert str(info.value) == (
        "nb is 0 for every input of output 'y' ('u'): the model would not use any input "
        "(a pure autoregression that free-run simulation cannot drive); give nb >= 1, the "
        "number of coefficients of an input"
    )


def test_rank_deficiency_from_a_constant_input_names_it_an_input():
    from blockid.errors import EstimationError

    rng = np.random.default_rng(0)
    data = Dataset.from_arrays(np.full(50, 2.0), rng.standard_normal(50), ["u"], ["y"])
    with pytest.raises(EstimationError) as info:
        fit_arx(data, na=1, nb=2, nk=1)  # u(t-1) and u(t-2) are the same column
    assert "input 'u' is constant over the estimation data (2 at every sample)" in str(info.value)


def test_aw_rls_estimator_gets_both_weights():
    from blockid.fitting.arx import make_estimator

    est = make_estimator("aw-rls", eps1=2.0, eps2=0.5)
    assert (est.eps1, est.eps2, est.initial_covariance) == (2.0, 0.5, 1e5)
    # and fit_arx hands eps2 on: another floor gives other estimates on noisy data
    u, y = _arx_data()
    noisy = Dataset.from_arrays(
        u, y + 0.3 * np.random.default_rng(1).standard_normal(y.size), ["u"], ["y"]
    )
    low = fit_arx(noisy, method="aw-rls", eps2=0.1).model.parameter_vector(0)
    high = fit_arx(noisy, method="aw-rls", eps2=5.0).model.parameter_vector(0)
    assert np.max(np.abs(low - high)) > 1e-6


def test_backlash_aw_rls_divergence_limit_grows_with_the_largest_output():
    # |x_hat| beyond 1e6 (1 + max|y|) counts as divergence (the kernel's third parameter)
    from blockid.fitting.backlash import BacklashAWRLS
    from blockid.fitting.recursive import normalised_signals

    _, data = _backlash_data(scale=1e4)
    signals = normalised_signals(data, False)
    y_max = float(np.max(np.abs(data.experiments[0].y)))
    assert signals.y_max == y_max > 1e3
    algorithm = BacklashAWRLS((1, 1, 1), (10.0, 0.1), signals)
    np.testing.assert_allclose(algorithm.params, [10.0, 0.1, 1e6 * (1.0 + y_max)], rtol=1e-15)


def test_estimator_without_outputs_says_what_to_give():
    u, _ = _arx_data()
    with pytest.raises(DataError) as info:
        ESTIMATORS["arx"](na=1, nb=1, nk=1).fit(u)
    assert str(info.value) == "give a Dataset, or the input array and the output array"


def test_estimator_simulate_passes_the_initial_outputs():
    u, y = _arx_data()
    est = ESTIMATORS["arx"](na=1, nb=1, nk=1).fit(u, y)
    sim = est.simulate(np.ones(4), [2.0])
    np.testing.assert_allclose(sim[:, 0], [2.0, 2.0, 2.0, 2.0], atol=1e-10)  # 0.5*2 + 1


def test_feedback_fit_records_the_time_of_the_initial_estimate():
    from blockid.fitting.feedback import fit_feedback

    _, data = _duffing_data(300)
    fit = fit_feedback(data, na=2, nb=2, nk=1, r=3, max_nfev=2)
    assert fit.history["initial_seconds"] >= 0.0


def test_hammerstein_wiener_first_candidate_is_the_linear_fit():
    from blockid.fitting.initial import (
        _linear_start,
        _signals,
        _template,
        _with_output_block,
    )
    from blockid.models import HammersteinWiener

    u, y = _arx_data()
    data = Dataset.from_arrays(u, y + 0.1 * y**3, ["u"], ["y"])
    template = _template(HammersteinWiener, data, 1, 2, 1, 3, 3, None, None)
    start = _linear_start(*_signals(data), template)
    first = _with_output_block(data, template)[0]
    np.testing.assert_array_equal(first.linear.a, start[1])
    np.testing.assert_array_equal(first.linear.b, start[2])


def test_key_term_rls_settings_record_r1():
    from blockid.fitting.key_term import fit_key_term_rls

    u, y = _arx_data()
    data = Dataset.from_arrays(u, y + 0.2 * y**2, ["u"], ["y"])
    fit = fit_key_term_rls(data, "hammerstein", na=1, nb=1, nk=1, r1=2)
    assert fit.settings["r1"] == 2 and "r2" not in fit.settings


def test_online_update_refuses_a_missing_output_sample():
    from blockid.fitting.online import online_estimator

    est = online_estimator("arx", "rls", {}, ["u"], ["y"])
    with pytest.raises(DataError, match="^the chunk contains NaN or inf"):
        est.update(1.0, np.nan)
    assert est.n_samples == 0


def test_online_arx_takes_its_orders_from_the_initial_model():
    from blockid.fitting.online import online_estimator
    from blockid.models import ARX

    initial = ARX(["u"], ["y"], 2, 1, 1, a={"y": {"y": [-0.5, 0.1]}}, b={"y": {"u": [1.0]}})
    est = online_estimator("arx", "rls", {"initial": initial}, ["u"], ["y"])
    assert est.template.na.tolist() == [[2]] and est.template.nb.tolist() == [[1]]
    np.testing.assert_allclose(est.model().parameter_vector(0), [-0.5, 0.1, 1.0])


def test_online_key_term_names_a_bad_initial_covariance():
    from blockid.fitting.online import online_estimator

    with pytest.raises(ParameterError, match="^initial_covariance must be > 0, got -1"):
        online_estimator("hammerstein", "key-term-rls", {"initial_covariance": -1}, "u", "y")


def test_online_backlash_step_that_diverges_names_the_method():
    from blockid.errors import EstimationError
    from blockid.fitting.online import online_estimator

    est = online_estimator("backlash", "aw-rls", {}, ["u"], ["y"])
    est.update(0.1, 0.1)
    est.update(1.0, 0.5)
    with pytest.raises(EstimationError) as info:
        est.update(1e12, 0.0)
    assert str(info.value).startswith(
        "AW-RLS diverged at sample 2 (counted from the first sample learned online): the "
        "estimated backlash output x exceeded 1e6 (1 + max|v|)."
    )


def test_order_test_names_the_bad_option():
    from blockid.fitting.orders import false_nearest_neighbours

    with pytest.raises(ParameterError, match=r"^max_na must be an integer >= 0, got -1") as info:
        false_nearest_neighbours(_dataset(), max_na=-1)
    assert info.value.parameter == "max_na"


def test_empty_trajectory_has_one_column_per_parameter():
    from blockid.fitting.recursive import _Trajectory

    theta, update = _Trajectory(5, 1).arrays()
    assert theta.shape == (0, 5) and update.shape == (0,)


def test_tail_is_kept_when_the_head_holds_one_sample_for_one_parameter():
    from blockid.fitting.simulation_error import _segments

    u = np.arange(10.0)
    data = Dataset.from_arrays(u, u, ["u"], ["y"])
    # N = 10, tail 5, n0 = 4: a head of 1 sample holds 1 parameter
    assert [s.n_fit for s in _segments(data, 4, 0.5, 1)] == [5]
    assert [s.n_fit for s in _segments(data, 4, 0.5, 2)] == [10]


def test_wiener_hammerstein_records_the_bla():
    from blockid.blocks import LinearBlock, Polynomial
    from blockid.fitting.wiener_hammerstein import fit_wiener_hammerstein
    from blockid.models import WienerHammerstein

    truth = WienerHammerstein(
        "u",
        "y",
        first=LinearBlock(1, 1, 1, a=[-0.5], b=[0.4]),
        static=Polynomial([0.0, 1.0, 0.2]),
        second=LinearBlock(1, 1, 0, a=[-0.3], b=[1.0]),
    )
    u = np.random.default_rng(0).standard_normal(300)
    data = Dataset.from_arrays(u, truth.simulate(u)[:, 0], ["u"], ["y"])
    fit = fit_wiener_hammerstein(data, na=2, nb=1, nk=1, r2=2, starts=1, max_nfev=3)
    bla = fit.settings["bla"]
    assert (bla["na"], bla["nb"], bla["nk"]) == (2, 1, 1)
    assert 0.0 < bla["simulation_mse"] < np.var(data.experiments[0].y)


def test_online_arx_names_the_sample_where_the_estimate_overflows():
    from blockid.errors import EstimationError
    from blockid.fitting.online import online_estimator

    est = online_estimator("arx", "rls", {}, ["u"], ["y"])
    with pytest.raises(EstimationError) as info:
        est.partial_fit(np.array([1.0, 2.0, 1e200, 1.0]), np.array([0.5, 1.0, 2.0, 1e200]))
    assert str(info.value).startswith(
        "RLS of output 'y' diverged at sample 3 (counted from the first sample learned online)"
    )
    assert info.value.sample == 3 and est.n_samples == 0


def test_bla_arx_with_a_zero_regressor_column_reports_rank_deficiency():
    # u is 0 up to its last sample: the column u(t-1) is all zero (its scale is set to 1)
    from blockid.errors import EstimationError
    from blockid.fitting.wiener_hammerstein import _arx

    u = np.zeros(20)
    u[-1] = 1.0
    y = np.random.default_rng(0).standard_normal(20)
    with pytest.raises(EstimationError, match=r"^least squares is rank deficient: regressor col"):
        _arx([u], [y], 1, 1, 1)
