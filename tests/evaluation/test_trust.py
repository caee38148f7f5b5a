"""Trust checks: internal signals beyond their ranges, free runs from rest, cancelling
poles and zeros; measured against hand-made models whose flaw is known."""

import numpy as np
import pytest

from blockid.blocks import Polynomial
from blockid.blocks.linear import LinearBlock
from blockid.data import Dataset
from blockid.evaluation.trust import MAX_RANGE_EXCESS, MAX_REST_RATIO, Trust, assess, rest_ratio
from blockid.fitting.checks import rest_notes
from blockid.models import ARX, ChainModel


def _record(model, u, noise=0.0, seed=0):
    rng = np.random.default_rng(seed)
    y = model.simulate(u)[:, 0] + noise * rng.standard_normal(len(u))
    return Dataset.from_arrays(u, y, ["u"], ["y"])


def _spiky():
    """The issue's Wiener-Hammerstein fit: a first block with b = [-9.5, 35, -51, 33,
    -8.5] (gain -1 at rest, 137 at the Nyquist frequency) on a 2-10 V input, fitted
    uncentred. Its data are its own run after a warm-up at the first input."""
    first = LinearBlock(0, 5, 0, a=[], b=[-9.5, 35.0, -51.0, 33.0, -8.5])
    second = LinearBlock(1, 1, 1, a=[-0.5], b=[1.0])
    model = ChainModel("u", "y", [first, Polynomial([1.0, 0.01], constant=False), second],
                       output_offset=18.0)  # fmt: skip
    rng = np.random.default_rng(0)
    u = 6.0 + np.convolve(rng.uniform(-4, 4, 2000), np.ones(50) / 50, mode="same")
    warm = model.simulate(np.concatenate([np.full(100, u[0]), u]))[100:, 0]
    return model, Dataset.from_arrays(u, warm, ["u"], ["y"])


def test_a_wiener_hammerstein_model_that_spikes_from_rest_is_not_trusted():
    """Started where its data are, the model follows them; from rest it swings to
    hundreds of volts before settling, on a record between 1 and 13 V."""
    spiky, data = _spiky()
    e = data.experiments[0]
    rest = spiky.simulate(e.u)[:, 0]
    assert np.max(np.abs(rest)) > 300 and 1 < e.y.min() and e.y.max() < 13
    ratio = rest_ratio(spiky, e.u, e.y)
    assert ratio > MAX_REST_RATIO
    trust = assess(spiky, data)
    assert any("free run from rest" in r for r in trust.reasons)
    (note,) = rest_notes(spiky, data)  # what fit_model adds to the result's warnings
    assert "runs away from rest" in note and "--initial-samples" in note
    # a well-conditioned model started from rest away from its data settles onto them
    calm = ChainModel("u", "y", [LinearBlock(1, 1, 1, a=[-0.8], b=[0.2])])
    calm_data = Dataset.from_arrays(e.u, calm.simulate(np.concatenate([np.full(100, e.u[0, 0]),
                                    e.u[:, 0]]))[100:, 0], ["u"], ["y"])  # fmt: skip
    assert rest_ratio(calm, calm_data.experiments[0].u, calm_data.experiments[0].y) <= 1.05
    assert assess(calm, calm_data).reasons == []


