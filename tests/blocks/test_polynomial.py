"""Tests of blockid.blocks.polynomial: Polynomial and TwoSegmentPolynomial (B1, B3)."""

import json

import numpy as np
import pytest

from blockid.blocks.base import BLOCK_TYPES, block_from_dict
from blockid.blocks.polynomial import Polynomial, TwoSegmentPolynomial
from blockid.errors import DataError, EstimationError, ParameterError


def two_segment_reference(f, p, u):
    """(B1) term by term, one sample at a time."""
    out = []
    for uk in u:
        h = 1.0 if uk < 0 else 0.0
        out.append(
            sum(fl * uk**l for l, fl in enumerate(f))
            + sum(pl * uk**l * h for l, pl in enumerate(p))
        )
    return np.array(out)


# ----------------------------------------------------------------------- Polynomial
def test_polynomial_values_with_and_without_constant():
    # 1 - 2u + 3u^2
    assert Polynomial([1.0, -2.0, 3.0])([-1.0, 0.0, 2.0]).tolist() == [6.0, 1.0, 9.0]
    # 2u - u^2 (B3 form, no constant)
    assert Polynomial([2.0, -1.0], constant=False)([-1.0, 0.0, 3.0]).tolist() == [-3.0, 0.0, -3.0]


def test_polynomial_keeps_input_shape():
    N = Polynomial([0.0, 1.0, 1.0])
    u = np.arange(6.0).reshape(2, 3)
    assert N(u).shape == (2, 3)
    np.testing.assert_array_equal(N(u), u + u**2)
    assert N(2.0).shape == ()
    assert float(N(2.0)) == 6.0


def test_polynomial_degree():
    assert Polynomial([1.0, 2.0, 3.0]).degree == 2
    assert Polynomial([1.0, 2.0, 3.0], constant=False).degree == 3


