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
