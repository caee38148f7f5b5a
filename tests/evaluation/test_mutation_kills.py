"""ModelOutput.to_dict, the JSON summary every command prints, key by key (a gap found by
mutation testing, see docs/testing.md)."""

import numpy as np

from blockid.data import Dataset
from blockid.evaluation import evaluate
from blockid.models import ARX


def test_to_dict_is_the_documented_summary():
    # y(t) = u(t-1) exactly: every error is zero and the fit is 100 %
    u = np.array([1.0, -1.0, 2.0, 0.0, 3.0])
    y = np.concatenate([[0.0], u[:-1]])
    data = Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"])
    model = ARX(["u"], ["y"], 0, 1, 1, b={"y": {"u": [1.0]}})
    out = evaluate(model, data).to_dict()
    assert list(out) == [
        "mode",
        "n_samples",
        "initial_samples_per_experiment",
        "metrics",
        "warnings",
    ]
    assert out["mode"] == "simulation"
    assert out["n_samples"] == 5
    assert out["initial_samples_per_experiment"] == model.max_lag
    assert out["metrics"]["mse"] == {"y": 0.0}
    assert out["metrics"]["fit_percent"] == {"y": 100.0}
    assert out["warnings"] == []
    assert evaluate(model, data, "one-step").to_dict()["mode"] == "one-step"
