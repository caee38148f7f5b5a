"""Model files keep every attribute: save_model -> load_model changes nothing.

A model file must give back the model that was saved, not one that merely looks like it:
offsets (non-zero), estimation ranges, delays (``nk = 0`` too), sampling time, the
parameters of every block kind, MIMO ARX matrices and network wiring. The reloaded
model must simulate and predict *bit-identically* (``np.array_equal``) on a record that
stays inside the recorded ranges and on one that leaves them, and report the same
extrapolation warnings (which is how the ranges act on a user's results).

Fixed cases cover every block kind with chosen, non-trivial values; ``hypothesis``
draws random orders, stable linear blocks, block parameters and offsets.
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from blockid.blocks import (
    Backlash,
    DeadZone,
    PiecewiseLinear,
    Polynomial,
    Saturation,
    TwoSegmentPolynomial,
)
from blockid.data import Dataset
from blockid.errors import BlockidError
from blockid.evaluation import evaluate
from blockid.fitting import fit_model
from blockid.models import (
    ARX,
    BacklashModel,
    Hammerstein,
    HammersteinWiener,
    Network,
    Wiener,
    load_model,
    save_model,
)


# ---------------------------------------------------------------------- helpers
def outcome(fn, *args) -> tuple[str, Any]:
    """``("value", result)`` or ``("error", (type, message))``: what a call gives."""
    try:
        return "value", fn(*args)
    except BlockidError as exc:
        return "error", (type(exc), str(exc))


def assert_same_outcome(got, want) -> None:
    """Same kind of outcome; arrays bit-identical (same shape, NaN where NaN)."""
    assert got[0] == want[0], (got, want)
    if want[0] == "value" and isinstance(want[1], np.ndarray):
        assert got[1].shape == want[1].shape
        assert np.array_equal(got[1], want[1], equal_nan=True)
    else:
        assert got[1] == want[1]


def reload(model, folder: Path, estimation: dict | None = None):
    path = save_model(model, folder / "model.json", estimation, overwrite=True)
    return load_model(path)


def assert_behaves_identically(again, model, u: np.ndarray, y: np.ndarray) -> None:
    """simulate (from rest and from measured initial outputs) and predict, bit for bit."""
    lag = model.max_lag
    assert_same_outcome(outcome(again.simulate, u), outcome(model.simulate, u))
    assert_same_outcome(outcome(again.simulate, u, y[:lag]), outcome(model.simulate, u, y[:lag]))
    assert_same_outcome(outcome(again.predict, u, y), outcome(model.predict, u, y))


def assert_same_evaluation(again, model, data: Dataset) -> None:
    """Metrics and extrapolation warnings of both modes agree exactly."""

    def summary(m, mode):
        return evaluate(m, data, mode).to_dict()

    for mode in ("simulation", "one-step"):
        assert_same_outcome(outcome(summary, again, mode), outcome(summary, model, mode))


def siso_data(model, u: np.ndarray, rng: np.random.Generator) -> Dataset:
    """The model's own response plus a little noise (so predict is not trivially y)."""
    y = model.simulate(u)[:, 0]
    y = y + 0.01 * (np.std(y) + 1.0) * rng.standard_normal(y.size)
    return Dataset.from_arrays(
        u, y, inputs=list(model.inputs), outputs=list(model.outputs), sampling_time=0.05
    )


# ---------------------------------------------------------------------- fixed cases
MONOTONE_Q = [1.0, 0.2, 0.05]  # 1 + 0.4 x + 0.15 x^2 > 0: invertible everywhere
A2 = [-1.3, 0.42]  # poles 0.7 and 0.6
A3 = [-1.1, 0.55, -0.125]  # poles 0.5 and 0.3 +- 0.4j


def _blocks() -> dict[str, Any]:
    return {
        "two-segment polynomial": TwoSegmentPolynomial(
            [0.15, 1.1, 0.3, -0.07], [-0.2, -0.45, 0.6, 0.11]
        ),
        "polynomial with constant": Polynomial([0.3, 0.9, -0.25, 0.04], constant=True),
        "polynomial without constant": Polynomial([0.8, 0.15, -0.06], constant=False),
        "dead zone": DeadZone(-0.35, 0.2, slope_left=1.7, slope_right=0.65),
        "saturation": Saturation(-0.6, 0.85, slope=1.35),
        "piecewise linear": PiecewiseLinear([-1.0, -0.2, 0.45, 1.3], [-0.9, -0.1, 0.3, 1.7]),
    }


