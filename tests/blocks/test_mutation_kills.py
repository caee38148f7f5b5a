"""Block behaviour at edges and defaults that the other block tests reach only on one
side (gaps found by mutation testing, see docs/testing.md); expected values by hand."""

import numpy as np
import pytest

from blockid.blocks import (
    Backlash,
    DeadZone,
    PiecewiseLinear,
    Polynomial,
    Saturation,
    TwoSegmentPolynomial,
    block_template,
)
from blockid.blocks.base import DynamicBlock, StaticBlock
from blockid.blocks.integrator import Integrator
from blockid.blocks.linear import LinearBlock
from blockid.errors import EstimationError, OrderError, ParameterError


def test_backlash_template_is_the_unit_backlash():
    assert Backlash.template().parameters == {
        "m_left": 1.0,
        "c_left": 0.0,
        "m_right": 1.0,
        "c_right": 0.0,
    }


def test_backlash_slope_lower_bounds_scale_with_each_slope():
    lower, upper = Backlash(2.0, 0.1, 3.0, 0.2).bounds()
    np.testing.assert_allclose(lower, [2e-6, 0.0, 3e-6, 0.0])
    assert np.all(np.isinf(upper))


def test_backlash_with_vector_takes_a_column():
    b = Backlash(2.0, 0.1, 3.0, 0.2).with_vector(np.array([[1.5], [0.0], [2.5], [0.1]]))
    assert b.parameters == {"m_left": 1.5, "c_left": 0.0, "m_right": 2.5, "c_right": 0.1}


@pytest.mark.parametrize(
    ("lo", "hi", "named"), [(float("nan"), 1.0, "u_min"), (0.0, float("inf"), "u_max")]
)
def test_backlash_check_branches_names_the_bad_end(lo, hi, named):
    with pytest.raises(ParameterError, match=f"^{named} must be finite"):
        Backlash(1.0, 0.1, 1.0, 0.1).check_branches(lo, hi)


def test_dead_zone_derivative_is_zero_on_the_closed_band():
    d = DeadZone(-1.0, 1.0, slope_left=2.0, slope_right=3.0)
    np.testing.assert_array_equal(
        d.derivative(np.array([-1.0, 0.0, 1.0, -1.5, 1.5])), [0, 0, 0, 2, 3]
    )


def test_saturation_jacobian_treats_both_limits_as_inside():
    s = Saturation(-1.0, 1.0, slope=2.0)
    # w = clip(2 u, -1, 1); columns d/d(lower, upper, slope): (1, 0, 0) below, (0, 1, 0)
    # above, (0, 0, u) on the closed interval, edges v = 2 u = -1 and 1 included
    np.testing.assert_array_equal(
        s.jacobian(np.array([-0.5, 0.5, 0.25, 1.0, -1.0])),
        [[0, 0, -0.5], [0, 0, 0.5], [0, 0, 0.25], [0, 1, 0], [1, 0, 0]],
    )


def test_saturation_bounds_leave_the_limits_free_and_the_slope_positive():
    lower, upper = Saturation(-1.0, 1.0).bounds()
    np.testing.assert_array_equal(lower, [-np.inf, -np.inf, 1e-6])
    np.testing.assert_array_equal(upper, [np.inf, np.inf, np.inf])


def test_linear_block_static_gain():
    # G(1) = (1 + 0.5) / (1 - 0.5) = 3
    assert LinearBlock(1, 2, 1, [-0.5], [1.0, 0.5]).static_gain() == 3.0
    assert LinearBlock(1, 1, 1, [-1.0], [1.0]).static_gain() == float("inf")  # integrator


def test_piecewise_linear_template_and_adapted_breakpoints():
    p = PiecewiseLinear.template(knots=3)
    assert p.parameters == {"breakpoints": [-1.0, 0.0, 1.0], "values": [0.0, 0.0, 0.0]}
    assert p.adapted(np.array([-2.0, 1.0, 5.0])).parameters["breakpoints"] == [-2.0, 1.5, 5.0]
    for bad in (1, True, 2.5):
        with pytest.raises(ParameterError, match="knots must be a whole number >= 2"):
            PiecewiseLinear.template(knots=bad)


