"""The key-term RLS kernel (B4, B5) against a slow, textbook twin written here."""

import numpy as np
import pytest

from blockid._kernels import key_term as k
from blockid._kernels.rls import OK

BLOCKS = {  # structure: (input block, output block)
    "hammerstein-wiener": (True, True),
    "hammerstein": (True, False),
    "wiener": (False, True),
    "arx": (False, False),
}


def key_term_reference(u, y, structure, theta0, na, nb, nk, r1, r2, lam, mu, trace_max):
    """Paper B's recursion, one sample at a time, in the textbook form of SPEC (B4, B5).

    Values before the record are 0; updates start at n0 = max(na, nk + nb - 1, 1).
    """
    has_in, has_out = BLOCKS[structure]
    N, n = len(u), len(theta0)
    theta = np.array(theta0, dtype=float)
    P = mu * np.eye(n)
    w, x = np.zeros(N), np.zeros(N)
    n0 = max(na, nk + nb - 1, 1)

    def past(sig, j):
        return sig[j] if j >= 0 else 0.0

    for t in range(N):
        # split theta = [f, p, b, a, q] (B4)
        pos = 0
        if has_in:
            f, p = theta[: r1 + 1], theta[r1 + 1 : 2 * r1 + 2]
            pos = 2 * r1 + 2
            b = np.concatenate(([1.0], theta[pos : pos + nb - 1]))
            pos += nb - 1
        else:
            b = theta[pos : pos + nb]
            pos += nb
        a = theta[pos : pos + na]
        # internal variables with the newest estimates (B5)
        if has_in:
            w[t] = sum(f[l] * u[t] ** l for l in range(r1 + 1)) + (u[t] < 0) * sum(
                p[l] * u[t] ** l for l in range(r1 + 1)
            )
        else:
            w[t] = u[t]
        if has_out:
            x[t] = sum(b[i] * past(w, t - nk - i) for i in range(nb)) - sum(
                a[j - 1] * past(x, t - j) for j in range(1, na + 1)
            )
        else:
            x[t] = y[t]
        if t < n0:
            continue
        phi = []
        if has_in:
            ud = u[t - nk]
            phi += [ud**l for l in range(r1 + 1)] + [ud**l * (ud < 0) for l in range(r1 + 1)]
            phi += [w[t - nk - i] for i in range(1, nb)]
        else:
            phi += [w[t - nk - i] for i in range(nb)]
        phi += [-x[t - j] for j in range(1, na + 1)]
        if has_out:
            phi += [x[t] ** m for m in range(2, r2 + 1)]
        phi = np.array(phi)[:, None]
        K = P @ phi / (lam[t] + (phi.T @ P @ phi).item())
        theta = theta + K[:, 0] * (y[t] - (phi.T @ theta).item())
        P = (P - K @ phi.T @ P) / lam[t]
        if lam[t] < 1 and np.trace(P) > trace_max:
            P *= trace_max / np.trace(P)
    return theta, P, w, x


def _n_params(structure, na, nb, r1, r2):
    has_in, has_out = BLOCKS[structure]
    return (2 * (r1 + 1) if has_in else 0) + nb - has_in + na + (r2 - 1 if has_out else 0)


def _run_kernel(u, y, structure, theta0, na, nb, nk, r1, r2, lam, mu, trace_max, x_limit=1e12):
    has_in, has_out = BLOCKS[structure]
    theta, P = np.array(theta0, dtype=float), mu * np.eye(len(theta0))
    n0 = max(na, nk + nb - 1, 1)
    orders = np.array([r1, nb, na, r2, nk, has_in, has_out, n0, 1], dtype=np.int64)
    w, x = np.empty(len(u)), np.empty(len(u))
    status = k.key_term_run(
        theta, P, u, y, lam, orders, np.array([trace_max, x_limit]), w, x, np.zeros((0, 0))
    )
    return status, theta, P, w, x


