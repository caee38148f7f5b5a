"""The pass driver of the papers' recursive fitters (fitting/recursive.py).

The driver is exercised with a toy algorithm written in plain Python (a static gain
estimated by least mean squares) whose every step is known, so that the history
decimation, the failure reports and the convergence rule can be checked exactly.
"""

import ast
from pathlib import Path

import numpy as np
import pytest

import blockid.fitting.recursive as recursive
from blockid._kernels.rls import OK
from blockid.config import config_context
from blockid.data import Dataset
from blockid.data.dataset import Experiment
from blockid.errors import DataError, EstimationError, ParameterError
from blockid.estimators import RecursiveLeastSquares
from blockid.estimators.forgetting import ForgettingSchedule
from blockid.fitting import fit_arx, fit_key_term_rls, fit_model
from blockid.fitting.recursive import RecursiveAlgorithm, fit_recursive, normalised_signals
from blockid.models import ARX, BlockModel

import reference
from reference import _dataset

GAIN = 2.0
LENGTHS = (301, 201)  # samples of the two experiments: 300 + 200 updates a pass (n0 = 1)


class StaticGainLMS(RecursiveAlgorithm):
    """``y = g u`` by LMS, ``theta += gain u (y - u theta) + drift``, in pure Python.

    Keeps ``trace`` (theta after every update, over all passes, in the recursion's
    units) and ``ends`` (theta after every pass). ``fail_at = (pass, sample)`` makes
    the run fail there with reason 7.
    """

    method = "toy"
    label = "toy-lms"
    names = ["g"]
    n0 = 1
    a = slice(0, 0)  # no linear block dynamics: nothing to check for stability
    reasons = {7: "the toy failed"}

    def __init__(self, signals, gain=0.05, drift=0.0, fail_at=None):
        self.factor = signals.y_map[1] / signals.u_map[1]
        self.gain, self.drift, self.fail_at = gain, drift, fail_at
        self.pass_number = 0
        self.trace: list[float] = []
        self.ends: list[float] = []
        self.last: float | None = None  # theta after the latest experiment

    def run(self, theta, P, u, y, count, hist, stride):
        if count == 0:
            self.pass_number += 1
            if self.last is not None:
                self.ends.append(self.last)
        for k in range(self.n0, u.size):
            if self.fail_at == (self.pass_number, k):
                return k, 7, " (as asked)"
            theta[0] += self.gain * u[k] * (y[k] - u[k] * theta[0]) + self.drift
            self.trace.append(float(theta[0]))
            done = k - self.n0 + 1
            if done % stride == 0 and done // stride <= hist.shape[0]:
                hist[done // stride - 1] = theta
        self.last = float(theta[0])
        return OK, 0, ""

    def to_data_units(self, theta):
        return theta * self.factor

    def from_data_units(self, theta):
        return theta / self.factor

    def model(self, theta, data):
        return BlockModel(data.inputs[0], data.outputs[0], na=0, nb=1, nk=0, b=theta)

    def settings(self, common):
        return {"toy": True, **common}


def _data(noise=0.05, seed=0):
    rng = np.random.default_rng(seed)
    exps = []
    for name, n in zip("ab", LENGTHS, strict=True):
        u = 3.0 * rng.standard_normal(n)
        exps.append(Experiment(name, u, GAIN * u + noise * rng.standard_normal(n)))
    return Dataset(("u",), ("y",), 1.0, exps)


def _fit(toy_options=None, **options):
    data = _data()
    signals = normalised_signals(data, True)
    toy = StaticGainLMS(signals, **(toy_options or {}))
    kwargs = dict(initial_parameters=0.0, initial_covariance=1.0, passes=20, tol=1e-6)
    kwargs.update(record_history=False)
    kwargs.update(options)
    return toy, lambda: fit_recursive(data, signals, toy, **kwargs)


def _pass_end_changes(toy):
    ends = np.array([*toy.ends, toy.last])
    return np.abs(np.diff(ends)) / (1.0 + np.abs(ends[1:]))


# ---------------------------------------------------------------------- history
def test_history_is_decimated_to_history_rows_with_the_right_update_counts():
    toy, fit = _fit(record_history=True, passes=3, tol=1.0)  # converges after pass 2
    with config_context(history_rows=100):
        history = fit().history
    # 3 passes (the most allowed) x 500 updates: every ceil(1500 / 100) = 15th is kept
    stride = 15
    toy_history = np.array(toy.trace)
    per_pass = np.concatenate(
        [stride * np.arange(1, 300 // stride + 1), 300 + stride * np.arange(1, 200 // stride + 1)]
    )
    expected = np.concatenate([per_pass, 500 + per_pass])
    assert len(history["update"]) <= 100
    np.testing.assert_array_equal(history["update"], expected)
    assert history["names"] == ["g"]
    np.testing.assert_array_equal(history["theta"][:, 0], toy_history[expected - 1] * toy.factor)


def test_a_short_record_keeps_every_update():
    toy, fit = _fit(record_history=True, passes=2, tol=1.0)
    history = fit().history
    np.testing.assert_array_equal(history["update"], np.arange(1, 1001))
    np.testing.assert_array_equal(history["theta"][:, 0], np.array(toy.trace) * toy.factor)


def test_a_failure_in_a_later_pass_carries_the_history_up_to_the_failing_sample():
    toy, fit = _fit({"fail_at": (2, 57)}, record_history=True)
    with pytest.raises(EstimationError) as info:
        fit()
    message = str(info.value)
    assert message.startswith(
        "toy diverged in pass 2, experiment 'a', at sample 57: the toy failed (as asked)."
    )
    history = info.value.history
    # all of pass 1 (500 updates), then the 56 updates of pass 2 before sample 57
    np.testing.assert_array_equal(history["update"], np.arange(1, 557))
    np.testing.assert_array_equal(history["theta"][:, 0], np.array(toy.trace) * toy.factor)
    assert history["names"] == ["g"]


def test_a_failure_carries_no_history_unless_asked():
    _, fit = _fit({"fail_at": (1, 10)})
    with pytest.raises(EstimationError, match="at sample 10") as info:
        fit()
    assert info.value.history is None


# ---------------------------------------------------------------------- convergence
def test_passes_stop_at_the_first_pass_that_changes_theta_less_than_tol():
    toy, fit = _fit({"gain": 0.003}, tol=1e-6)  # slow: about 0.2 of the error left a pass
    result = fit()
    changes = _pass_end_changes(toy)
    n = result.settings["passes_run"]
    assert 2 < n < 20 and result.settings["converged"] is True
    assert changes[-1] < 1e-6 and np.all(changes[:-1] >= 1e-6)  # stopped at the first
    assert len(toy.ends) + 1 == n
    assert result.model.simulate(np.ones(3))[-1, 0] == pytest.approx(GAIN, abs=5e-3)
    assert result.method == "toy-lms" and result.settings["toy"] is True


def test_one_pass_is_not_checked_for_convergence():
    _, fit = _fit({"drift": 1e-7}, passes=1)
    result = fit()
    assert result.settings["passes_run"] == 1 and result.settings["converged"] is None


def test_not_converging_in_passes_raises_with_the_relative_change():
    toy, fit = _fit({"gain": 0.0, "drift": 1e-3}, passes=4, tol=1e-9, record_history=True)
    with pytest.raises(EstimationError) as info:
        fit()
    change = _pass_end_changes(toy)[-1]
    assert change > 1e-9
    assert (
        f"toy did not converge in 4 passes: the parameters still changed by up to "
        f"{change:.3g} (relative) in the last pass, tolerance 1e-09" in str(info.value)
    )
    assert info.value.history["theta"].shape == (4 * 500, 1)


def test_an_unstable_linear_block_after_a_pass_is_a_failure():
    class Unstable(StaticGainLMS):
        a = slice(0, 1)  # read theta as a_1: a pole at -theta

    data = _data()
    signals = normalised_signals(data, True)
    toy = Unstable(signals, gain=0.0, drift=1e-2)
    with pytest.raises(EstimationError, match=r"after pass 1 the linear block is unstable"):
        fit_recursive(
            data,
            signals,
            toy,
            initial_parameters=0.0,
            initial_covariance=1.0,
            passes=3,
            tol=1e-6,
            record_history=False,
        )


def test_initial_parameters_as_a_vector_are_in_the_data_units():
    toy, fit = _fit(initial_parameters=[GAIN], passes=1)
    fit()
    # the first update moved theta only a little away from GAIN / factor
    assert toy.trace[0] * toy.factor == pytest.approx(GAIN, abs=0.05)


# ---------------------------------------------------------------------- forgetting
def _arx_data():
    arx = ARX(["u"], ["y"], 2, 2, 1, a={"y": {"y": [-1.2, 0.5]}}, b={"y": {"u": [1.0, 0.4]}})
    u = np.random.default_rng(3).uniform(-1.0, 1.0, 800)
    y = arx.simulate(u)[:, 0] + 0.01 * np.random.default_rng(4).standard_normal(800)
    return Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"])


def test_a_forgetting_schedule_and_its_string_give_identical_estimates():
    data = _arx_data()
    schedule = ForgettingSchedule((0.98, 1.0), (200,))
    kw = dict(na=2, nb=2, nk=1)
    text = fit_key_term_rls(data, "arx", forgetting="0.98:200,1", **kw)
    instance = fit_key_term_rls(data, "arx", forgetting=schedule, **kw)
    np.testing.assert_array_equal(
        instance.model.parameter_vector(0), text.model.parameter_vector(0)
    )
    assert instance.settings == text.settings
    by_text = fit_arx(data, 2, 2, 1, method="rls", forgetting="0.95:100,0.999", passes=2)
    by_instance = fit_arx(
        data,
        2,
        2,
        1,
        method="rls",
        forgetting=ForgettingSchedule.parse("0.95:100,0.999"),
        passes=2,
    )
    np.testing.assert_array_equal(
        by_instance.model.parameter_vector(0), by_text.model.parameter_vector(0)
    )


def test_fit_arx_reads_the_forgetting_string_once(monkeypatch):
    # two outputs, two experiments, two passes: eight partial_fit calls
    texts = []
    parse = ForgettingSchedule.parse.__func__

    def counting(cls, spec):
        if isinstance(spec, str):
            texts.append(spec)
        return parse(cls, spec)

    monkeypatch.setattr(ForgettingSchedule, "parse", classmethod(counting))
    rng = np.random.default_rng(5)
    exps = [
        Experiment(n, rng.standard_normal((400, 1)), rng.standard_normal((400, 2))) for n in "ab"
    ]
    data = Dataset(("u",), ("y1", "y2"), 1.0, exps)
    fit_arx(
        data,
        1,
        1,
        1,
        method="hierarchical-rls",
        forgetting="0.98",
        passes=2,
        max_mse_ratio=None,
        allow_unstable=True,
    )
    assert texts == ["0.98"]


def test_an_estimator_accepts_a_schedule_and_gives_the_same_chunked_estimates():
    rng = np.random.default_rng(6)
    Phi = rng.standard_normal((600, 3))
    y = Phi @ [1.0, -2.0, 0.5] + 0.1 * rng.standard_normal(600)
    whole = RecursiveLeastSquares(forgetting="0.95:300,0.999").fit(Phi, y)
    chunked = RecursiveLeastSquares(forgetting=ForgettingSchedule.parse("0.95:300,0.999"))
    for start in range(0, 600, 150):
        chunked.partial_fit(Phi[start : start + 150], y[start : start + 150])
    np.testing.assert_array_equal(chunked.coef_, whole.coef_)


@pytest.mark.parametrize("forgetting", ["0.98:x", "1.5", "0.98:200,"])
def test_a_bad_forgetting_is_rejected_before_any_data_work(forgetting):
    # the data are not even a Dataset: reading `forgetting` comes first
    with pytest.raises(ParameterError, match="forgetting"):
        fit_key_term_rls(None, "arx", forgetting=forgetting)
    with pytest.raises(ParameterError, match="forgetting"):
        fit_arx(None, method="rls", forgetting=forgetting)
    with pytest.raises(DataError):  # while a good one gets as far as the data
        fit_key_term_rls(None, "arx", forgetting="0.98:200,1")


# ---------------------------------------------------------------------- layout
@pytest.mark.parametrize("module", ["key_term", "backlash", "recursive"])
def test_fitters_share_the_driver_and_import_nothing_private(module):
    path = Path(recursive.__file__).with_name(f"{module}.py")
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module:
            private = [a.name for a in node.names if a.name.startswith("_")]
            assert not private, f"{module} imports {private} from {node.module}"
            others = {"blockid.fitting.key_term", "blockid.fitting.backlash"}
            assert node.module not in others, f"{module} imports from {node.module}"


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
def test_recursive_fitters_refuse_what_is_not_a_dataset():
    u, y = reference._arx_data(20)
    with pytest.raises(DataError, match="key-term RLS needs a blockid Dataset, got ndarray"):
        fit_model(u, "hammerstein", method="key-term-rls")


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


def test_empty_trajectory_has_one_column_per_parameter():
    from blockid.fitting.recursive import _Trajectory

    theta, update = _Trajectory(5, 1).arrays()
    assert theta.shape == (0, 5) and update.shape == (0,)
