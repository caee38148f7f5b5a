"""Export (blockid.models.export): the NumPy-only module reproduces ``model.simulate`` to
1e-10; transfer functions match the linear blocks. The command's tests are in
tests/cli/test_export.py, the runtime's in tests/models/test_export_runtime.py."""

from __future__ import annotations

import ast
import sys

import numpy as np
import pytest

from blockid.blocks import (
    DeadZone,
    LinearBlock,
    PiecewiseLinear,
    Polynomial,
    Saturation,
    TwoSegmentPolynomial,
)
from blockid.blocks.base import StaticBlock
from blockid.data import Dataset
from blockid.errors import ParameterError
from blockid.models import (
    ARX,
    Hammerstein,
    HammersteinWiener,
    Network,
    Wiener,
    WienerHammerstein,
)
from blockid.models.export import (
    export_text,
    to_control,
    to_python_module,
    to_scipy,
    transfer_functions,
)
from blockid.models.feedback import LinearFeedback
from blockid.models.state_space import PolynomialStateSpace, StateSpace
from plants_for_options import PLANTS

from reference import _load

LIN = {"na": 2, "nb": 2, "nk": 1, "a": [-1.2, 0.35], "b": [1.0, 0.4]}


def _mimo_arx() -> ARX:
    return ARX(
        ["u1", "u2"],
        ["y1", "y2"],
        na=[[2, 1], [0, 1]],
        nb=[[1, 2], [2, 0]],
        nk=[[1, 0], [2, 1]],
        a={"y1": {"y1": [-0.9, 0.2], "y2": [0.1]}, "y2": {"y2": [-0.5]}},
        b={"y1": {"u1": [0.5], "u2": [0.3, -0.1]}, "y2": {"u1": [1.0, 0.2]}},
        input_offset=[0.1, -0.2],
        output_offset=[1.0, 2.0],
    )


def _models() -> dict:
    """Every structure and block kind the module copies (offsets non-zero)."""
    plants = {name: make() for name, make in PLANTS.items()}
    return {
        "arx": plants["arx"],
        "arx-mimo": _mimo_arx(),
        "hammerstein": plants["hammerstein"],
        "hammerstein-dead-zone": Hammerstein(
            "u", "y", input_block=DeadZone(-0.2, 0.3, 0.8, 1.2), **LIN
        ),
        "hammerstein-saturation": Hammerstein(
            "u", "y", input_block=Saturation(-0.5, 0.6, 1.3), **LIN
        ),
        "hammerstein-piecewise": Hammerstein(
            "u", "y", input_block=PiecewiseLinear([-1, 0, 0.5, 1], [-0.5, 0, 0.7, 0.8]), **LIN
        ),
        "wiener": plants["wiener"],
        "wiener-piecewise": Wiener(
            "u", "y", output_block=PiecewiseLinear([-3.0, 0.0, 3.0], [-2.0, 0.0, 4.0]), **LIN
        ),
        "hammerstein-wiener": plants["hammerstein-wiener"],
        "backlash": plants["backlash"],
        "wiener-hammerstein": plants["wiener-hammerstein"],
        "output-error": plants["output-error"],
        "feedback": plants["feedback"],
        "feedback-dead-zone": LinearFeedback(
            "u", "y", linear=LinearBlock(2, 1, 1, a=[-1.5, 0.7], b=[0.5]),
            feedback=DeadZone(-0.2, 0.3, 0.8, 0.6),
        ),
        "feedback-saturation": LinearFeedback(
            "u", "y", linear=LinearBlock(2, 1, 1, a=[-1.5, 0.7], b=[0.5]),
            feedback=Saturation(-0.5, 0.4, 0.7),
        ),
        "feedback-piecewise": LinearFeedback(
            "u", "y", linear=LinearBlock(2, 1, 1, a=[-1.5, 0.7], b=[0.5]),
            feedback=PiecewiseLinear([-1.0, 0.0, 0.5, 1.0], [-0.6, 0.0, 0.1, 0.6]),
        ),
        "state-space-mimo": StateSpace(
            ["u1", "u2"], ["y1", "y2"], A=[[0.8, 0.2], [-0.2, 0.7]], B=[[1.0, 0.0], [0.5, 1.0]],
            C=[[1.0, 0.0], [0.3, 1.0]], D=[[0.0, 0.1], [0.0, 0.0]], input_offset=[0.4, 0.4],
            input_scale=[2.0, 1.0], output_offset=[1.0, -1.0], output_scale=[3.0, 0.5],
        ),
        "polynomial-state-space": PolynomialStateSpace(
            ["u"], ["y"], A=[[1.2, -0.35], [1.0, 0.0]], B=[[1.0], [0.0]], C=[[1.0, 0.4]],
            D=[[0.0]], E=[[0.02, 0.05, 0.0, -0.05], [0.0, 0.0, 0.0, 0.0]],
            F=[[0.0, 0.0, 0.01, 0.0]], exponents=[[0, 0, 0], [2, 0, 0], [1, 1, 0], [3, 0, 0]],
            lower=[-1.5, -1.5, -1.0], upper=[1.5, 1.5, 1.0], input_offset=0.4,
            input_scale=0.8, output_offset=-0.3, output_scale=2.0,
        ),
    }  # fmt: skip


