"""Model-level estimators: the scikit-learn contract over the registry."""

import numpy as np
import pytest

import blockid
from blockid import errors
from blockid.blocks import Polynomial, TwoSegmentPolynomial
from blockid.data import Dataset
from blockid.errors import DataError
from blockid.evaluation import evaluate
from blockid.fitting import fit_model
from blockid.fitting.estimator import ESTIMATORS, ModelEstimator
from blockid.fitting.registry import STRUCTURES
from blockid.models import HammersteinWiener

from reference import _arx_data


def hw_record(n=1500, seed=0):
    plant = HammersteinWiener(
        "u",
        "y",
        input_block=TwoSegmentPolynomial([0.1, 1.0, 0.5], [-0.2, -0.4, 0.3]),
        output_block=Polynomial([1.0, 0.2], constant=False),
        na=2,
        nb=2,
        nk=1,
        a=[-1.2, 0.5],
        b=[1.0, 0.4],
    )
    u = np.random.default_rng(seed).uniform(-1, 1, n)
    return plant, Dataset.from_arrays(u, plant.simulate(u), ["u"], ["y"])


def test_one_estimator_class_per_registered_structure():
    assert set(ESTIMATORS) == set(STRUCTURES)
    assert blockid.HammersteinWienerEstimator is ESTIMATORS["hammerstein-wiener"]
    assert blockid.ARXEstimator.structure == "arx"


def test_constructor_stores_and_fit_validates_then_returns_self():
    est = blockid.HammersteinWienerEstimator(na=2, nb=2, nk=1, r1=2, r2=2, bogus=3)
    assert est.get_params()["bogus"] == 3  # stored, not checked yet
    _, data = hw_record()
    with pytest.raises(errors.ParameterError, match="bogus not used by hammerstein-wiener"):
        est.fit(data)
    est.set_params(bogus=None)
    assert est.fit(data) is est


def test_fit_equals_fit_model_and_learned_attributes_end_in_underscore():
    plant, data = hw_record()
    est = blockid.HammersteinWienerEstimator(na=2, nb=2, nk=1, r1=2, r2=2).fit(data)
    ref = fit_model(data, "hammerstein-wiener", na=2, nb=2, nk=1, r1=2, r2=2)
    assert np.array_equal(est.model_.free_parameters(), ref.model.free_parameters())
    np.testing.assert_allclose(est.model_.free_parameters(), plant.free_parameters(), atol=1e-7)
    assert est.n_samples_ == 1500 and est.result_.method == "simulation-error"
    u = data.experiments[0].u[:, 0]
    assert np.array_equal(est.simulate(u), est.model_.simulate(u))
    assert est.score(data) == pytest.approx(100.0, abs=1e-4)


def test_fit_from_arrays_names_the_signals():
    _, data = hw_record()
    e = data.experiments[0]
    est = blockid.ARXEstimator(na=2, nb=2, nk=1).fit(e.u[:, 0], e.y[:, 0])
    assert est.model_.inputs == ("u",) and est.model_.outputs == ("y",)
    with pytest.raises(errors.DataError, match="not both"):
        blockid.ARXEstimator().fit(data, e.y)


def test_no_model_before_fit_and_non_recursive_methods_do_not_learn_online():
    est = blockid.HammersteinEstimator(na=2, nb=2, nk=1)
    with pytest.raises(errors.ParameterError, match="no model yet"):
        est.simulate(np.zeros(10))
    _, data = hw_record(300)
    with pytest.raises(errors.ParameterError, match="is not recursive"):
        est.partial_fit(data)


def test_online_arx_rls_equals_the_offline_recursive_fit():
    rng = np.random.default_rng(3)
    u = rng.standard_normal(800)
    y = np.zeros(800)
    for k in range(2, 800):
        y[k] = 1.2 * y[k - 1] - 0.5 * y[k - 2] + 0.7 * u[k - 1] + 0.01 * rng.standard_normal()
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    est = blockid.ARXEstimator(method="rls", na=2, nb=1, nk=1, forgetting="0.99")
    for start in range(0, 800, 137):
        est.partial_fit(data.select(start, min(start + 137, 800)))
    offline = fit_model(data, "arx", method="rls", na=2, nb=1, nk=1, forgetting="0.99")
    assert isinstance(est, ModelEstimator) and est.n_samples_ == 800
    np.testing.assert_allclose(est.model_.a["y"]["y"], offline.model.a["y"]["y"], rtol=1e-6)


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
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


def test_estimator_classes_carry_their_structure_and_a_docstring():
    from blockid.fitting.registry import STRUCTURES

    for name, cls in ESTIMATORS.items():
        assert cls.structure == name
        assert cls.__doc__.startswith(f"Estimator of {STRUCTURES[name].help} models")
        assert f"(structure ``{name}``)" in cls.__doc__
    doc = ESTIMATORS["hammerstein"].__doc__
    assert "Methods: simulation-error, key-term-rls (default simulation-error)." in doc


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
