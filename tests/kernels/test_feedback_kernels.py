"""The feedback (Lur'e) kernels against slow, textbook twins written here."""

import numpy as np
import pytest

from blockid._kernels.feedback import (
    feedback_sensitivity,
    feedback_sensitivity_given,
    feedback_simulate,
    feedback_simulate_table,
    polynomial_value,
    table_value,
)


def _past(sig, t):
    return sig[t] if t >= 0 else 0.0


def simulate_reference(a, b, c, nk, u, y_init, n0):
    """``A y = z^-nk B (u - N(y))`` one sample at a time; ``N(y) = sum_m c_m y^m``."""
    N = len(u)
    y = np.zeros(N)
    y[:n0] = y_init[:n0]

    def n_of(x):
        return sum(c[m - 1] * x**m for m in range(1, len(c) + 1))

    for t in range(n0, N):
        y[t] = -sum(a[j - 1] * _past(y, t - j) for j in range(1, len(a) + 1)) + sum(
            b[i] * (_past(u, t - nk - i) - (n_of(y[t - nk - i]) if t - nk - i >= 0 else 0.0))
            for i in range(len(b))
        )
    return y


def sensitivity_reference(a, b, c, nk, u, y_init, n0):
    """∂y/∂[a, b, c] by differentiating the recursion term by term (NumPy, per sample)."""
    y = simulate_reference(a, b, c, nk, u, y_init, n0)
    na, nb, r = len(a), len(b), len(c)
    N = len(u)
    powers = np.column_stack([y**m for m in range(1, r + 1)])  # y^m
    slope = np.array([sum(m * c[m - 1] * x ** (m - 1) for m in range(1, r + 1)) for x in y])
    v = u - powers @ np.asarray(c)
    S = np.zeros((N, na + nb + r))
    for t in range(n0, N):
        row = np.zeros(na + nb + r)
        for j in range(1, na + 1):
            if t - j >= 0:
                row -= a[j - 1] * S[t - j]
                row[j - 1] -= y[t - j]
        for i in range(nb):
            d = t - nk - i
            if d >= 0:
                dv = -slope[d] * S[d]
                dv[na + nb :] -= powers[d]
                row += b[i] * dv
                row[na + i] += v[d]
        S[t] = row
    return y, S


CASES = [  # a, b, c, nk
    ([-1.6, 0.8], [0.2], [0.0, 0.0, 2.0], 1),
    ([-1.2, 0.5, -0.05], [0.3, 0.1], [0.0, -0.2, 1.5, 0.2], 2),
    ([-0.5], [1.0, -0.3, 0.2], [0.0, 0.2, 0.5], 1),
    ([], [0.4], [0.1, 0.3], 1),
]


@pytest.mark.parametrize("a, b, c, nk", CASES)
@pytest.mark.parametrize("n0", [0, 3])
def test_simulation_matches_the_reference(a, b, c, nk, n0):
    rng = np.random.default_rng(1)
    u = rng.uniform(-0.5, 0.5, 300)
    y_init = rng.uniform(-0.5, 0.5, 300)
    expected = simulate_reference(a, b, c, nk, u, y_init, n0)
    assert np.all(np.isfinite(expected))
    y = np.zeros(300)
    y[:n0] = y_init[:n0]
    v = feedback_simulate(np.array(a, float), np.array(b, float), np.array(c, float), nk, u, y, n0)
    np.testing.assert_allclose(y, expected, rtol=0, atol=1e-12)
    N = sum(ci * y ** (m + 1) for m, ci in enumerate(c))
    np.testing.assert_allclose(v, u - N, rtol=0, atol=1e-12)


@pytest.mark.parametrize("a, b, c, nk", CASES)
@pytest.mark.parametrize("n0", [0, 3])
def test_sensitivities_match_the_reference(a, b, c, nk, n0):
    rng = np.random.default_rng(2)
    u = rng.uniform(-0.5, 0.5, 200)
    y_init = rng.uniform(-0.5, 0.5, 200)
    y_ref, S_ref = sensitivity_reference(a, b, c, nk, u, y_init, n0)
    y = np.zeros(200)
    y[:n0] = y_init[:n0]
    arrays = [np.array(x, float) for x in (a, b, c)]
    _, dy = feedback_sensitivity(*arrays, nk, u, y, n0)
    np.testing.assert_allclose(y, y_ref, rtol=0, atol=1e-12)
    np.testing.assert_allclose(dy.T, S_ref, rtol=0, atol=1e-12)


@pytest.mark.parametrize("a, b, c, nk", CASES)
def test_sensitivities_match_finite_differences(a, b, c, nk):
    rng = np.random.default_rng(3)
    u = rng.uniform(-0.5, 0.5, 150)
    y_init = rng.uniform(-0.5, 0.5, 150)
    n0 = 2
    theta = np.array(a + b + c, float)
    na, nb = len(a), len(b)

    def split(th):
        return th[:na].copy(), th[na : na + nb].copy(), th[na + nb :].copy()

    def run(th):
        y = np.zeros(150)
        y[:n0] = y_init[:n0]
        feedback_simulate(*split(th), nk, u, y, n0)
        return y

    y = np.zeros(150)
    y[:n0] = y_init[:n0]
    _, dy = feedback_sensitivity(*split(theta), nk, u, y, n0)
    h = 1e-6
    for p in range(theta.size):
        step = np.zeros_like(theta)
        step[p] = h
        fd = (run(theta + step) - run(theta - step)) / (2 * h)
        np.testing.assert_allclose(dy[p], fd, rtol=1e-6, atol=1e-8)


