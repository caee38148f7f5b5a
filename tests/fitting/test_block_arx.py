"""Hammerstein models of several inputs and outputs on a matrix-ARX core
(:mod:`blockid.fitting.block_arx`): against a plant whose blocks and core are known, the
recursion against exact batch least squares, online against offline, the realisation
against the ARX it realises, files and export."""

import json

import numpy as np
import pytest

from blockid.data import Dataset
from blockid.errors import ParameterError
from blockid.fitting import fit_model
from blockid.fitting.block_arx import CONSTANT, arx_core_model, input_basis, regression_orders
from blockid.fitting.online import online_estimator
from blockid.models import ARX, load_model, save_model

#: The plant's static blocks (linear coefficient 1, the family's normalisation).
GAMMA = {"u1": [1.0, 0.3, -0.2], "u2": [1.0, 0.0, -0.4]}


def _plant_record(n=3000, seed=0, snr_db=None, offset=0.3):
    """Two inputs, two outputs: cubic blocks, then a coupled first-order ARX core with
    input lags 1 and 2; plus an output offset (and white output noise at ``snr_db``)."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.5, 1.5, (n, 2))
    w = np.column_stack(
        [u[:, c] * GAMMA[k][0] + u[:, c] ** 2 * GAMMA[k][1] + u[:, c] ** 3 * GAMMA[k][2]
         for c, k in enumerate(GAMMA)]
    )  # fmt: skip
    y = np.zeros((n, 2))
    for t in range(2, n):
        y[t, 0] = 0.6 * y[t - 1, 0] - 0.1 * y[t - 1, 1] + 1.0 * w[t - 1, 0] + 0.5 * w[t - 2, 1]
        y[t, 1] = 0.2 * y[t - 1, 0] + 0.5 * y[t - 1, 1] + 0.8 * w[t - 1, 1] - 0.3 * w[t - 2, 0]
    y = y + offset
    if snr_db is not None:
        y = y + rng.standard_normal(y.shape) * y.std(axis=0) * 10 ** (-snr_db / 20)
    return Dataset.from_arrays(u, y, ["u1", "u2"], ["y1", "y2"])


def _blocks(model):
    return [b.coefficients[1:] for b in model.input_blocks]


@pytest.mark.parametrize("method", ["batch", "rls"])
def test_blocks_and_core_of_a_noisy_two_by_two_plant_within_two_percent(method):
    """40 dB output noise, 3 000 samples: every block coefficient within 0.02 of the
    truth (absolute, coefficients of order 1), the core's poles within 0.01."""
    data = _plant_record(snr_db=40)
    fit = fit_model(data, "block-state-space", method=method, na=1, nb=2, nk=1)
    for got, (name, true) in zip(_blocks(fit.model), GAMMA.items(), strict=True):
        np.testing.assert_allclose(got, true, atol=0.02, err_msg=name)
    poles = np.sort_complex(fit.model.poles()[np.abs(fit.model.poles()) > 1e-6])
    true_poles = np.sort_complex(np.linalg.eigvals([[0.6, -0.1], [0.2, 0.5]]))
    np.testing.assert_allclose(poles, true_poles, atol=0.01)
    assert max(fit.settings["rank_ratio"].values()) < 0.05


def test_noise_free_the_batch_fit_simulates_the_plant():
    """The output offset too (the intercept, carried by the state and output biases)."""
    data = _plant_record()
    e = data.experiments[0]
    fit = fit_model(data, "block-state-space", method="batch", na=1, nb=2, nk=1)
    np.testing.assert_allclose(fit.model.simulate(e.u, e.y[:20])[20:], e.y[20:], atol=1e-8)
    assert fit.metrics_mode == "simulation"


