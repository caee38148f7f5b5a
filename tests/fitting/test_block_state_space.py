"""Fitting block state-space models: known plants of several inputs and outputs, the
blocks' parameters against the truth, the start never bettered by a worse model, and
clear errors."""

import numpy as np
import pytest

from blockid import fit_model
from blockid.blocks import Polynomial
from blockid.data import Dataset
from blockid.errors import ParameterError
from blockid.fitting.block_state_space import fit_block_state_space, near_identity
from blockid.models import model_from_dict
from blockid.models.export import to_python_module

from reference import MIMO_HW_INPUT, MIMO_HW_OUTPUT, mimo_hw_plant, mimo_hw_record

INPUT, OUTPUT = MIMO_HW_INPUT, MIMO_HW_OUTPUT


def _data(n=4000, snr_db=40.0, seed=1):
    return mimo_hw_record(n, snr_db, seed)


@pytest.fixture(scope="module")
def hw_fit():
    data, u = _data()
    fit = fit_block_state_space(
        data, nx=3, input_block="polynomial:degree=3", output_block="polynomial:degree=3"
    )
    return data, u, fit


def test_two_input_two_output_hammerstein_wiener_blocks_within_5_percent(hw_fit):
    """Each fitted block, as a function of the plant's own signal (the input ``u``; the
    true core output ``z``, of which the fitted core output is an affine map), is a
    cubic whose coefficients, normalised like the plant's (no constant, unit linear
    coefficient), lie within 5 % of the largest coefficient of the true block."""
    data, u, fit = hw_fit
    m, plant = fit.model, mimo_hw_plant()
    un = m.normalised_input(u)
    w = m.block_inputs(un)
    for i, true in enumerate(INPUT):
        c = np.polynomial.polynomial.polyfit(u[:, i], w[:, i], 3)
        c = (c - np.r_[c[0], 0, 0, 0]) / c[1]
        np.testing.assert_allclose(c, true, rtol=0, atol=0.05 * max(np.abs(true)))
    z_fit = m.run(un, m.initial_state(u, data.experiments[0].y[:30]))[1]
    z_true = plant.run(plant.normalised_input(u))[1]
    y_fit = m.output_offset + m.output_scale * m.block_outputs(z_fit)
    for j, true in enumerate(OUTPUT):
        c = np.polynomial.polynomial.polyfit(z_true[:, j], y_fit[:, j], 3)
        c = (c - np.r_[c[0], 0, 0, 0]) / c[1]
        np.testing.assert_allclose(c, true, rtol=0, atol=0.05 * max(np.abs(true)))


def test_it_ends_far_below_the_linear_start_and_near_the_noise(hw_fit):
    _, _, fit = hw_fit
    for name in ("y1", "y2"):
        linear = fit.settings["linear_simulation_metrics"]["fit_percent"][name]
        assert fit.estimation_metrics["fit_percent"][name] > 98.5 > linear + 25


def test_a_miso_model_fitted_saved_loaded_and_exported_simulates_identically():
    data, u = _data(n=1500)
    miso = Dataset.from_arrays(u, data.experiments[0].y[:, 0], inputs=["u1", "u2"], outputs=["y"])
    fit = fit_model(miso, "block-state-space", nx=3, input_block=["u1=polynomial:degree=3"])
    m = fit.model
    assert m.input_blocks[1] is None and m.kind == "hammerstein"
    back = model_from_dict(m.to_dict())
    namespace: dict = {}
    exec(to_python_module(back), namespace)  # noqa: S102 - the module under test
    y0 = miso.experiments[0].y[:20]
    for start in (None, y0):
        ours = m.simulate(u, start)
        np.testing.assert_array_equal(back.simulate(u, start), ours)
        np.testing.assert_allclose(namespace["simulate"](u, start), ours, rtol=0, atol=1e-10)


def test_the_start_is_the_linear_model_so_the_fit_never_ends_worse():
    rng = np.random.default_rng(4)
    u = rng.standard_normal((600, 2))
    y = np.column_stack((np.convolve(u[:, 0], [0.0, 1.0, 0.5])[:600], u[:, 1]))
    y = y + 0.01 * rng.standard_normal(y.shape)
    data = Dataset.from_arrays(u, y, inputs=["a", "b"], outputs=["p", "q"])
    fit = fit_block_state_space(data, nx=2, output_block="polynomial:degree=3")
    lin = fit.settings["linear_simulation_metrics"]["mse"]
    for name in ("p", "q"):
        assert fit.estimation_metrics["mse"][name] <= lin[name] * 1.0001


def test_near_identity_is_the_identity_where_the_family_holds_it():
    v = np.linspace(-2.0, 3.0, 200)
    for spec in (Polynomial.template(3), Polynomial.output_template(3)):
        block = near_identity(spec, v)
        np.testing.assert_allclose(block(v), v, atol=1e-8)


def test_without_any_block_the_error_says_which_structure_to_use():
    data, _ = _data(n=300)
    with pytest.raises(ParameterError, match="'state-space'"):
        fit_block_state_space(data, nx=2)


def test_a_channel_that_is_not_in_the_data_is_named():
    data, _ = _data(n=300)
    with pytest.raises(ParameterError, match=r"\['u7'\]"):
        fit_model(data, "block-state-space", input_block="u7=dead-zone")


def test_blocks_per_channel_given_to_a_one_channel_chain_are_refused():
    data, u = _data(n=300)
    siso = Dataset.from_arrays(u[:, 0], data.experiments[0].y[:, 0])
    with pytest.raises(ParameterError, match="block-state-space"):
        fit_model(siso, "hammerstein", na=2, nb=2, nk=1, input_block=["u=dead-zone"])


def test_two_blocks_without_channel_names_are_refused():
    data, _ = _data(n=300)
    with pytest.raises(ParameterError, match="name each one's channel"):
        fit_model(data, "block-state-space", input_block=["dead-zone", "polynomial"])
