"""Exports of single models (blockid.models.export), by hand: transfer functions, SciPy
systems, the Python module's SPEC and its simulation, and the exact refusals. The
command line's export and the module against ``blockid simulate`` are in
``tests/test_export.py``."""

import numpy as np
import pytest

from blockid.blocks import PiecewiseLinear, Polynomial
from blockid.models import ARX, Hammerstein, Wiener

from reference import _feedback

U = np.array([0.0, 1.0, -2.0, 0.5, 3.0, -1.0])


def _module(model):
    from blockid.models.export import to_python_module

    namespace = {}
    exec(to_python_module(model), namespace)
    return namespace


def test_transfer_functions_of_a_linear_block_and_an_arx_model():
    from blockid.blocks.linear import LinearBlock
    from blockid.models.export import transfer_functions

    # z^-1 (0.5 + 0.25 z^-1) / (1 - 1.2 z^-1 + 0.35 z^-2) = (0.5 z + 0.25) / (z^2 - 1.2 z + 0.35)
    assert transfer_functions(LinearBlock(2, 2, 1, a=[-1.2, 0.35], b=[0.5, 0.25])) == [
        {"num": [0.5, 0.25], "den": [1.0, -1.2, 0.35], "dt": None}
    ]
    # a zero numerator keeps one coefficient
    assert transfer_functions(LinearBlock(2, 1, 1, a=[-1.2, 0.35], b=[0.0])) == [
        {"num": [0.0], "den": [1.0, -1.2, 0.35], "dt": None}
    ]
    # SISO ARX, delay 2: z^-2 / (1 - 0.5 z^-1) = 1 / (z^2 - 0.5 z)
    arx = ARX(
        ["u"], ["y"], 1, 1, 2, a={"y": {"y": [-0.5]}}, b={"y": {"u": [1.0]}}, sampling_time=0.1
    )
    assert transfer_functions(arx) == [{"num": [1.0], "den": [1.0, -0.5, 0.0], "dt": 0.1}]


def _wiener_hammerstein():
    from blockid.blocks.linear import LinearBlock
    from blockid.models import WienerHammerstein

    return WienerHammerstein(
        "u",
        "y",
        first=LinearBlock(1, 1, 1, a=[-0.5], b=[1.0]),
        static=Polynomial([1.0, 0.2], constant=False),
        second=LinearBlock(1, 1, 1, a=[-0.25], b=[1.0]),
        sampling_time=0.5,
    )


def test_transfer_functions_and_scipy_of_a_chain_with_two_linear_blocks():
    import json

    from blockid.errors import ParameterError
    from blockid.models.export import export_text, to_scipy, transfer_functions

    wh = _wiener_hammerstein()
    assert transfer_functions(wh) == [
        {"num": [1.0], "den": [1.0, -0.5], "dt": 0.5},
        {"num": [1.0], "den": [1.0, -0.25], "dt": 0.5},
    ]
    with pytest.raises(ParameterError) as info:
        to_scipy(wh)
    assert str(info.value) == "the model has 2 linear blocks; choose one with index=0..1"
    assert info.value.parameter == "index"
    second = to_scipy(wh, index=1)
    assert second.poles.tolist() == [0.25]
    assert second.dt == 0.5
    doc = json.loads(export_text(wh, "scipy-json"))
    assert doc["note"] == (
        "scipy.signal.dlti(num, den, dt=dt or True) per linear block, input side first; "
        "positive powers of z; the model's offsets and nonlinear blocks are not included"
    )
    assert doc["transfer_functions"] == transfer_functions(wh)


