"""Model paths the other model tests leave out (found by mutation testing, see
docs/testing.md): model files written before chains, parameter names, the signals
inside a chain, and the messages of damaged files."""

import numpy as np
import pytest

from blockid.blocks import PiecewiseLinear, Polynomial, TwoSegmentPolynomial
from blockid.errors import ModelFileError
from blockid.models import ARX, Hammerstein, HammersteinWiener, Wiener
from blockid.models.base import model_from_dict

U = np.array([0.0, 1.0, -2.0, 0.5, 3.0, -1.0])


def _version1(structure, blocks, parameters, orders=(1, 2, 1)):
    na, nb, nk = orders
    return {
        "structure": structure,
        "inputs": ["u"],
        "outputs": ["y"],
        "orders": {"na": na, "nb": nb, "nk": nk},
        "blocks": blocks,
        "parameters": parameters,
    }


def test_version1_hammerstein_with_a_polynomial_input_block():
    # before chains: SPEC names (f for the input polynomial), orders beside them
    data = _version1(
        "hammerstein", {"input": "polynomial"}, {"f": [0.0, 1.0, 0.5], "a": [-0.5], "b": [1.0, 0.3]}
    )
    model = model_from_dict(data)
    expected = Hammerstein(
        "u", "y", input_block=Polynomial([0.0, 1.0, 0.5]), na=1, nb=2, nk=1, a=[-0.5], b=[1.0, 0.3]
    )
    assert model.to_dict()["chain"] == expected.to_dict()["chain"]
    np.testing.assert_array_equal(model.simulate(U), expected.simulate(U))


def test_version1_hammerstein_wiener_with_its_output_polynomial():
    data = _version1(
        "hammerstein-wiener",
        {"input": "two-segment-polynomial", "output": "polynomial"},
        {"f": [0.0, 1.0], "p": [0.0, -0.5], "a": [-0.5], "b": [1.0, 0.3], "q": [1.0, 0.2]},
    )
    model = model_from_dict(data)
    expected = HammersteinWiener(
        "u", "y",
        input_block=TwoSegmentPolynomial([0.0, 1.0], [0.0, -0.5]),
        output_block=Polynomial([1.0, 0.2], constant=False),
        na=1, nb=2, nk=1, a=[-0.5], b=[1.0, 0.3],
    )  # fmt: skip
    assert model.to_dict()["chain"] == expected.to_dict()["chain"]
    np.testing.assert_array_equal(model.simulate(U), expected.simulate(U))


def test_version1_output_block_must_be_a_polynomial_with_q():
    data = _version1("wiener", {"output": "dead-zone"}, {"a": [-0.5], "b": [1.0, 0.3], "q": [1.0]})
    with pytest.raises(
        ModelFileError, match="the output block must be a polynomial with parameters 'q'"
    ):
        model_from_dict(data)


def test_damaged_model_description_names_the_missing_entry():
    data = Hammerstein(
        "u", "y", input_block=Polynomial([0.0, 1.0]), na=1, nb=1, nk=1, a=[-0.5]
    ).to_dict()
    del data["parameters"], data["chain"]
    with pytest.raises(
        ModelFileError, match=r"hammerstein model description is damaged or incomplete \(KeyError: "
    ):
        model_from_dict(data)


def test_free_parameter_names_of_a_two_segment_input_block():
    m = Hammerstein(
        "u",
        "y",
        input_block=TwoSegmentPolynomial([0.0, 1.0], [0.0, -0.5]),
        na=1,
        nb=2,
        nk=1,
        a=[-0.5],
        b=[1.0, 0.3],
    )
    # b_0 = 1 is fixed by the normalisation after a nonlinear block
    assert m.free_parameter_names() == ["f_0", "f_1", "p_0", "p_1", "a_1", "b_1"]
    assert len(m.free_parameter_names()) == len(m.free_parameters())


def test_block_inputs_are_the_signals_entering_each_block():
    m = Wiener(
        "u",
        "y",
        output_block=Polynomial([1.0, 2.0], constant=False),
        na=1,
        nb=1,
        nk=1,
        a=[-0.5],
        b=[1.0],
    )
    u_in, x_in = m.block_inputs(U.reshape(-1, 1))
    np.testing.assert_array_equal(u_in, U)
    # x(t) = 0.5 x(t-1) + u(t-1)
    x = np.zeros(len(U))
    for t in range(1, len(U)):
        x[t] = 0.5 * x[t - 1] + U[t - 1]
    np.testing.assert_allclose(x_in, x)
    np.testing.assert_allclose(m.simulate(U)[:, 0], x + 2.0 * x**2)


def test_arx_from_dict_without_offsets_has_zero_offsets():
    m = ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [-0.5]}}, b={"y": {"u": [1.0]}})
    data = m.to_dict()
    data.pop("offsets", None)
    loaded = model_from_dict(data)
    np.testing.assert_array_equal(loaded.simulate(U), m.simulate(U))
    assert list(np.ravel(loaded.input_offset)) == [0.0]


