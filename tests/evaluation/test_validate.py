"""evaluate(): free-run and one-step output, initial samples skipped, by hand.

The model is ``y(t) = 0.5 y(t-1) - 0.25 y(t-2) + u(t-1)`` (``max_lag = 2``) on two
short experiments; every number below is worked out in the comments, in binary-exact
arithmetic, so the metrics are compared exactly or to rounding.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from blockid.blocks import Polynomial
from blockid.data import Dataset
from blockid.data.dataset import Experiment
from blockid.errors import DataError, OrderError, ParameterError
from blockid.evaluation import evaluate
from blockid.models import ARX, Hammerstein, Network

MODEL = ARX(["u"], ["y"], 2, 1, 1, a={"y": {"y": [-0.5, 0.25]}}, b={"y": {"u": [1.0]}})

U_A = [1.0, 0.0, 2.0, 0.0, 0.0, 0.0]
Y_A = [0.0, 1.0, 0.5, 2.0, 1.0, 0.0]
U_B = [0.0, 0.0, -4.0, 0.0]
Y_B = [2.0, 0.0, 0.0, -8.0]

# Free run from the first two measured outputs:
#   A: t2 = 0.5*1 - 0.25*0 + 0 = 0.5;  t3 = 0.25 - 0.25 + 2 = 2;  t4 = 1 - 0.125 = 0.875;
#      t5 = 0.4375 - 0.5 = -0.0625
#   B: t2 = 0 - 0.5 + 0 = -0.5;  t3 = -0.25 - 0 - 4 = -4.25
SIM_A = [0.0, 1.0, 0.5, 2.0, 0.875, -0.0625]
SIM_B = [2.0, 0.0, -0.5, -4.25]
SIM_ERR = [0.0, 0.0, 0.125, 0.0625, 0.5, -3.75]  # y - y_sim after the first two of each
# One step ahead from measured past outputs:
#   A: t2 = 0.5;  t3 = 0.25 - 0.25 + 2 = 2;  t4 = 1 - 0.125 = 0.875;  t5 = 0.5 - 0.5 = 0
#   B: t2 = -0.5;  t3 = 0 - 0 - 4 = -4
PRED_A = [0.0, 1.0, 0.5, 2.0, 0.875, 0.0]
PRED_B = [2.0, 0.0, -0.5, -4.0]
PRED_ERR = [0.0, 0.0, 0.125, 0.0, 0.5, -4.0]
Y_KEPT = [0.5, 2.0, 1.0, 0.0, 0.0, -8.0]  # mean -0.75; sum of squared deviations 65.875


def _data() -> Dataset:
    def exp(name, u, y):
        return Experiment(name, np.array(u)[:, None], np.array(y)[:, None])

    return Dataset(("u",), ("y",), 0.1, [exp("A", U_A, Y_A), exp("B", U_B, Y_B)])


def test_the_hand_computation_is_right():
    # the numbers above, checked once against the definition (not against blockid)
    assert sum((y - m) ** 2 for y, m in zip(Y_KEPT, [-0.75] * 6, strict=True)) == 65.875
    kept_sim = SIM_A[2:] + SIM_B[2:]
    assert [y - s for y, s in zip(Y_KEPT, kept_sim, strict=True)] == SIM_ERR


def test_free_run_outputs_and_metrics():
    out = evaluate(MODEL, _data(), "simulation")
    assert out.skip == 2 and out.mode == "simulation"
    assert out.outputs[0][:, 0].tolist() == SIM_A
    assert out.outputs[1][:, 0].tolist() == SIM_B
    m = out.metrics
    # over the 6 samples after the initial two of each experiment (not 10)
    assert m["mse"]["y"] == pytest.approx(14.33203125 / 6, rel=1e-15)
    assert m["rmse"]["y"] == pytest.approx(math.sqrt(14.33203125 / 6), rel=1e-15)
    assert m["mae"]["y"] == pytest.approx(4.4375 / 6, rel=1e-15)
    assert m["max_abs_error"]["y"] == 3.75  # from a negative error
    assert m["fit_percent"]["y"] == pytest.approx(
        100.0 * (1.0 - math.sqrt(14.33203125 / 65.875)), rel=1e-14
    )
    assert out.to_dict()["n_samples"] == 10
    assert out.to_dict()["initial_samples_per_experiment"] == 2


def test_one_step_outputs_and_metrics():
    out = evaluate(MODEL, _data(), "one-step")
    assert out.outputs[0][:, 0].tolist() == PRED_A
    assert out.outputs[1][:, 0].tolist() == PRED_B
    m = out.metrics
    assert m["mse"]["y"] == pytest.approx(16.265625 / 6, rel=1e-15)
    assert m["mae"]["y"] == pytest.approx(4.625 / 6, rel=1e-15)
    assert m["max_abs_error"]["y"] == 4.0
    assert m["fit_percent"]["y"] == pytest.approx(
        100.0 * (1.0 - math.sqrt(16.265625 / 65.875)), rel=1e-14
    )
    frame = out.to_frame()
    assert frame["y_pred"].tolist() == PRED_A + PRED_B


def test_two_outputs_are_scored_separately():
    # y1 is MODEL on u; y2 = u(t-1) (a pure delay). Both free-run from rest values.
    model = ARX(
        ["u"],
        ["y1", "y2"],
        na=[[2, 0], [0, 0]],
        nb=1,
        nk=1,
        a={"y1": {"y1": [-0.5, 0.25], "y2": []}, "y2": {"y1": [], "y2": []}},
        b={"y1": {"u": [1.0]}, "y2": {"u": [1.0]}},
    )
    u = np.array(U_A)
    y = np.column_stack([Y_A, [5.0, 1.0, 0.0, 2.0, 0.0, -3.0]])
    data = Dataset.from_arrays(u, y, inputs=["u"], outputs=["y1", "y2"])
    m = evaluate(model, data, "simulation").metrics
    # y1 errors after t = 2: [0, 0, 0.125, 0.0625]; y2: u(t-1) = [0, 2, 0, 0] vs
    # [0, 2, 0, -3]: errors [0, 0, 0, -3]
    assert m["mse"] == {"y1": 0.01953125 / 4, "y2": 9.0 / 4}
    assert m["max_abs_error"] == {"y1": 0.125, "y2": 3.0}


def test_bad_mode_and_mismatched_signals():
    with pytest.raises(ParameterError, match="mode must be one of simulation, one-step"):
        evaluate(MODEL, _data(), "two-step")
    other = Dataset.from_arrays(np.zeros(5), np.zeros(5), inputs=["v"], outputs=["y"])
    with pytest.raises(DataError, match=r"expects inputs \['u'\].*have inputs \['v'\]"):
        evaluate(MODEL, other)


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
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


# ---------------------------------------------- warnings before a model misleads (issue 37)
def _first_order(a: float, b: float) -> ARX:
    return ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [a]}}, b={"y": {"u": [b]}})


def _plant_record() -> Dataset:
    """``y(t) = 0.8 y(t-1) + 0.2 u(t-1)`` on a 0-10 V staircase: y within [0.17, 9.3]."""
    rng = np.random.default_rng(3)
    u = np.repeat(rng.uniform(0.0, 10.0, 40), 10)
    y = np.zeros(u.size)
    for t in range(1, u.size):
        y[t] = 0.8 * y[t - 1] + 0.2 * u[t - 1]
    return Dataset(("u",), ("y",), 1.0, [Experiment("test", u[:, None], y[:, None])])


def test_an_output_far_beyond_the_measured_range_is_warned_in_both_modes():
    data = _plant_record()
    assert evaluate(_first_order(-0.8, 0.2), data).warnings == []  # the plant itself
    loud = _first_order(-0.8, 1.0)  # five times the plant's gain
    (sim,) = evaluate(loud, data).warnings
    assert "free run of 'y' reaches [0.8565, 46.54] against the measured range" in sim
    assert "by 4.07 times its width" in sim
    (pred,) = evaluate(loud, data, "one-step").warnings
    assert "one-step prediction of 'y' reaches" in pred


def test_an_unstable_model_is_warned_and_its_diverged_free_run_marked():
    data = _plant_record()
    unstable = _first_order(-1.05, 0.2)
    sim = evaluate(unstable, data)
    assert any(w.startswith("the model is unstable: its linear part has a pole at 1.05")
               for w in sim.warnings)  # fmt: skip
    assert "reaches 3.41e+09" in sim.diverged and "a pole at 1.05" in sim.diverged
    assert sim.to_dict()["diverged"] == sim.diverged
    one_step = evaluate(unstable, data, "one-step")  # predicts one step: not diverged
    assert one_step.diverged is None and "diverged" not in one_step.to_dict()
    assert any("unstable" in w for w in one_step.warnings)
    assert evaluate(_first_order(-0.8, 0.2), data).diverged is None