def fixed_models() -> dict[str, Any]:
    """Non-trivial SISO block models: every block kind, offsets, ranges, nk = 0 and > 0."""
    models: dict[str, Any] = {}
    for i, (name, block) in enumerate(_blocks().items()):
        models[f"hammerstein, {name}"] = Hammerstein(
            "u",
            "y",
            input_block=block,
            na=2,
            nb=3,
            nk=i % 3,  # 0, 1 and 2
            a=A2,
            b=[1.0, 0.35, -0.12],
            sampling_time=0.02,
            input_offset=2.5,
            output_offset=-7.25,
        )
        models[f"hammerstein-wiener, {name}"] = HammersteinWiener(
            "u",
            "y",
            input_block=block,
            output_block=Polynomial(MONOTONE_Q, constant=False),
            na=3,
            nb=2,
            nk=(i + 1) % 3,
            a=A3,
            b=[1.0, -0.4],
            sampling_time=0.05,
            input_offset=-1.75,
            output_offset=3.5,
        )
    models["wiener, nk=0"] = Wiener(
        "current",
        "velocity",
        output_block=Polynomial([1.0, -0.3, 0.08], constant=False),
        na=2,
        nb=2,
        nk=0,
        a=A2,
        b=[0.6, 0.25],
        sampling_time=0.1,
        input_offset=0.4,
        output_offset=-0.9,
    )
    models["backlash"] = BacklashModel(
        "u2",
        "v2",
        input_block=Backlash(0.9, 0.8, 1.1, 0.85),
        na=2,
        nb=2,
        nk=1,
        a=[-1.0, 0.17],
        b=[1.0, 0.3],
        sampling_time=0.05,
        input_offset=355.0,
        output_offset=350.0,
    )
    for model in models.values():
        model.ranges = {"u": [-1.0, 1.2]}
        if getattr(model, "output_block", None) is not None:
            model.ranges["x"] = [-2.5, 3.0]
    return models


FIXED = fixed_models()


@pytest.mark.parametrize("name", list(FIXED))
def test_block_model_survives_the_file_bit_for_bit(name, tmp_path, rng):
    model = FIXED[name]
    again = reload(model, tmp_path, {"method": "test", "settings": {"seed": 1}})
    assert type(again) is type(model)
    assert again.to_dict() == model.to_dict()
    assert (again.inputs, again.outputs) == (model.inputs, model.outputs)
    assert again.sampling_time == model.sampling_time
    assert (again.na, again.nb, again.nk) == (model.na, model.nb, model.nk)
    assert again.input_offset == model.input_offset != 0.0
    assert again.output_offset == model.output_offset != 0.0
    assert again.ranges == model.ranges and again.ranges
    assert again.parameters == model.parameters
    assert np.array_equal(again.free_parameters(), model.free_parameters())
    if model.input_block is not None:
        assert type(again.input_block) is type(model.input_block)
        assert again.input_block.parameters == model.input_block.parameters
    inside = model.input_offset + rng.uniform(-0.9, 1.1, 400)
    outside = model.input_offset + 4.0 * np.sin(np.arange(400) / 9.0)
    for u in (inside, outside):
        data = siso_data(model, u, rng)
        e = data.experiments[0]
        assert_behaves_identically(again, model, e.u, e.y)
        assert_same_evaluation(again, model, data)


def test_fixed_cases_do_exercise_both_sides_of_the_ranges(rng):
    # The round trip above is only a test of the ranges if they change what a user sees:
    # a polynomial-input model warns outside its range and not inside.
    model = FIXED["hammerstein-wiener, two-segment polynomial"]
    inside = siso_data(model, model.input_offset + rng.uniform(-0.9, 1.1, 400), rng)
    outside = siso_data(model, model.input_offset + 4.0 * np.sin(np.arange(400) / 9.0), rng)
    assert evaluate(model, inside).warnings == []
    assert any("'u'" in w for w in evaluate(model, outside).warnings)


def test_ranges_that_forbid_one_step_prediction_survive(tmp_path, rng):
    # q = [1, 0.5, -0.3] turns at x = -0.636 and 1.747: over the recorded x range
    # [-1, 1] it cannot be inverted, so predict refuses; with the ranges lost on load
    # the reloaded model would predict instead.
    model = HammersteinWiener(
        "u",
        "y",
        input_block=_blocks()["two-segment polynomial"],
        output_block=Polynomial([1.0, 0.5, -0.3], constant=False),
        na=2,
        nb=2,
        nk=1,
        a=A2,
        b=[1.0, 0.2],
        input_offset=0.5,
        output_offset=1.5,
    )
    model.ranges = {"u": [-0.5, 0.5], "x": [-1.0, 1.0]}
    again = reload(model, tmp_path)
    u = 0.5 + rng.uniform(-0.4, 0.4, 300)
    y = model.simulate(u)[:, 0]
    assert outcome(model.predict, u, y)[0] == "error"
    assert_behaves_identically(again, model, u, y)


