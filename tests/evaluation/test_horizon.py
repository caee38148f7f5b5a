"""Prediction k samples ahead against its two ends (the one-step prediction and the free
run) and a hand-iterated ARX predictor."""

from __future__ import annotations

import numpy as np
import pytest

from blockid.data import Dataset
from blockid.errors import ParameterError
from blockid.evaluation import evaluate, predict
from blockid.fitting import fit_model


def _record(n=400, seed=0, noise=0.2, cubic=0.0):
    rng = np.random.default_rng(seed)
    u, e = rng.standard_normal(n), noise * rng.standard_normal(n)
    w = u + cubic * u**3
    y = np.zeros(n)
    for t in range(2, n):
        y[t] = 1.5 * y[t - 1] - 0.7 * y[t - 2] + w[t - 1] + 0.5 * w[t - 2] + e[t]
    return Dataset.from_arrays(u, y, ["u"], ["y"])


_MODELS = {
    "arx": dict(na=2, nb=2, nk=1),
    "output-error": dict(na=2, nb=2, nk=1),
    "hammerstein": dict(na=2, nb=2, nk=1, r1=3),
}


def _fitted(structure):
    data = _record(cubic=0.2 if structure == "hammerstein" else 0.0)
    return data, fit_model(data, structure, **_MODELS[structure]).model


