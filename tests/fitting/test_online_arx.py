"""The online ARX learners (fitting/online_arx.py: RLS, AW-RLS, hierarchical RLS, several
channels): any chunking ends where the offline one-pass fit ends, held samples are rows
left out, divergence rolls every output back."""

import numpy as np
import pytest

from blockid.data import Dataset
from blockid.errors import EstimationError
from blockid.fitting.arx import fit_arx
from blockid.fitting.online import online_estimator
from blockid.models import ARX
from fitting.online_cases import (
    ARX_METHODS,
    ARX_ORDERS,
    TITO,
    _dataset,
    _record,
    _same,
    _three_ways,
    _vector,
)


# ---------------------------------------------------------------------- equivalence
@pytest.mark.parametrize("method", list(ARX_METHODS))
def test_arx_any_chunking_equals_the_offline_one_pass_fit(method):
    options = {**ARX_ORDERS, **ARX_METHODS[method]}
    u, y = _record(TITO, 1500, noise=0.01)
    data = _dataset(TITO, u, y)
    offline = fit_arx(data, method=method, scaling="none", max_mse_ratio=None, **options).model
    reference = np.concatenate([offline.parameter_vector(i) for i in range(2)])
    estimates = _three_ways("arx", method, options, TITO, u, y)
    _same(estimates, reference)
    assert isinstance(estimates[0].model(), ARX)
    assert np.max(np.abs(reference - np.concatenate([TITO.parameter_vector(i) for i in range(2)])))
    assert estimates[0].parameters() == offline.to_dict()["parameters"]


def test_arx_with_given_scales_equals_fit_arx_with_those_scales():
    options = {**ARX_ORDERS, "forgetting": 0.995, "initial_covariance": 1e3}
    u, y = _record(TITO, 800, amplitude=50.0, noise=0.5)
    scales = ([40.0, 30.0], [60.0, 70.0])
    data = _dataset(TITO, u, y)
    offline = fit_arx(data, method="rls", scaling=scales, max_mse_ratio=None, **options).model
    reference = np.concatenate([offline.parameter_vector(i) for i in range(2)])
    online = {**options, "input_scale": scales[0], "output_scale": scales[1]}
    _same(_three_ways("arx", "rls", online, TITO, u, y), reference)
    raw = fit_arx(data, method="rls", scaling="none", max_mse_ratio=None, **options).model
    assert not np.array_equal(raw.parameter_vector(0), offline.parameter_vector(0))


def test_arx_divergence_rolls_back_every_output():
    u, y = _record(TITO, 200, noise=0.01)
    y[150, 1] = 1e300  # only output y2's recursion fails (y1's regressor has no y2 lag)
    orders = {**ARX_ORDERS, "na": [[2, 0], [1, 2]]}
    online = online_estimator("arx", "rls", orders, ["u1", "u2"], ["y1", "y2"])
    online.partial_fit(u[:100], y[:100])
    good = _vector(online)
    # sample 150 only throws theta far; its square in the regressor of 151 overflows
    with pytest.raises(EstimationError, match="output 'y2' diverged at sample 151"):
        online.partial_fit(u[100:], y[100:])
    np.testing.assert_array_equal(_vector(online), good)  # y1 rolled back too


