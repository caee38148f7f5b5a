"""Kernel edge cases found by mutation testing (docs/testing.md): each test pins a
branch that the reference-twin tests reach only on its common side."""

import numpy as np

from blockid._kernels.rls import rls_step


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


def test_arx_simulate_uses_every_autoregressive_lag_from_the_first():
    """The compiled ARX simulation against a plain loop, two outputs with cross terms and
    two lags: dropping lag 1 of A (a loop starting at 2) changes every sample."""
    import numpy as np

    from blockid._kernels.arx import arx_simulate

    rng = np.random.default_rng(4)
    A = np.zeros((2, 2, 3))
    A[:, :, 1] = [[-0.5, 0.1], [0.05, -0.3]]
    A[:, :, 2] = [[0.1, 0.0], [0.0, 0.05]]
    B = np.zeros((2, 1, 3))
    B[:, 0, 1:] = [[1.0, 0.3], [0.4, -0.2]]
    u = rng.standard_normal((50, 1))
    y = np.zeros((50, 2))
    arx_simulate(A, B, u, y, 0)
    ref = np.zeros((50, 2))
    for t in range(50):
        for i in range(2):
            acc = 0.0
            for k in range(1, 3):
                if t - k >= 0:
                    acc -= A[i, 0, k] * ref[t - k, 0] + A[i, 1, k] * ref[t - k, 1]
                    acc += B[i, 0, k] * u[t - k, 0]
            ref[t, i] = acc
    np.testing.assert_allclose(y, ref, rtol=1e-13, atol=1e-13)