def _hw_data(rng, N):
    """A stable H-W plant simulated by hand, so that the internal signals are small."""
    u = rng.uniform(-1.0, 1.0, N)
    w = np.where(u >= 0, 0.3 * u + 0.1 * u**2, 0.15 * u - 0.05 * u**2)
    x = np.zeros(N)
    for t in range(N):
        x[t] = (w[t - 2] if t >= 2 else 0.0) + (0.5 * w[t - 3] if t >= 3 else 0.0)
        x[t] += 0.9 * x[t - 1] - 0.2 * x[t - 2] if t >= 2 else 0.0
    y = x + 0.2 * x**2 + 0.01 * rng.standard_normal(N)
    return u, y


@pytest.mark.parametrize("structure", list(BLOCKS))
@pytest.mark.parametrize("forget", [1.0, 0.97])
def test_kernel_matches_reference(rng, structure, forget):
    na, nb, nk, r1, r2, N = 2, 2, 2, 2, 3, 300
    u, y = _hw_data(rng, N)
    n = _n_params(structure, na, nb, r1, r2)
    theta0 = np.full(n, 0.01)
    lam = np.full(N, forget)
    lam[150:] = 1.0
    # P(0) = 100 I keeps P well conditioned, so the two round-off histories agree closely
    args = (u, y, structure, theta0, na, nb, nk, r1, r2, lam, 1e2, 1e2 * n)
    status, theta, P, w, x = _run_kernel(*args)
    assert status == (OK, k.REASON_OK)
    theta_ref, P_ref, w_ref, x_ref = key_term_reference(*args)
    assert np.max(np.abs(theta - theta_ref)) < 1e-10 * (1 + np.max(np.abs(theta_ref)))
    np.testing.assert_allclose(P, P_ref, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(w, w_ref, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(x, x_ref, rtol=1e-10, atol=1e-12)
    assert np.max(np.abs(theta - theta0)) > 1e-3  # the run really moved the estimate


def test_arx_structure_is_plain_rls_on_the_arx_regressor(rng):
    from blockid._kernels.rls import rls_run

    na, nb, nk, N = 2, 3, 1, 400
    u = rng.standard_normal(N)
    y = np.zeros(N)
    for t in range(3, N):
        y[t] = 1.2 * y[t - 1] - 0.5 * y[t - 2] + u[t - 1] + 0.3 * u[t - 2] - 0.2 * u[t - 3]
    y += 0.01 * rng.standard_normal(N)
    lam = np.full(N, 0.99)
    status, theta, P, w, x = _run_kernel(
        u, y, "arx", np.full(5, 0.01), na, nb, nk, 0, 1, lam, 1e6, 5e6
    )
    assert status == (OK, k.REASON_OK)
    n0 = 3
    Phi = np.column_stack(
        [u[n0 - nk - i : N - nk - i] for i in range(nb)]
        + [-y[n0 - j : N - j] for j in range(1, na + 1)]
    )
    theta_rls, P_rls = np.full(5, 0.01), 1e6 * np.eye(5)
    assert rls_run(theta_rls, P_rls, Phi, y[n0:], lam[n0:], 5e6, np.empty(N - n0)) == OK
    np.testing.assert_array_equal(theta, theta_rls)  # the same operations, bit for bit
    np.testing.assert_allclose(theta, [1.0, 0.3, -0.2, -1.2, 0.5], atol=0.02)


def test_kernel_records_every_stride_th_estimate(rng):
    u, y = _hw_data(rng, 200)
    n0, stride = 3, 7
    orders = np.array([0, 2, 2, 1, 2, 0, 0, n0, stride], dtype=np.int64)
    limits, lam = np.array([1e9, 1e9]), np.ones(200)

    def run(stop, hist):
        theta, P = np.full(4, 0.01), 1e4 * np.eye(4)
        w, x = np.empty(stop), np.empty(stop)
        k.key_term_run(theta, P, u[:stop], y[:stop], lam[:stop], orders, limits, w, x, hist)
        return theta

    hist = np.zeros(((200 - n0) // stride, 4))  # 28 rows: updates 7, 14, .., 196
    run(200, hist)
    for row in (0, 2, 27):
        updates = stride * (row + 1)
        np.testing.assert_array_equal(hist[row], run(n0 + updates, np.zeros((0, 4))))
    assert np.all(np.abs(np.diff(hist, axis=0)).max(axis=1) > 0)


def test_exploding_internal_signal_is_reported_with_its_sample(rng):
    u, y = _hw_data(rng, 100)
    n = _n_params("hammerstein-wiener", 2, 2, 2, 3)
    theta0 = np.full(n, 0.01)
    theta0[7:9] = [-2.5, 1.6]  # a_1, a_2: A(z) with poles of magnitude 1.26
    lam = np.ones(100)
    status, *_ = _run_kernel(
        u, y, "hammerstein-wiener", theta0, 2, 2, 2, 2, 3, lam, 1e-12, 1.0, x_limit=10.0
    )
    assert status[1] == k.REASON_EXPLODED
    assert 3 < status[0] < 100


def test_non_finite_step_is_reported_with_its_sample(rng):
    u, y = _hw_data(rng, 100)
    u[40] = 1e200  # u^3 overflows: the regressor of sample 40 + nk is not finite
    n = _n_params("hammerstein", 2, 2, 2, 3)
    status, *_ = _run_kernel(
        u, y, "hammerstein", np.full(n, 0.01), 2, 2, 2, 2, 3, np.ones(100), 1e4, 1e9
    )
    assert status == (42, k.REASON_STEP)


@pytest.mark.parametrize("structure", list(BLOCKS))
def test_a_pass_continued_from_carried_history_equals_one_pass(rng, structure):
    # orders[9] = start: samples before it are history (u, y, w, x as given)
    na, nb, nk, r1, r2, N, cut = 2, 2, 2, 2, 3, 300, 117
    u, y = _hw_data(rng, N)
    n = _n_params(structure, na, nb, r1, r2)
    has_in, has_out = BLOCKS[structure]
    lam = np.where(np.arange(N) < 150, 0.97, 1.0)
    limits, no_hist = np.array([1e2 * n, 1e12]), np.zeros((0, n))
    n0 = L = max(na, nk + nb - 1, 1)
    status, theta, P, w, x = _run_kernel(
        u, y, structure, np.full(n, 0.01), na, nb, nk, r1, r2, lam, 1e2, 1e2 * n
    )
    assert status == (OK, k.REASON_OK)
    th, Pc = np.full(n, 0.01), 1e2 * np.eye(n)
    orders = np.array([r1, nb, na, r2, nk, has_in, has_out, n0, 1], dtype=np.int64)
    w1, x1 = np.empty(cut), np.empty(cut)
    k.key_term_run(th, Pc, u[:cut], y[:cut], lam[:cut], orders, limits, w1, x1, no_hist)
    w2, x2 = np.empty(N - cut + L), np.empty(N - cut + L)
    w2[:L], x2[:L] = w1[-L:], x1[-L:]
    orders = np.append(orders, L)
    orders[7] = L  # the first update: at once
    err = np.full(N - cut + L, np.nan)
    args = (u[cut - L :], y[cut - L :], lam[cut - L :], orders, limits, w2, x2, no_hist, err)
    assert k.key_term_run(th, Pc, *args) == (OK, k.REASON_OK)
    np.testing.assert_array_equal(th, theta)
    np.testing.assert_array_equal(Pc, P)
    np.testing.assert_array_equal(x2[L:], x[cut:])
    assert np.all(np.isnan(err[:L])) and np.all(np.isfinite(err[L:]))


def test_key_term_step_without_forgetting_ignores_the_trace_bound():
    """lam = 1 exactly: no anti-wind-up, whatever trace_max says (SPEC A2), in the step
    the key-term kernels share (the RLS kernels' own test holds rls_run to the same)."""
    from blockid._kernels.key_term import output_step

    theta, P = np.zeros(2), 100.0 * np.eye(2)
    phi, g, out = np.array([1.0, 0.0]), np.zeros(2), np.zeros(2)
    hist, err = np.zeros((1, 2)), np.zeros(1)
    sizes = (0, 2, 2, 1, 0, 1)  # na, ia, iq, r2, n0, stride: no output part
    row = output_step(theta, P, phi, g, out, np.zeros(1), 1.0, 0, 1.0, sizes, False, 1e-3,
                      err, hist, 0)  # fmt: skip
    assert row == 1 and err[0] == 1.0
    np.testing.assert_allclose(P, [[100.0 / 101.0, 0.0], [0.0, 100.0]])
    np.testing.assert_allclose(theta, [100.0 / 101.0, 0.0])