def test_extrapolation_names_the_linear_blocks_output_leaving_its_range():
    m = Wiener(
        "u",
        "y",
        output_block=Polynomial([1.0, 2.0], constant=False),
        na=1,
        nb=1,
        nk=1,
        a=[-0.5],
        b=[1.0],
    ).replace(ranges={"u": [-1.0, 1.0], "x": [-1.0, 1.0]})
    # x(t) = 0.5 x(t-1) + u(t-1) = [0, 0, 3, 1.5]: 2 of 4 samples above 1 (by 2 = 100 %)
    assert m.extrapolation(np.array([0.0, 3.0, 0.0, 0.0])) == [
        "the linear block's output x (input of the output block) leaves the range seen in "
        "estimation [-1, 1] in 2 of 4 samples (by up to 100 % of that range): the model "
        "extrapolates there (along the block's tangent at the range's end)"
    ]
    assert m.extrapolation(np.array([0.0, 1.0, 0.0, 0.0])) == []


def test_saved_chain_whose_blocks_do_not_fit_names_the_structure():
    data = Wiener(
        "u", "y", output_block=Polynomial([1.0, 0.5], constant=False), na=1, nb=1, nk=1, a=[-0.5]
    ).to_dict()
    data["chain"] = Hammerstein(
        "u", "y", input_block=Polynomial([0.0, 1.0]), na=1, nb=1, nk=1, a=[-0.5]
    ).to_dict()["chain"]
    with pytest.raises(ModelFileError) as info:
        model_from_dict(data)
    assert (
        str(info.value) == "the wiener model's blocks do not fit: a wiener model has no input block"
    )


# ----------------------------------------------------------------------------- messages
def test_backlash_model_refuses_another_input_block():
    from blockid.errors import OrderError
    from blockid.models.block import BacklashModel

    with pytest.raises(OrderError, match="^a backlash model's input block must be a Backlash$"):
        BacklashModel("u", "y", input_block=Polynomial([0.0, 1.0]), na=1, nb=1, nk=1, a=[-0.5])


def test_unknown_model_structure_lists_the_known_ones():
    from blockid.models.base import MODEL_TYPES

    with pytest.raises(ModelFileError) as info:
        model_from_dict({"structure": "nope"})
    known = str(info.value).split("; known: ")[1].split(", ")
    assert str(info.value).startswith("unknown model structure 'nope'; known: ")
    assert known == sorted(MODEL_TYPES)
    assert {"arx", "hammerstein", "wiener", "network", "feedback"} <= set(known)


def test_model_document_without_format_is_named_by_default():
    from blockid.models.serialization import model_from_document

    with pytest.raises(ModelFileError) as info:
        model_from_document({})
    assert str(info.value) == (
        'the model document is not a blockid model file (no "format": "blockid-model")'
    )


# ----------------------------------------------------------------------------- feedback
def _feedback(c, **kwargs):
    from blockid.blocks.linear import LinearBlock
    from blockid.models.feedback import LinearFeedback

    return LinearFeedback(
        "u",
        "y",
        linear=kwargs.pop("linear", LinearBlock(1, 1, 1, a=[-0.5], b=[1.0])),
        feedback=Polynomial(c, constant=False),
        **kwargs,
    )


def test_feedback_block_without_kind_is_refused_by_name():
    from blockid.blocks.linear import LinearBlock
    from blockid.errors import OrderError
    from blockid.models.feedback import LinearFeedback

    with pytest.raises(OrderError) as info:
        LinearFeedback("u", "y", linear=LinearBlock(1, 1, 1, a=[-0.5], b=[1.0]), feedback=object())
    assert str(info.value) == (
        "the feedback block must be a static block (polynomial, dead-zone, saturation, "
        "piecewise-linear, ...), got object; a dynamic or linear block cannot be fed back"
    )


def test_feedback_template_refuses_a_degree_below_one():
    from blockid.errors import OrderError
    from blockid.models.feedback import LinearFeedback

    with pytest.raises(OrderError) as info:
        LinearFeedback.template("u", "y", na=1, nb=1, nk=1, r=0)
    assert str(info.value) == "the feedback degree r must be a whole number >= 1, got 0"


def test_feedback_ranges_of_a_diverging_free_run_keep_the_measured_outputs():
    # N(y) = y^2: y(t) = 0.5 y(t-1) + u(t-1) - y(t-1)^2 runs to -inf, then NaN
    model = _feedback([0.0, 1.0])
    u = np.array([0.0] + [3.0] * 15)
    y = np.array([0.0, 0.5, 1.0, -1.0, 2.0] + [0.0] * 11)
    assert not np.isfinite(model.simulate(u)).all()
    assert model.estimation_ranges([(u, y)]) == {"u": [0.0, 3.0], "y": [-1.0, 2.0]}