def _prepared(name: str):
    """The model with offsets and ranges recorded on a smaller input than the test
    input (so the polynomials' tangent continuation is exercised), and test data."""
    model = _models()[name]
    rng = np.random.default_rng(7)
    nu = len(model.inputs)
    u = 0.4 + 1.3 * rng.uniform(-1, 1, (500, nu))
    if hasattr(model, "with_ranges"):
        model = model.replace(input_offset=0.4, output_offset=-0.3)
        small = 0.4 + 0.8 * rng.uniform(-1, 1, (300, nu))
        model = model.with_ranges([(small, model.simulate(small))])
    y = model.simulate(u) + 0.01 * rng.standard_normal((500, len(model.outputs)))
    return model, u, y


@pytest.mark.parametrize("name", list(_models()))
def test_exported_module_reproduces_simulate(name, tmp_path):
    model, u, y = _prepared(name)
    path = tmp_path / f"{name.replace('-', '_')}.py"
    path.write_text(to_python_module(model))
    module = _load(path)
    starts = [None, y[: model.max_lag], y[:1], y[:50]]
    for y0 in starts:
        # the module starts a chain from the first max_lag outputs of a longer y0 (the
        # estimated start of a chain given more is not exported); a state-space model
        # estimates its initial state from all of them, as in blockid
        whole = isinstance(model, PolynomialStateSpace)
        expected = model.simulate(u, None if y0 is None else y0 if whole else y0[: model.max_lag])
        got = module.simulate(u, y0)
        assert got.shape == expected.shape
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-10)
    if len(model.inputs) == 1:
        np.testing.assert_allclose(module.simulate(u[:, 0]), model.simulate(u), atol=1e-10)
    assert module.INPUTS == list(model.inputs) and module.OUTPUTS == list(model.outputs)