def test_block_template_defaults_and_option_values():
    assert isinstance(block_template("two-segment"), TwoSegmentPolynomial)
    assert isinstance(block_template(""), TwoSegmentPolynomial)
    assert block_template("polynomial:degree=3").parameters["coefficients"] == [0.0] * 4
    with pytest.raises(ParameterError, match=r"degree must be a whole number >= 1, got 2\.0"):
        block_template("polynomial:degree=2.0")  # "2.0" stays a float: not a whole number


def test_inverse_on_a_decreasing_block():
    block = Polynomial([1.0, -2.0])  # w = 1 - 2 u, decreasing
    u = block.inverse_on(np.array([1.0, 0.0, -1.0, 5.0]), (-1.0, 1.0))
    np.testing.assert_allclose(u, [0.0, 0.5, 1.0, -1.0], atol=1e-12)  # 5 lies beyond w(-1) = 3


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


def test_backlash_plot_draws_the_loop_over_the_given_input():
    import matplotlib.pyplot as plt

    block = Backlash(1.0, 0.2, 1.5, 0.1)
    u = np.array([0.0, 1.0, 2.0, 1.0, -1.0, -2.0])
    ax = block.plot(u=u)
    try:
        loop, left, right = ax.get_lines()[:3]
        np.testing.assert_array_equal(loop.get_xdata(), u)
        # from x = 0: dead band at u = 0, right branch 1.5 (u - 0.1) up to u = 2, then
        # left branch u + 0.2 on the way down
        np.testing.assert_allclose(loop.get_ydata(), [0.0, 1.35, 2.85, 1.2, -0.8, -1.8])
        np.testing.assert_array_equal(left.get_xdata(), [-2.0, 2.0])  # the input's span
        np.testing.assert_allclose(right.get_ydata(), [-3.15, 2.85])
    finally:
        plt.close(ax.figure)


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


def test_piecewise_linear_template_on_given_breakpoints_stays_there():
    p = PiecewiseLinear.template(breakpoints=[-1, 0.5, 2])
    assert p.parameters == {"breakpoints": [-1.0, 0.5, 2.0], "values": [0.0, 0.0, 0.0]}
    # given breakpoints are not spread over the estimation input's range
    assert p.adapted(np.array([-5.0, 5.0])) is p
    with pytest.raises(ParameterError, match="breakpoints"):
        PiecewiseLinear.template(breakpoints=[1.0])


def test_backlash_with_vector_reports_a_missing_value_as_not_finite():
    # the vector is read as floats first: None becomes NaN, refused as not finite
    with pytest.raises(ParameterError, match=r"^m_left must be finite, got nan$"):
        Backlash.template().with_vector([None, 0.0, 1.0, 0.0])


def test_default_invert_widens_the_seen_range_by_half_on_both_sides():
    # StaticBlock.invert (PiecewiseLinear has no own): seen (-1, 1) becomes (-2, 2); the
    # outer segments continue their slopes (2 on the left, 1 on the right)
    block = PiecewiseLinear([-1.0, 0.0, 1.0], [-2.0, 0.0, 1.0])
    u = block.invert(np.array([-3.0, -1.0, 0.5, 1.5, 5.0]), (-1.0, 1.0))
    np.testing.assert_allclose(u, [-1.5, -0.5, 0.5, 1.5, 2.0], atol=1e-9)


def test_polynomial_is_monotone_names_its_range_argument():
    with pytest.raises(
        ParameterError, match=r"^\(u_min, u_max\) must have low < high, got \(1\.0, 0\.0\)$"
    ):
        Polynomial([0.0, 1.0]).is_monotone(1.0, 0.0)


def test_two_segment_from_segments_names_the_bad_segment():
    with pytest.raises(ParameterError, match=r"^positive needs at least 1 value\(s\), got 0$"):
        TwoSegmentPolynomial.from_segments([], [1.0])


def test_piecewise_linear_vector_names():
    p = PiecewiseLinear([-1.0, 0.0, 1.0], [0.0, 1.0, 2.0])
    assert p.vector_names() == ["values_0", "values_1", "values_2"]
    assert p.vector_names({"values": "v"}) == ["v_0", "v_1", "v_2"]


