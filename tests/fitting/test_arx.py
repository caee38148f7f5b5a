import numpy as np
import pytest

from blockid import errors
from blockid.config import config_context
from blockid.data import Dataset
from blockid.errors import EstimationError, OrderError, ParameterError
from blockid.fitting import fit_arx
from blockid.models import ARX

import reference
from reference import _arx_data, _dataset


def tito_plant():
    return reference.tito_arx()


def tito_data(rng, N, noise=0.0, offsets=(0.0, 0.0)):
    plant = tito_plant()
    u = rng.standard_normal((N, 2))
    y = plant.simulate(u) + noise * rng.standard_normal((N, 2)) + np.asarray(offsets)
    return plant, Dataset.from_arrays(u, y, inputs=["v1", "v2"], outputs=["y1", "y2"])


def params(model):
    return np.concatenate([model.parameter_vector(i) for i in range(len(model.outputs))])


@pytest.mark.parametrize("method", ["batch", "rls", "aw-rls"])
def test_noise_free_tito_recovers_truth(rng, method):
    plant, data = tito_data(rng, 3000)
    model = fit_arx(data, 2, 2, 1, method=method).model
    np.testing.assert_allclose(params(model), params(plant), atol=1e-6)


def test_hierarchical_rls_converges_to_full_rls_on_noise_free_tito(rng):
    _, data = tito_data(rng, 20000)
    full = fit_arx(data, 2, 2, 1, method="rls").model
    hier = fit_arx(data, 2, 2, 1, method="hierarchical-rls", forgetting=0.95).model
    np.testing.assert_allclose(params(hier), params(full), atol=1e-9)


def test_rls_with_forgetting_one_equals_batch_whatever_the_units(rng):
    """Column scaling makes the default P(0) 'large' for tiny and huge signals alike."""
    _, data = tito_data(rng, 2000, noise=0.05)
    for scale in (1e-4, 1.0, 1e4):
        scaled = Dataset.from_arrays(
            np.vstack([e.u for e in data.experiments]) * scale,
            np.vstack([e.y for e in data.experiments]) * scale,
            inputs=data.inputs,
            outputs=data.outputs,
        )
        batch = params(fit_arx(scaled, 2, 2, 1, method="batch").model)
        rls = params(fit_arx(scaled, 2, 2, 1, method="rls", forgetting=1).model)
        np.testing.assert_allclose(rls, batch, rtol=1e-8, atol=1e-12)


def test_hierarchical_without_forgetting_is_reported_not_returned(rng):
    _, data = tito_data(rng, 1500, noise=0.01)
    with pytest.raises(errors.EstimationError, match="did not converge.*least-squares optimum"):
        fit_arx(data, 2, 2, 1, method="hierarchical-rls")


def test_center_fits_around_the_operating_point(rng):
    plant, data = tito_data(rng, 3000, offsets=(110.0, 0.578))
    model = fit_arx(data, 2, 2, 1, method="rls", center=True).model
    # an ARX without offsets cannot absorb the constant; with them it recovers the truth
    np.testing.assert_allclose(params(model), params(plant), atol=1e-3)
    assert abs(model.output_offset[0] - 110.0) < 0.5


def test_multiple_experiments_do_not_straddle(rng):
    plant, d1 = tito_data(rng, 800)
    _, d2 = tito_data(rng, 800, offsets=(5.0, -5.0))  # a jump between the records
    both = Dataset(
        d1.inputs,
        d1.outputs,
        None,
        [
            d1.experiments[0],
            type(d1.experiments[0])(
                "second", d2.experiments[0].u, d2.experiments[0].y - [5.0, -5.0]
            ),
        ],
    )
    np.testing.assert_allclose(params(fit_arx(both, 2, 2, 1).model), params(plant), atol=1e-8)


def test_unstable_result_is_reported(rng):
    u = rng.standard_normal(500)
    y = np.cumsum(np.cumsum(u))  # double integrator: poles at 1
    data = Dataset.from_arrays(u, y)
    with pytest.raises(errors.EstimationError, match="unstable"):
        fit_arx(data, 2, 1, 1)
    assert not fit_arx(data, 2, 1, 1, allow_unstable=True).model.is_stable(margin=-1e-6)