def test_arx_mimo_with_offsets_and_delays(tmp_path, rng):
    model = ARX(
        ["u1", "u2", "u3"],
        ["y1", "y2"],
        na=[[2, 1], [0, 3]],
        nb=[[2, 0, 1], [1, 3, 2]],
        nk=[[0, 1, 2], [3, 0, 1]],
        a={
            "y1": {"y1": [-0.9, 0.2], "y2": [0.15]},
            "y2": {"y1": [], "y2": [-0.6, 0.11, -0.02]},
        },
        b={
            "y1": {"u1": [0.7, -0.3], "u2": [], "u3": [0.25]},
            "y2": {"u1": [1.3], "u2": [0.05, -0.4, 0.9], "u3": [-0.2, 0.6]},
        },
        sampling_time=0.05,
        input_offset=[410.0, -3.25, 0.5],
        output_offset=[110.0, 0.578],
    )
    again = reload(model, tmp_path, {"method": "batch"})
    assert again.to_dict() == model.to_dict()
    for name in ("na", "nb", "nk"):
        assert np.array_equal(getattr(again, name), getattr(model, name))
    assert np.array_equal(again.input_offset, [410.0, -3.25, 0.5])
    assert np.array_equal(again.output_offset, [110.0, 0.578])
    for yi in model.outputs:
        for yj in model.outputs:
            assert np.array_equal(again.a[yi][yj], model.a[yi][yj])
        for um in model.inputs:
            assert np.array_equal(again.b[yi][um], model.b[yi][um])
    u = model.input_offset + rng.standard_normal((300, 3))
    y = model.simulate(u) + 0.01 * rng.standard_normal((300, 2))
    assert_behaves_identically(again, model, u, y)


def _paper_a_network() -> Network:
    s1 = ARX(
        ["u1"],
        ["v1"],
        1,
        1,
        1,
        a={"v1": {"v1": [-0.62]}},
        b={"v1": {"u1": [0.39]}},
        input_offset=[400.0],
        output_offset=[417.5],
    )
    s2 = BacklashModel(
        "u2",
        "v2",
        input_block=Backlash(0.9, 0.8, 0.9, 0.85),
        na=2,
        nb=1,
        nk=1,
        a=[-1.0, 0.17],
        input_offset=350.0,
        output_offset=355.0,
    )
    s3 = ARX(
        ["v1", "v2"],
        ["y1", "y2"],
        na=2,
        nb=2,
        nk=[[1, 2], [0, 1]],
        a={
            "y1": {"y1": [-1.2, 0.4], "y2": [0.1, 0.0]},
            "y2": {"y1": [0.05, 0.02], "y2": [-0.9, 0.2]},
        },
        b={
            "y1": {"v1": [0.05, 0.02], "v2": [0.01, -0.005]},
            "y2": {"v1": [0.0, 0.003], "v2": [0.04, 0.01]},
        },
        input_offset=[417.5, 355.0],
        output_offset=[110.0, 0.578],
    )
    return Network([("S1", s1), ("S2", s2), ("S3", s3)], sampling_time=0.05)


def test_network_wiring_and_subsystems_survive(tmp_path, rng):
    net = _paper_a_network()
    again = reload(net, tmp_path)
    assert again.to_dict() == net.to_dict()
    assert [n for n, _ in again.subsystems] == ["S1", "S2", "S3"]
    assert again.inputs == ("u1", "u2") and again.outputs == ("v1", "v2", "y1", "y2")
    assert again.sampling_time == 0.05
    for name, sub in net.subsystems:
        assert type(again[name]) is type(sub)
        assert again[name].to_dict() == sub.to_dict()
        assert (again[name].inputs, again[name].outputs) == (sub.inputs, sub.outputs)
    u = np.column_stack([400.0 + rng.uniform(-5, 5, 300), 350.0 + rng.uniform(-5, 5, 300)])
    y = net.simulate(u) + 0.01 * rng.standard_normal((300, 4))
    assert_behaves_identically(again, net, u, y)


# ---------------------------------------------------------------------- fitted Wiener
@pytest.fixture(scope="module")
def centred_wiener():
    """A Wiener model as fit_model returns it: centred (the default), offsets non-zero."""
    plant = Wiener(
        "u",
        "y",
        output_block=Polynomial([1.0, 0.3, 0.1], constant=False),
        na=1,
        nb=2,
        nk=1,
        a=[-0.6],
        b=[0.5, 0.3],
    )
    rng = np.random.default_rng(7)
    u = 3.0 + rng.uniform(-1.0, 1.0, 1500)
    y = plant.simulate(u - 3.0)[:, 0] + 2.0 + 0.01 * rng.standard_normal(1500)
    data = Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"], sampling_time=0.1)
    return fit_model(data, "wiener", na=1, nb=2, nk=1, r2=3)