def test_saturation_names_a_bad_lower_limit():
    with pytest.raises(ParameterError, match=r"^lower must be a real number, got 'low'$"):
        Saturation("low", 1.0)


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


def test_integrator_refuses_a_complex_initial_output():
    # read as floats: a complex start is an error, not cut to its real part
    np.testing.assert_array_equal(Integrator().simulate(np.ones(3), x_init=[2]), [2.0, 3.0, 4.0])
    with pytest.raises(TypeError):
        Integrator().simulate(np.ones(3), x_init=[2.0 + 1.0j])


def test_linear_block_defaults_and_stored_coefficients():
    g = LinearBlock(1, 2, 1)
    assert g.a.tolist() == [0.0] and g.b.tolist() == [0.0, 0.0]  # b_0 = 0 unless unit_b0
    assert LinearBlock(1, 2, 1, unit_b0=True).b.tolist() == [1.0, 0.0]
    h = LinearBlock(1, 2, 1, a=[0], b=[1, 2])  # whole numbers are stored as floats
    assert h.a.dtype == np.float64 and h.b.dtype == np.float64
    assert all(type(v) is float for v in h.to_dict()["b"])
    with pytest.raises(ValueError, match="read-only"):
        h.a[0] = 0.5
    with pytest.raises(ValueError, match="read-only"):
        h.b[0] = 0.5


def test_linear_block_names_a_bad_na():
    with pytest.raises(OrderError, match=r"^na=-1: a block-oriented \(single-input"):
        LinearBlock(-1)


def test_linear_block_simulate_takes_a_column_of_initial_outputs():
    g = LinearBlock(2, 1, 1, a=[-0.5, 0.0], b=[1.0])
    # the first max_lag = 2 outputs given (x(0) = 2, x(1) = 4), the third row unused; then
    # x(k) = 0.5 x(k-1) + w(k-1): 3, 2.5
    x = g.simulate(np.ones(4), x_init=np.array([[2.0], [4.0], [7.0]]))
    np.testing.assert_array_equal(x, [2.0, 4.0, 3.0, 2.5])


def test_polynomial_inverse_checks_tol_and_reports_non_convergence():
    p = Polynomial([0.0, 0.0, 0.0, 1.0])  # w = u^3
    for bad in (0.0, -1e-3):
        with pytest.raises(ParameterError, match=r"^tol must be > 0, got -?0\.0"):
            p.inverse(np.array([8.0]), tol=bad)
    # from the bracket's middle 0, w = 0 is solved at once; 8 and 1 need more steps
    with pytest.raises(
        EstimationError,
        match=r"^polynomial inverse did not converge in 1 iterations for 2 sample\(s\); "
        r"raise max_iter or tol$",
    ):
        p.inverse(np.array([8.0, 1.0, 0.0]), max_iter=1)


def test_two_segment_check_data_message():
    with pytest.raises(EstimationError) as info:
        TwoSegmentPolynomial.template().check_data(np.array([1.0, 2.0]))
    assert str(info.value) == (
        "the input never changes sign, so the two polynomials of the two-segment input "
        "block (B1) cannot both be identified; use data that span both signs of u, or a "
        "Polynomial input block"
    )


def test_dead_zone_jacobian_edges_do_not_move_on_the_band():
    d = DeadZone(-0.5, 1.0, slope_left=2.0, slope_right=3.0)
    # columns d/d(lower, upper, slope_left, slope_right); at u = lower and u = upper the
    # output is 0 on the band side, as the derivative
    np.testing.assert_array_equal(
        d.jacobian(np.array([-0.5, 1.0, -1.0, 2.0])),
        [[0, 0, 0, 0], [0, 0, 0, 0], [-2, 0, -0.5, 0], [0, -3, 0, 1]],
    )


def test_piecewise_linear_and_saturation_name_the_bad_argument():
    with pytest.raises(ParameterError, match=r"^values needs at least 2 value\(s\), got 1$"):
        PiecewiseLinear([0.0, 1.0], [0.0])
    with pytest.raises(ParameterError, match=r"^upper must be a real number, got 'x'$"):
        Saturation(-1.0, "x")


def test_saturation_template_is_the_unit_saturation():
    assert Saturation.template().parameters == {"lower": -1.0, "upper": 1.0, "slope": 1.0}
