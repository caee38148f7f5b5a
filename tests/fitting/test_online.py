"""Online learning (fitting/online.py): any chunking of a record ends where the offline
one-pass fit with the matching scaling ends, bit for bit."""

import numpy as np
import pytest

from blockid import ARXEstimator, HammersteinWienerEstimator
from blockid.errors import ParameterError
from blockid.fitting.key_term import fit_key_term_rls
from blockid.fitting.online import online_estimator
from blockid.models import HammersteinWiener
from fitting.online_cases import (
    ARX_ORDERS,
    LINEAR,
    N1,
    N2,
    ORDERS,
    PLANTS,
    TITO,
    _dataset,
    _offline_history,
    _record,
    _same,
    _vector,
)


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
