"""A fit's result (fitting/result.py): the model file's estimation entry it writes, and
that a changed result is a new one."""

import dataclasses

import numpy as np
import pytest

from blockid.data import Dataset
from blockid.fitting import fit_model
from blockid.fitting.result import FitResult, simulation_result


def _result(**kwargs):
    metrics = {"rmse": {"y": 0.5}}
    return FitResult("model", "batch", {"na": 2}, metrics, 300, **kwargs)


@pytest.mark.parametrize(
    ("mode", "key"),
    [("one-step", "one_step_on_estimation_data"), ("simulation", "simulation_on_estimation_data")],
)
def test_the_estimation_record_names_its_metrics_by_their_mode(mode, key):
    assert _result(metrics_mode=mode).estimation_record() == {
        "method": "batch",
        "settings": {"na": 2},
        "n_samples": 300,
        key: {"rmse": {"y": 0.5}},
    }


def test_a_result_is_frozen_and_replace_derives_a_new_one():
    result = _result()
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.method = "rls"
    changed = dataclasses.replace(result, method="rls")
    assert (changed.method, result.method) == ("rls", "batch")


def test_a_fit_records_its_samples_method_and_free_run_metrics():
    rng = np.random.default_rng(0)
    u = rng.standard_normal(200)
    y = np.zeros(200)
    for t in range(1, 200):
        y[t] = 0.5 * y[t - 1] + u[t - 1]
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    record = fit_model(data, "arx", method="batch", na=1, nb=1, nk=1).estimation_record()
    assert record["method"] == "batch" and record["n_samples"] == 200
    assert record["one_step_on_estimation_data"]["rmse"]["y"] < 1e-10


def test_a_simulation_result_holds_free_run_metrics_of_the_data():
    data = Dataset.from_arrays(np.zeros(40), np.zeros(40), ["u"], ["y"])
    metrics = {"rmse": {"y": 0.25}}
    result = simulation_result("model", data, "simulation-error", {"na": 1}, metrics)
    assert result == FitResult(
        "model", "simulation-error", {"na": 1}, metrics, 40, {}, metrics_mode="simulation"
    )
    timed = simulation_result("model", data, "subspace", {}, metrics, {"seconds": 1.5})
    assert timed.history == {"seconds": 1.5}
    assert "simulation_on_estimation_data" in timed.estimation_record()
