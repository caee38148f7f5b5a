import numpy as np
import pytest
from scipy.signal import lfilter

from blockid import errors
from blockid.blocks import Backlash, DeadZone, Polynomial, TwoSegmentPolynomial
from blockid.errors import ModelFileError
from blockid.models import (
    BacklashModel,
    Hammerstein,
    HammersteinWiener,
    Wiener,
    load_model,
    save_model,
)
from blockid.models.base import model_from_dict

N1 = TwoSegmentPolynomial([0.05, 1.0, 0.3, -0.1], [-0.05, -0.4, 0.2, 0.05])
N2 = Polynomial([1.0, 0.2, 0.1], constant=False)
A = [-1.2, 0.5, -0.1]
B = [1.0, 0.4, 0.2]


def hw(**kw):
    return HammersteinWiener(
        "u", "y", input_block=N1, output_block=N2, na=3, nb=3, nk=2, a=A, b=B, **kw
    )


def test_hw_simulation_is_the_cascade(rng):
    u = rng.uniform(-1.5, 1.5, 400)
    x = lfilter(np.r_[0, 0, B], np.r_[1, A], N1(u))
    np.testing.assert_allclose(hw().simulate(u)[:, 0], N2(x), atol=1e-12)


def test_one_step_prediction_is_exact_on_noise_free_data(rng):
    u = rng.uniform(-1.5, 1.5, 400)
    for model in (
        hw(),
        Hammerstein("u", "y", input_block=N1, na=3, nb=3, nk=2, a=A, b=B),
        Wiener("u", "y", output_block=N2, na=3, nb=3, nk=2, a=A, b=[0.5, 0.4, 0.2]),
        BacklashModel(
            "u", "y", input_block=Backlash(0.9, 0.3, 0.8, 0.35), na=2, nb=1, nk=1, a=[-1.0, 0.17]
        ),
    ):
        y = model.simulate(u)
        np.testing.assert_allclose(model.predict(u, y), y, atol=1e-9)


def test_simulate_with_measured_initial_conditions_continues_the_record(rng):
    model = hw(output_offset=2.0, input_offset=0.5)
    u = rng.uniform(-1, 2, 300)
    y = model.simulate(u)
    # restart at sample 100 from the measured outputs there: the continuation matches
    # after the linear block's memory of w has passed (nk + nb - 1 samples)
    again = model.simulate(u[100:], y[100 : 100 + model.max_lag])
    np.testing.assert_allclose(again[20:, 0], y[120:, 0], atol=1e-6)


def test_free_parameter_vector_round_trip():
    model = hw()
    theta = model.free_parameters()
    assert theta.size == 8 + 3 + 2 + 2  # f,p | a | b1,b2 | q2,q3
    again = model.with_free_parameters(theta * 1.1)
    np.testing.assert_allclose(again.free_parameters(), theta * 1.1)
    assert again.b[0] == 1.0 and again.output_block.coefficients[0] == 1.0


def test_spec_parameter_names_and_file_round_trip(tmp_path, rng):
    bl = BacklashModel(
        "u2", "v2", input_block=Backlash(0.9, 0.8, 0.9, 0.85), na=2, nb=1, nk=1, a=[-1.0, 0.17]
    )
    assert set(bl.parameters) == {"m_left", "c_left", "m_right", "c_right", "a", "b"}
    assert set(hw().parameters) == {"f", "p", "a", "b", "q"}
    u = rng.uniform(0, 10, 300)
    for model in (
        hw(sampling_time=0.05),
        bl,
        Hammerstein("u", "y", input_block=DeadZone(-0.2, 0.3), na=1, a=[-0.5]),
    ):
        path = save_model(model, tmp_path / f"{model.structure}.json")
        again = load_model(path)
        assert type(again) is type(model)
        assert np.array_equal(again.simulate(u), model.simulate(u))
        y = model.simulate(u)
        if model.output_block is None or model.output_block.is_monotone(y.min(), y.max()):
            assert np.array_equal(again.predict(u, y), model.predict(u, y))


