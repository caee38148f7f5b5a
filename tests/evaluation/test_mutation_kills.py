"""ModelOutput.to_dict, the JSON summary every command prints, key by key; the warnings
of a network's subsystems and of a single model; data one sample too short (gaps found by
mutation testing, see docs/testing.md)."""

import numpy as np
import pytest

from blockid.blocks import Polynomial
from blockid.data import Dataset
from blockid.errors import OrderError
from blockid.evaluation import evaluate
from blockid.models import ARX, Hammerstein, Network


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


_LEAVES = (
    "input 'u1' leaves the range seen in estimation [-1, 1] in 1 of 6 samples (by up to "
    "100 % of that range): the model extrapolates there (along the block's tangent at the "
    "range's end) (experiment 'experiment 1')"
)


def _two_subsystems():
    # S1: w = u + 0.5 u^2 (polynomial, fitted on u in [-1, 1]), v1(t) = 0.5 v1(t-1) + w(t-1)
    # S2: y(t) = 0.3 y(t-1) + 2 v1(t-1), fed by S1 only
    s1 = Hammerstein(
        "u1", "v1", input_block=Polynomial([0.0, 1.0, 0.5]), na=1, nb=1, nk=1, a=[-0.5]
    ).replace(ranges={"u": [-1.0, 1.0]})
    s2 = ARX(["v1"], ["y"], 1, 1, 1, a={"y": {"y": [-0.3]}}, b={"y": {"v1": [2.0]}})
    return s1, s2


U1 = np.array([0.0, 0.5, 3.0, 0.0, -0.5, 0.0])  # 3 lies beyond [-1, 1] by its width


def test_network_warnings_name_the_subsystem_that_extrapolates():
    s1, s2 = _two_subsystems()
    net = Network([("S1", s1), ("S2", s2)])
    y = net.simulate(U1)
    # beyond u = 1 the polynomial continues along its tangent: w(3) = 1.5 + 2 * 2 = 5.5
    np.testing.assert_allclose(y[:, 0], [0.0, 0.0, 0.625, 5.8125, 2.90625, 1.078125])
    data = Dataset.from_arrays(U1, y, inputs=["u1"], outputs=["v1", "y"])
    out = evaluate(net, data)
    assert out.warnings == [f"S1: {_LEAVES}"]
    assert out.metrics["fit_percent"] == {"v1": 100.0, "y": 100.0}


def test_single_model_warnings_have_no_subsystem_prefix():
    s1, _ = _two_subsystems()
    data = Dataset.from_arrays(U1, s1.simulate(U1), inputs=["u1"], outputs=["v1"])
    assert evaluate(s1, data).warnings == [_LEAVES]


def test_too_short_data_name_the_model_and_the_shortest_length_passes():
    # y(t) = 0.5 y(t-1) - 0.25 y(t-2) + u(t-1): looks back 2 samples
    model = ARX(["u"], ["y"], 2, 1, 1, a={"y": {"y": [-0.5, 0.25]}}, b={"y": {"u": [1.0]}})
    u, y = np.array([1.0, 2.0, 0.0]), np.array([0.5, -1.0, 1.625])
    too_short = Dataset.from_arrays(u[:2], y[:2], inputs=["u"], outputs=["y"])
    with pytest.raises(OrderError) as info:
        evaluate(model, too_short)
    assert str(info.value).startswith(
        "the arx model looks back 2 samples, so it needs more than 2 samples in every "
        "experiment, but experiment 'experiment 1' has only 2"
    )
    # three samples leave one to score: y(2) = 0.5 (-1) - 0.25 (0.5) + 2 = 1.375
    out = evaluate(model, Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"]))
    assert out.skip == 2
    np.testing.assert_allclose(out.outputs[0][:, 0], [0.5, -1.0, 1.375])
    assert out.metrics["mse"] == {"y": pytest.approx(0.0625)}