def test_centred_wiener_fit_survives_with_its_offsets(centred_wiener, tmp_path, rng):
    result = centred_wiener
    model = result.model
    assert result.settings["center"] is True
    # the centring is real: the input offset is the data mean (about 3), and the output
    # offset the refined constant: the plant's 2.0 (measured 1.9956), not the output's
    # mean 2.069, which the square term lifts
    assert model.input_offset == pytest.approx(3.0, abs=0.05)
    assert model.output_offset == pytest.approx(2.0, abs=0.01)
    again = reload(model, tmp_path, result.estimation_record())
    assert again.input_offset == model.input_offset
    assert again.output_offset == model.output_offset
    assert again.ranges == model.ranges and set(again.ranges) == {"u", "x"}
    for u in (3.0 + rng.uniform(-0.9, 0.9, 500), 3.0 + 3.0 * np.sin(np.arange(500) / 11.0)):
        data = siso_data(model, u, rng)
        e = data.experiments[0]
        assert_behaves_identically(again, model, e.u, e.y)
        assert_same_evaluation(again, model, data)


def test_a_file_without_the_offsets_would_fail_the_round_trip(centred_wiener, tmp_path, rng):
    # What the round trip above guards against: the same file with its offsets dropped
    # loads a model that simulates differently.
    model = centred_wiener.model
    path = save_model(model, tmp_path / "m.json")
    doc = json.loads(path.read_text())
    del doc["model"]["offsets"]
    path.write_text(json.dumps(doc))
    stripped = load_model(path)
    u = 3.0 + rng.uniform(-0.9, 0.9, 300)
    assert not np.array_equal(stripped.simulate(u), model.simulate(u))
    assert np.max(np.abs(stripped.simulate(u) - model.simulate(u))) > 1.0


# ---------------------------------------------------------------------- hypothesis
def coef(bound: float) -> st.SearchStrategy[float]:
    return st.floats(-bound, bound, allow_nan=False)


