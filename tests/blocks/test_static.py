"""Tests of blockid.blocks.static: DeadZone, Saturation, PiecewiseLinear."""

import json

import numpy as np
import pytest

from blockid.blocks.base import BLOCK_TYPES, block_from_dict
from blockid.blocks.static import DeadZone, PiecewiseLinear, Saturation
from blockid.errors import ParameterError


def dead_zone_reference(lower, upper, m_left, m_right, u):
    out = []
    for uk in u:
        if uk < lower:
            out.append(m_left * (uk - lower))
        elif uk > upper:
            out.append(m_right * (uk - upper))
        else:
            out.append(0.0)
    return np.array(out)


# ------------------------------------------------------------------------ DeadZone
def test_dead_zone_values():
    dz = DeadZone(-1.0, 2.0, slope_left=0.5, slope_right=3.0)
    u = np.array([-3.0, -1.0, 0.0, 2.0, 2.5])
    assert dz(u).tolist() == [-1.0, 0.0, 0.0, 0.0, 1.5]
    rng = np.random.default_rng(10)
    u = rng.uniform(-4, 5, size=200)
    np.testing.assert_allclose(dz(u), dead_zone_reference(-1.0, 2.0, 0.5, 3.0, u))


def test_dead_zone_default_slopes_shape_and_zero_width():
    dz = DeadZone(-0.5, 0.5)
    u = np.array([[-1.5, 0.2], [0.5, 4.0]])
    np.testing.assert_array_equal(dz(u), [[-1.0, 0.0], [0.0, 3.5]])
    kink = DeadZone(1.0, 1.0, slope_left=2.0)  # width 0: two slopes meeting at (1, 0)
    assert kink([0.0, 1.0, 3.0]).tolist() == [-2.0, 0.0, 2.0]


def test_dead_zone_bad_parameters():
    with pytest.raises(ParameterError, match=r"lower <= upper.*lower=2.0, upper=1.0; swap"):
        DeadZone(2.0, 1.0)
    with pytest.raises(ParameterError, match="slope_left must be > 0, got -1.0"):
        DeadZone(0.0, 1.0, slope_left=-1.0)
    with pytest.raises(ParameterError, match="slope_right must be > 0, got 0.0"):
        DeadZone(0.0, 1.0, slope_right=0.0)
    with pytest.raises(ParameterError, match="upper must be finite"):
        DeadZone(0.0, np.inf)
    with pytest.raises(ParameterError, match="lower must be a real number, got 'a'"):
        DeadZone("a", 1.0)


# ---------------------------------------------------------------------- Saturation
def test_saturation_values():
    sat = Saturation(-1.0, 2.0)
    assert sat([-5.0, -1.0, 0.5, 2.0, 7.0]).tolist() == [-1.0, -1.0, 0.5, 2.0, 2.0]
    steep = Saturation(-1.0, 2.0, slope=4.0)
    assert steep([-1.0, -0.25, 0.1, 0.5, 1.0]).tolist() == [-1.0, -1.0, 0.4, 2.0, 2.0]
    assert steep(np.zeros((3, 2))).shape == (3, 2)


def test_saturation_bad_parameters():
    with pytest.raises(ParameterError, match="lower < upper, got lower=1.0, upper=1.0"):
        Saturation(1.0, 1.0)
    with pytest.raises(ParameterError, match="slope must be > 0"):
        Saturation(-1.0, 1.0, slope=-2.0)


# ----------------------------------------------------------------- PiecewiseLinear
def test_piecewise_linear_interpolates_and_extrapolates():
    pwl = PiecewiseLinear([0.0, 1.0, 3.0], [0.0, 2.0, 3.0])
    # inside: as np.interp
    u_in = np.linspace(0.0, 3.0, 31)
    np.testing.assert_allclose(pwl(u_in), np.interp(u_in, [0.0, 1.0, 3.0], [0.0, 2.0, 3.0]))
    # outside: first segment has slope 2, last slope 0.5
    assert pwl([-1.0, -0.5, 5.0, 7.0]).tolist() == [-2.0, -1.0, 4.0, 5.0]
    # exactly at the breakpoints
    assert pwl([0.0, 1.0, 3.0]).tolist() == [0.0, 2.0, 3.0]
    assert pwl(np.ones((2, 2, 2))).shape == (2, 2, 2)