def test_feedback_extrapolation_tolerates_two_percent_of_the_range():
    from blockid.blocks.linear import LinearBlock

    # N = 0 and y(t) = u(t-1); range [-1, 49]: 2 % is 1, so y = -2 and 50 are still inside
    model = _feedback(
        [0.0, 0.0], linear=LinearBlock(0, 1, 1, b=[1.0]), ranges={"u": [-2, 50], "y": [-1, 49]}
    )
    assert model.extrapolation(np.array([-2.0, 50.0, 0.0])) == []
    assert model.extrapolation(np.array([-2.0, -2.5, 0.0])) == [
        "the output 'y' (input of the feedback polynomial) leaves the range seen in "
        "estimation [-1, 49] in 1 of 3 samples (by up to 3 % of that range): the model "
        "extrapolates there"
    ]


def test_feedback_from_dict_without_offsets_has_zero_offsets():
    model = _feedback([0.0, 0.1], input_offset=0.5, output_offset=1.0)
    data = model.to_dict()
    data.pop("offsets")
    loaded = model_from_dict(data)
    assert (loaded.input_offset, loaded.output_offset) == (0.0, 0.0)
    np.testing.assert_array_equal(loaded.simulate(U), _feedback([0.0, 0.1]).simulate(U))


# ----------------------------------------------------------------------------- network
def test_check_wiring_messages_name_the_signal_and_the_whole_cycle():
    from blockid.errors import OrderError
    from blockid.models.network import check_wiring

    with pytest.raises(OrderError) as info:
        check_wiring([("S1", ["u"], ["v"]), ("S2", ["u"], ["v"])])
    assert str(info.value) == (
        "signal 'v' is made by subsystem 'S1' and by 'S2'; each signal must come from one subsystem"
    )
    tail = (
        "; every signal in it is made inside the network, so the loop has no external input "
        "to start from. Feed one of them from outside (a measured input), or model the loop "
        "inside one subsystem"
    )
    loop3 = [("S1", ["v3"], ["v1"]), ("S2", ["v1"], ["v2"]), ("S3", ["v2"], ["v3"])]
    with pytest.raises(OrderError) as info:
        check_wiring(loop3)
    assert str(info.value) == (
        "the subsystems form a cycle: 'S1' -> v1 -> 'S2' -> v2 -> 'S3' -> v3 -> 'S1'" + tail
    )
    with pytest.raises(OrderError) as info:
        check_wiring([("S1", ["u", "v1"], ["v1"])])
    assert str(info.value) == "the subsystems form a cycle: 'S1' -> v1 -> 'S1'" + tail


def test_network_to_dict_lists_its_external_inputs_and_all_outputs():
    s1 = ARX(["u"], ["v"], 1, 1, 1, a={"v": {"v": [-0.5]}}, b={"v": {"u": [1.0]}})
    s2 = ARX(["v"], ["y"], 1, 1, 1, a={"y": {"y": [-0.25]}}, b={"y": {"v": [2.0]}})
    from blockid.models.network import Network

    data = Network([("S1", s1), ("S2", s2)], sampling_time=0.1).to_dict()
    assert data["structure"] == "network"
    assert data["inputs"] == ["u"]
    assert data["outputs"] == ["v", "y"]
    assert [s["name"] for s in data["subsystems"]] == ["S1", "S2"]


# ----------------------------------------------------------------------------- export
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


# ------------------------------------------------- survivors of the run at fdcd170
def test_a_block_model_of_two_outputs_is_refused_with_the_advice():
    from blockid.blocks import Polynomial
    from blockid.errors import OrderError
    from blockid.models.block import Hammerstein

    with pytest.raises(OrderError) as info:
        Hammerstein("u", ["y1", "y2"], input_block=Polynomial([0.0, 1.0]), na=1, nb=1, nk=1)
    assert str(info.value) == (
        "block-oriented models have one output; got 2 (['y1', 'y2']). "
        "Use an ARX model or a network of blocks for several signals"
    )


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
        "2 input(s) and 1 output(s): export it as a Python module instead"
    )


def test_model_files_are_indented_by_two_and_name_the_non_finite_entry(tmp_path):
    import json
    import math

    from blockid.errors import ModelFileError
    from blockid.models import ARX, save_model
    from blockid.models.serialization import check_finite

    model = ARX("u", "y", 1, 1, 1, a={"y": {"y": [-0.5]}}, b={"y": {"u": [1.0]}})
    path = tmp_path / "m.json"
    save_model(model, path)
    text = path.read_text()
    assert text.startswith('{\n  "') and text == json.dumps(json.loads(text), indent=2) + "\n"
    document = {"parameters": {"y": {"a": [0.1, math.nan]}}}
    with pytest.raises(ModelFileError) as info:
        check_finite(document)
    assert "parameters.y.a[1] is nan" in str(info.value)


def test_a_model_with_a_nan_parameter_is_not_written(tmp_path):
    """json's allow_nan=False is the guard: a NaN would make a file no reader accepts."""
    import math

    from blockid.models import ARX, save_model

    model = ARX("u", "y", 1, 1, 1, a={"y": {"y": [math.nan]}}, b={"y": {"u": [1.0]}})
    path = tmp_path / "m.json"
    with pytest.raises(ValueError, match="Out of range float values"):
        save_model(model, path)
    assert not path.exists()
