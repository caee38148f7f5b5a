"""Model paths the other model tests leave out (found by mutation testing, see
docs/testing.md): model files written before chains, parameter names, the signals
inside a chain, and the messages of damaged files."""

import numpy as np
import pytest

from blockid.blocks import Polynomial, TwoSegmentPolynomial
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
