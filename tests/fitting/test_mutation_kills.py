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