def test_python_module_of_an_arx_model_simulates_like_it():
    import blockid

    arx = ARX(
        ["u1", "u2"], ["y"], 1, 1, 1, a={"y": {"y": [-0.5]}}, b={"y": {"u1": [1.0], "u2": [0.5]}}
    )
    ns = _module(arx)
    assert ns["__doc__"].startswith(
        f"Arx model from u1, u2 to y.\n\nExported by blockid {blockid.__version__} "
        "(blockid export)."
    )
    assert ns["MODEL"] == arx.to_dict()
    assert ns["SPEC"] == {
        "form": "arx",
        "A": [[[0.0, -0.5]]],
        "B": [[[0.0, 1.0], [0.0, 0.5]]],
        "max_lag": 1,
    }
    u = np.column_stack([U, U[::-1]])
    np.testing.assert_allclose(ns["simulate"](u), arx.simulate(u), rtol=1e-12)


def test_python_module_of_a_feedback_model_simulates_like_it():
    model = _feedback([0.0, 0.1], input_offset=0.5, output_offset=1.0)
    ns = _module(model)
    assert ns["SPEC"] == {"form": "feedback", "max_lag": 1}
    np.testing.assert_allclose(ns["simulate"](U), model.simulate(U), rtol=1e-12)


def test_python_module_of_a_network_is_refused():
    from blockid.errors import ParameterError
    from blockid.models.network import Network

    with pytest.raises(ParameterError) as info:
        _module(Network([("S1", _feedback([0.0, 0.1]))]))
    assert str(info.value) == "cannot export a Network (a network?); export each subsystem"


def test_python_module_of_a_wiener_model_inverts_its_polynomial_branch():
    model = Wiener(
        "u", "y", output_block=Polynomial([1.0, 0.2], constant=False), na=1, nb=1, nk=1,
        a=[-0.5], b=[1.0],
    ).replace(ranges={"u": [-2.0, 3.0], "x": [-1.0, 2.0]})  # fmt: skip
    ns = _module(model)
    # x + 0.2 x^2 turns at x = -2.5; beyond [-1, 2] it continues along its tangent
    assert ns["SPEC"] == {
        "form": "chain",
        "last_linear": 0,
        "max_lag": 1,
        "tangents": [None, [-1.0, 2.0]],
        "inverses": [{"method": "branch", "range": [-2.5, np.inf]}],
    }
    y0 = [0.7, 1.3]  # more than max_lag: the module starts from the first max_lag
    expected = model.simulate(U, y_initial=y0[: model.max_lag])
    np.testing.assert_allclose(ns["simulate"](U, y0), expected, rtol=1e-9)
    np.testing.assert_allclose(ns["simulate"](U), model.simulate(U), rtol=1e-12)


def test_python_module_bisects_a_block_without_its_own_inverse():
    model = Wiener(
        "u", "y", output_block=PiecewiseLinear([-1.0, 0.0, 1.0], [-2.0, 0.0, 1.0]), na=1, nb=1,
        nk=1, a=[-0.5], b=[1.0],
    ).replace(ranges={"u": [-2.0, 3.0], "x": [-1.0, 1.0]})  # fmt: skip
    ns = _module(model)
    # the seen range [-1, 1] widened by half on both sides; w(-2) = -4, w(2) = 2
    ((spec,),) = [ns["SPEC"]["inverses"]]
    assert spec["method"] == "bisect"
    assert spec["sign"] == 1.0
    np.testing.assert_allclose(spec["range"], [-2.0, 2.0], atol=1e-11)
    np.testing.assert_allclose(spec["clip"], [-4.0, 2.0], atol=1e-11)
    y0 = [0.7, 1.3]  # more than max_lag: the module starts from the first max_lag
    expected = model.simulate(U, y_initial=y0[: model.max_lag])
    np.testing.assert_allclose(ns["simulate"](U, y0), expected, rtol=1e-9)


def test_python_module_of_a_dead_zone_input_block_has_no_tangents():
    from blockid.blocks import DeadZone

    model = Hammerstein(
        "u", "y", input_block=DeadZone(-0.5, 0.5), na=1, nb=1, nk=1, a=[-0.5], b=[1.0]
    ).replace(ranges={"u": [-1.0, 1.0]})
    ns = _module(model)
    assert ns["SPEC"]["tangents"] == [None, None]
    np.testing.assert_allclose(ns["simulate"](U), model.simulate(U), rtol=1e-12)