def test_the_module_imports_numpy_and_the_standard_library_only():
    tree = ast.parse(to_python_module(_models()["hammerstein-wiener"]))
    imported = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    imported |= {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    assert imported == {"json", "numpy"}


def _wiener_with_start(q, x_range):
    model = Wiener("u", "y", output_block=Polynomial(q, constant=False), **LIN)
    return model.replace(ranges={"u": [-1.0, 1.0], "x": list(x_range)})


@pytest.mark.parametrize(
    ("q", "x_range", "inverts"),
    [
        ([1.0, 0.1], (-2.0, 2.0), True),  # monotone on its range: x0 = N^-1(y0)
        ([1.0, 0.0, -0.5], (-2.0, 2.0), False),  # turns at +-0.82: from rest
        ([1.0, 0.3, 0.05], (-20.0, 20.0), True),  # monotone everywhere
    ],
)
def test_the_start_from_measured_outputs_follows_the_model(q, x_range, inverts, tmp_path):
    model = _wiener_with_start(q, x_range)
    y0 = np.array([0.3, -0.4, 0.9])  # one more than max_lag: the module uses two
    assert (model.initial_state(y0) is not None) is inverts
    u = np.random.default_rng(1).uniform(-1, 1, 200)
    ns: dict = {}
    exec(to_python_module(model), ns)
    expected = model.simulate(u, y0[: model.max_lag])
    np.testing.assert_allclose(ns["simulate"](u, y0), expected, atol=1e-10)


def test_an_output_block_that_cannot_be_inverted_starts_from_rest():
    model = Wiener("u", "y", output_block=Saturation(-1.0, 1.0), **LIN)
    model = model.replace(ranges={"x": [-3.0, 3.0]})
    y0 = np.array([0.2, 0.5])
    assert model.initial_state(y0) is None
    ns: dict = {}
    exec(to_python_module(model), ns)
    u = np.linspace(-1, 1, 50)
    np.testing.assert_allclose(ns["simulate"](u, y0), model.simulate(u, y0), atol=1e-10)


class _Cube(StaticBlock):
    """A user block (not registered: no kind name)."""

    @property
    def parameters(self):
        return {"gain": 1.0}

    def __call__(self, u):
        return np.asarray(u, dtype=float) ** 3


def test_models_the_module_cannot_copy_are_refused():
    with pytest.raises(ParameterError, match="cannot export"):
        to_python_module(Hammerstein("u", "y", input_block=_Cube(), **LIN))
    network = Network([("s1", PLANTS["arx"]())])
    with pytest.raises(ParameterError, match="network"):
        to_python_module(network)
    with pytest.raises(ParameterError, match="unknown export format"):
        export_text(PLANTS["arx"](), "matlab")


# ----------------------------------------------------------------------------- transfer functions
def test_to_scipy_step_response_equals_the_linear_block():
    from scipy import signal

    block = LinearBlock(2, 3, 2, a=[-1.2, 0.35], b=[0.5, -0.2, 0.1])
    _, (step,) = signal.dstep(to_scipy(block), n=60)
    np.testing.assert_allclose(step[:, 0], block.simulate(np.ones(60)), atol=1e-12)
    arx = ARX(["u"], ["y"], 2, 2, 1, a={"y": {"y": LIN["a"]}}, b={"y": {"u": LIN["b"]}})
    arx.sampling_time = 0.1
    system = to_scipy(arx)
    assert system.dt == 0.1
    _, (step,) = signal.dstep(system, n=40)
    np.testing.assert_allclose(step[:, 0], arx.simulate(np.ones(40))[:, 0], atol=1e-12)


def test_to_scipy_picks_a_linear_block_of_a_chain():
    wh = PLANTS["wiener-hammerstein"]()
    with pytest.raises(ParameterError, match="2 linear blocks"):
        to_scipy(wh)
    from scipy import signal

    for index, block in enumerate(wh.linear_blocks):
        _, (step,) = signal.dstep(to_scipy(wh, index=index), n=30)
        np.testing.assert_allclose(step[:, 0], block.simulate(np.ones(30)), atol=1e-12)
    with pytest.raises(ParameterError, match="single-input single-output"):
        transfer_functions(_mimo_arx())


def test_to_control_is_optional(monkeypatch):
    monkeypatch.setitem(sys.modules, "control", None)  # as if not installed
    with pytest.raises(ParameterError, match="python-control is not installed"):
        to_control(LinearBlock(1, 1, 1, a=[-0.5], b=[1.0]))


def test_to_control_when_installed():
    control = pytest.importorskip("control")
    block = LinearBlock(2, 2, 1, a=[-1.2, 0.35], b=[1.0, 0.4])
    system = to_control(block)
    _, step = control.step_response(system, T=np.arange(40))
    np.testing.assert_allclose(np.ravel(step), block.simulate(np.ones(40)), atol=1e-10)


def test_state_space_to_control_gives_each_input_output_pair():
    control = pytest.importorskip("control")
    model = _models()["state-space-mimo"]
    zero = model.simulate(np.tile(model.input_offset, (40, 1)))  # the offsets' response
    for k, tf in enumerate(transfer_functions(model)):
        i, j = model.inputs.index(tf["input"]), model.outputs.index(tf["output"])
        u = np.tile(model.input_offset, (40, 1))
        u[:, i] += 1.0
        _, step = control.step_response(to_control(model, index=k), T=np.arange(40))
        np.testing.assert_allclose(np.ravel(step), model.simulate(u)[:, j] - zero[:, j], atol=1e-10)


def test_hammerstein_wiener_two_segment_start(tmp_path):
    model = HammersteinWiener(
        "u",
        "y",
        input_block=TwoSegmentPolynomial.from_segments([0.1, 1.0, 0.5], [-0.2, 0.6, -0.3]),
        output_block=Polynomial([1.0, 0.2, 0.05], constant=False),
        **LIN,
    )
    data = Dataset.from_arrays(
        u := np.random.default_rng(2).uniform(-1, 1, 300), model.simulate(u), ["u"], ["y"]
    )
    model = model.with_ranges([(e.u, e.y) for e in data.experiments])
    ns: dict = {}
    exec(to_python_module(model), ns)
    y0 = data.experiments[0].y[:2]
    np.testing.assert_allclose(ns["simulate"](u, y0), model.simulate(u, y0), atol=1e-10)


def test_wiener_hammerstein_constructor_in_module():
    model = WienerHammerstein(
        "u",
        "y",
        first=LinearBlock(1, 1, 1, [-0.8], [0.5]),
        static=Polynomial([0.0, 1.0, 0.0, -0.3]),
        second=LinearBlock(1, 2, 0, [-0.5], [1.0, 0.4]),
    )
    ns: dict = {}
    exec(to_python_module(model), ns)
    u = np.random.default_rng(3).uniform(-1, 1, 100)
    np.testing.assert_allclose(ns["simulate"](u, [0.1]), model.simulate(u, [0.1]), atol=1e-10)
