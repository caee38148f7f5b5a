"""Online learning (fitting/online.py): any chunking of a record ends where the offline
one-pass fit with the matching scaling ends, bit for bit."""

import json

import numpy as np
import pytest

from blockid import ARXEstimator, HammersteinWienerEstimator
from blockid.blocks import Backlash, Polynomial, TwoSegmentPolynomial
from blockid.data import Dataset
from blockid.errors import DataError, EstimationError, ParameterError
from blockid.fitting.arx import fit_arx
from blockid.fitting.backlash import fit_backlash_aw_rls
from blockid.fitting.key_term import fit_key_term_rls
from blockid.fitting.online import online_estimator
from blockid.models import ARX, BacklashModel, Hammerstein, HammersteinWiener, Wiener

from reference import _backlash_data

# paper B's orders and a stable third-order linear block
N1 = TwoSegmentPolynomial.from_segments(
    positive=[0, 0.3, 0.1, -0.05], negative=[0, 0.15, -0.05, 0.03]
)
N2 = Polynomial([1.0, 0.2, 0.05], constant=False)
LINEAR = dict(na=3, nb=3, nk=8, a=np.real(np.poly([0.7, 0.5, -0.3]))[1:], b=[1.0, 0.5, 0.2])
ORDERS = dict(na=3, nb=3, nk=8)
PLANTS = {
    "hammerstein-wiener": HammersteinWiener("u", "y", input_block=N1, output_block=N2, **LINEAR),
    "hammerstein": Hammerstein("u", "y", input_block=N1, **LINEAR),
    "wiener": Wiener("u", "y", output_block=N2, **LINEAR),
}
BACKLASH = BacklashModel(
    "u", "y", input_block=Backlash(0.9, 0.8, 0.9, 0.85), na=2, nb=1, nk=1, a=[-1.0, 0.17]
)
# two inputs, two outputs, unequal orders (every lag bookkeeping path)
ARX_ORDERS = dict(na=[[2, 1], [1, 2]], nb=[[2, 1], [1, 2]], nk=[[1, 2], [1, 1]])
TITO = ARX(
    ["u1", "u2"],
    ["y1", "y2"],
    **ARX_ORDERS,
    a={"y1": {"y1": [-0.5, 0.1], "y2": [0.05]}, "y2": {"y1": [0.1], "y2": [-0.3, 0.05]}},
    b={"y1": {"u1": [1.0, 0.3], "u2": [0.2]}, "y2": {"u1": [0.4], "u2": [1.0, -0.2]}},
)
ARX_METHODS = {
    "rls": {"forgetting": "0.98:100,0.999"},
    "aw-rls": {},
    "hierarchical-rls": {"forgetting": 0.98},
}


def _record(plant, n, amplitude=1.0, seed=1, noise=0.0):
    rng = np.random.default_rng(seed)
    u = amplitude * rng.uniform(-1.0, 1.0, (n, len(plant.inputs)))
    y = plant.simulate(u)
    return u, y + noise * rng.standard_normal(y.shape)


def _dataset(plant, u, y):
    return Dataset.from_arrays(u, y, inputs=list(plant.inputs), outputs=list(plant.outputs))


def _vector(online):
    return np.array(list(online.estimate().values()))


def _three_ways(structure, method, options, plant, u, y, seed=0):
    """Estimates after the whole record, random chunks, and sample-by-sample updates."""
    names = (list(plant.inputs), list(plant.outputs))
    whole = online_estimator(structure, method, options, *names).partial_fit(u, y)
    chunked = online_estimator(structure, method, options, *names)
    cuts = np.sort(np.random.default_rng(seed).choice(np.arange(4, len(u)), 12, replace=False))
    for a, b in zip(np.r_[0, 1, 2, 3, cuts], np.r_[1, 2, 3, cuts, len(u)], strict=True):
        chunked.partial_fit(u[a:b], y[a:b])  # incl. chunks of one sample within max_lag
    single = online_estimator(structure, method, options, *names)
    for k in range(len(u)):
        single.update(u[k], y[k])
    for est in (whole, chunked, single):
        assert est.n_samples == len(u)
    return whole, chunked, single