def test_export_messages_are_exact():
    from blockid.errors import ParameterError
    from blockid.models import ARX
    from blockid.models.export import FORMATS, export_text, transfer_functions

    model = ARX(["u1", "u2"], ["y1"], [[1]], [[1, 1]], [[1, 1]])
    with pytest.raises(ParameterError) as info:
        export_text(model, "fortran")
    assert str(info.value) == f"unknown export format 'fortran'; choose one of {', '.join(FORMATS)}"
    with pytest.raises(ParameterError) as info:
        transfer_functions(model)
    assert str(info.value) == (
        "a transfer function here is single-input single-output; the ARX model has "
        "2 input(s) and 1 output(s): export it as a Python module, or as one state space "
        "with to_control(model)"
    )


# ----------------------------------------------------------------------------- block rules
def test_the_module_holds_the_rules_of_the_models_blocks_only():
    from blockid.blocks import DeadZone, TwoSegmentPolynomial
    from blockid.models import HammersteinWiener
    from blockid.models.export import to_python_module

    model = HammersteinWiener(
        "u", "y", input_block=TwoSegmentPolynomial([0.0, 1.0], [0.0, -0.5]),
        output_block=Polynomial([1.0, 0.2], constant=False), na=1, nb=1, nk=1, a=[-0.5],
        b=[1.0],
    )  # fmt: skip
    text = to_python_module(model)
    assert "def _block_two_segment_polynomial():" in text
    assert "    # 'polynomial': blockid.blocks.polynomial.Polynomial.export_source\n" in text
    ns = _module(model)
    assert list(ns["_BLOCKS"]) == ["two-segment-polynomial", "polynomial"]
    assert ns["_BLOCKS"]["polynomial"]["tangent"] is True
    assert set(ns["_BLOCKS"]["polynomial"]) == {"evaluate", "slope", "scalar", "tangent"}
    dz = _module(Hammerstein("u", "y", input_block=DeadZone(-0.5, 0.5), na=1, nb=1, nk=1,
                             a=[-0.5], b=[1.0]))  # fmt: skip
    assert list(dz["_BLOCKS"]) == ["dead-zone"] and dz["_BLOCKS"]["dead-zone"]["tangent"] is False
    assert _module(ARX(["u"], ["y"], 1, 1, 1))["_BLOCKS"] == {}


def test_the_header_is_the_template_file_filled_in():
    from importlib.resources import files

    from blockid.models.export import to_python_module

    template = files("blockid.models").joinpath("export_header.txt").read_text(encoding="utf-8")
    text = to_python_module(ARX(["u"], ["y"], 1, 1, 1))
    head, tail = template.split("{title}", 1)
    assert text.startswith(head + "Arx model from u to y.")
    assert template.endswith('SAMPLING_TIME = MODEL.get("sampling_time")\n')
    assert 'SAMPLING_TIME = MODEL.get("sampling_time")\n\n\n# --- blocks:' in text


class _Plain:
    """A static block's parts for the refusal tests (subclassed with StaticBlock)."""

    @property
    def parameters(self):
        return {}

    def __call__(self, u):
        return np.asarray(u, dtype=float)


def _refusal(model) -> str:
    from blockid.errors import ParameterError
    from blockid.models.export import to_python_module

    with pytest.raises(ParameterError) as info:
        to_python_module(model)
    return str(info.value)


