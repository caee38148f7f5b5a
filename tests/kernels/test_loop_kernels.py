"""The loop kernels (blockid._kernels.loop): the blocks they compile against their
formulas, the free run against the equations written as a plain loop, and the forward
sensitivities against central differences of that run."""

import numpy as np
import pytest

from blockid._kernels.loop import (
    KIND_POLYNOMIAL,
    KIND_TABLE,
    KIND_TWO_SEGMENT,
    block_value,
    loop_sensitivity,
    loop_simulate,
)

POLY = np.array([3.0, 0.5, -1.0, 2.0])  # 0.5 - s + 2 s^2


@pytest.mark.parametrize(("s", "value"), [(0.25, 0.375), (-0.5, 1.5), (1.0, 1.5)])
def test_a_polynomial_inside_its_range_is_its_formula(s, value):
    assert block_value(KIND_POLYNOMIAL, POLY, -1.0, 1.0, s) == pytest.approx(value, abs=1e-15)


def test_a_polynomial_continues_along_its_tangent_beyond_the_range():
    # at hi = 1: value 1.5, slope -1 + 4 = 3; at lo = -1: value 3.5, slope -5
    assert block_value(KIND_POLYNOMIAL, POLY, -1.0, 1.0, 3.0) == pytest.approx(1.5 + 3 * 2.0)
    assert block_value(KIND_POLYNOMIAL, POLY, -1.0, 1.0, -2.0) == pytest.approx(3.5 + 5.0)
    assert block_value(KIND_POLYNOMIAL, POLY, -np.inf, np.inf, 3.0) == pytest.approx(15.5)
    assert np.isnan(block_value(KIND_POLYNOMIAL, POLY, -1.0, 1.0, np.nan))


def test_a_two_segment_polynomial_adds_its_second_part_below_zero():
    c = np.array([2.0, 0.0, 1.0, 0.5, 2.0])  # f(s) = s, p(s) = 0.5 + 2 s
    assert block_value(KIND_TWO_SEGMENT, c, -np.inf, np.inf, 0.5) == pytest.approx(0.5)
    assert block_value(KIND_TWO_SEGMENT, c, -np.inf, np.inf, -0.5) == pytest.approx(-1.0)
    # below lo = -1 the tangent of f + p: value -1 + 0.5 - 2 = -2.5, slope 3
    assert block_value(KIND_TWO_SEGMENT, c, -1.0, 1.0, -2.0) == pytest.approx(-5.5)


def test_a_table_is_the_piecewise_linear_map_with_its_end_slopes():
    # breakpoints -1, 0, 1 with values -0.5, 0, 2; slopes 0.1 to the left, 0 to the right
    c = np.array([3.0, -1.0, 0.0, 1.0, -0.5, 0.0, 2.0, 0.1, 0.0])
    values = [block_value(KIND_TABLE, c, -np.inf, np.inf, s) for s in (-3, -0.5, 0.5, 4)]
    np.testing.assert_allclose(values, [-0.7, -0.25, 1.0, 2.0], rtol=0, atol=1e-15)


# a 2-state core, one input, one polynomial loop block, one output
A = np.array([[0.6, 0.2], [-0.1, 0.5]])
B = np.array([[1.0, 0.3], [0.2, -0.4]])  # [input, loop]
C = np.array([[1.0, -0.5]])
D = np.array([[0.1, 0.2]])
E = np.array([0.05, -0.02])
CP = np.array([[0.4, 0.3]])
DP = np.array([[0.5]])
LOOP = np.array([3.0, 0.0, 1.0, -0.3])  # q = p - 0.3 p^2


def _simulate(A, B, C, D, e, Cp, Dp, coef, x0, w):
    N = w.shape[0]
    X, P, Q, z = np.empty((N, 2)), np.empty((N, 1)), np.empty((N, 1)), np.empty((N, 1))
    x = x0.copy()
    loop_simulate(A, B, C, D, e, Cp, Dp, np.array([KIND_POLYNOMIAL]), coef,
                  np.array([0, coef.size]), np.array([-np.inf]), np.array([np.inf]),
                  w, x, X, P, Q, z)  # fmt: skip
    return X, P, Q, z, x


def test_the_free_run_is_the_equations_as_a_plain_loop():
    w = np.random.default_rng(0).uniform(-1, 1, (60, 1))
    X, P, Q, z, last = _simulate(A, B, C, D, E, CP, DP, LOOP, np.array([0.1, -0.2]), w)
    x = np.array([0.1, -0.2])
    for k in range(60):
        p = CP @ x + DP @ w[k]
        q = p - 0.3 * p**2
        v = np.concatenate([w[k], q])
        for got, want in zip((X[k], P[k], Q[k], z[k]), (x, p, q, C @ x + D @ v), strict=True):
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-13)
        x = A @ x + B @ v + E
    np.testing.assert_allclose(last, x, rtol=0, atol=1e-13)


def test_the_sensitivities_are_the_central_differences_of_the_run():
    w = np.random.default_rng(1).uniform(-1, 1, (40, 1))
    x0 = np.array([0.1, -0.2])
    mats = [A, B, C, D, E, CP, DP, LOOP[1:]]
    sizes = [m.size for m in mats]
    starts = np.cumsum(sizes)  # where B, C, D, e, C_p, D_p, the loop block, x(0) start
    offsets = np.insert(starts, 6, starts[6]).astype(np.int64)  # no input blocks
    theta = np.concatenate([m.ravel() for m in mats] + [x0])
    n = theta.size

    def run(th):
        parts = np.split(th, starts)
        shaped = [p.reshape(m.shape) for p, m in zip(parts[:-1], mats, strict=True)]
        coef = np.concatenate([[3.0], shaped[-1]])
        return _simulate(*shaped[:-1], coef, parts[-1], w)

    X, P, Q, _, _ = run(theta)
    p = P[:, 0]
    S = np.zeros((2, n))
    S[:, -2:] = np.eye(2)  # x(0)'s own columns
    J = np.empty((40, n))
    loop_sensitivity(
        A, B, C, D, CP, DP, X, np.column_stack([w, Q]), (1.0 - 0.6 * p)[:, None],
        np.empty((40, 0)), np.empty(0, dtype=np.int64),
        np.column_stack([np.ones(40), p, p**2]), np.zeros(3, dtype=np.int64),
        offsets, S, J,
    )  # fmt: skip
    h = 1e-6
    numeric = np.column_stack(
        [(run(theta + h * d)[3] - run(theta - h * d)[3])[:, 0] / (2 * h) for d in np.eye(n)]
    )
    np.testing.assert_allclose(J, numeric, rtol=0, atol=1e-7)
