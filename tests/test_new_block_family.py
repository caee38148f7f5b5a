"""A static block family written in one file (this one) works end to end with no other
edit: fitted, searched by ``identify``, reported and exported as a NumPy-only module.

The family is defined inside a fixture and taken out of the registry afterwards, so that
the other tests' searches never see it. Streaming cannot learn it: the online learners
are the papers' recursive methods, whose blocks are fixed (two-segment polynomials).
"""

from __future__ import annotations

import importlib.util
from typing import Any, ClassVar

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from blockid.blocks.base import BLOCK_TYPES, StaticBlock
from blockid.data import Dataset
from blockid.errors import ParameterError
from blockid.models import Hammerstein, Wiener, save_model
from blockid.models.block_state_space import BlockStateSpace
from blockid.models.export import to_python_module

KIND = "test-tanh"
LIN = {"na": 2, "nb": 2, "nk": 1, "a": [-1.2, 0.5], "b": [1.0, 0.3]}


def _define() -> type[StaticBlock]:
    class TanhSaturation(StaticBlock):
        """``w = level * tanh(u / width)``: a smooth saturation at +-level. ``level``
        carries the gain a Hammerstein's input block needs (``b_0 = 1``)."""

        kind = KIND
        search_specs: ClassVar[dict[str, str]] = {"input": KIND, "output": KIND}
        anchored: ClassVar[bool] = True  # its form sits at its input's zero
        export_source: ClassVar[str | None] = """
            def evaluate(p, s):
                return p["level"] * np.tanh(s / p["width"])
        """

        def __init__(self, level: float = 1.0, width: float = 1.0) -> None:
            if not (level > 0 and width > 0):
                raise ValueError(f"level and width must be > 0, got {level}, {width}")
            self.level, self.width = float(level), float(width)

        @property
        def parameters(self) -> dict[str, Any]:
            return {"level": self.level, "width": self.width}

        @classmethod
        def template(cls, level: float = 1.0, width: float = 1.0) -> TanhSaturation:
            return cls(level, width)

        def __call__(self, u):
            return self.level * np.tanh(np.asarray(u, dtype=float) / self.width)

        def bounds(self):
            return 1e-6 * self.to_vector(), np.full(2, np.inf)

        def scaled(self, gain: float) -> TanhSaturation:
            return type(self)(gain * self.level, self.width)

        def free_mask(self, after_linear: bool) -> np.ndarray:
            return np.array([True, not after_linear])  # after a linear block: its gain

        def initial_grid(self, u, around=None):
            if around is not None:
                return []
            peak = float(np.max(np.abs(u))) or 1.0
            return [type(self)(1.0, f * peak) for f in (0.25, 0.5, 1.0, 2.0)]

    return TanhSaturation


@pytest.fixture(scope="module")
def tanh():
    cls = _define()
    yield cls
    del BLOCK_TYPES[KIND]


def _record(model, n, seed, noise=0.005):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1.5, 1.5, n // 3), 3)
    y = model.simulate(u)[:, 0] + noise * rng.standard_normal(u.size)
    return Dataset.from_arrays(u, y, ["u"], ["y"])


def _exported(model) -> dict:
    namespace: dict = {}
    exec(to_python_module(model), namespace)  # noqa: S102 - the module under test
    return namespace


@pytest.fixture(scope="module")
def plant(tanh):
    return Hammerstein("u", "y", input_block=tanh(0.8, 0.5), **LIN)


@pytest.fixture(scope="module")
def fitted(tanh, plant):
    from blockid.fitting import fit_model

    return fit_model(_record(plant, 1500, 0), "hammerstein", na=2, nb=2, nk=1,
                     input_block=KIND, center=False)  # fmt: skip


def test_fit_model_finds_the_plant(fitted):
    p = fitted.model.parameters
    assert type(fitted.model.input_block).kind == KIND
    np.testing.assert_allclose([p["level"], p["width"]], [0.8, 0.5], rtol=0.02)
    np.testing.assert_allclose(p["a"], LIN["a"], atol=0.01)


def test_the_exported_module_simulates_as_the_model(fitted):
    model = fitted.model
    rng = np.random.default_rng(5)
    u = rng.uniform(-3.0, 3.0, 400)  # beyond the estimation range too
    ns = _exported(model)
    assert list(ns["_BLOCKS"]) == [KIND]
    np.testing.assert_allclose(ns["simulate"](u), model.simulate(u), rtol=0, atol=1e-12)
    y0 = model.simulate(u)[:2, 0] + 0.01
    np.testing.assert_allclose(ns["simulate"](u, y0), model.simulate(u, y0), rtol=0, atol=1e-12)


