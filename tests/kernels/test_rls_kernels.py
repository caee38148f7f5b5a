"""Compiled RLS kernels against their slow NumPy twins (tests/reference.py)."""

import numpy as np
import pytest

from blockid._kernels import rls as k
from blockid._kernels.rls import rls_step

import reference


def _data(rng, N=400, n=5):
    Phi = rng.standard_normal((N, n))
    y = Phi @ rng.standard_normal(n) + 0.1 * rng.standard_normal(N)
    return Phi, y


@pytest.mark.parametrize("lam_value", [1.0, 0.97])
def test_rls_kernel_matches_reference(rng, lam_value):
    Phi, y = _data(rng)
    lam = np.full(len(Phi), lam_value)
    theta, P, E = np.zeros(5), 1e4 * np.eye(5), np.empty(len(y))
    assert k.rls_run(theta, P, Phi, y, lam, 5e4, E) == k.OK
    theta_ref, P_ref = reference.rls(Phi, y, lam, 1e4, trace_max=5e4)
    np.testing.assert_allclose(theta, theta_ref[:, 0], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(P, P_ref, rtol=1e-7, atol=1e-12)


def test_rls_kernel_applies_trace_bound_like_reference(rng):
    Phi, y = _data(rng, N=300)
    Phi[100:250] = 0.0  # no excitation: P grows by 1/lambda per sample until bounded
    lam = np.full(len(Phi), 0.9)
    theta, P, E = np.zeros(5), 10.0 * np.eye(5), np.empty(len(y))
    assert k.rls_run(theta, P, Phi, y, lam, 50.0, E) == k.OK
    theta_ref, P_ref = reference.rls(Phi, y, lam, 10.0, trace_max=50.0)
    np.testing.assert_allclose(theta, theta_ref[:, 0], rtol=1e-8)
    np.testing.assert_allclose(P, P_ref, rtol=1e-7)
    assert np.trace(P) <= 50.0 * (1 + 1e-12)


def test_aw_rls_kernel_matches_reference(rng):
    Phi, y = _data(rng)
    theta, P = np.full(5, 0.01), 1e5 * np.eye(5)
    E, W = np.empty(len(y)), np.empty(len(y))
    assert k.aw_rls_run(theta, P, Phi, y, 1.0, 0.1, W, E) == k.OK
    theta_ref, P_ref, w_ref = reference.aw_rls(Phi, y, 1.0, 0.1, 1e5)
    np.testing.assert_allclose(theta, theta_ref[:, 0], rtol=1e-8)
    np.testing.assert_allclose(P, P_ref, rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(W, w_ref, rtol=1e-6)


def test_hierarchical_kernel_matches_reference(rng):
    Phi, y = _data(rng, n=6)
    lam = np.full(len(Phi), 0.99)
    theta, P, E = np.zeros(6), 1e4 * np.eye(6), np.empty(len(y))
    bounds = np.array([0, 2, 6], dtype=np.int64)
    assert k.hierarchical_rls_run(theta, P, Phi, y, bounds, lam, 1e12, E) == k.OK
    theta_ref, (P1, P2) = reference.hierarchical_rls(Phi, y, [[0, 1], [2, 3, 4, 5]], lam, 1e4)
    np.testing.assert_allclose(theta, theta_ref[:, 0], rtol=1e-8)
    np.testing.assert_allclose(P[:2, :2], P1, rtol=1e-7, atol=1e-12)
    np.testing.assert_allclose(P[2:, 2:], P2, rtol=1e-7, atol=1e-12)
    assert np.all(P[:2, 2:] == 0.0)  # groups never couple


def test_kernel_reports_non_finite_step(rng):
    Phi, y = _data(rng, N=50)
    Phi[20, 0] = 1e300  # s overflows to inf at sample 20
    theta, P, E = np.zeros(5), 1e4 * np.eye(5), np.empty(50)
    assert k.rls_run(theta, P, Phi, y, np.ones(50), 1e9, E) == 20


def test_covariance_stays_exactly_symmetric_over_a_long_run(rng):
    n, N = 8, 300_000
    Phi = rng.standard_normal((N, n)) * np.logspace(-2, 2, n)
    y = Phi @ rng.standard_normal(n) + rng.standard_normal(N)
    theta, P, E = np.zeros(n), 1e8 * np.eye(n), np.empty(N)
    assert k.rls_run(theta, P, Phi, y, np.full(N, 0.99), 8e8, E) == k.OK
    assert np.array_equal(P, P.T)
    assert np.all(np.linalg.eigvalsh(P) > 0)


def test_textbook_update_loses_symmetry_where_ours_does_not(rng):
    """The reason for the symmetric form: the textbook update drifts."""
    n, N = 6, 20_000
    Phi = rng.standard_normal((N, n)) * np.logspace(-1, 1, n)
    y = Phi @ rng.standard_normal(n)
    P = 1e4 * np.eye(n)
    for t in range(N):
        phi = Phi[t]
        K = P @ phi / (0.99 + phi @ P @ phi)
        P = (P - np.outer(K, phi @ P)) / 0.99
    assert np.abs(P - P.T).max() > 0.0
    theta, Pk, E = np.zeros(n), 1e4 * np.eye(n), np.empty(N)
    k.rls_run(theta, Pk, Phi, y, np.full(N, 0.99), np.inf, E)
    assert np.array_equal(Pk, Pk.T)


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
def _step(P0, phi, rho0, s_coef=1.0, inv_lam=1.0, trace_max=1e9):
    n = len(phi)
    theta = np.zeros(n)
    P = np.array(P0, dtype=float)
    out = np.zeros(2)
    ok = rls_step(
        theta, P, np.asarray(phi, float), 1.0, np.zeros(n), rho0, s_coef, inv_lam, trace_max, out
    )
    return ok, theta, P


def test_rls_step_refuses_a_negative_finite_denominator():
    # d = rho0 + s = -1 + 0.25 < 0: the update would divide by a negative number.
    ok, _, _ = _step([[1.0]], [0.5], rho0=-1.0)
    assert not ok


def test_rls_step_accepts_a_positive_denominator_on_the_same_data():
    ok, theta, P = _step([[1.0]], [0.5], rho0=1.0)
    assert ok
    # theta = P phi e / (1 + 0.25) with e = 1; P = 1 - 0.25 / 1.25
    np.testing.assert_allclose(theta, [0.4])
    np.testing.assert_allclose(P, [[0.8]])


def test_rls_step_refuses_a_covariance_diagonal_of_exactly_zero():
    # rho0 = 0, P = 1, phi = 1: d = 1 and P(t) = 1 - 1 * 1 / 1 = 0 exactly.
    ok, _, P = _step([[1.0]], [1.0], rho0=0.0)
    assert P[0, 0] == 0.0
    assert not ok


def test_rls_run_without_forgetting_ignores_the_trace_bound():
    # lam = 1 exactly: no anti-wind-up, whatever trace_max says (SPEC A2).
    from blockid._kernels.rls import OK, rls_run

    theta = np.zeros(2)
    P = 100.0 * np.eye(2)
    E = np.zeros(1)
    status = rls_run(theta, P, np.array([[1.0, 0.0]]), np.array([1.0]), np.array([1.0]), 1e-3, E)
    assert status == OK
    # P(1) = P - P phi phi^T P / (1 + phi^T P phi)
    np.testing.assert_allclose(P, [[100.0 / 101.0, 0.0], [0.0, 100.0]])
    np.testing.assert_allclose(theta, [100.0 / 101.0, 0.0])
    assert E[0] == 1.0  # the a-priori error y - phi^T theta(0), not phi^T P phi = 100


def test_hierarchical_rls_without_forgetting_ignores_the_trace_bound():
    from blockid._kernels.rls import OK, hierarchical_rls_run

    theta = np.zeros(2)
    P = 100.0 * np.eye(2)
    E = np.zeros(1)
    Phi = np.array([[1.0, 0.0]])
    bounds = np.array([0, 1, 2])
    status = hierarchical_rls_run(theta, P, Phi, np.array([1.0]), bounds, np.array([1.0]), 1e-3, E)
    assert status == OK
    # group 1 sees phi = 1: P = 100 - 100^2 / 101; group 2 sees phi = 0: unchanged
    np.testing.assert_allclose(np.diag(P), [100.0 / 101.0, 100.0])
    assert E[0] == 1.0


def test_recorded_step_keeps_its_record_inside_the_history_and_fails_with_minus_one():
    """The bookkeeping after an RLS step (the key-term and backlash kernels): the error
    into ``err[k]``, ``theta`` into the next history row every ``stride``-th update, no
    row past the history's end, and -1 (the callers test the sign) on a failed step or a
    non-finite error."""
    theta, out = np.array([1.0, 2.0]), np.array([0.5, 0.0])
    hist, err = np.zeros((2, 2)), np.zeros(6)
    assert k.recorded_step(True, theta, out, err, hist, 1, 0, 2, 0) == 1  # (1 - 0 + 1) % 2
    assert hist[0].tolist() == [1.0, 2.0] and err[1] == 0.5
    assert k.recorded_step(True, theta, out, err, hist, 2, 0, 2, 1) == 1  # not its turn
    assert k.recorded_step(True, theta, out, err, hist, 3, 0, 2, 1) == 2
    assert k.recorded_step(True, theta, out, err, hist, 5, 0, 2, 2) == 2  # history full
    assert k.recorded_step(False, theta, out, err, hist, 4, 0, 2, 2) == -1
    out[0] = np.nan
    assert k.recorded_step(True, theta, out, err, hist, 4, 0, 2, 2) == -1
    assert err[4] == 0.0  # a failed step records nothing
