"""What every block inherits from blockid.blocks.base: the default finite-difference
jacobian and sensitivity, the bisection inverse and its widened range, ``repr`` and
``block_template``; shown on small user blocks and on blocks without their own."""

import numpy as np
import pytest

from blockid.blocks import DeadZone, PiecewiseLinear, TwoSegmentPolynomial, block_template
from blockid.blocks.base import DynamicBlock, StaticBlock
from blockid.errors import ParameterError


def test_block_template_defaults_and_option_values():
    assert isinstance(block_template("two-segment"), TwoSegmentPolynomial)
    assert isinstance(block_template(""), TwoSegmentPolynomial)
    assert block_template("polynomial:degree=3").parameters["coefficients"] == [0.0] * 4
    with pytest.raises(ParameterError, match=r"degree must be a whole number >= 1, got 2\.0"):
        block_template("polynomial:degree=2.0")  # "2.0" stays a float: not a whole number


def test_repr_names_the_block_class():
    assert (
        repr(DeadZone(-1.0, 1.0))
        == "DeadZone(lower=-1.0, upper=1.0, slope_left=1.0, slope_right=1.0)"
    )


def test_default_inverse_on_a_decreasing_piecewise_linear_block():
    # the bisection of StaticBlock.inverse_on (Polynomial has its own): w falls from 1 to -2
    block = PiecewiseLinear([-1.0, 0.0, 1.0], [1.0, 0.0, -2.0])
    u = block.inverse_on(np.array([1.0, 0.5, 0.0, -1.0, -2.0, 5.0]), (-1.0, 1.0))
    np.testing.assert_allclose(u, [-1.0, -0.5, 0.0, 0.5, 1.0, -1.0], atol=1e-12)


class _FirstOrderLag(DynamicBlock):
    """A user block with memory, x(k) = pole x(k-1) + gain u(k), relying on the default
    ``sensitivity``; it builds its output like its input (``empty_like``)."""

    def __init__(self, pole: float = 0.5, gain: float = 1.0) -> None:
        self.pole, self.gain = float(pole), float(gain)

    @property
    def parameters(self):
        return {"pole": self.pole, "gain": self.gain}

    def simulate(self, u, x0=0.0):
        x, prev = np.empty_like(u), x0
        for k, uk in enumerate(u):
            prev = x[k] = self.pole * prev + self.gain * uk
        return x


def test_default_dynamic_sensitivity_is_the_finite_difference_on_a_float_input():
    block = _FirstOrderLag(0.5, 2.0)
    u = [1, 0, 2, -1, 3]  # whole numbers: the default must hand simulate a float array
    x, G = block.sensitivity(u)
    # by hand from rest: x = 2 u(k) + 0.5 x(k-1)
    np.testing.assert_allclose(x, [2.0, 1.0, 4.5, 0.25, 6.125])
    # dx/dpole = x(k-1) + 0.5 dx/dpole(k-1), dx/dgain = u(k) + 0.5 dx/dgain(k-1)
    d_pole, d_gain, x_prev = np.zeros(5), np.zeros(5), 0.0
    for k in range(5):
        d_pole[k] = x_prev + (0.5 * d_pole[k - 1] if k else 0.0)
        d_gain[k] = u[k] + (0.5 * d_gain[k - 1] if k else 0.0)
        x_prev = x[k]
    assert G.shape == (5, 2)
    np.testing.assert_allclose(G, np.column_stack([d_pole, d_gain]), atol=1e-5)


def test_default_invert_widens_the_seen_range_by_half_on_both_sides():
    # StaticBlock.invert (PiecewiseLinear has no own): seen (-1, 1) becomes (-2, 2); the
    # outer segments continue their slopes (2 on the left, 1 on the right)
    block = PiecewiseLinear([-1.0, 0.0, 1.0], [-2.0, 0.0, 1.0])
    u = block.invert(np.array([-3.0, -1.0, 0.5, 1.5, 5.0]), (-1.0, 1.0))
    np.testing.assert_allclose(u, [-1.5, -0.5, 0.5, 1.5, 2.0], atol=1e-9)


class _QuadraticGain(StaticBlock):
    """A user block ``w = gain u^2`` with ``gain >= 0``, on the default (finite-difference)
    jacobian: at ``gain = 0`` the step down is refused by the constructor."""

    def __init__(self, gain: float = 1.0) -> None:
        if gain < 0:
            raise ParameterError(f"gain must be >= 0, got {gain}")
        self.gain = float(gain)

    @property
    def parameters(self):
        return {"gain": self.gain}

    def __call__(self, u):
        return self.gain * np.asarray(u, dtype=float) ** 2


class _Sign(StaticBlock):
    """A user block without parameters whose output is whole numbers (an int array)."""

    @property
    def parameters(self):
        return {}

    def __call__(self, u):
        return np.sign(np.asarray(u, dtype=float)).astype(int)


def test_default_jacobian_is_one_sided_at_a_parameter_bound():
    u = np.array([-2.0, 0.5, 3.0])
    # gain - h is refused: (w(gain + h) - w(gain)) / h = u^2 exactly for w linear in gain
    np.testing.assert_allclose(_QuadraticGain(0.0).jacobian(u), [[4.0], [0.25], [9.0]])
    np.testing.assert_allclose(_QuadraticGain(2.0).jacobian(u), [[4.0], [0.25], [9.0]])


def test_static_forward_hands_on_a_float_output():
    w, S = _Sign().forward(np.array([-2.0, 0.0, 3.0]), np.zeros((3, 1)), np.zeros(0, int))
    assert w.dtype == np.float64
    assert w.tolist() == [-1.0, 0.0, 1.0]
    np.testing.assert_array_equal(S, np.zeros((3, 1)))


def test_degeneracy_limits_are_the_ones_the_docs_state():
    """A block's degeneracy (issue 37): the default finds none; the limits are those
    docs/cli.md's table of warnings states."""
    from pathlib import Path

    from blockid.blocks.base import EDGE_DISTANCE, EDGE_GAP, SLOPE_RATIO

    assert TwoSegmentPolynomial.from_segments([0.0, 1.0], [0.0, 2.0]).degeneracy(-1, 1) == []
    doc = (Path(__file__).parents[2] / "docs" / "cli.md").read_text()
    assert f"closer than {EDGE_GAP:g} of the range (`blocks.base.EDGE_GAP`)" in doc
    assert f"more than {EDGE_DISTANCE:g} range width outside it (`EDGE_DISTANCE`)" in doc
    assert f"below {SLOPE_RATIO:g} of the block's steepest (`SLOPE_RATIO`" in doc
