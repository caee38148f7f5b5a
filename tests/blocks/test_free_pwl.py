"""Tests of blockid.blocks.free_pwl: FreePiecewiseLinear (breakpoints estimated)."""

import json

import numpy as np
import pytest

from blockid.blocks import FreePiecewiseLinear, PiecewiseLinear, block_template
from blockid.blocks.base import BLOCK_TYPES, LinearFamily, block_from_dict
from blockid.data import Dataset
from blockid.errors import ParameterError
from blockid.fitting import fit_model
from blockid.fitting.checks import simulation_mse
from blockid.models import Hammerstein, Wiener, load_model, save_model

BP = [-1.0, -0.2, 0.45, 1.3]
VALUES = [-0.9, -0.1, 0.3, 1.7]


def _block() -> FreePiecewiseLinear:
    return FreePiecewiseLinear(BP, VALUES)


def _central_differences(block: FreePiecewiseLinear, u: np.ndarray, h: float = 1e-7):
    theta = block.to_vector()
    columns = []
    for k in range(theta.size):
        step = np.zeros_like(theta)
        step[k] = h
        up, down = block.with_vector(theta + step)(u), block.with_vector(theta - step)(u)
        columns.append((up - down) / (2 * h))
    return np.column_stack(columns)


def _kink(block: FreePiecewiseLinear) -> float:
    """The interior breakpoint with the largest change of slope."""
    slopes = np.diff(block.values) / np.diff(block.breakpoints)
    return float(block.breakpoints[1 + int(np.argmax(np.abs(np.diff(slopes))))])


# ------------------------------------------------------------------ the map
def test_same_map_as_piecewise_linear_but_not_linear_in_parameters():
    u = np.linspace(-3.0, 3.0, 61)
    np.testing.assert_array_equal(_block()(u), PiecewiseLinear(BP, VALUES)(u))
    assert FreePiecewiseLinear.kind == "piecewise-linear-free"
    assert BLOCK_TYPES["piecewise-linear-free"] is FreePiecewiseLinear
    assert not FreePiecewiseLinear.linear_in_parameters


def test_vector_is_breakpoints_then_values():
    block = _block()
    np.testing.assert_array_equal(block.to_vector(), BP + VALUES)
    assert block.vector_names() == [f"breakpoints_{j}" for j in range(4)] + [
        f"values_{j}" for j in range(4)
    ]
    moved = block.with_vector([-1.0, 0.1, 0.5, 1.3, 0.0, 1.0, 2.0, 3.0])
    assert type(moved) is FreePiecewiseLinear
    assert moved.parameters == {
        "breakpoints": [-1.0, 0.1, 0.5, 1.3],
        "values": [0.0, 1.0, 2.0, 3.0],
    }
    assert block.parameters == {"breakpoints": BP, "values": VALUES}  # unchanged
    with pytest.raises(ParameterError, match=r"theta must have 8 entries"):
        block.with_vector(np.zeros(4))


@pytest.mark.parametrize(
    ("breakpoints", "message"),
    [
        ([-1.0, 0.5, 0.2, 1.3], r"breakpoints_2 = 0\.2 is not above breakpoints_1 = 0\.5"),
        ([-1.0, 0.5, 0.5, 1.3], r"breakpoints_2 = 0\.5 is not above breakpoints_1 = 0\.5"),
        ([2.0, -0.2, 0.45, 1.3], r"breakpoints_1 = -0\.2 is not above breakpoints_0 = 2"),
    ],
)
def test_with_vector_rejects_unordered_breakpoints(breakpoints, message):
    with pytest.raises(ParameterError, match="breakpoints must stay strictly increasing") as exc:
        _block().with_vector(breakpoints + VALUES)
    assert exc.match(message)
    assert exc.value.parameter == "theta"


def test_jacobian_matches_central_differences():
    block = _block()
    rng = np.random.default_rng(3)
    near = np.concatenate([[b - 1e-3, b + 1e-3] for b in BP])  # either side of every kink
    beyond = np.array([-4.0, -1.5, 2.0, 5.0])  # the continued end segments
    u = np.concatenate((rng.uniform(-1.0, 1.3, 40), near, beyond))
    G = block.jacobian(u)
    assert G.shape == (u.size, 8)
    np.testing.assert_allclose(G, _central_differences(block, u), rtol=1e-6, atol=1e-6)
    # the values' columns are the hat functions
    np.testing.assert_allclose(G[:, 4:], block.regressors(u), atol=1e-15)
    # the derivative in u: central differences and the segment slopes
    h = 1e-7
    np.testing.assert_allclose(
        block.derivative(u), (block(u + h) - block(u - h)) / (2 * h), rtol=1e-6, atol=1e-6
    )
    slopes = np.diff(VALUES) / np.diff(BP)
    assert block.derivative(np.array([-5.0, 0.0, 0.45, 9.0])).tolist() == pytest.approx(
        [slopes[0], slopes[1], slopes[2], slopes[2]]
    )