def test_internal_signals_leaving_their_range_more_than_the_input_is_not_trusted():
    """A Wiener model whose linear block amplifies a band the estimation input lacks:
    on held-back data with that band the output block's input x leaves its range far
    more than u leaves its own."""
    notch = LinearBlock(2, 3, 0, a=[0.0, 0.81], b=[1.0, 0.0, 0.81])  # passes slow inputs ...
    peaky = LinearBlock(2, 3, 0, a=[0.0, 0.81], b=[1.0, 0.0, -0.19])  # ... 10x at fs/4
    model = ChainModel("u", "y", [peaky, Polynomial([1.0, 0.1], constant=False)])
    t = np.arange(2000)
    slow = np.sin(2 * np.pi * t / 400)
    est = _record(model, slow)
    model = model.with_ranges([(e.u, e.y) for e in est.experiments])
    fast = Dataset.from_arrays(0.9 * np.sin(np.pi * t / 2), np.zeros(2000), ["u"], ["y"])
    trust = assess(model, est, fast)
    assert trust.range_excess > MAX_RANGE_EXCESS
    assert "internal signal leaves its estimation range" in trust.reasons[0]
    # the input alone leaving its range (a bigger excitation) is not held against it
    big = Dataset.from_arrays(1.5 * slow, np.zeros(2000), ["u"], ["y"])
    assert assess(model, est, big).range_excess == pytest.approx(0.0, abs=0.05)
    plain = ChainModel("u", "y", [notch, Polynomial([1.0, 0.1], constant=False)])
    plain = plain.with_ranges([(e.u, e.y) for e in est.experiments])
    assert assess(plain, est, big).reasons == []


def test_cancelling_poles_and_zeros_and_large_coefficients_are_flagged_not_rejected():
    p = 0.9
    cancelling = LinearBlock(2, 2, 1, a=list(-np.poly([p, 0.5])[1:] * -1), b=[1.0, -p * 1.001])
    model = ChainModel("u", "y", [cancelling])
    rng = np.random.default_rng(1)
    data = _record(model, rng.standard_normal(1000))
    trust = assess(model, data)
    assert trust.reasons == []
    assert any("nearly cancel" in f for f in trust.flags)
    plain = ChainModel("u", "y", [LinearBlock(2, 2, 1, a=[-1.2, 0.35], b=[1.0, 0.4])])
    assert assess(plain, _record(plain, rng.standard_normal(1000))).flags == []


def test_linear_models_have_nothing_to_leave_and_trust_combines_the_worst():
    arx = ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [-0.5]}}, b={"y": {"u": [1.0]}})
    u = np.random.default_rng(2).standard_normal(300)
    data = Dataset.from_arrays(u, arx.simulate(u)[:, 0], ["u"], ["y"])
    trust = assess(arx, data, data)
    assert trust.range_excess == 0.0 and trust.reasons == [] and trust.flags == []
    worse = trust.worst(Trust(0.7, float("inf"), ["x"]))
    assert worse.range_excess == 0.7 and not np.isfinite(worse.rest_ratio)
    assert len(worse.reasons) == 2 and worse.to_dict()["rest_ratio"] is None


def test_large_coefficients_are_judged_against_the_gain_on_the_data_in_its_units():
    """The flag compares sum |b| with 100 times the block's gain on the data (output
    spread over input spread): a differencing block b = [25, -25] on a slow input of
    spread 7 passes 0.4 % of it, far below its coefficients; a product of the spreads
    in place of their ratio would put the limit above 50 and miss it."""
    diff = ChainModel("u", "y", [LinearBlock(0, 2, 0, a=[], b=[25.0, -25.0])])
    t = np.arange(2000)
    data = _record(diff, 10.0 * np.sin(2 * np.pi * t / 2000))
    (flag,) = assess(diff, data).flags
    assert "sum |b| = 50" in flag and "times its gain on the data (0.0" in flag
    plain = ChainModel("u", "y", [LinearBlock(0, 2, 0, a=[], b=[0.5, 0.5])])
    assert assess(plain, _record(plain, 10.0 * np.sin(2 * np.pi * t / 2000))).flags == []


def test_an_unbounded_excursion_is_named_so_and_the_reasons_are_in_the_record():
    trust = Trust(range_excess=float("inf"))
    (reason,) = trust.reasons
    assert "by an unbounded amount of that range" in reason and "inf" not in reason
    record = trust.to_dict()
    assert record["reasons"] == trust.reasons and record["range_excess"] is None
    assert Trust(0.6).to_dict()["reasons"] == [
        "on held-back data an internal signal leaves its estimation range by 60 % of that "
        "range more than the input leaves its own (limit 50 %)"
    ]
