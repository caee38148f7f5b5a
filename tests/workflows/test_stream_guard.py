"""The outlier guard of a stream (workflows/stream_guard.py), issue 37: a glitch is not
learned from, nor are the samples whose regressors hold it; a clean record loses no
sample to the guard (the equivalence with the offline fit stands); a change that
lasts is learned; a divergence puts back the last good estimate."""

from __future__ import annotations

import json

import numpy as np
import pytest

from blockid.blocks import Backlash, Polynomial, TwoSegmentPolynomial
from blockid.errors import ParameterError
from blockid.fitting.online import online_estimator
from blockid.models import ARX, BacklashModel, Hammerstein, HammersteinWiener, Wiener
from blockid.workflows.stream import Failure, Step, stream_identification
from blockid.workflows.stream_guard import StreamGuard

from reference import tito_arx

N1 = TwoSegmentPolynomial.from_segments(
    positive=[0, 0.3, 0.1, -0.05], negative=[0, 0.15, -0.05, 0.03]
)
N2 = Polynomial([1.0, 0.2, 0.05], constant=False)
LINEAR = dict(na=3, nb=3, nk=8, a=np.real(np.poly([0.7, 0.5, -0.3]))[1:], b=[1.0, 0.5, 0.2])
KEY_TERM = {"na": 3, "nb": 3, "nk": 8}
SISO = ARX(["u"], ["y"], na=2, nb=2, nk=1, a={"y": {"y": [-1.5, 0.7]}}, b={"y": {"u": [1.0, 0.5]}})
TITO = tito_arx(inputs=("u1", "u2"))  # two inputs, two outputs
ARX_ORDERS = {"na": 2, "nb": 2, "nk": 1}

#: name -> (structure, method, options, plant)
LEARNERS = {
    "arx-rls": ("arx", "rls", ARX_ORDERS, SISO),
    "arx-aw-rls": ("arx", "aw-rls", ARX_ORDERS, SISO),
    "arx-hierarchical-rls": ("arx", "hierarchical-rls", {**ARX_ORDERS, "forgetting": 0.99}, SISO),
    "arx-two-outputs": ("arx", "rls", ARX_ORDERS, TITO),
    "hammerstein": (
        "hammerstein",
        "key-term-rls",
        KEY_TERM,
        Hammerstein("u", "y", input_block=N1, **LINEAR),
    ),
    "wiener": ("wiener", "key-term-rls", KEY_TERM, Wiener("u", "y", output_block=N2, **LINEAR)),
    "hammerstein-wiener": (
        "hammerstein-wiener",
        "key-term-rls",
        {**KEY_TERM, "forgetting": 0.999},
        HammersteinWiener("u", "y", input_block=N1, output_block=N2, **LINEAR),
    ),
    "backlash": (
        "backlash",
        "aw-rls",
        {"na": 2, "nb": 1, "nk": 1},
        BacklashModel(
            "u", "y", input_block=Backlash(0.9, 0.8, 0.9, 0.85), na=2, nb=1, nk=1, a=[-1.0, 0.17]
        ),
    ),  # fmt: skip
}


def _record(plant, n, seed=1, noise=0.01):
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.0, 1.0, (n, len(plant.inputs)))
    y = plant.simulate(u)
    return u, y + noise * rng.standard_normal(y.shape)


def _lines(u, y, plant):
    head = ",".join([*plant.inputs, *plant.outputs])
    return [head] + [",".join(map(repr, row)) for row in np.c_[u, y].tolist()]


def _stream(name, u, y, guard=10.0):
    structure, method, options, plant = LEARNERS[name]
    return list(
        stream_identification(_lines(u, y, plant), structure, list(plant.inputs),
                              list(plant.outputs), method=method, options=options, guard=guard)
    )  # fmt: skip


def _vector(parameters):
    if isinstance(parameters, dict):
        return np.concatenate([_vector(v) for v in parameters.values()])
    return np.atleast_1d(np.asarray(parameters, dtype=float))


def _not_learned(events):
    return [e.k for e in events if isinstance(e, Step) and e.not_learned]


@pytest.mark.parametrize("noise", [0.01, 0.0], ids=["noisy", "noise-free"])
@pytest.mark.parametrize("name", list(LEARNERS))
def test_a_clean_record_loses_no_sample_to_the_guard(name, noise):
    """Every learner, 3000 clean samples (noise-free too: its errors end at rounding
    level, below the scale's floor): nothing rejected, and the estimate of the stream
    without a guard, bit for bit (so the one-pass offline fit's)."""
    u, y = _record(LEARNERS[name][3], 3000, noise=noise)
    guarded, free = _stream(name, u, y), _stream(name, u, y, guard=None)
    assert _not_learned(guarded) == []
    assert guarded[-1].guard == {**guarded[-1].guard, "rejected": 0, "held": 0, "relented": 0}
    assert guarded[-1].parameters == free[-1].parameters


@pytest.mark.parametrize("name", list(LEARNERS))
def test_an_output_glitch_is_rejected_by_every_learner(name):
    """One output sample 1e6 times the signal at row 2000: rejected (with the rows whose
    regressors hold it), no divergence, learning goes on, and the estimate stays within
    5 % of the clean record's (largest coefficient as the yardstick)."""
    u, y = _record(LEARNERS[name][3], 3000)
    clean = _vector(_stream(name, u, y)[-1].parameters)
    y[2000, 0] = 1e6
    events = _stream(name, u, y)
    final = events[-1]
    assert final.guard["rejected"] == 1 and final.guard["diverged"] == 0
    assert _not_learned(events)[0] == 2000 and max(_not_learned(events)) <= 2000 + 20
    assert final.problem is None
    deviation = np.max(np.abs(_vector(final.parameters) - clean)) / np.max(np.abs(clean))
    assert deviation < 0.05