def test_polynomial_derivative_exact_and_against_finite_differences():
    # d/du (1 - 2u + 3u^2) = -2 + 6u ; d/du (2u - u^2) = 2 - 2u
    assert Polynomial([1.0, -2.0, 3.0]).derivative([0.0, 1.0]).tolist() == [-2.0, 4.0]
    assert Polynomial([2.0, -1.0], constant=False).derivative([0.0, 2.0]).tolist() == [2.0, -2.0]
    rng = np.random.default_rng(1)
    N = Polynomial(rng.normal(size=4), constant=False)
    u = rng.uniform(-2, 2, size=50)
    eps = 1e-6
    fd = (N(u + eps) - N(u - eps)) / (2 * eps)
    np.testing.assert_allclose(N.derivative(u), fd, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("constant", [True, False])
def test_polynomial_regressors_times_vector_is_output(constant):
    rng = np.random.default_rng(2)
    N = Polynomial(rng.normal(size=4), constant=constant)
    u = rng.uniform(-3, 3, size=(5, 8))
    phi = N.regressors(u)
    assert phi.shape == (40, 4)
    np.testing.assert_allclose(phi @ N.to_vector(), N(u).ravel(), rtol=1e-12, atol=1e-12)


def test_polynomial_regressors_are_powers():
    assert Polynomial([0.0, 0.0, 0.0]).regressors([2.0, -1.0]).tolist() == [
        [1.0, 2.0, 4.0],
        [1.0, -1.0, 1.0],
    ]
    assert Polynomial([0.0, 0.0], constant=False).regressors([3.0]).tolist() == [[3.0, 9.0]]


def test_polynomial_with_vector_returns_new_block():
    N = Polynomial([1.0, 2.0], constant=False)
    M = N.with_vector(np.array([3.0, -1.0]))
    assert M is not N
    assert M.parameters == {"coefficients": [3.0, -1.0], "constant": False}
    assert N.parameters == {"coefficients": [1.0, 2.0], "constant": False}
    v = N.to_vector()
    v[0] = 99.0  # a copy: the block must not change
    assert N.coefficients[0] == 1.0
    with pytest.raises(ParameterError, match=r"theta must have 2 entries"):
        N.with_vector([1.0, 2.0, 3.0])


@pytest.mark.parametrize(
    ("coefficients", "interval", "expected"),
    [
        ([0.0, 0.0, 1.0], (-1.0, 1.0), False),  # u^2 turns at 0
        ([0.0, 0.0, 1.0], (0.0, 1.0), True),
        ([0.0, 0.0, 1.0], (-2.0, -0.1), True),
        ([0.0, 0.0, 0.0, 1.0], (-np.inf, np.inf), True),  # u^3: derivative touches 0 only
        ([0.0, 1.0, 0.0, 1.0], (-np.inf, np.inf), True),  # u + u^3
        ([0.0, -1.0, 0.0, 1.0], (-np.inf, np.inf), False),  # u^3 - u
        ([0.0, -1.0, 0.0, 1.0], (-10.0, -0.6), True),  # turning points at +-0.577
        ([0.0, -1.0, 0.0, 1.0], (-10.0, -0.5), False),
        ([0.0, -1.0, 0.0, 1.0], (-0.5, 0.5), True),
        ([1.0, -3.0, 3.0, -1.0], (-np.inf, np.inf), True),  # (1 - u)^3: triple point at 1
        ([5.0], (-1.0, 1.0), False),  # constant
        ([2.0, 0.0, 0.0], (-np.inf, np.inf), False),  # constant with zero high powers
        ([0.0, 1.0, 0.0, 0.0], (-np.inf, np.inf), True),  # u with zero high powers
    ],
)
def test_is_monotone(coefficients, interval, expected):
    assert Polynomial(coefficients).is_monotone(*interval) is expected


def test_is_monotone_default_is_whole_line():
    assert Polynomial([1.0, 0.0, 1.0], constant=False).is_monotone()
    assert not Polynomial([0.0, 1.0], constant=False).is_monotone()


@pytest.mark.parametrize(
    "coefficients",
    [
        [0.0, 1.0, 0.4, 0.2],  # increasing, odd degree
        [0.3, -2.0, 0.1, -0.5],  # decreasing
        [1.0, 2.0],  # linear
        [0.0, 1.0, 0.0, 0.0, 0.0, 0.1],  # degree 5
    ],
)
def test_inverse_on_whole_line_recovers_input(coefficients):
    rng = np.random.default_rng(3)
    N = Polynomial(coefficients)
    u = rng.uniform(-4, 4, size=(20, 10))
    u_hat = N.inverse(N(u))
    assert u_hat.shape == u.shape
    np.testing.assert_allclose(u_hat, u, rtol=0, atol=1e-9)


def test_inverse_on_range_of_non_monotone_polynomial():
    square = Polynomial([0.0, 1.0], constant=False)  # u^2
    assert square.inverse([4.0, 0.25], u_range=(0.0, 3.0)).tolist() == pytest.approx([2.0, 0.5])
    assert square.inverse([4.0, 0.25], u_range=(-3.0, 0.0)).tolist() == pytest.approx([-2.0, -0.5])
    # B3-style output block, monotone only for x below its turning point at 10/3
    q = Polynomial([1.0, 0.3, -0.1], constant=False)
    x = np.linspace(-1.0, 3.0, 41)
    np.testing.assert_allclose(q.inverse(q(x), u_range=(-1.0, 3.0)), x, atol=1e-10)


def test_inverse_through_flat_point():
    cube = Polynomial([0.0, 0.0, 0.0, 1.0])
    np.testing.assert_allclose(cube.inverse([8.0, -27.0, 0.0, 1e-9]), [2.0, -3.0, 0.0, 1e-3])
    # (u - 1)^3 + 1 is flat at u = 1: u is ill-conditioned there, but N(u) must match w
    shifted = Polynomial([0.0, 3.0, -3.0, 1.0])
    w = np.linspace(-7.0, 9.0, 33)
    np.testing.assert_allclose(shifted(shifted.inverse(w)), w, atol=1e-12)


def test_inverse_starting_guess_nan_and_clip():
    N = Polynomial([0.0, 1.0, 0.0, 1.0])  # u + u^3
    u = np.array([-1.5, 0.5, 2.0])
    np.testing.assert_allclose(N.inverse(N(u), u0=u + 0.3), u, atol=1e-10)
    np.testing.assert_allclose(N.inverse(N(u), u0=0.0), u, atol=1e-10)
    out = N.inverse([np.nan, 2.0])
    assert np.isnan(out[0]) and out[1] == pytest.approx(1.0)
    clipped = N.inverse([-100.0, 2.0, 100.0], u_range=(-1.0, 1.5), clip=True)
    np.testing.assert_allclose(clipped, [-1.0, 1.0, 1.5], atol=1e-10)


def test_inverse_errors():
    N = Polynomial([0.0, 1.0, 0.0, 1.0])
    with pytest.raises(ParameterError, match=r"outside \[-2.0, 2.0\].*widen u_range or pass clip"):
        N.inverse([3.0], u_range=(-1.0, 1.0))
    wavy = Polynomial([0.0, -1.0, 0.0, 1.0])
    with pytest.raises(ParameterError, match="not strictly monotone on the whole real line"):
        wavy.inverse([0.0])
    with pytest.raises(ParameterError, match=r"not strictly monotone on u_range=\(-1.0, 1.0\)"):
        wavy.inverse([0.0], u_range=(-1.0, 1.0))
    with pytest.raises(ParameterError, match="u_range must have low < high"):
        N.inverse([0.0], u_range=(1.0, -1.0))
    with pytest.raises(ParameterError, match="u_range must hold finite numbers"):
        N.inverse([0.0], u_range=(0.0, np.inf))
    with pytest.raises(ParameterError, match="u_range must be a pair"):
        N.inverse([0.0], u_range=(0.0, 1.0, 2.0))
    with pytest.raises(ParameterError, match="u0 must be a number or broadcast"):
        N.inverse([0.0, 1.0], u0=[0.0, 1.0, 2.0])
    with pytest.raises(ParameterError, match="max_iter must be >= 1"):
        N.inverse([0.0], max_iter=0)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"coefficients": []}, "coefficients needs at least 1 value"),
        ({"coefficients": [1.0, np.nan]}, "coefficients must contain finite numbers"),
        ({"coefficients": ["a", "b"]}, "coefficients must be a list of real numbers"),
        ({"coefficients": [[1.0, 2.0]]}, "coefficients must be a flat list"),
        ({"coefficients": [1.0], "constant": "yes"}, "constant must be True or False"),
    ],
)
def test_polynomial_bad_parameters(kwargs, message):
    with pytest.raises(ParameterError, match=message):
        Polynomial(**kwargs)