def test_polynomial_value_and_slope():
    c = np.array([0.5, -0.4, 1.5, 0.2])
    for y in (-1.3, 0.0, 0.7):
        value, slope = polynomial_value(c, y)
        assert value == pytest.approx(sum(ci * y ** (m + 1) for m, ci in enumerate(c)), abs=1e-14)
        assert slope == pytest.approx(sum((m + 1) * ci * y**m for m, ci in enumerate(c)), abs=1e-14)


# ----------------------------------------------------------- other blocks in feedback
def _table_reference(xs, ys, left, right, x):
    """Piecewise-linear through (xs, ys), straight beyond the ends (NumPy's interp)."""
    if x < xs[0]:
        return ys[0] + left * (x - xs[0])
    if x > xs[-1]:
        return ys[-1] + right * (x - xs[-1])
    return float(np.interp(x, xs, ys))


TABLES = [  # xs, ys, left slope, right slope
    ([-0.3, 0.4], [0.0, 0.0], 0.8, 0.6),  # dead zone
    ([-0.5, 0.4], [-0.35, 0.28], 0.0, 0.0),  # saturation
    ([-1.0, 0.0, 0.5, 1.0], [-0.6, 0.0, 0.1, 0.6], 0.6, 1.0),
    ([0.2, 0.2], [0.0, 0.0], 1.5, 0.5),  # a dead zone of zero width
]


@pytest.mark.parametrize("xs, ys, left, right", TABLES)
def test_table_value_is_the_piecewise_linear_map(xs, ys, left, right):
    xs, ys = np.array(xs), np.array(ys)
    for x in np.concatenate((np.linspace(-3, 3, 601), xs, xs + 1e-12, xs - 1e-12)):
        assert table_value(xs, ys, left, right, x) == pytest.approx(
            _table_reference(xs, ys, left, right, x), abs=1e-12
        )


@pytest.mark.parametrize("xs, ys, left, right", TABLES)
def test_a_nan_argument_gives_nan_not_a_division_by_zero(xs, ys, left, right):
    """An exploding run (NaN) through a dead zone of zero width raised
    ZeroDivisionError from the kernel (seen in identify on WH 2009)."""
    assert np.isnan(table_value(np.array(xs), np.array(ys), left, right, np.nan))


@pytest.mark.parametrize("xs, ys, left, right", TABLES)
@pytest.mark.parametrize("n0", [0, 2])
def test_table_loop_matches_the_textbook_recursion(xs, ys, left, right, n0):
    xs, ys = np.array(xs), np.array(ys)
    a, b, nk = np.array([-1.5, 0.7]), np.array([0.5, 0.2]), 1
    u = np.random.default_rng(3).normal(0.0, 1.0, 300)
    y0 = np.array([0.3, -0.2])
    y = np.zeros(300)
    y[:n0] = y0[:n0]
    v = feedback_simulate_table(a, b, xs, ys, left, right, nk, u, y, n0)
    ref = np.zeros(300)
    ref[:n0] = y0[:n0]
    vr = np.zeros(300)
    for t in range(300):
        if t >= n0:
            ref[t] = -sum(a[j - 1] * _past(ref, t - j) for j in (1, 2)) + sum(
                b[i] * _past(vr, t - nk - i) for i in (0, 1)
            )
        vr[t] = u[t] - _table_reference(xs, ys, left, right, ref[t])
    np.testing.assert_allclose(y, ref, rtol=0, atol=1e-12)
    np.testing.assert_allclose(v, vr, rtol=0, atol=1e-12)


@pytest.mark.parametrize("a, b, c, nk", CASES[:3])
@pytest.mark.parametrize("n0", [0, 3])
def test_given_sensitivities_of_a_polynomial_equal_the_polynomial_kernel(a, b, c, nk, n0):
    """The block-agnostic recursion, fed N'(y) and dN/dc = y^m, is the polynomial one."""
    a, b, c = np.array(a, float), np.array(b, float), np.array(c, float)
    u = np.random.default_rng(5).normal(0.0, 0.4, 250)
    y = np.zeros(250)
    y[:n0] = 0.1 * np.arange(1, n0 + 1)
    y_poly = y.copy()
    v, dy_poly = feedback_sensitivity(a, b, c, nk, u, y_poly, n0)
    slope = np.array([polynomial_value(c, x)[1] for x in y_poly])
    forcing = np.ascontiguousarray(np.vstack([y_poly**m for m in range(1, c.size + 1)]))
    dy = feedback_sensitivity_given(a, b, nk, y_poly, v, slope, forcing, n0)
    np.testing.assert_allclose(dy, dy_poly, rtol=1e-12, atol=1e-12)