def test_jacobian_beyond_the_ends_by_formula():
    """Beyond the first breakpoint the first segment's formulas continue."""
    block = FreePiecewiseLinear([0.0, 1.0, 3.0], [0.0, 2.0, 3.0])
    G = block.jacobian(np.array([-1.0]))
    # h = 1, dv = 2, u - β_1 = -2, u - β_0 = -1
    assert G[0].tolist() == pytest.approx([2 * -2.0, -2 * -1.0, 0.0, 2.0, -1.0, 0.0])


# ------------------------------------------------------------------ normalisation, bounds
def test_free_mask_fixes_end_breakpoints_and_after_a_linear_block_one_more():
    block = _block()
    assert block.free_mask(False).tolist() == [False, True, True, False] + [True] * 4
    # |1.3| >= |-1.0|: the breakpoint next to the right end carries the input gain
    assert block.free_mask(True).tolist() == [False, True, False, False] + [True] * 4
    left = FreePiecewiseLinear([-3.0, -1.0, 0.5, 1.0], VALUES)
    assert left.free_mask(True).tolist() == [False, False, True, False] + [True] * 4
    three = FreePiecewiseLinear([-1.0, 0.0, 1.0], [0.0, 0.0, 1.0])
    assert three.free_mask(True).tolist() == three.free_mask(False).tolist()


def test_bounds_keep_breakpoints_near_the_range_values_free():
    lower, upper = _block().bounds()
    margin = 0.5 * 2.3 / 3
    np.testing.assert_allclose(lower[:4], -1.0 - margin)
    np.testing.assert_allclose(upper[:4], 1.3 + margin)
    assert np.all(np.isneginf(lower[4:])) and np.all(np.isposinf(upper[4:]))


# ------------------------------------------------------------------ fitting aids
def test_template_by_name_and_adapted_to_the_input():
    block = block_template("piecewise-linear-free:knots=5")
    assert type(block) is FreePiecewiseLinear
    assert block.breakpoints.tolist() == [-1.0, -0.5, 0.0, 0.5, 1.0]
    assert block.values.tolist() == [0.0] * 5
    placed = block.adapted(np.array([0.5, 2.5, 1.0, 4.5]))
    assert type(placed) is FreePiecewiseLinear
    assert placed.breakpoints.tolist() == [0.5, 1.5, 2.5, 3.5, 4.5]
    assert _block().adapted(np.array([7.0, 9.0])) is not None
    assert _block().adapted(np.array([7.0, 9.0])).parameters == _block().parameters
    given = FreePiecewiseLinear.template(breakpoints=[0.0, 1.0, 2.0])
    assert given.adapted(np.array([5.0, 6.0])).breakpoints.tolist() == [0.0, 1.0, 2.0]
    with pytest.raises(ParameterError, match="knots must be a whole number >= 2"):
        block_template("piecewise-linear-free:knots=1")


def test_output_template_and_identity_pass_the_input_through():
    out = block_template("piecewise-linear-free:knots=4", output=True)
    assert type(out) is FreePiecewiseLinear
    x = np.linspace(-5.0, 5.0, 11)
    np.testing.assert_allclose(out(x), x)
    np.testing.assert_allclose(_block().identity()(x), x)
    assert _block().identity().breakpoints.tolist() == BP


def test_initial_grid_is_the_hat_function_family():
    block = _block()
    grid = block.initial_grid(np.linspace(-1, 1, 5))
    assert len(grid) == 1 and isinstance(grid[0], LinearFamily)
    assert block.initial_grid(np.linspace(-1, 1, 5), around=grid[0]) == []
    u = np.linspace(-2.0, 2.0, 41)
    built = grid[0].build(np.array([1.0, 0.0, 2.0, -1.0]))
    assert type(built) is FreePiecewiseLinear and built.breakpoints.tolist() == BP
    np.testing.assert_allclose(grid[0].regressors(u) @ [1.0, 0.0, 2.0, -1.0], built(u))


def test_scaled_multiplies_the_values():
    u = np.linspace(-2.0, 2.0, 9)
    for gain in (2.5, -0.5):
        scaled = _block().scaled(gain)
        assert type(scaled) is FreePiecewiseLinear
        np.testing.assert_allclose(scaled(u), gain * _block()(u))