def test_non_numeric_input_is_a_data_error():
    with pytest.raises(DataError, match="block input u must be numeric"):
        Polynomial([1.0])("abc")


# ------------------------------------------------------------- TwoSegmentPolynomial
def test_two_segment_values():
    N = TwoSegmentPolynomial(f=[1.0, 2.0, 3.0], p=[0.5, -1.0, 2.0])
    # u = 2: f only -> 1 + 4 + 12; u = -1: f + p -> (1 - 2 + 3) + (0.5 + 1 + 2); h(0) = 0
    assert N([2.0, -1.0, 0.0]).tolist() == [17.0, 5.5, 1.0]
    rng = np.random.default_rng(4)
    f, p = rng.normal(size=4), rng.normal(size=4)
    u = rng.uniform(-2, 2, size=30)
    np.testing.assert_allclose(TwoSegmentPolynomial(f, p)(u), two_segment_reference(f, p, u))


def test_two_segment_from_segments_pads_and_gives_g():
    N = TwoSegmentPolynomial.from_segments(positive=[0.0, 2.0, 1.0], negative=[0.1, 0.5])
    assert N.parameters == {"f": [0.0, 2.0, 1.0], "p": [0.1, -1.5, -1.0]}
    assert N.order == 2
    np.testing.assert_allclose(N.g, [0.1, 0.5, 0.0])
    u = np.array([-2.0, -0.5, 0.5, 2.0])
    np.testing.assert_allclose(N(u), np.where(u < 0, 0.1 + 0.5 * u, 2 * u + u**2))