def test_a_plant_at_rest_does_not_count_towards_the_warm_up():
    """100 rows at rest (errors exactly zero), then the plant moves: a scale taken from
    the rest would be zero and reject the first excited samples; none is rejected."""
    u, y = _record(SISO, 600)
    u[:100], y[:100] = 0.0, 0.0
    y[100:] = SISO.simulate(u[100:]) + 0.01 * np.random.default_rng(2).standard_normal((500, 1))
    events = _stream("arx-rls", u, y)
    assert _not_learned(events) == [] and events[-1].problem is None


@pytest.mark.parametrize("row", [8, 15])
def test_a_glitch_learned_during_the_warm_up_starts_it_again(row):
    """An output glitch of 50 (five times the output's range, so within the range test's
    reach) before the error scale exists is learned and spoils the estimate; at the
    end of the warm-up its error stands out, the start's estimate comes back, and the
    stream ends within 0.1 % of the clean record's estimate."""
    u, y = _record(SISO, 400)
    clean = _vector(_stream("arx-rls", u, y)[-1].parameters)
    y[row, 0] = 50.0
    final = _stream("arx-rls", u, y)[-1]
    assert final.guard["restarted"] == 1 and final.problem is None
    np.testing.assert_allclose(_vector(final.parameters), clean, rtol=1e-3)


def test_a_plant_that_idles_then_moves_is_learned_after_the_guard_steps_aside():
    """100 rows of measurement noise only, then the plant moves: the motion looks like
    glitches to a scale taken from the noise; after its warm-up length of rows not
    learned from, the guard steps aside and the estimate is the plant's."""
    rng = np.random.default_rng(0)
    u = rng.standard_normal((600, 1))
    u[:100] = 0.0
    y = SISO.simulate(u) + 0.01 * rng.standard_normal((600, 1))
    events = _stream("arx-rls", u, y)
    assert events[-1].guard["relented"] == 1 and _not_learned(events) == list(range(101, 121))
    np.testing.assert_allclose(_vector(events[-1].parameters), [-1.5, 0.7, 1.0, 0.5], rtol=0.01)


def test_a_change_that_lasts_is_learned_after_the_guard_steps_aside():
    """The plant's gain jumps 30-fold at row 400: the guard rejects the first rows of
    the new plant, steps aside after its warm-up length of rows not learned from, and
    the forgetting estimate ends at the new plant."""
    u, y = _record(SISO, 1200)
    changed = ARX(["u"], ["y"], na=2, nb=2, nk=1, a={"y": {"y": [-1.5, 0.7]}},
                  b={"y": {"u": [30.0, 15.0]}})  # fmt: skip
    y[400:] = changed.simulate(u)[400:]
    structure, _, _, plant = LEARNERS["arx-rls"]
    events = list(
        stream_identification(_lines(u, y, plant), structure, ["u"], ["y"],
                              options={**ARX_ORDERS, "forgetting": 0.97})
    )  # fmt: skip
    final = events[-1]
    assert final.guard["relented"] >= 1 and final.problem is None
    assert 400 in _not_learned(events) and max(_not_learned(events)) < 500
    np.testing.assert_allclose(_vector(final.parameters), [-1.5, 0.7, 30.0, 15.0], rtol=0.01)


def test_without_the_guard_a_learned_glitch_is_refused_at_the_end():
    """guard=None learns the 1e8 output glitch of issue 37 (the estimate is ruined); the
    estimate never predicts 20 samples in a row within the threshold again, so the
    stream says it is not to be trusted instead of handing it over."""
    u, y = _record(SISO, 400)
    y[70, 0] = 1e8
    final = _stream("arx-rls", u, y, guard=None)[-1]
    assert final.guard["threshold"] is None and final.guard["outliers"] >= 1
    assert "learned from" in final.problem and "did not recover" in final.problem


def test_a_divergence_during_the_warm_up_goes_back_to_the_start():
    """An input of 1e300 at row 5, before the guard has a scale: the recursion diverges
    on the row whose regressor holds it, the start's estimate comes back, and the
    stream ends with the estimate of the plant."""
    u, y = _record(SISO, 400)
    u[5, 0] = 1e300
    events = _stream("arx-rls", u, y)
    failures = [e for e in events if isinstance(e, Failure)]
    assert [e.k for e in failures] == [6] and "(of the start) is restored" in failures[0].message
    final = events[-1]
    assert final.guard["diverged"] == 1 and final.problem is None
    np.testing.assert_allclose(_vector(final.parameters), [-1.5, 0.7, 1.0, 0.5], atol=0.02)


def test_the_threshold_must_exceed_one():
    online = online_estimator("arx", "rls", {}, ["u"], ["y"])
    for bad in (1.0, 0.5, float("inf"), float("nan")):
        with pytest.raises(ParameterError, match="outlier threshold must be a number above 1"):
            StreamGuard(online, bad)


def test_the_guard_state_goes_through_json():
    """A checkpoint holds the guard's state as JSON (infinite bounds as null)."""
    online = online_estimator("arx", "rls", ARX_ORDERS, ["u"], ["y"])
    guard = StreamGuard(online)
    fresh = json.loads(json.dumps(guard.state()))
    assert StreamGuard(online).restore(fresh).state() == guard.state()
    u, y = _record(SISO, 100)
    for k in range(100):
        values = (float(u[k, 0]), float(y[k, 0]))
        if guard.before(k, values) is None:
            error = [y[k, 0] - online.update(u[k], y[k])[0]]
            guard.after(k, values, error)
    saved = json.loads(json.dumps(guard.state()))
    assert StreamGuard(online).restore(saved).state() == guard.state()