# ---------------------------------------------------------------------- not learning
def test_arx_a_held_sample_is_a_regression_row_left_out():
    """Issue 37: ``update(.., learn=False)`` takes the sample into the regressors of the
    samples after it (their lags stay true) and learns nothing from it: the estimate
    is the exact least-squares answer (with RLS's prior 1/P(0)) over the other rows;
    the prediction it returns is the model's one-step prediction."""
    u, y = _record(TITO, 400, noise=0.05)
    held = {60, 61, 200}
    online = online_estimator("arx", "rls", ARX_ORDERS, ["u1", "u2"], ["y1", "y2"])
    for k in range(len(u)):
        before = online.model()
        prediction = online.update(u[k], y[k], learn=k not in held)
        if k in held:
            np.testing.assert_allclose(prediction, before.predict(u[: k + 1], y[: k + 1])[-1])
    assert online.n_samples == len(u)
    model, lag = online.model(), TITO.max_lag
    keep = [t - lag for t in range(lag, len(u)) if t not in held]
    for i in range(2):
        Phi, target = TITO.regressors(u, y, i)
        Phi, target = Phi[keep], target[keep]
        mu = 1e8  # RLS's default P(0): a prior of weight 1/mu on theta(0) = 0
        exact = np.linalg.solve(Phi.T @ Phi + np.eye(Phi.shape[1]) / mu, Phi.T @ target)
        np.testing.assert_allclose(model.parameter_vector(i), exact, rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize("method", ["rls", "aw-rls", "hierarchical-rls"])
def test_arx_update_predictions_equal_the_chunk_path_and_it_mixes_with_partial_fit(method):
    """ARX ``update`` gathers one regressor row per output without building matrices;
    its a-priori predictions are the chunk path's bit for bit, also with different
    orders per output (H-RLS column groups permuted) and updates interleaved with
    chunks."""
    orders = {**ARX_ORDERS, "na": [[2, 0], [1, 2]], "nk": [[1, 2], [0, 1]], **ARX_METHODS[method]}
    u, y = _record(TITO, 300, noise=0.01)
    names = (["u1", "u2"], ["y1", "y2"])
    whole = online_estimator("arx", method, orders, *names).partial_fit(u, y)
    single = online_estimator("arx", method, orders, *names)
    predictions = np.array([single.update(u[k], y[k]) for k in range(len(u))])
    np.testing.assert_array_equal(predictions, whole.predictions_)
    assert np.isnan(predictions[: whole.template.max_lag]).all()
    mixed = online_estimator("arx", method, orders, *names)
    for k in range(100):
        mixed.update(u[k], y[k])
    mixed.partial_fit(u[100:180], y[100:180])
    for k in range(180, 300):
        mixed.update(u[k], y[k])
    np.testing.assert_array_equal(_vector(mixed), _vector(whole))


def test_arx_update_divergence_rolls_back_every_output():
    u, y = _record(TITO, 200, noise=0.01)
    y[150, 1] = 1e300
    orders = {**ARX_ORDERS, "na": [[2, 0], [1, 2]]}
    online = online_estimator("arx", "rls", orders, ["u1", "u2"], ["y1", "y2"])
    for k in range(151):
        online.update(u[k], y[k])
    good = _vector(online)
    with pytest.raises(EstimationError, match="output 'y2' diverged at sample 151"):
        online.update(u[151], y[151])
    np.testing.assert_array_equal(_vector(online), good)  # y1 rolled back too
    assert online.n_samples == 151


@pytest.mark.parametrize("method", ["rls", "aw-rls", "hierarchical-rls"])
def test_arx_with_lags_of_three_or_more_learns_from_the_first_sample(method):
    """Issue 21: ``update`` crashed from the first samples for any ARX whose longest
    lag is 3 or more (a regressor slice wrapped around before ``max_lag`` samples had
    arrived); sample by sample it now ends where the one-chunk fit ends, bit for bit."""
    from blockid import ARXEstimator

    rng = np.random.default_rng(4)
    u = rng.standard_normal(300)
    y = np.convolve(u, [0.0, 0.5, 0.3, 0.1], "full")[:300] + 0.01 * rng.standard_normal(300)
    orders = dict(na=3, nb=3, nk=2)
    one = ARXEstimator(method=method, **orders)
    for k in range(300):
        one.update(u[k : k + 1], y[k : k + 1])
    whole = ARXEstimator(method=method, **orders).partial_fit(_dataset_siso(u, y))
    np.testing.assert_array_equal(one.model_.parameter_vector(0), whole.model_.parameter_vector(0))


def _dataset_siso(u, y):
    return Dataset.from_arrays(u, y, ["u"], ["y"])


def test_online_arx_takes_its_orders_from_the_initial_model():
    from blockid.fitting.online import online_estimator
    from blockid.models import ARX

    initial = ARX(["u"], ["y"], 2, 1, 1, a={"y": {"y": [-0.5, 0.1]}}, b={"y": {"u": [1.0]}})
    est = online_estimator("arx", "rls", {"initial": initial}, ["u"], ["y"])
    assert est.template.na.tolist() == [[2]] and est.template.nb.tolist() == [[1]]
    np.testing.assert_allclose(est.model().parameter_vector(0), [-0.5, 0.1, 1.0])


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