def test_a_block_the_module_cannot_run_is_refused_naming_its_kind_and_why():
    from blockid.blocks import BLOCK_TYPES, LinearBlock
    from blockid.blocks.base import StaticBlock
    from blockid.blocks.integrator import Integrator
    from blockid.models.block import ChainModel

    class NoRule(_Plain, StaticBlock):
        kind = "test-no-rule"

    class Broken(_Plain, StaticBlock):
        kind = "test-broken-rule"
        export_source = "def evaluate(p, s)\n    return s\n"

    class Misnamed(_Plain, StaticBlock):
        kind = "test-misnamed-rule"
        export_source = "def value(p, s):\n    return s\n"

    class Unnamed(_Plain, StaticBlock):
        pass

    def hammerstein(block):
        return Hammerstein("u", "y", input_block=block, na=1, nb=1, nk=1, a=[-0.5], b=[1.0])

    try:
        assert _refusal(hammerstein(NoRule())) == (
            "cannot export the 'test-no-rule' block (NoRule): its class gives no "
            "export_source, the NumPy source of its evaluation that the module copies "
            "(docs/extending.md)"
        )
        assert _refusal(hammerstein(Broken())) == (
            "cannot export the 'test-broken-rule' block (Broken): its export_source is not "
            "Python (expected ':', line 1)"
        )
        assert _refusal(hammerstein(Misnamed())) == (
            "cannot export the 'test-misnamed-rule' block (Misnamed): its export_source "
            "defines no evaluate(p, ...)"
        )
        assert _refusal(hammerstein(Unnamed())) == (
            "cannot export a Unnamed block: it has no kind, the name the module would find "
            "its rule by"
        )
    finally:
        for kind in ("test-no-rule", "test-broken-rule", "test-misnamed-rule"):
            del BLOCK_TYPES[kind]
    chain = ChainModel(["u"], ["y"], [LinearBlock(1, 1, 1, [-0.5], [1.0]), Integrator()])
    assert _refusal(chain) == (
        "cannot export the 'integrator' block (Integrator): the module runs the linear "
        "block of kind 'linear' (a, b, nk) only"
    )


def test_a_slope_the_model_needs_and_the_rule_lacks_is_refused():
    """A block with its own derivative, continued along its tangent, needs its slope in
    the module too; without a derivative of its own blockid's central differences are
    taken, in the module as in blockid."""
    from blockid.blocks import BLOCK_TYPES

    class Cube(Polynomial):
        kind = "test-cube-rule"
        export_source = "def evaluate(p, s):\n    return _polyval(s, [0.0, *p['coefficients']])\n"

    try:
        model = Wiener("u", "y", output_block=Cube([1.0, 0.0, 0.1], constant=False), na=1,
                       nb=1, nk=1, a=[-0.5], b=[1.0])  # fmt: skip
        _module(model)  # no range recorded: no tangent, no slope needed
        ranged = model.replace(ranges={"u": [-1.0, 1.0], "x": [-1.0, 1.0]})
        assert _refusal(ranged) == (
            "cannot export the 'test-cube-rule' block (Cube): the model continues it along "
            "its tangent outside its estimation range, and its export_source defines no "
            "slope(p, s) for its own derivative"
        )
    finally:
        del BLOCK_TYPES["test-cube-rule"]


def test_two_blocks_of_one_kind_with_two_rules_are_refused():
    from blockid.blocks import DeadZone, LinearBlock
    from blockid.models.block import ChainModel

    class Other(DeadZone):  # the kind inherited: not registered
        export_source = "def evaluate(p, s):\n    return s\n"

    first, linear = DeadZone(-0.1, 0.1), LinearBlock(1, 1, 1, [-0.5], [1.0])
    assert _refusal(ChainModel(["u"], ["y"], [first, linear, Other(-0.2, 0.2)])) == (
        "cannot export the 'dead-zone' block (Other): another block of the model has its "
        "kind and another rule"
    )


def test_a_subclass_that_changes_the_evaluation_gives_its_own_rule():
    """An inherited export_source would simulate the parent block: refused."""
    from blockid.blocks import DeadZone

    class Doubled(DeadZone):  # the kind inherited: not registered
        def __call__(self, u):
            return 2.0 * super().__call__(u)

    model = Hammerstein("u", "y", input_block=Doubled(-0.1, 0.1), na=1, nb=1, nk=1,
                        a=[-0.5], b=[1.0])  # fmt: skip
    assert _refusal(model) == (
        "cannot export the 'dead-zone' block (Doubled): Doubled changes __call__ and "
        "inherits the export_source of DeadZone, which would simulate the parent: give "
        "Doubled its own"
    )