def _same(estimates, reference, names=None):
    for est in estimates:
        if names is not None:
            assert list(est.estimate()) == names
        np.testing.assert_allclose(_vector(est), reference, rtol=1e-9, atol=1e-12)
        np.testing.assert_array_equal(_vector(est), reference)  # in fact bit for bit


def _offline_history(fit, *args, **kwargs):
    """The one-pass offline estimate (recursion order, data units), also when the fit
    refuses its model (one pass of H-W key-term RLS does not converge)."""
    try:
        return fit(*args, passes=1, record_history=True, **kwargs).history
    except EstimationError as exc:
        return exc.history


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


@pytest.mark.parametrize("structure", list(PLANTS))
def test_key_term_any_chunking_equals_the_offline_one_pass_fit(structure):
    plant = PLANTS[structure]
    u, y = _record(plant, 2500)
    options = {**ORDERS, "forgetting": "0.98:200,1"}
    data = _dataset(plant, u, y)
    history = _offline_history(fit_key_term_rls, data, structure, normalize=False, **options)
    estimates = _three_ways(structure, "key-term-rls", options, plant, u, y)
    _same(estimates, history["theta"][-1], history["names"])
    assert type(estimates[0].model()) is type(plant)
    if structure != "hammerstein-wiener":  # the offline fit accepts its one-pass model
        offline = fit_key_term_rls(data, structure, passes=1, normalize=False, **options)
        assert estimates[1].parameters() == offline.model.to_dict()["parameters"]


def test_key_term_with_given_scales_equals_the_offline_fit_with_those_scales():
    plant = PLANTS["hammerstein"]
    u, y = _record(plant, 1500, amplitude=3.0)
    data = _dataset(plant, u, y)
    history = _offline_history(
        fit_key_term_rls, data, "hammerstein", scales=(2.0, 0.5), r1=3, **ORDERS
    )
    options = {**ORDERS, "r1": 3, "input_scale": 2.0, "output_scale": 0.5, "normalize": True}
    _same(_three_ways("hammerstein", "key-term-rls", options, plant, u, y), history["theta"][-1])


@pytest.mark.parametrize("scales", [None, (3.0, 2.0)])
def test_backlash_any_chunking_equals_the_offline_one_pass_fit(scales):
    u, y = _record(BACKLASH, 2000, amplitude=5.0)
    data = _dataset(BACKLASH, u, y)
    kwargs = {"normalize": False} if scales is None else {"scales": scales}
    offline = fit_backlash_aw_rls(data, record_history=True, **kwargs)
    options = {} if scales is None else {"input_scale": scales[0], "output_scale": scales[1]}
    estimates = _three_ways("backlash", "aw-rls", options, BACKLASH, u, y)
    _same(estimates, offline.history["theta"][-1], offline.history["names"])
    model = estimates[2].model()
    assert isinstance(model, BacklashModel)
    np.testing.assert_array_equal(model.free_parameters(), offline.model.free_parameters())
    np.testing.assert_allclose(model.free_parameters(), BACKLASH.free_parameters(), atol=1e-5)


def test_a_starting_model_sets_theta0_as_initial_parameters_do_offline():
    plant = PLANTS["hammerstein-wiener"]
    u, y = _record(plant, 1200)
    start = online_estimator("hammerstein-wiener", "key-term-rls", {"initial": plant}, "u", "y")
    theta0 = np.concatenate((N1.f, N1.p, LINEAR["b"][1:], LINEAR["a"], N2.coefficients[1:]))
    np.testing.assert_array_equal(_vector(start), theta0)  # B4 order, orders from the model
    assert start.model().parameters == plant.parameters
    history = _offline_history(
        fit_key_term_rls,
        _dataset(plant, u, y),
        "hammerstein-wiener",
        normalize=False,
        initial_parameters=theta0,
    )
    _same([start.partial_fit(u, y)], history["theta"][-1])


