"""The AW-RLS backlash kernel (A6–A8) against a slow twin written from SPEC's equations."""

import numpy as np
import pytest

from blockid._kernels import backlash_awrls as k
from blockid._kernels.backlash import backlash_step
from blockid._kernels.rls import OK


def h(s):
    """Switching function of (A4): 1 for s <= 0."""
    return 1.0 if s <= 0 else 0.0


def aw_rls_backlash_reference(u, v, theta0, na, nb, nk, eps1, eps2, mu):
    """(A6)–(A8) one sample at a time; internal variables by (A7) literally.

    theta = [mL, mL cL, mR, mR cR, b_1..b_{nb-1}, a_1..a_na]; before the record the
    backlash rests mid-dead-band at u(0); updates start at n0 = max(na, nk + nb - 1, 1).
    """
    N, n = len(u), len(theta0)
    theta = np.array(theta0, dtype=float)
    P = mu * np.eye(n)
    x, f1, f2 = np.zeros(N), np.zeros(N), np.zeros(N)
    n0 = max(na, nk + nb - 1, 1)

    x_rest = 0.5 * ((theta[0] * u[0] + theta[1]) + (theta[2] * u[0] - theta[3]))

    def past(sig, j):
        return sig[j] if j >= 0 else x_rest

    for t in range(N):
        if t >= n0:
            d = t - nk
            phi = [u[d] * f1[d], f1[d], u[d] * f2[d], -f2[d]]  # (A6)
            phi += [past(x, d - i) for i in range(1, nb)]
            phi += [-v[t - j] for j in range(1, na + 1)]
            phi = np.array(phi)[:, None]
            target = v[t] - past(x, d - 1) * (1 - f1[d]) * (1 - f2[d])
            s = (phi.T @ P @ phi).item()  # (A8)
            weight = eps1 * s + eps2
            e = target - (phi.T @ theta).item()
            theta = theta + (P @ phi)[:, 0] * e / (weight + s)
            P = P - P @ phi @ phi.T @ P / (weight + s)
        mL, mLcL, mR, mRcR = theta[:4]  # (A7), newest estimates
        xp = past(x, t - 1)
        f1[t] = h((mL * u[t] + mLcL - xp) / mL)
        f2[t] = h((xp - mR * u[t] + mRcR) / mR)
        x[t] = (
            mL * u[t] * f1[t]
            + mLcL * f1[t]
            + mR * u[t] * f2[t]
            - mRcR * f2[t]
            + xp * (1 - f1[t]) * (1 - f2[t])
        )  # (A4)
    return theta, P, x, f1, f2


def _plant(rng, N, nb=1, nk=1, noise=0.0):
    """Backlash (mL = 0.9, cL = 0.8, mR = 1.1, cR = 0.5) then a second-order block."""
    u = rng.uniform(-5.0, 5.0, N)
    x = np.empty(N)
    prev = 0.0
    for t in range(N):
        prev = x[t] = backlash_step(u[t], prev, 0.9, 0.8, 1.1, 0.5)[0]
    b = [1.0, 0.4][:nb]
    v = np.zeros(N)
    for t in range(N):
        v[t] = sum(bi * x[t - nk - i] for i, bi in enumerate(b) if t - nk - i >= 0)
        v[t] += (1.0 * v[t - 1] if t >= 1 else 0.0) - (0.17 * v[t - 2] if t >= 2 else 0.0)
    return u, v + noise * rng.standard_normal(N)


def _run(u, v, theta0, na, nb, nk, eps1, eps2, mu, x_limit=1e12):
    theta, P = np.array(theta0, dtype=float), mu * np.eye(len(theta0))
    orders = np.array([nb, na, nk, max(na, nk + nb - 1, 1), 1], dtype=np.int64)
    x, f1, f2 = np.empty(len(u)), np.empty(len(u)), np.empty(len(u))
    status = k.backlash_aw_rls_run(
        theta, P, u, v, orders, np.array([eps1, eps2, x_limit]), x, f1, f2, np.zeros((0, 0))
    )
    return status, theta, P, x, f1, f2