def test_a_two_segment_input_block_of_a_plant_with_one_is_recovered():
    """Any block linear in its parameters: a two-segment cubic (other coefficients for
    u < 0) on both channels of a noise-free plant, recovered to 1e-6."""
    from blockid.blocks import TwoSegmentPolynomial

    rng = np.random.default_rng(4)
    u = rng.uniform(-1.5, 1.5, (2000, 2))
    true = TwoSegmentPolynomial([0.0, 1.0, 0.2, -0.1], [0.0, 0.5, -0.3, 0.0])
    w = np.column_stack([true(u[:, 0]), true(u[:, 1])])
    y = np.zeros((2000, 1))
    for t in range(1, 2000):
        y[t] = 0.7 * y[t - 1] + w[t - 1, 0] - 0.5 * w[t - 1, 1]
    data = Dataset.from_arrays(u, y, ["u1", "u2"], ["y"])
    fit = fit_model(data, "block-state-space", method="batch", na=1, nb=1, nk=1,
                    input_block="two-segment-polynomial:degree=3")  # fmt: skip
    for block in fit.model.input_blocks:
        grid = np.linspace(-1.5, 1.5, 31)
        np.testing.assert_allclose(block(grid), true(grid), atol=1e-6)


@pytest.mark.parametrize("na,nb,nk", [(2, 3, 1), (1, 1, 0), (0, 2, 2), (3, 1, 2)])
def test_the_realisation_simulates_as_the_arx_on_the_powers(na, nb, nk):
    """An ARX on the powers whose coefficient matrices are rank one per channel (a true
    Hammerstein model), realised as a block state-space model: the same free run to
    1e-10, with delays, feedthrough (nk = 0) and no output lags (na = 0)."""
    rng = np.random.default_rng(na * 10 + nb + nk)
    inputs, outputs = ("a", "b"), ("p", "q")
    basis = input_basis("polynomial:degree=2")
    NA, NB, NK = regression_orders(2, 2, basis.size, na, nb, nk)
    arx = ARX(basis.inputs(inputs), outputs, NA, NB, NK)
    gamma = rng.uniform(0.5, 1.0, (2, basis.size)) * [1, 0.3]
    for i, yi in enumerate(outputs):
        for j, yj in enumerate(outputs):
            if na:  # stable: a small diagonal-dominant polynomial
                arx.a[yi][yj] = rng.uniform(-0.2, 0.2, na) / na + (-0.5 if i == j else 0) * (
                    np.arange(na) == 0
                )
        for c in range(2):
            b = rng.standard_normal(nb)
            for p in range(basis.size):
                arx.b[yi][arx.inputs[c * basis.size + p]] = b * gamma[c, p]
        arx.b[yi][CONSTANT] = np.array([0.1 * (i + 1)])
    assert arx.is_stable()
    model, ratios = arx_core_model(arx, inputs, basis)
    assert max(ratios) < 1e-12
    u = rng.uniform(-1, 1, (300, 2))
    via_arx = arx.simulate(basis.expanded(u))
    via_model = model.simulate(u)
    settle = max(na, nb + nk)
    # both start at rest; the ARX's first max_lag outputs are zero, the model's are not
    np.testing.assert_allclose(via_model[settle + 50 :], via_arx[settle + 50 :], atol=1e-10)


def test_the_recursion_is_exact_batch_least_squares_on_the_same_regression():
    """RLS from P(0) = 1e8 I on unscaled regressors, one pass, online and in chunks:
    the regression's coefficients equal those of least squares with an intercept to
    1e-6; the per-sample path and the chunked one bit for bit."""
    data = _plant_record(n=2000, snr_db=30)
    e = data.experiments[0]
    online = online_estimator("block-state-space", "rls", {"na": 1, "nb": 2, "nk": 1},
                              data.inputs, data.outputs)  # fmt: skip
    online.partial_fit(e.u[:700], e.y[:700])
    for k in range(700, 2000):
        online.update(e.u[k], e.y[k])
    chunked = online_estimator("block-state-space", "rls", {"na": 1, "nb": 2, "nk": 1},
                               data.inputs, data.outputs)  # fmt: skip
    chunked.partial_fit(e.u, e.y)
    assert online.estimate() == chunked.estimate()
    batch = fit_model(data, "block-state-space", method="batch", na=1, nb=2, nk=1)
    est = online.model()
    for got, want in zip(_blocks(est), _blocks(batch.model), strict=True):
        np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose(est.A, batch.model.A, atol=1e-7)
    np.testing.assert_allclose(est.output_bias, batch.model.output_bias, atol=1e-7)


