"""The key-term pass of several inputs (blockid._kernels.key_term_channels) against the
recursion written plainly with NumPy."""

import numpy as np
import pytest

from blockid._kernels.key_term_channels import OK, key_term_channels_run


# ---------------------------------------------------------------------- the kernel
def _reference_pass(theta, P, phi_u, y, lam, nb, na, r2, has_in, has_out, n0, delays, bias):
    """The recursion written plainly with NumPy (no compiled code)."""
    N, m, nf = phi_u.shape
    w, x = np.zeros((N, m)), np.zeros(N)
    b_first = 1 if has_in else 0
    ib = 1 + m * nf if has_in else int(bias)
    ia = ib + m * (nb - b_first)
    for k in range(N):
        for c in range(m):
            if has_in:
                w[k, c] = (theta[0] if c == 0 else 0.0) + theta[
                    1 + c * nf : 1 + (c + 1) * nf
                ] @ phi_u[k, c]
            else:
                w[k, c] = phi_u[k, c, 0]
        if has_out:
            xk = 0.0
            for c in range(m):
                for i in range(nb):
                    j = k - delays[c] - i
                    if j >= 0:
                        coef = 1.0 if (has_in and i == 0) else theta[ib + c * (nb - b_first)
                                                                     + i - b_first]  # fmt: skip
                        xk += coef * w[j, c]
            x[k] = xk - sum(theta[ia + j - 1] * x[k - j] for j in range(1, na + 1) if k >= j)
        else:
            x[k] = y[k]
        if k < n0:
            continue
        parts = [[1.0]] if bias else []
        if has_in:
            parts.append([1.0])
            parts += [phi_u[k - delays[c], c] for c in range(m)]
        for c in range(m):
            parts.append([w[k - delays[c] - i, c] for i in range(b_first, nb)])
        parts.append(-x[k - np.arange(1, na + 1)])
        if has_out:
            parts.append(x[k] ** np.arange(2, r2 + 1))
        phi = np.concatenate([np.asarray(p, dtype=float) for p in parts])
        g = P @ phi
        d = lam[k] + phi @ g
        theta += g * (y[k] - phi @ theta) / d
        P[:] = (P - np.outer(g, g) / d) / lam[k]
    return theta, P


@pytest.mark.parametrize(
    ("has_in", "has_out", "bias"), [(1, 1, 0), (1, 0, 0), (0, 1, 0), (0, 1, 1), (0, 0, 0)]
)
@pytest.mark.parametrize(
    ("delays", "nb", "na"),
    [((2, 1), 2, 2), ((0, 3), 1, 2), ((2, 2), 2, 0), ((1, 4, 0), 3, 1)],
    ids=["2,1", "0,3-nb1", "2,2-na0", "three-inputs"],
)
def test_the_compiled_pass_is_the_plain_recursion(has_in, has_out, bias, delays, nb, na):
    rng = np.random.default_rng(3)
    N, m, nf, r2 = 120, len(delays), 3, 3
    delays = np.array(delays, dtype=np.int64)
    phi_u = rng.uniform(-1, 1, (N, m, nf if has_in else 1))
    y = rng.standard_normal(N) * 0.3
    n = (1 + m * nf if has_in else bias) + m * (nb - has_in) + na + (r2 - 1 if has_out else 0)
    theta0, lam = rng.uniform(-0.05, 0.05, n), np.full(N, 0.99)
    n0 = int(max(na, delays.max() + nb - 1, 1))
    theta, P = theta0.copy(), 10.0 * np.eye(n)
    orders = np.array([nb, na, r2, has_in, has_out, n0, 1, 0, bias], dtype=np.int64)
    status, _ = key_term_channels_run(
        theta, P, phi_u, y, lam, orders, delays, np.array([np.inf, 1e9]),
        np.empty((N, m)), np.empty(N), np.zeros((0, n)), np.empty(N),
    )  # fmt: skip
    assert status == OK
    ref_theta, ref_P = _reference_pass(
        theta0.copy(), 10.0 * np.eye(n), phi_u, y, lam, nb, na, r2, has_in, has_out, n0,
        delays, bias,
    )  # fmt: skip
    np.testing.assert_allclose(theta, ref_theta, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(P, ref_P, rtol=1e-9, atol=1e-12)