@st.composite
def stable_a(draw, na: int) -> list[float]:
    """``[a_1..a_na]`` of a polynomial with every root inside radius 0.95."""
    poles: list[complex] = []
    for _ in range(na // 2):
        r = draw(st.floats(0.0, 0.95))
        w = draw(st.floats(0.0, np.pi))
        poles += [r * np.exp(1j * w), r * np.exp(-1j * w)]
    if na % 2:
        poles.append(draw(st.floats(-0.95, 0.95)))
    return np.real(np.poly(poles))[1:].tolist() if poles else []


@st.composite
def static_blocks(draw):
    kind = draw(st.sampled_from(["two-segment", "polynomial", "dead-zone", "saturation", "pwl"]))
    if kind == "two-segment":
        r1 = draw(st.integers(0, 3))
        f = draw(st.lists(coef(2.0), min_size=r1 + 1, max_size=r1 + 1))
        p = draw(st.lists(coef(2.0), min_size=r1 + 1, max_size=r1 + 1))
        return TwoSegmentPolynomial(f, p)
    if kind == "polynomial":
        c = draw(st.lists(coef(2.0), min_size=1, max_size=4))
        return Polynomial(c, constant=draw(st.booleans()))
    if kind == "dead-zone":
        lo, hi = sorted(draw(st.tuples(coef(1.0), coef(1.0))))
        return DeadZone(lo, hi, draw(st.floats(0.05, 3.0)), draw(st.floats(0.05, 3.0)))
    if kind == "saturation":
        lo = draw(st.floats(-2.0, -0.01))
        hi = draw(st.floats(0.01, 2.0))
        return Saturation(lo, hi, draw(st.floats(0.05, 3.0)))
    bps = draw(st.lists(coef(3.0), min_size=2, max_size=5, unique=True))
    values = draw(st.lists(coef(3.0), min_size=len(bps), max_size=len(bps)))
    return PiecewiseLinear(sorted(bps), values)


@st.composite
def block_models(draw):
    structure = draw(st.sampled_from(["hammerstein", "wiener", "hammerstein-wiener", "backlash"]))
    na = draw(st.integers(0, 3))
    nb = draw(st.integers(1, 3))
    nk = draw(st.integers(0, 3))
    a = draw(stable_a(na))
    b = draw(st.lists(coef(1.5), min_size=nb, max_size=nb))
    kwargs: dict[str, Any] = dict(
        na=na,
        nb=nb,
        nk=nk,
        a=a,
        sampling_time=draw(st.none() | st.floats(1e-4, 10.0)),
        input_offset=draw(coef(500.0)),
        output_offset=draw(coef(500.0)),
    )
    q = [1.0, *draw(st.lists(coef(0.5), min_size=0, max_size=2))]
    if structure == "wiener":
        model = Wiener("u", "y", output_block=Polynomial(q, constant=False), b=b, **kwargs)
    elif structure == "backlash":
        block = Backlash(
            draw(st.floats(0.1, 3.0)),
            draw(st.floats(0.0, 2.0)),
            draw(st.floats(0.1, 3.0)),
            draw(st.floats(0.0, 2.0)),
        )
        model = BacklashModel("u", "y", input_block=block, b=[1.0, *b[1:]], **kwargs)
    else:
        cls = Hammerstein if structure == "hammerstein" else HammersteinWiener
        extra = {"output_block": Polynomial(q, constant=False)} if cls is HammersteinWiener else {}
        model = cls("u", "y", input_block=draw(static_blocks()), b=[1.0, *b[1:]], **kwargs, **extra)
    if draw(st.booleans()):
        lo, hi = sorted(draw(st.tuples(coef(2.0), coef(2.0))))
        model.ranges = {"u": [lo, hi + 0.1]}
        if model.output_block is not None and draw(st.booleans()):
            lo, hi = sorted(draw(st.tuples(coef(5.0), coef(5.0))))
            model.ranges["x"] = [lo, hi + 0.1]
    return model


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(model=block_models(), seed=st.integers(0, 2**32 - 1))
def test_random_block_models_survive_the_file(model, seed):
    rng = np.random.default_rng(seed)
    u_in = model.input_offset + rng.uniform(-1.0, 1.0, 80)
    u_out = model.input_offset + 6.0 * rng.standard_normal(80)
    with tempfile.TemporaryDirectory() as folder:
        again = reload(model, Path(folder))
    assert again.to_dict() == model.to_dict()
    assert again.ranges == model.ranges
    assert np.array_equal(again.free_parameters(), model.free_parameters())
    for u in (u_in, u_out):
        y = model.simulate(u)[:, 0] + rng.standard_normal(u.size)
        assert_behaves_identically(again, model, u, y)


@st.composite
def arx_models(draw):
    nu = draw(st.integers(1, 3))
    ny = draw(st.integers(1, 2))
    na = draw(st.lists(st.integers(0, 2), min_size=ny * ny, max_size=ny * ny))
    nb = draw(st.lists(st.integers(0, 3), min_size=ny * nu, max_size=ny * nu))
    nk = draw(st.lists(st.integers(0, 3), min_size=ny * nu, max_size=ny * nu))
    outputs = [f"y{i + 1}" for i in range(ny)]
    inputs = [f"u{m + 1}" for m in range(nu)]
    # small coefficients: sum |a| < 1 keeps every output row contracting
    a = {
        yi: {
            yj: draw(st.lists(coef(0.4 / ny), min_size=na[i * ny + j], max_size=na[i * ny + j]))
            for j, yj in enumerate(outputs)
        }
        for i, yi in enumerate(outputs)
    }
    b = {
        yi: {
            um: draw(st.lists(coef(2.0), min_size=nb[i * nu + m], max_size=nb[i * nu + m]))
            for m, um in enumerate(inputs)
        }
        for i, yi in enumerate(outputs)
    }
    return ARX(
        inputs,
        outputs,
        na=na,
        nb=nb,
        nk=nk,
        a=a,
        b=b,
        sampling_time=draw(st.none() | st.floats(1e-4, 10.0)),
        input_offset=draw(st.lists(coef(500.0), min_size=nu, max_size=nu)),
        output_offset=draw(st.lists(coef(500.0), min_size=ny, max_size=ny)),
    )


@settings(max_examples=30, deadline=None)
@given(model=arx_models(), seed=st.integers(0, 2**32 - 1))
def test_random_arx_models_survive_the_file(model, seed):
    rng = np.random.default_rng(seed)
    u = model.input_offset + rng.standard_normal((60, len(model.inputs)))
    y = model.simulate(u) + rng.standard_normal((60, len(model.outputs)))
    with tempfile.TemporaryDirectory() as folder:
        again = reload(model, Path(folder))
    assert again.to_dict() == model.to_dict()
    assert np.array_equal(again.input_offset, model.input_offset)
    assert np.array_equal(again.output_offset, model.output_offset)
    assert_behaves_identically(again, model, u, y)