# ---------------------------------------------------------------------- predictions
def test_update_returns_the_prediction_of_the_model_before_the_update():
    u, y = _record(TITO, 300, noise=0.05)
    online = online_estimator(
        "arx", "rls", {**ARX_ORDERS, "forgetting": 0.99}, *[list(TITO.inputs), list(TITO.outputs)]
    )
    lag = TITO.max_lag
    for k in range(len(u)):
        before = online.model()
        prediction = online.update(u[k], y[k])
        assert prediction.shape == (2,)
        if k < lag:
            assert np.all(np.isnan(prediction))  # no regressor yet
        elif k % 7 == 0:
            expected = before.predict(u[: k + 1], y[: k + 1])[-1]
            np.testing.assert_allclose(prediction, expected, rtol=1e-12, atol=1e-12)
    # a chunk keeps the same predictions
    chunked = online_estimator(
        "arx", "rls", {**ARX_ORDERS, "forgetting": 0.99}, *[list(TITO.inputs), list(TITO.outputs)]
    )
    chunked.partial_fit(u[:100], y[:100])
    before = chunked.model()
    chunked.partial_fit(u[100:101], y[100:101])
    np.testing.assert_allclose(
        chunked.predictions_[0], before.predict(u[:101], y[:101])[-1], rtol=1e-12
    )


def test_key_term_predictions_are_the_a_priori_ones_and_shrink():
    plant = PLANTS["hammerstein"]
    u, y = _record(plant, 2000)
    online = online_estimator("hammerstein", "key-term-rls", {**ORDERS, "r1": 3}, "u", "y")
    predictions = np.array([online.update(u[k], y[k])[0] for k in range(len(u))])
    assert np.all(np.isnan(predictions[:10])) and np.all(np.isfinite(predictions[10:]))
    early = np.abs(y[10:200, 0] - predictions[10:200]).mean()
    late = np.abs(y[-200:, 0] - predictions[-200:]).mean()
    assert late < 0.05 * early  # measured 0.017
    whole = online_estimator("hammerstein", "key-term-rls", {**ORDERS, "r1": 3}, "u", "y")
    np.testing.assert_array_equal(whole.partial_fit(u, y).predictions_[:, 0], predictions)


# ---------------------------------------------------------------------- long run, memory
def test_long_hammerstein_wiener_run_is_finite_and_close_to_the_truth():
    # one pass with lambda = 1 keeps the first, wrong internal estimates for ever (the
    # offline fit repeats passes instead); online, a forgetting factor below 1 does it
    plant = PLANTS["hammerstein-wiener"]
    u, y = _record(plant, 50_000)
    online = online_estimator(
        "hammerstein-wiener", "key-term-rls", {**ORDERS, "forgetting": 0.999}, "u", "y"
    )
    sizes = []
    for a in range(0, 50_000, 5000):
        online.partial_fit(u[a : a + 5000], y[a : a + 5000])
        sizes.append(sum(v.nbytes for v in vars(online).values() if isinstance(v, np.ndarray)))
    model = online.model()
    assert np.all(np.isfinite(model.free_parameters()))
    assert np.max(np.abs(model.free_parameters() - plant.free_parameters())) < 1e-3
    assert len(set(sizes[1:])) == 1  # the state does not grow with the record


# ---------------------------------------------------------------------- divergence
def test_divergence_names_the_sample_and_leaves_the_last_good_state():
    plant = PLANTS["hammerstein"]
    u, y = _record(plant, 400)
    bad = u.copy()
    bad[140] = 1e200  # u^3 overflows: the regressor of sample 140 + nk is not finite
    options = {**ORDERS, "r1": 3}
    online = online_estimator("hammerstein", "key-term-rls", options, "u", "y")
    online.partial_fit(u[:100], y[:100])
    good = _vector(online)
    with pytest.raises(EstimationError, match="at sample 148") as info:
        online.partial_fit(bad[100:200], y[100:200])
    assert info.value.sample == 148
    assert online.n_samples == 100
    np.testing.assert_array_equal(_vector(online), good)
    # the stream goes on from the last good state: as if the bad chunk had not come
    online.partial_fit(u[100:], y[100:])
    clean = online_estimator("hammerstein", "key-term-rls", options, "u", "y")
    np.testing.assert_array_equal(_vector(online), _vector(clean.partial_fit(u, y)))

    single = online_estimator("hammerstein", "key-term-rls", options, "u", "y")
    for k in range(148):
        single.update(bad[k], y[k])
    before = _vector(single)
    with pytest.raises(EstimationError, match="at sample 148"):
        single.update(bad[148], y[148])
    np.testing.assert_array_equal(_vector(single), before)
    assert single.n_samples == 148


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