@pytest.mark.parametrize(("nb", "nk"), [(1, 1), (2, 1), (2, 3)])
def test_kernel_matches_reference(rng, nb, nk):
    u, v = _plant(rng, 400, nb=nb, nk=nk, noise=0.01)
    theta0 = np.full(4 + nb - 1 + 2, 0.01)
    args = (u, v, theta0, 2, nb, nk, 1.0, 0.1, 1e5)
    status, theta, P, x, f1, f2 = _run(*args)
    assert status == (OK, k.REASON_OK)
    theta_ref, P_ref, x_ref, f1_ref, f2_ref = aw_rls_backlash_reference(*args)
    assert np.max(np.abs(theta - theta_ref)) < 1e-10 * (1 + np.max(np.abs(theta_ref)))
    np.testing.assert_allclose(P, P_ref, rtol=1e-6, atol=1e-9)
    np.testing.assert_array_equal(f1, f1_ref)
    np.testing.assert_array_equal(f2, f2_ref)
    np.testing.assert_allclose(x, x_ref, rtol=1e-10, atol=1e-12)
    assert np.max(np.abs(theta - theta0)) > 0.1  # the run really moved the estimate


def test_zero_slope_estimate_is_reported(rng):
    u, v = _plant(rng, 50)
    theta0 = np.array([0.0, 0.01, 0.01, 0.01, 0.01, 0.01])
    status, *_ = _run(u, v, theta0, 2, 1, 1, 1.0, 0.1, 1e5)
    assert status == (0, k.REASON_ZERO_SLOPE)


def test_exploding_internal_signal_is_reported(rng):
    u, v = _plant(rng, 50)
    status, *_ = _run(u, v, np.full(6, 0.01), 2, 1, 1, 1.0, 0.1, 1e5, x_limit=1.0)
    assert status[1] == k.REASON_EXPLODED
    assert 0 < status[0] < 50


def test_non_finite_step_is_reported(rng):
    u, v = _plant(rng, 50)
    v = v.copy()
    v[30] = np.inf  # the a-priori error of sample 30 is not finite
    status, *_ = _run(u, v, np.full(6, 0.01), 2, 1, 1, 1.0, 0.1, 1e5)
    assert status == (30, k.REASON_STEP)


def test_a_pass_continued_from_carried_history_equals_one_pass(rng):
    # orders[5] = start: samples before it are history (u, v, x, f1, f2 as given)
    na, nb, nk, N, cut = 2, 2, 3, 400, 211
    u, v = _plant(rng, N, nb=nb, nk=nk, noise=0.01)
    theta0 = np.full(4 + nb - 1 + na, 0.01)
    status, theta, P, x, f1, f2 = _run(u, v, theta0, na, nb, nk, 1.0, 0.1, 1e5)
    assert status == (OK, k.REASON_OK)
    n0 = max(na, nk + nb - 1, 1)
    L = max(n0, nk + 1)
    params, no_hist = np.array([1.0, 0.1, 1e12]), np.zeros((0, 0))
    th, Pc = theta0.copy(), 1e5 * np.eye(theta0.size)
    first = [np.empty(cut) for _ in range(3)]
    orders = np.array([nb, na, nk, n0, 1], dtype=np.int64)
    k.backlash_aw_rls_run(th, Pc, u[:cut], v[:cut], orders, params, *first, no_hist)
    rest = [np.empty(N - cut + L) for _ in range(3)]
    for carried, signal in zip(rest, first, strict=True):
        carried[:L] = signal[-L:]
    orders = np.array([nb, na, nk, L, 1, L], dtype=np.int64)
    err = np.full(N - cut + L, np.nan)
    status = k.backlash_aw_rls_run(
        th, Pc, u[cut - L :], v[cut - L :], orders, params, *rest, no_hist, err
    )
    assert status == (OK, k.REASON_OK)
    np.testing.assert_array_equal(th, theta)
    np.testing.assert_array_equal(Pc, P)
    np.testing.assert_array_equal(rest[0][L:], x[cut:])
    assert np.all(np.isfinite(err[L:])) and np.all(np.isnan(err[:L]))
    assert k.backlash_rest(theta0, u[0]) == 0.5 * (0.01 * u[0] + 0.01 + 0.01 * u[0] - 0.01)