def test_normalisation_and_structure_errors():
    with pytest.raises(errors.OrderError, match="b_0 is fixed to 1"):
        Hammerstein("u", "y", input_block=N1, nb=2, b=[2.0, 1.0])
    with pytest.raises(errors.OrderError, match="q_1 is fixed to 1"):
        Wiener("u", "y", output_block=Polynomial([2.0, 1.0], constant=False))
    with pytest.raises(errors.OrderError, match="one input"):
        Hammerstein(["u1", "u2"], "y", input_block=N1)
    with pytest.raises(errors.OrderError, match="without constant"):
        Wiener("u", "y", output_block=Polynomial([0.0, 1.0]))


def test_output_block_monotone_over_the_data_is_enough_for_one_step(rng):
    # y = x + 0.1 x^2 turns at x = -5, far outside the data: prediction is exact
    model = Wiener(
        "u",
        "y",
        output_block=Polynomial([1.0, 0.1], constant=False),
        na=1,
        nb=1,
        nk=1,
        a=[-0.5],
        b=[0.4],
    )
    u = rng.uniform(-1, 1, 300)
    y = model.simulate(u)
    model = model.with_ranges([(u, y)])
    np.testing.assert_allclose(model.predict(u, y), y, atol=1e-12)


def test_non_invertible_output_block_refuses_one_step_prediction(rng):
    # y = x - 2 x^2 turns at x = 0.25, inside the range the model works on
    model = Wiener(
        "u", "y", output_block=Polynomial([1.0, -2.0], constant=False), na=1, a=[-0.5], b=[1.0]
    )
    u = rng.uniform(-2, 2, 100)
    y = model.simulate(u)
    model = model.with_ranges([(u, y)])
    with pytest.raises(errors.EstimationError, match="not monotone over the range of x"):
        model.predict(u, y)


def test_extrapolation_is_flagged_outside_the_recorded_ranges(rng, tmp_path):
    model = hw()
    u = rng.uniform(-1.0, 1.0, 500)
    model = model.with_ranges([(u, None)])
    assert model.extrapolation(rng.uniform(-0.9, 0.9, 200)) == []
    notes = model.extrapolation(np.r_[u[:100], 1.6])
    assert len(notes) >= 1 and "input 'u' leaves the range seen in estimation" in notes[0]
    again = load_model(save_model(model, tmp_path / "m.json"))  # ranges travel with the file
    assert again.ranges == model.ranges


def test_polynomial_input_block_without_constant_round_trips(rng, tmp_path):
    model = Hammerstein(
        "u", "y", input_block=Polynomial([1.0, 0.5], constant=False), na=1, nb=1, nk=1, a=[-0.5]
    )
    again = load_model(save_model(model, tmp_path / "m.json"))
    u = rng.uniform(-1, 1, 50)
    assert np.array_equal(again.simulate(u), model.simulate(u))


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
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


def test_backlash_model_refuses_another_input_block():
    from blockid.errors import OrderError
    from blockid.models.block import BacklashModel

    with pytest.raises(OrderError, match="^a backlash model's input block must be a Backlash$"):
        BacklashModel("u", "y", input_block=Polynomial([0.0, 1.0]), na=1, nb=1, nk=1, a=[-0.5])


def test_a_block_model_of_two_outputs_is_refused_with_the_advice():
    from blockid.blocks import Polynomial
    from blockid.errors import OrderError
    from blockid.models.block import Hammerstein

    with pytest.raises(OrderError) as info:
        Hammerstein("u", ["y1", "y2"], input_block=Polynomial([0.0, 1.0]), na=1, nb=1, nk=1)
    assert str(info.value) == (
        "a chain of blocks has one output; got 2 (['y1', 'y2']). For several signals use "
        "structure arx, state-space, polynomial-state-space or block-state-space "
        "(--structure / --structures), paper B's key-term-rls method, or a network of blocks"
    )