LEARNERS = {
    "arx-rls": ("arx", "rls", ARX_ORDERS, TITO),
    "arx-aw-rls": ("arx", "aw-rls", ARX_ORDERS, TITO),
    "arx-hierarchical-rls": ("arx", "hierarchical-rls", ARX_ORDERS, TITO),
    "hammerstein-wiener": (
        "hammerstein-wiener",
        "key-term-rls",
        ORDERS,
        PLANTS["hammerstein-wiener"],
    ),
    "backlash": ("backlash", "aw-rls", {"na": 2, "nb": 1, "nk": 1}, BACKLASH),
}


@pytest.mark.parametrize("name", list(LEARNERS))
def test_hold_revert_and_rewind_leave_the_estimate_and_move_the_memory(name):
    """Every learner: a held sample leaves theta and P as they were and is counted;
    revert takes back the last update exactly; rewind puts back a snapshot's estimate
    while the memory stays current (the next predictions are those of that estimate
    on the true lags)."""
    structure, method, options, plant = LEARNERS[name]
    names = [list(plant.inputs), list(plant.outputs)]
    u, y = _record(plant, 300, noise=0.01)
    online = online_estimator(structure, method, options, *names)
    twin = online_estimator(structure, method, options, *names)  # learns every sample
    for k in range(200):
        online.update(u[k], y[k])
        twin.update(u[k], y[k])
    snapshot, estimate = online.snapshot(), _vector(online)
    online.update(u[200], y[200], learn=False)
    np.testing.assert_array_equal(_vector(online), estimate)
    assert online.n_samples == 201
    online.update(u[201], y[201])
    online.revert()
    np.testing.assert_array_equal(_vector(online), estimate)
    for k in range(202, 250):
        online.update(u[k], y[k])
    assert not np.array_equal(_vector(online), estimate)
    online.rewind(snapshot)
    np.testing.assert_array_equal(_vector(online), estimate)
    assert online.n_samples == 250
    if structure == "arx":  # the prediction of the rewound estimate on the true lags
        model = online.model()
        np.testing.assert_allclose(
            online.update(u[250], y[250]), model.predict(u[:251], y[:251])[-1], rtol=1e-12
        )
    json.dumps(snapshot)  # JSON-ready (a stream's checkpoint holds it)


def test_revert_after_a_glitch_leaves_no_trace_in_the_key_term_limit():
    """A reverted output glitch does not stay in max|y| (the divergence limit of the
    internal estimates), which a checkpoint saves."""
    plant = PLANTS["hammerstein"]
    u, y = _record(plant, 200, noise=0.01)
    online = online_estimator("hammerstein", "key-term-rls", {**ORDERS, "r1": 3}, "u", "y")
    online.partial_fit(u[:150], y[:150])
    state = online.state()
    online.update(u[150], 1e8)
    online.revert()
    after = online.state()
    for key in ("theta", "P", "_y_max", "_limits"):
        assert after[key] == state[key], key


# ---------------------------------------------------------------------- options
@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"passes": 3}, "one pass"),
        ({"normalize": True}, "input_scale and output_scale"),
        ({"center": True}, "center=True"),
        ({"input_scale": 2.0}, "both input_scale and output_scale"),
        ({"eps1": 1.0}, "eps1 not used by hammerstein-wiener"),
        ({"initial": PLANTS["hammerstein"]}, "must be a HammersteinWiener"),
        ({"initial": PLANTS["hammerstein-wiener"], "initial_parameters": 0.1}, "not both"),
    ],
)
def test_options_a_stream_cannot_honour_are_refused(options, message):
    with pytest.raises(ParameterError, match=message):
        online_estimator("hammerstein-wiener", "key-term-rls", options, "u", "y")


def test_a_non_recursive_method_cannot_learn_online():
    with pytest.raises(ParameterError, match="not recursive"):
        online_estimator("arx", "batch", {}, ["u"], ["y"])