def test_a_checkpointed_learner_resumes_exactly():
    data = _plant_record(n=1200)
    e = data.experiments[0]
    opts = {"na": 1, "nb": 2, "nk": 1}
    whole = online_estimator("block-state-space", "rls", opts, data.inputs, data.outputs)
    whole.partial_fit(e.u, e.y)
    first = online_estimator("block-state-space", "rls", opts, data.inputs, data.outputs)
    first.partial_fit(e.u[:500], e.y[:500])
    saved = json.loads(json.dumps(first.state()))
    second = online_estimator("block-state-space", "rls", opts, data.inputs, data.outputs)
    second.restore(saved).partial_fit(e.u[500:], e.y[500:])
    assert second.estimate() == whole.estimate()
    np.testing.assert_array_equal(second.model().input_range, whole.model().input_range)


def test_saved_loaded_and_exported_the_model_simulates_identically(tmp_path):
    from blockid.models.export import to_python_module

    data = _plant_record(n=1500, snr_db=40)
    model = fit_model(data, "block-state-space", method="batch", na=2, nb=2, nk=1).model
    path = tmp_path / "m.json"
    save_model(model, path)
    loaded = load_model(path)
    e = data.experiments[0]
    u2 = e.u * 1.3  # beyond the estimation range too: the tangent continuation
    np.testing.assert_array_equal(loaded.simulate(u2, e.y[:10]), model.simulate(u2, e.y[:10]))
    namespace: dict = {}
    exec(to_python_module(model), namespace)  # noqa: S102 - the module under test
    np.testing.assert_allclose(namespace["simulate"](u2), model.simulate(u2), atol=1e-10)
    np.testing.assert_allclose(
        namespace["simulate"](u2, e.y[:10]), model.simulate(u2, e.y[:10]), atol=1e-10
    )


@pytest.mark.parametrize(
    "options,message",
    [
        ({"output_block": "polynomial"}, "input blocks only"),
        ({"input_block": "dead-zone"}, "linear in its parameters"),
        ({"input_block": "piecewise-linear"}, "sum to a constant"),
        ({"na": "1,1;1,1"}, "one whole number"),
        ({"nb": 0}, "nb must be at least 1"),
    ],
)
def test_what_the_regression_cannot_hold_is_refused_with_the_option_named(options, message):
    data = _plant_record(n=300)
    with pytest.raises(ParameterError, match=message):
        fit_model(data, "block-state-space", method="batch", **{"na": 1, "nb": 2, **options})


def test_an_input_that_never_moves_or_copies_another_is_named():
    from blockid.errors import DataError

    data = _plant_record(n=400)
    e = data.experiments[0]
    still = Dataset.from_arrays(np.column_stack([e.u[:, 0], np.full(400, 0.7)]), e.y,
                                ["u1", "u2"], ["y1", "y2"])  # fmt: skip
    with pytest.raises(DataError, match="input 'u2' is constant"):
        fit_model(still, "block-state-space", method="batch", na=1, nb=2)
    copy = Dataset.from_arrays(np.column_stack([e.u[:, 0], 2 * e.u[:, 0] + 1]), e.y,
                               ["u1", "u2"], ["y1", "y2"])  # fmt: skip
    with pytest.raises(DataError, match="'u1', 'u2' are \\(nearly\\) linear combinations"):
        fit_model(copy, "block-state-space", method="rls", na=1, nb=2)