def test_piecewise_linear_regressors_are_hat_functions():
    pwl = PiecewiseLinear([0.0, 1.0, 3.0], [0.0, 2.0, 3.0])
    # at the breakpoints the basis is the identity
    np.testing.assert_allclose(pwl.regressors([0.0, 1.0, 3.0]), np.eye(3), atol=1e-15)
    assert pwl.regressors([0.5, 2.5, -1.0, 4.0]).tolist() == [
        [0.5, 0.5, 0.0],
        [0.0, 0.25, 0.75],
        [2.0, -1.0, 0.0],  # extrapolated left: t = -1
        [0.0, -0.5, 1.5],  # extrapolated right: t = 1.5
    ]
    rng = np.random.default_rng(11)
    pwl = PiecewiseLinear(np.sort(rng.uniform(-2, 2, 7)), rng.normal(size=7))
    u = rng.uniform(-3, 3, size=(10, 10))
    phi = pwl.regressors(u)
    assert phi.shape == (100, 7)
    np.testing.assert_allclose(phi.sum(axis=1), 1.0)  # partition of unity
    np.testing.assert_allclose(phi @ pwl.to_vector(), pwl(u).ravel(), rtol=1e-12, atol=1e-12)


def test_piecewise_linear_with_vector():
    pwl = PiecewiseLinear([0.0, 1.0], [0.0, 1.0])
    other = pwl.with_vector(np.array([1.0, -1.0]))
    assert other.parameters == {"breakpoints": [0.0, 1.0], "values": [1.0, -1.0]}
    assert pwl.parameters["values"] == [0.0, 1.0]
    with pytest.raises(ParameterError, match=r"theta must have 2 entries"):
        pwl.with_vector([1.0])


@pytest.mark.parametrize(
    ("breakpoints", "values", "message"),
    [
        ([0.0, 1.0, 1.0], [0.0, 1.0, 2.0], "breakpoints must be strictly increasing"),
        ([1.0, 0.0], [0.0, 1.0], "breakpoints must be strictly increasing"),
        ([0.0], [0.0], "breakpoints needs at least 2 value"),
        ([0.0, 1.0], [0.0, 1.0, 2.0], r"values must have one entry per breakpoint \(2\), got 3"),
        ([0.0, np.nan], [0.0, 1.0], "breakpoints must contain finite numbers"),
    ],
)
def test_piecewise_linear_bad_parameters(breakpoints, values, message):
    with pytest.raises(ParameterError, match=message):
        PiecewiseLinear(breakpoints, values)


def test_parameters_are_read_only():
    pwl = PiecewiseLinear([0.0, 1.0], [0.0, 1.0])
    with pytest.raises(ValueError, match="read-only"):
        pwl.values[0] = 5.0


# ------------------------------------------------------------------ serialisation
@pytest.mark.parametrize(
    "block",
    [
        DeadZone(-0.2, 0.3, slope_left=0.8, slope_right=1.1),
        Saturation(-1.0, 1.5, slope=2.0),
        PiecewiseLinear([-1.0, 0.0, 2.0], [0.5, 0.0, 1.0]),
    ],
    ids=repr,
)
def test_dict_and_json_round_trip(block):
    data = block.to_dict()
    assert BLOCK_TYPES[data["kind"]] is type(block)
    again = block_from_dict(json.loads(json.dumps(data)))
    assert type(again) is type(block)
    assert again.parameters == block.parameters
    u = np.linspace(-3, 3, 13)
    np.testing.assert_array_equal(again(u), block(u))


def test_kinds_and_flags():
    assert (DeadZone.kind, Saturation.kind, PiecewiseLinear.kind) == (
        "dead-zone",
        "saturation",
        "piecewise-linear",
    )
    assert PiecewiseLinear.linear_in_parameters
    assert not DeadZone.linear_in_parameters and not Saturation.linear_in_parameters


@pytest.mark.parametrize(
    ("block", "expected"),
    [
        (DeadZone(-1.0, 2.0), (-4.0, 5.0)),
        (DeadZone(1.0, 1.0), (0.0, 2.0)),
        (Saturation(-1.0, 2.0, slope=2.0), (-1.25, 1.75)),
        (PiecewiseLinear([0.0, 10.0], [0.0, 1.0]), (-1.0, 11.0)),
    ],
    ids=repr,
)
def test_default_u_range_shows_the_kinks(block, expected):
    assert block.default_u_range() == pytest.approx(expected)


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
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


