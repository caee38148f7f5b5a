"""Models as chains of blocks: any chain simulates, differentiates, refines and saves."""

import numpy as np
import pytest

from blockid import errors
from blockid.blocks import Backlash, DeadZone, Polynomial, Saturation, TwoSegmentPolynomial
from blockid.blocks.linear import LinearBlock
from blockid.data import Dataset
from blockid.fitting import refine
from blockid.fitting.simulation_error import simulate_with_sensitivities
from blockid.models import (
    BacklashModel,
    ChainModel,
    Hammerstein,
    HammersteinWiener,
    WienerHammerstein,
    load_model,
    save_model,
)


def wiener_hammerstein():
    return WienerHammerstein(
        "u",
        "y",
        first=LinearBlock(2, 2, 0, a=[-1.1, 0.35], b=[0.4, 0.2]),
        static=Polynomial([1.0, 0.3, -0.2], constant=False),
        second=LinearBlock(1, 2, 1, a=[-0.6], b=[1.0, 0.5]),
    )


MODELS = {
    "wiener-hammerstein": wiener_hammerstein,
    "hammerstein-wiener": lambda: HammersteinWiener(
        "u",
        "y",
        input_block=TwoSegmentPolynomial([0.1, 1.0, 0.3], [0.0, -0.4, 0.2]),
        output_block=Polynomial([1.0, 0.15], constant=False),
        na=2,
        nb=2,
        nk=1,
        a=[-1.2, 0.5],
        b=[1.0, 0.4],
    ),
    "backlash": lambda: BacklashModel(
        "u", "y", input_block=Backlash(0.9, 0.1, 1.1, 0.15), na=2, nb=1, nk=1, a=[-1.0, 0.3]
    ),
    "dead zone": lambda: Hammerstein(
        "u", "y", input_block=DeadZone(-0.2, 0.1, 1.2, 0.8), na=1, nb=2, nk=1, a=[-0.7], b=[1, 0.3]
    ),
    "saturation": lambda: Hammerstein(
        "u", "y", input_block=Saturation(-0.5, 0.6, 1.5), na=1, nb=1, nk=0, a=[-0.5]
    ),
}


def _finite_difference(model, u, y0, h=1e-6):
    theta = model.free_parameters()
    cols = []
    for i in range(theta.size):
        step = h * max(1.0, abs(theta[i]))
        up, down = theta.copy(), theta.copy()
        up[i] += step
        down[i] -= step
        y_up = model.with_free_parameters(up).simulate(u, y0)[:, 0]
        y_down = model.with_free_parameters(down).simulate(u, y0)[:, 0]
        cols.append((y_up - y_down) / (2 * step))
    return np.column_stack(cols)


@pytest.mark.parametrize("name", sorted(MODELS))
@pytest.mark.parametrize("start_from_data", [False, True])
def test_chain_sensitivities_equal_finite_differences(name, start_from_data):
    model = MODELS[name]()
    u = 0.8 * np.sin(np.arange(300) / 7.0) + 0.3 * np.sin(np.arange(300) / 2.3)
    y = model.simulate(u)[:, 0]
    model = model.with_ranges([(u, y)])
    y0 = y[: model.max_lag] + 0.05 if start_from_data else None
    y_sim, S = simulate_with_sensitivities(model, u, y0)
    np.testing.assert_allclose(y_sim, model.simulate(u, y0)[:, 0], atol=1e-12)
    # backlash and dead zone have kinks: compare away from switching samples
    np.testing.assert_allclose(S, _finite_difference(model, u, y0), atol=2e-5, rtol=1e-4)


def test_wiener_hammerstein_is_refined_from_a_perturbed_start_to_the_truth():
    truth = wiener_hammerstein()
    rng = np.random.default_rng(1)
    u = rng.uniform(-1.0, 1.0, 3000)
    data = Dataset.from_arrays(u, truth.simulate(u), ["u"], ["y"])
    start = truth.with_free_parameters(
        truth.free_parameters() * (1 + 0.05 * rng.standard_normal(8))
    )
    fit = refine(start, data, tail_fraction=0.0)
    np.testing.assert_allclose(fit.model.free_parameters(), truth.free_parameters(), atol=1e-7)
    assert fit.model.structure == "wiener-hammerstein"
    assert fit.settings["na1"] == 2 and fit.settings["nk2"] == 1


def test_wiener_hammerstein_file_round_trip_is_bit_identical(tmp_path):
    model = wiener_hammerstein().replace(input_offset=0.25, output_offset=-1.5)
    u = np.sin(np.arange(200) / 5.0)
    model = model.with_ranges([(u, model.simulate(u))])
    again = load_model(save_model(model, tmp_path / "wh.json"))
    assert type(again) is WienerHammerstein
    assert again.ranges == model.ranges and again.output_offset == -1.5
    assert np.array_equal(again.simulate(u), model.simulate(u))
    assert again.parameters == model.parameters
    assert set(again.parameters) == {"a1", "b1", "coefficients", "a2", "b2"}


def test_chain_orders_and_names():
    model = wiener_hammerstein()
    assert model.linear_orders() == (3, 3, 1)  # the product of the two linear blocks
    # q_1 = 1 after the first linear block and b_0 = 1 after the static block are fixed
    assert model.free_parameter_names() == [
        "a1_1",
        "a1_2",
        "b1_0",
        "b1_1",
        "coefficients_2",
        "coefficients_3",
        "a2_1",
        "b2_1",
    ]
    assert model.free_parameters().size == 8
    assert model.max_lag == 2


def test_chains_that_make_no_sense_are_refused():
    with pytest.raises(errors.OrderError, match="needs a linear block"):
        ChainModel("u", "y", [Polynomial([1.0, 0.5])])
    with pytest.raises(errors.OrderError, match="put it first"):
        ChainModel(
            "u",
            "y",
            [
                LinearBlock(1, 1, 1, a=[-0.5], b=[1.0]),
                Backlash(1, 0, 1, 0),
                LinearBlock(1, 1, 1, a=[-0.5], b=[1.0]),
            ],
        )
    with pytest.raises(errors.OrderError, match="b_0 is fixed to 1"):
        ChainModel("u", "y", [Polynomial([0.0, 1.0]), LinearBlock(1, 1, 1, b=[2.0])])
    with pytest.raises(errors.OrderError, match="linear block, static block, linear block"):
        WienerHammerstein._from_blocks("u", "y", (LinearBlock(), Polynomial([1.0], constant=False)))