# ------------------------------------------------------------------ files
def test_dict_json_and_model_file_round_trip(tmp_path):
    block = _block()
    again = block_from_dict(json.loads(json.dumps(block.to_dict())))
    assert type(again) is FreePiecewiseLinear and again.parameters == block.parameters
    model = Hammerstein("u", "y", input_block=block, na=2, nb=2, nk=1, a=[-1.2, 0.5],
                        b=[1.0, 0.3])  # fmt: skip
    path = tmp_path / "free_pwl.json"
    save_model(model, path)
    loaded = load_model(path)
    u = np.random.default_rng(5).uniform(-2.0, 2.0, 300)
    np.testing.assert_array_equal(loaded.simulate(u), model.simulate(u))
    assert type(loaded.input_block) is FreePiecewiseLinear


# ------------------------------------------------------------------ fits
def test_hammerstein_fit_finds_an_off_grid_kink_and_beats_fixed_breakpoints():
    """Slope 0.2 below u = 0.23, 1.5 above: the fixed breakpoints (-1, -1/3, 1/3, 1)
    cannot put a kink there; the free ones move to it."""
    kinked = PiecewiseLinear([-1.0, 0.23, 1.0], [-0.2 * 1.23, 0.0, 1.5 * 0.77])
    truth = Hammerstein("u", "y", input_block=kinked, na=2, nb=2, nk=1, a=[-1.2, 0.5],
                        b=[1.0, 0.3])  # fmt: skip
    rng = np.random.default_rng(0)
    u = rng.uniform(-1.0, 1.0, 1500)
    y = truth.simulate(u)[:, 0] + 0.01 * rng.standard_normal(u.size)
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    orders = {"na": 2, "nb": 2, "nk": 1, "center": False}
    fixed = fit_model(data, "hammerstein", input_block="piecewise-linear:knots=4", **orders)
    free = fit_model(data, "hammerstein", input_block="piecewise-linear-free:knots=4", **orders)
    block = free.model.input_block
    assert type(block) is FreePiecewiseLinear
    assert abs(_kink(block) + free.model.input_offset - 0.23) < 0.02
    mse_fixed, mse_free = simulation_mse(fixed.model, data), simulation_mse(free.model, data)
    assert mse_free < 0.1 * mse_fixed
    assert mse_free < 2e-4  # the noise variance is 1e-4
    np.testing.assert_allclose(free.model.a, [-1.2, 0.5], atol=0.02)


def test_wiener_fit_with_a_free_output_map():
    """A monotone output map with a knee at x = 0.4 (slope 1, then 0.3)."""
    knee = FreePiecewiseLinear([-2.0, 0.4, 2.0], [-2.0, 0.4, 0.4 + 0.3 * 1.6])
    truth = Wiener("u", "y", output_block=knee, na=2, nb=2, nk=1, a=[-1.2, 0.5], b=[0.5, 0.3])
    rng = np.random.default_rng(1)
    u = rng.uniform(-1.0, 1.0, 1500)
    y = truth.simulate(u)[:, 0] + 0.01 * rng.standard_normal(u.size)
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    orders = {"na": 2, "nb": 2, "nk": 1}
    fit = fit_model(data, "wiener", output_block="piecewise-linear-free:knots=4", **orders)
    cubic = fit_model(data, "wiener", output_block="polynomial:degree=3", **orders)
    assert type(fit.model.output_block) is FreePiecewiseLinear
    assert "breakpoints_2" not in fit.model.free_parameter_names()  # fixed: the input gain
    mse = simulation_mse(fit.model, data)
    assert mse < 2e-4 and mse < 0.1 * simulation_mse(cubic.model, data)
    np.testing.assert_allclose(fit.model.a, [-1.2, 0.5], atol=0.02)


def test_a_plant_with_negative_gain_is_fitted_and_exported(tmp_path):
    """Free values can follow a negative gain (the positive-slope refusal is for the
    profile shapes only), and the exported NumPy module simulates the fitted model."""
    from blockid.models.export import to_python_module

    kinked = PiecewiseLinear([-1.0, 0.23, 1.0], [0.2 * 1.23, 0.0, -1.5 * 0.77])
    truth = Hammerstein("u", "y", input_block=kinked, na=2, nb=2, nk=1, a=[-1.2, 0.5],
                        b=[1.0, 0.3])  # fmt: skip
    rng = np.random.default_rng(1)
    u = rng.uniform(-1.0, 1.0, 1500)
    y = truth.simulate(u)[:, 0] + 0.01 * rng.standard_normal(u.size)
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    orders = {"na": 2, "nb": 2, "nk": 1, "center": False}
    fit = fit_model(data, "hammerstein", input_block="piecewise-linear-free:knots=4", **orders)
    assert simulation_mse(fit.model, data) < 2e-4
    namespace: dict = {}
    exec(to_python_module(fit.model), namespace)
    np.testing.assert_allclose(
        np.ravel(namespace["simulate"](u)), fit.model.simulate(u)[:, 0], rtol=0, atol=1e-10
    )