def test_two_segment_regressors_follow_b4_ordering():
    N = TwoSegmentPolynomial([0.0, 0.0], [0.0, 0.0])
    assert N.regressors([-2.0, 3.0, 0.0]).tolist() == [
        [1.0, -2.0, 1.0, -2.0],
        [1.0, 3.0, 0.0, 0.0],
        [1.0, 0.0, 0.0, 0.0],
    ]
    rng = np.random.default_rng(5)
    M = TwoSegmentPolynomial(rng.normal(size=4), rng.normal(size=4))
    u = rng.uniform(-3, 3, size=(4, 25))
    assert M.regressors(u).shape == (100, 8)
    np.testing.assert_allclose(M.regressors(u) @ M.to_vector(), M(u).ravel(), rtol=1e-12)


def test_two_segment_vector_round_trip():
    N = TwoSegmentPolynomial([1.0, 2.0], [3.0, 4.0])
    assert N.to_vector().tolist() == [1.0, 2.0, 3.0, 4.0]
    M = N.with_vector([5.0, 6.0, 7.0, 8.0])
    assert M.parameters == {"f": [5.0, 6.0], "p": [7.0, 8.0]}
    with pytest.raises(ParameterError, match=r"theta must have 4 entries \(f then p\)"):
        N.with_vector([1.0, 2.0])


def test_two_segment_bad_parameters():
    with pytest.raises(ParameterError, match="f and p must have the same length"):
        TwoSegmentPolynomial([1.0, 2.0], [1.0])
    with pytest.raises(ParameterError, match="p needs at least 1 value"):
        TwoSegmentPolynomial([1.0], [])
    with pytest.raises(ParameterError, match="f must contain finite numbers"):
        TwoSegmentPolynomial([np.inf], [0.0])


# ------------------------------------------------------------------ serialisation
@pytest.mark.parametrize(
    "block",
    [
        Polynomial([0.5, -1.0, 2.0]),
        Polynomial([1.0, 0.2, -0.03], constant=False),
        TwoSegmentPolynomial([0.0, 1.2, 0.1], [0.05, -0.4, 0.02]),
    ],
    ids=repr,
)
def test_dict_and_json_round_trip(block):
    data = block.to_dict()
    assert BLOCK_TYPES[data["kind"]] is type(block)
    again = block_from_dict(json.loads(json.dumps(data)))
    assert type(again) is type(block)
    assert again.parameters == block.parameters
    u = np.linspace(-2, 2, 9)
    np.testing.assert_array_equal(again(u), block(u))
    assert type(block).from_dict(data).parameters == block.parameters


def test_kinds():
    assert Polynomial.kind == "polynomial"
    assert TwoSegmentPolynomial.kind == "two-segment-polynomial"
    assert Polynomial.linear_in_parameters and TwoSegmentPolynomial.linear_in_parameters


@pytest.mark.parametrize("tiny", [1e-308, 5e-324, -1e-300, 1e-20])
def test_negligible_leading_coefficient_puts_turning_points_at_infinity(tiny):
    """A leading coefficient far below the others (found by the round-trip property
    test: q_3 = 1e-308 made the root finder overflow to NaN) acts where its roots are,
    beyond any input: the monotone branch is the lower-degree one's."""
    block = Polynomial([1.0, 0.3, tiny], constant=False)
    assert block.monotone_branch() == pytest.approx((-1 / 0.6, np.inf))
    w = np.array([-0.1, 0.5, 1.0])
    np.testing.assert_allclose(block(block.invert(w)), w, rtol=1e-12)


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
def test_inverse_on_a_decreasing_block():
    block = Polynomial([1.0, -2.0])  # w = 1 - 2 u, decreasing
    u = block.inverse_on(np.array([1.0, 0.0, -1.0, 5.0]), (-1.0, 1.0))
    np.testing.assert_allclose(u, [0.0, 0.5, 1.0, -1.0], atol=1e-12)  # 5 lies beyond w(-1) = 3


def test_polynomial_is_monotone_names_its_range_argument():
    with pytest.raises(
        ParameterError, match=r"^\(u_min, u_max\) must have low < high, got \(1\.0, 0\.0\)$"
    ):
        Polynomial([0.0, 1.0]).is_monotone(1.0, 0.0)


def test_two_segment_from_segments_names_the_bad_segment():
    with pytest.raises(ParameterError, match=r"^positive needs at least 1 value\(s\), got 0$"):
        TwoSegmentPolynomial.from_segments([], [1.0])


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
