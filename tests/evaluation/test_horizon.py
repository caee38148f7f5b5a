"""k-step-ahead prediction against its two ends and a hand-iterated ARX predictor."""

from __future__ import annotations

import numpy as np
import pytest

from blockid.data import Dataset
from blockid.errors import DataError, ParameterError
from blockid.evaluation import evaluate
from blockid.evaluation.horizon import k_step_prediction
from blockid.fitting import fit_model


def _record(n=400, seed=0, noise=0.2):
    rng = np.random.default_rng(seed)
    u, e = rng.standard_normal(n), noise * rng.standard_normal(n)
    y = np.zeros(n)
    for t in range(2, n):
        y[t] = 1.5 * y[t - 1] - 0.7 * y[t - 2] + u[t - 1] + 0.5 * u[t - 2] + e[t]
    return Dataset.from_arrays(u, y, ["u"], ["y"])


@pytest.mark.parametrize("structure", ["arx", "output-error"])
def test_one_step_ahead_is_the_one_step_prediction(structure):
    data = _record()
    model = fit_model(data, structure, na=2, nb=2, nk=1).model
    one = k_step_prediction(model, data, 1)
    pred = evaluate(model, data, "one-step")
    np.testing.assert_allclose(one.outputs[0][model.max_lag :],
                               pred.outputs[0][model.max_lag :], rtol=1e-10, atol=1e-12)  # fmt: skip


def test_the_arx_predictor_iterated_by_hand_and_the_error_growing_with_the_horizon():
    data = _record()
    model = fit_model(data, "arx", na=2, nb=2, nk=1).model
    a, b = model.a["y"]["y"], model.b["y"]["u"]
    u0, y0 = float(model.input_offset[0]), float(model.output_offset[0])
    u = data.experiments[0].u[:, 0] - u0
    y = data.experiments[0].y[:, 0] - y0
    k, t = 3, 50
    guess = {s: y[s] for s in range(t - k + 1)}  # measured up to t - k
    for s in range(t - k + 1, t + 1):
        guess[s] = -a[0] * guess[s - 1] - a[1] * guess[s - 2] + b[0] * u[s - 1] + b[1] * u[s - 2]
    out = k_step_prediction(model, data, k)
    assert out.outputs[0][t, 0] == pytest.approx(guess[t] + y0, rel=1e-9)
    rmse = [k_step_prediction(model, data, h).metrics["rmse"]["y"] for h in (1, 3, 10)]
    assert rmse[0] < rmse[1] < rmse[2]
    free = evaluate(model, data, "simulation").metrics["rmse"]["y"]
    far = k_step_prediction(model, data, 50).metrics["rmse"]["y"]
    assert far == pytest.approx(free, rel=0.1)  # a long horizon is nearly the free run


def test_a_bad_horizon_and_a_record_too_short_are_named():
    data = _record(n=30)
    model = fit_model(data, "arx", na=2, nb=2, nk=1).model
    with pytest.raises(ParameterError, match="steps ahead"):
        k_step_prediction(model, data, 0)
    with pytest.raises(DataError, match="fewer steps ahead"):
        k_step_prediction(model, data, 40)