def test_piecewise_linear_template_and_adapted_breakpoints():
    p = PiecewiseLinear.template(knots=3)
    assert p.parameters == {"breakpoints": [-1.0, 0.0, 1.0], "values": [0.0, 0.0, 0.0]}
    assert p.adapted(np.array([-2.0, 1.0, 5.0])).parameters["breakpoints"] == [-2.0, 1.5, 5.0]
    for bad in (1, True, 2.5):
        with pytest.raises(ParameterError, match="knots must be a whole number >= 2"):
            PiecewiseLinear.template(knots=bad)


def test_piecewise_linear_template_on_given_breakpoints_stays_there():
    p = PiecewiseLinear.template(breakpoints=[-1, 0.5, 2])
    assert p.parameters == {"breakpoints": [-1.0, 0.5, 2.0], "values": [0.0, 0.0, 0.0]}
    # given breakpoints are not spread over the estimation input's range
    assert p.adapted(np.array([-5.0, 5.0])) is p
    with pytest.raises(ParameterError, match="breakpoints"):
        PiecewiseLinear.template(breakpoints=[1.0])


def test_piecewise_linear_vector_names():
    p = PiecewiseLinear([-1.0, 0.0, 1.0], [0.0, 1.0, 2.0])
    assert p.vector_names() == ["values_0", "values_1", "values_2"]
    assert p.vector_names({"values": "v"}) == ["v_0", "v_1", "v_2"]


def test_saturation_names_a_bad_lower_limit():
    with pytest.raises(ParameterError, match=r"^lower must be a real number, got 'low'$"):
        Saturation("low", 1.0)


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


# ------------------------------------------------------ degenerate blocks (issue 37)
def test_dead_zone_degeneracy_names_coinciding_and_far_edges_and_a_flat_side():
    # the loop blocks: edges 9e-6 apart, a lower edge at -292 313 with slope 6e-7
    (kink,) = DeadZone(-4.5e-6, 4.5e-6).degeneracy(-2.0, 3.0)
    assert "only 9e-06 apart, 1.8e-06 of the range" in kink and "[-2, 3]" in kink
    assert "a kink with two slopes" in kink and "use data that show a dead band" in kink
    (far,) = DeadZone(-292313.0, 0.3, 6e-7, 1.0).degeneracy(-2.0, 3.0)
    assert "lower = -292313 (slope_left = 6e-07 below it), 5.85e+04 widths outside" in far
    assert "no data reach it" in far and "use data that reach it" in far
    (flat,) = DeadZone(-0.5, 0.5, 1e-5, 1.0).degeneracy(-2.0, 3.0)
    assert "slope_left = 1e-05" in flat and "one-sided dead zone" in flat
    # a flat side the data never reach is not a note; a sound dead zone has none
    assert DeadZone(-2.5, 0.5, 1e-5, 1.0).degeneracy(-2.0, 3.0) == []
    assert DeadZone(-0.5, 0.5, 0.5, 2.0).degeneracy(-2.0, 3.0) == []
    assert DeadZone(-1e-6, 1e-6).degeneracy(0.0, 0.0) == []  # no range to judge on


def test_saturation_and_piecewise_linear_degeneracy():
    (relay,) = Saturation(-1.0, -1.0 + 1e-4, slope=1.0).degeneracy(-2.0, 2.0)
    assert "its knees" in relay and "a relay" in relay
    (never,) = Saturation(-1.0, 1e6).degeneracy(-2.0, 3.0)
    assert "upper knee upper / slope = 1e+06" in never and "widths outside" in never
    assert Saturation(-1.0, 1.0).degeneracy(-2.0, 3.0) == []
    (jump,) = PiecewiseLinear([-2.0, 0.0, 1e-6, 2.0], [0.0, 0.0, 1.0, 1.0]).degeneracy(-2, 2)
    assert "breakpoints_1 = 0 and breakpoints_2 = 1e-06 only 1e-06 apart" in jump
    (beyond,) = PiecewiseLinear([-2.0, 0.0, 50.0], [0.0, 1.0, 1.0]).degeneracy(-2.0, 2.0)
    assert "breakpoints_2 = 50, 12 widths outside" in beyond
    # flat segments are a shape (a saturation), not a degeneracy
    assert PiecewiseLinear([-2.0, -1.0, 1.0, 2.0], [-1.0, -1.0, 1.0, 1.0]).degeneracy(-2, 2) == []