def test_orders_too_large_for_the_data(rng):
    data = Dataset.from_arrays(rng.standard_normal(30), rng.standard_normal(30))
    with pytest.raises(errors.OrderError, match="needs at least 40 regression rows"):
        fit_arx(data, 20, 20, 1)


def test_block_model_on_the_edge_of_stability_is_rejected(rng):
    from blockid.blocks import TwoSegmentPolynomial
    from blockid.fitting import check_model
    from blockid.models import Hammerstein

    block = TwoSegmentPolynomial([0.0, 1.0], [0.0, 0.0])
    u = rng.uniform(-1, 1, 400)
    edge = Hammerstein("u", "y", input_block=block, na=1, nb=1, nk=1, a=[0.9996])  # pole -0.9996
    data = Dataset.from_arrays(u, edge.simulate(u)[:, 0])
    with pytest.raises(errors.EstimationError, match="edge of stability"):
        check_model(edge, data, "test")
    fine = Hammerstein("u", "y", input_block=block, na=1, nb=1, nk=1, a=[0.95])
    check_model(fine, Dataset.from_arrays(u, fine.simulate(u)[:, 0]), "test")


@pytest.mark.parametrize("method", ["batch", "rls", "aw-rls", "hierarchical-rls"])
def test_chunked_regressors_give_the_whole_record_fit(rng, method):
    """Long records are fitted chunk by chunk (bounded memory): chunks of 7 rows, which
    cut every experiment in many places and leave a short last chunk, give the fit of
    one chunk per experiment (the recursions bit for bit, least squares to rounding)."""
    import blockid.fitting.arx as arx_fitting

    _, d1 = tito_data(rng, 700, noise=0.05)
    _, d2 = tito_data(rng, 500, noise=0.05)
    second = type(d2.experiments[0])("second", d2.experiments[0].u, d2.experiments[0].y)
    data = Dataset(d1.inputs, d1.outputs, None, [d1.experiments[0], second])
    options = {"forgetting": 0.99, "max_mse_ratio": None} if method == "hierarchical-rls" else {}
    # fixed column scales: the recursion sees the same numbers whatever the chunks
    fixed = {} if method == "batch" else {"scaling": (1.0, 1.0)}
    whole = fit_arx(data, 2, 2, 1, method=method, **options, **fixed)
    whole_rms = fit_arx(data, 2, 2, 1, method=method, **options)
    with config_context(regressor_rows=7):
        assert len(list(arx_fitting.regressor_chunks(whole.model, data, 0))) == 100 + 72
        chunked = fit_arx(data, 2, 2, 1, method=method, **options, **fixed)
        # RMS scales summed chunk by chunk differ in the last bits, which P(0) = 1e8
        # amplifies to about 1e-9
        chunked_rms = fit_arx(data, 2, 2, 1, method=method, **options)
    if method == "batch":
        np.testing.assert_allclose(params(chunked.model), params(whole.model), rtol=1e-12)
    else:
        np.testing.assert_array_equal(params(chunked.model), params(whole.model))
        np.testing.assert_allclose(params(chunked_rms.model), params(whole_rms.model), rtol=1e-7)
    for key, values in whole.estimation_metrics.items():
        for name, value in values.items():
            assert chunked.estimation_metrics[key][name] == pytest.approx(value, rel=1e-9)


def test_chunked_least_squares_names_a_column_the_whole_record_leaves_unexcited(rng):
    """A chunk alone may not excite every column (an input at rest for the first
    rows): only the whole record decides rank deficiency."""
    u = rng.standard_normal((3000, 2))
    u[:2000, 1] = 0.0  # the second input rests for the first chunks
    y = reference.tito_arx().simulate(u)
    data = Dataset.from_arrays(u, y, inputs=["v1", "v2"], outputs=["y1", "y2"])
    import blockid.fitting.arx as arx_fitting

    full = fit_arx(data, 2, 2, 1).model
    chunked = arx_fitting.least_squares(full, data, 0)
    np.testing.assert_allclose(chunked, full.parameter_vector(0), rtol=1e-10)
    u[:, 1] = 0.0
    dead = Dataset.from_arrays(u, y, inputs=["v1", "v2"], outputs=["y1", "y2"])
    with pytest.raises(errors.EstimationError, match="v2"):
        fit_arx(dead, 2, 2, 1)


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
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


