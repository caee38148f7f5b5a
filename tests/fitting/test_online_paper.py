"""The online learners of the papers' recursions (fitting/online_paper.py: key-term RLS,
backlash AW-RLS): any chunking ends where the offline one-pass fit ends, a priori
predictions, long runs, divergence named with its sample."""

import numpy as np
import pytest

from blockid.errors import EstimationError, ParameterError
from blockid.fitting.backlash import fit_backlash_aw_rls
from blockid.fitting.key_term import fit_key_term_rls
from blockid.fitting.online import online_estimator
from blockid.models import BacklashModel
from fitting.online_cases import (
    BACKLASH,
    ORDERS,
    PLANTS,
    _dataset,
    _offline_history,
    _record,
    _same,
    _three_ways,
    _vector,
)

from reference import _backlash_data


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