def test_the_export_command_writes_it(fitted, tmp_path):
    from blockid.cli.export import export

    app = typer.Typer()
    app.command("export")(export)
    app.callback()(lambda: None)
    model_file = save_model(fitted.model, tmp_path / "tanh.json", fitted.estimation_record())
    out = tmp_path / "tanh_model.py"
    result = CliRunner().invoke(app, ["export", str(model_file), "--to", "python", "-o", str(out)])
    assert result.exit_code == 0, result.output
    spec = importlib.util.spec_from_file_location("tanh_model", out)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    u = np.linspace(-2.0, 2.0, 300)
    np.testing.assert_allclose(module.simulate(u), fitted.model.simulate(u), rtol=0, atol=1e-12)


def test_as_an_output_block_it_is_inverted_for_the_start_from_measured_outputs(tanh):
    model = Wiener("u", "y", output_block=tanh(1.2, 1.0), **LIN)
    model = model.replace(ranges={"u": [-1.0, 1.0], "x": [-2.0, 2.0]})
    u = np.random.default_rng(1).uniform(-1, 1, 200)
    y0 = np.array([0.3, -0.4])
    assert model.initial_state(y0) is not None  # blockid inverts it: so does the module
    ns = _exported(model)
    assert ns["SPEC"]["inverses"][0]["method"] == "bisect"
    np.testing.assert_allclose(ns["simulate"](u, y0), model.simulate(u, y0), rtol=0, atol=1e-12)


def test_without_a_slope_of_its_own_the_module_differentiates_as_blockid(tanh):
    """The block has no ``derivative``: blockid takes central differences, and so does
    the module where it needs the slope (a block state space's start)."""
    m = BlockStateSpace(
        ["u1", "u2"], ["y1", "y2"], A=[[0.7, 0.2], [-0.2, 0.6]], B=[[1.0, 0.0], [0.0, 0.5]],
        C=[[1.0, 0.0], [0.0, 1.0]], D=[[0.0, 0.0], [0.0, 0.0]],
        input_blocks=[tanh(1.5, 0.7), None], output_blocks=[None, tanh(2.0, 1.0)],
        input_offset=[0.2, 0.0], input_scale=[1.5, 1.0],
    )  # fmt: skip
    ns = _exported(m)
    s = np.linspace(-3.0, 3.0, 61)
    block = m.input_blocks[0]
    assert np.array_equal(ns["_slope"](block.to_dict(), s), block.derivative(s))
    u = np.random.default_rng(2).standard_normal((300, 2))
    y = m.simulate(u) + 0.01
    np.testing.assert_allclose(ns["simulate"](u), m.simulate(u), rtol=0, atol=1e-12)
    np.testing.assert_allclose(ns["simulate"](u, y[:10]), m.simulate(u, y[:10]), atol=1e-10)


@pytest.fixture(scope="module")
def identified(tanh, plant):
    from blockid.workflows.identify import Effort, identify

    effort = Effort("small", 3, 2, 3, 2, 1, None, 15, 10_000, 2, 40, 1)
    data, validation = _record(plant, 1200, 1), _record(plant, 600, 2)
    return identify(data, validation, structures=["arx", "hammerstein"], effort=effort,
                    jobs=1), data, validation  # fmt: skip


def test_identify_searches_it_and_chooses_it_for_its_plant(identified):
    result, _, _ = identified
    tried = {s.candidate.options.get("input_block") for s in result.ranked}
    assert KIND in tried and "dead-zone" in tried
    assert result.selected.candidate.options["input_block"] == KIND
    ns = _exported(result.model)
    u = np.linspace(-1.5, 1.5, 200)
    np.testing.assert_allclose(ns["simulate"](u), result.model.simulate(u), rtol=0, atol=1e-12)


def test_the_report_shows_it(identified):
    from blockid.reporting import build_report
    from blockid.reporting.notebook import identify_html

    result, data, validation = identified
    assert KIND in identify_html(result)
    html = build_report(identify=result, estimation=data, validation=validation)
    assert html.count(KIND) >= 2 and "level" in html


def test_a_stream_cannot_learn_it_and_says_why(fitted):
    from blockid.workflows.stream import StreamSession

    model = fitted.model
    u = np.random.default_rng(3).uniform(-1, 1, 100)
    lines = ["u,y", *(f"{a!r},{b!r}" for a, b in zip(u, model.simulate(u)[:, 0], strict=True))]
    with pytest.raises(ParameterError, match="input block"):
        list(StreamSession(lines, "hammerstein", ["u"], ["y"], initial=model))