# ---------------------------------------------------------------------- ModelEstimator
def test_model_estimator_learns_online_end_to_end():
    plant = PLANTS["hammerstein-wiener"]
    u, y = _record(plant, 3000)
    est = HammersteinWienerEstimator(method="key-term-rls", forgetting=0.999, **ORDERS)
    est.partial_fit(_dataset(plant, u[:2000], y[:2000]))
    assert isinstance(est.model_, HammersteinWiener) and est.n_samples_ == 2000
    for k in range(2000, 3000):
        prediction, error = est.update(u[k], y[k])
    assert prediction.shape == error.shape == (1,)
    np.testing.assert_allclose(error, y[-1] - prediction)
    assert est.n_samples_ == 3000
    whole = online_estimator(
        "hammerstein-wiener", "key-term-rls", {**ORDERS, "forgetting": 0.999}, "u", "y"
    )
    np.testing.assert_array_equal(_vector(est._online), _vector(whole.partial_fit(u, y)))
    assert est.online_model_.parameters == whole.model().parameters


def test_partial_fit_after_fit_with_a_batch_method_is_refused_clearly():
    u, y = _record(TITO, 300, noise=0.01)
    est = ARXEstimator(method="batch", **ARX_ORDERS).fit(_dataset(TITO, u, y))
    with pytest.raises(ParameterError, match="method='batch' of arx is not recursive"):
        est.partial_fit(_dataset(TITO, u, y))


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


@pytest.mark.parametrize(
    ("structure", "method", "start", "given"),
    [
        ("arx", "rls", ARX(["u"], ["y"], 2, 2, 1, a={"y": {"y": [-1.2, 0.35]}},
                           b={"y": {"u": [1.0, 0.4]}}), {"na": 3, "nb": 1}),
        ("arx", "rls", ARX(["u"], ["y"], 2, 2, 1), {"na": 1}),
        ("arx", "rls", ARX(["u"], ["y"], 2, 2, 1), {"nb": 1}),
        ("arx", "rls", ARX(["u"], ["y"], 2, 2, 1), {"nk": 2}),
        ("hammerstein-wiener", "key-term-rls", PLANTS["hammerstein-wiener"], {"nk": 2}),
        ("hammerstein-wiener", "key-term-rls", PLANTS["hammerstein-wiener"], {"r2": 2}),
    ],
)  # fmt: skip
def test_orders_given_beside_a_starting_model_must_be_its_own(structure, method, start, given):
    """The starting model's parameters were laid out by the orders given instead of its
    own: taken silently (ARX na=3, nb=1 read the 2+2 numbers as 3+1) or failing deep in
    NumPy ("operands could not be broadcast")."""
    with pytest.raises(ParameterError, match="differs from the starting model's"):
        online_estimator(structure, method, {**given, "initial": start}, ["u"], ["y"])
    own = {k: getattr(start, k) for k in ("na", "nb", "nk")}
    online_estimator(structure, method, {**own, "initial": start}, ["u"], ["y"])  # its own: fine
    # none given: every order is the starting model's own (mutation run 3: nb, nk fell
    # back to the defaults, which then differed from the model's)
    online_estimator(structure, method, {"initial": start}, ["u"], ["y"])
    if structure == "arx":  # a delay that is not the default's
        delayed = ARX(["u"], ["y"], 2, 2, 3)
        est = online_estimator(structure, method, {"initial": delayed}, ["u"], ["y"])
        assert np.all(np.asarray(est.template.nk) == 3)


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
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


@pytest.mark.parametrize(
    ("structure", "method", "declared"),
    [
        ("hammerstein-wiener", "key-term-rls", "KEY_TERM_AT_LEAST"),
        ("backlash", "aw-rls", "BACKLASH_AT_LEAST"),
    ],  # fmt: skip
)
def test_the_batch_and_the_online_fit_refuse_orders_below_one_declaration(
    structure, method, declared
):
    """Each paper method declares its smallest orders once (beside the fitter); the
    batch fit and the online learner refuse one below it alike, naming that minimum."""
    from blockid.data import Dataset
    from blockid.errors import ParameterError
    from blockid.fitting import backlash, fit_model, key_term_channels
    from blockid.fitting.online import online_estimator

    minimums = getattr(key_term_channels if declared.startswith("KEY") else backlash, declared)
    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, 400)
    data = Dataset.from_arrays(u, np.convolve(u, [0.0, 1.0, 0.5])[:400], ["u"], ["y"])
    for name, low in minimums.items():
        message = f"{name}={low - 1} must be a whole number >= {low}"
        with pytest.raises(ParameterError, match=message):
            fit_model(data, structure, method=method, **{name: low - 1})
        with pytest.raises(ParameterError, match=message):
            online_estimator(structure, method, {name: low - 1}, ["u"], ["y"])