def test_the_aw_rls_takes_the_initial_covariance_it_is_given():
    """A tiny P(0) keeps AW-RLS near its start theta(0) = 0.01 over a short record; the
    default (1e5) learns the plant's b = 1 (mutation run 3: the given value was
    dropped)."""
    data = Dataset.from_arrays(*_arx_data(n=60), ["u"], ["y"])
    learned = fit_arx(data, 1, 1, 1, method="aw-rls", max_mse_ratio=None)
    held = fit_arx(data, 1, 1, 1, method="aw-rls", initial_covariance=1e-6, max_mse_ratio=None)
    b_learned = np.asarray(learned.model.b["y"]["u"])
    b_held = np.asarray(held.model.b["y"]["u"])
    assert np.abs(b_held - 0.01).max() < 0.005 and np.abs(b_learned - 1.0).max() < 0.05


def test_a_rank_deficient_fit_names_a_glitch_by_its_row():
    """One input sample of 1e12 among values near 1: the rank error says which row."""
    from blockid.errors import EstimationError

    rng = np.random.default_rng(3)
    u = rng.standard_normal(400)
    y = np.convolve(u, [0.0, 1.0, 0.5])[:400] + 0.01 * rng.standard_normal(400)
    u[123] = 1e12
    with pytest.raises(EstimationError, match=r"input 'u1' is 1e\+12 at row 123 \(0-based\)"):
        fit_arx(Dataset.from_arrays(u, y), na=2, nb=2, nk=1)


def test_nb_zero_for_every_input_is_refused_but_some_zero_is_fine():
    rng = np.random.default_rng(0)
    u = rng.standard_normal((200, 2))
    data = Dataset.from_arrays(u, u[:, 0] + 0.1 * rng.standard_normal(200))
    with pytest.raises(OrderError, match="nb is 0 for every input of output 'y1'") as info:
        fit_arx(data, 1, [[0, 0]], 1)
    assert info.value.parameter == "nb"
    fit_arx(data, 1, [[1, 0]], 1)  # one of two inputs left out: allowed


def test_constant_input_names_the_signal_and_lag():
    rng = np.random.default_rng(0)
    data = Dataset.from_arrays(np.full(200, 0.5), rng.standard_normal(200), ["u"], ["y"])
    with pytest.raises(EstimationError, match=r"u at lag 2 .*input 'u' is constant"):
        fit_arx(data, 1, 2, 1)


def _hrls_data(n):
    plant = ARX(
        ["u1", "u2"],
        ["y"],
        2,
        2,
        1,
        a={"y": {"y": [-1.2, 0.35]}},
        b={"y": {"u1": [1.0, 0.4], "u2": [0.5, -0.2]}},
    )
    u = np.random.default_rng(0).standard_normal((n, 2))
    return Dataset.from_arrays(u, plant.simulate(u), ["u1", "u2"], ["y"])


def test_hrls_on_noise_free_data_is_accepted_when_it_predicts_to_the_floor():
    # one-step MSE ~3e-9 of var(y) against a least-squares optimum of ~1e-31
    result = fit_arx(_hrls_data(1300), 2, 2, 1, method="hierarchical-rls", forgetting=0.95)
    assert result.model.parameter_vector(0) == pytest.approx(
        [-1.2, 0.35, 1, 0.4, 0.5, -0.2], abs=1e-3
    )


def test_hrls_advice_fits_the_forgetting_used():
    with pytest.raises(EstimationError, match="forgetting 0.95 was used") as info:
        fit_arx(_hrls_data(600), 2, 2, 1, method="hierarchical-rls", forgetting=0.95)
    assert "below 1" not in str(info.value)
    with pytest.raises(EstimationError, match="needs a forgetting factor below 1"):
        fit_arx(_hrls_data(600), 2, 2, 1, method="hierarchical-rls", forgetting=1.0)