@pytest.mark.parametrize("structure", list(_MODELS))
def test_horizon_one_is_the_one_step_prediction_and_the_window_agrees(structure):
    data, model = _fitted(structure)
    one = predict(model, data, horizon=1)
    today = evaluate(model, data, "one-step")
    assert one.mode == "one-step"
    np.testing.assert_array_equal(one.outputs[0], today.outputs[0])
    assert one.metrics == today.metrics
    # the window of L + 1 samples from L measured outputs is the same predictor
    lag, exp = model.max_lag, data.experiments[0]
    for t in (lag, 57, exp.n_samples - 1):
        run = model.simulate(exp.u[t - lag : t + 1], exp.y[t - lag : t])
        assert run[-1, 0] == pytest.approx(today.outputs[0][t, 0], rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("structure", list(_MODELS))
def test_a_horizon_as_long_as_the_record_is_the_free_run(structure):
    """Bit for bit: where a window would start before the record the prediction is the
    free run's sample (the free run over the inputs up to t is the first t + 1 samples of
    the whole run, checked below to 1e-12), and at this horizon every window does."""
    data, model = _fitted(structure)
    free = evaluate(model, data, "simulation")
    n = data.experiments[0].n_samples
    for horizon in (n - model.max_lag, n, 10 * n):
        far = predict(model, data, horizon=horizon)
        assert far.mode == "k-step" and far.horizon == horizon
        np.testing.assert_array_equal(far.outputs[0], free.outputs[0])
        assert far.metrics == free.metrics
    exp = data.experiments[0]
    for t in (50, 201, n - 2):  # causality: the run's prefix is the run over the prefix
        run = model.simulate(exp.u[: t + 1], exp.y[: model.max_lag])
        np.testing.assert_allclose(run, free.outputs[0][: t + 1], rtol=1e-12, atol=1e-12)
    # a shorter horizon: the free run's samples until the first window inside the record
    h, lag = 20, model.max_lag
    near = predict(model, data, horizon=h)
    np.testing.assert_array_equal(near.outputs[0][: lag + h], free.outputs[0][: lag + h])
    assert near.outputs[0][lag + h, 0] != free.outputs[0][lag + h, 0]


def test_the_arx_predictor_iterated_by_hand_and_the_error_growing_with_the_horizon():
    data, model = _fitted("arx")
    a, b = model.a["y"]["y"], model.b["y"]["u"]
    u0, y0 = float(model.input_offset[0]), float(model.output_offset[0])
    u = data.experiments[0].u[:, 0] - u0
    y = data.experiments[0].y[:, 0] - y0
    k, t = 3, 50
    guess = {s: y[s] for s in range(t - k + 1)}  # measured up to t - k
    for s in range(t - k + 1, t + 1):
        guess[s] = -a[0] * guess[s - 1] - a[1] * guess[s - 2] + b[0] * u[s - 1] + b[1] * u[s - 2]
    out = predict(model, data, horizon=k)
    assert out.outputs[0][t, 0] == pytest.approx(guess[t] + y0, rel=1e-9)
    rmse = [predict(model, data, horizon=h).metrics["rmse"]["y"] for h in (1, 3, 10)]
    assert rmse[0] < rmse[1] < rmse[2]
    free = evaluate(model, data, "simulation").metrics["rmse"]["y"]
    far = predict(model, data, horizon=50).metrics["rmse"]["y"]
    assert far == pytest.approx(free, rel=0.1)  # a long horizon is nearly the free run
    assert out.to_dict()["horizon"] == 3 and out.to_dict()["mode"] == "k-step"


def test_a_model_without_a_predictor_predicts_by_its_free_run():
    data = _record()
    model = fit_model(data, "state-space", nx=2).model
    one = evaluate(model, data, "one-step")
    free = evaluate(model, data, "simulation")
    if not np.array_equal(one.outputs[0], free.outputs[0]):
        pytest.skip("this state space has a predictor gain")
    out = predict(model, data, horizon=5)
    np.testing.assert_array_equal(out.outputs[0], free.outputs[0])
    assert any("free run at every horizon" in w for w in out.warnings)


def test_a_bad_horizon_is_named():
    data, model = _fitted("arx")
    for bad in (0, -1, 2.5, True):
        with pytest.raises(ParameterError, match="horizon must be a whole number >= 1"):
            predict(model, data, horizon=bad)


def _wiener_hammerstein():
    from blockid.blocks import LinearBlock, Polynomial
    from blockid.models import WienerHammerstein

    return WienerHammerstein(
        "u", "y",
        first=LinearBlock(2, 2, 0, a=[-1.1, 0.35], b=[0.4, 0.2]),
        static=Polynomial([1.0, 0.3, -0.2], constant=False),
        second=LinearBlock(1, 2, 1, a=[-0.6], b=[1.0, 0.5]),
    )  # fmt: skip


def test_a_chain_keeps_the_dynamics_before_its_last_linear_block():
    """A Wiener-Hammerstein model's first linear block is not set by measured outputs:
    it runs over the whole record, as in its one-step predictor, so the model predicts
    its own noise-free output exactly at every horizon (a window restarting it at rest
    missed by 1.49 at 3 steps, against the output's standard deviation of 1.87)."""
    model = _wiener_hammerstein()
    u = np.random.default_rng(2).standard_normal(300)
    data = Dataset.from_arrays(u, model.simulate(u)[:, 0], ["u"], ["y"])
    for h in (2, 3, 10, 100):
        assert predict(model, data, horizon=h).metrics["rmse"]["y"] < 1e-9
    noisy = Dataset.from_arrays(u, data.experiments[0].y[:, 0] + 0.05 * np.sin(np.arange(300)),
                                ["u"], ["y"])  # fmt: skip
    rmse = [predict(model, noisy, horizon=h).metrics["rmse"]["y"] for h in (1, 2, 300)]
    assert rmse[0] > 0 and rmse[1] > 0 and rmse[2] == evaluate(model, noisy).metrics["rmse"]["y"]


def test_a_chain_s_recursion_is_its_window_where_no_block_precedes_the_linear_one():
    """Output error: the chain's recursion and a window of the model's own free run are
    the same prediction, to rounding."""
    data, model = _fitted("output-error")
    exp, lag = data.experiments[0], model.max_lag
    for h in (2, 7, 40):
        out = predict(model, data, horizon=h).outputs[0]
        for t in (lag + h, 123, exp.n_samples - 1):
            run = model.simulate(exp.u[t - h - lag + 1 : t + 1], exp.y[t - h - lag + 1 : t - h + 1])
            assert out[t, 0] == pytest.approx(run[-1, 0], rel=1e-10, abs=1e-12)
