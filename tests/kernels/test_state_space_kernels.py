"""The state-space kernels against slow references written from their equations."""

import numpy as np

from blockid._kernels.state_space import channel_response


def _channel_response_reference(A, B, C, D, chans, G, X0):
    """x_q(k+1) = A x_q(k) + B[:, chans[q]] G[k, q];  out[k, :, q] = C x_q(k) + D[:, chans[q]] G[k, q]."""
    N, p = G.shape
    out = np.zeros((N, C.shape[0], p))
    X = X0.copy()
    for q in range(p):
        x = X0[:, q].copy()
        for k in range(N):
            out[k, :, q] = C @ x + D[:, chans[q]] * G[k, q]
            x = A @ x + B[:, chans[q]] * G[k, q]
        X[:, q] = x
    return out, X


def test_channel_response_matches_the_equations_and_carries_its_state():
    rng = np.random.default_rng(0)
    nx, nu, ny, p, N = 3, 2, 2, 4, 150
    A = 0.4 * rng.standard_normal((nx, nx))
    B, C, D = (
        rng.standard_normal((nx, nu)),
        rng.standard_normal((ny, nx)),
        rng.standard_normal((ny, nu)),
    )
    chans = np.array([0, 1, 1, 0], dtype=np.int64)
    G = rng.standard_normal((N, p))
    X0 = rng.standard_normal((nx, p))
    want, X_end = _channel_response_reference(A, B, C, D, chans, G, X0)
    # in two pieces, the state carried between them
    X = X0.copy()
    first, second = np.zeros((60, ny, p)), np.zeros((N - 60, ny, p))
    channel_response(A, B, C, D, chans, G[:60].copy(), X, first)
    channel_response(A, B, C, D, chans, G[60:].copy(), X, second)
    np.testing.assert_allclose(np.concatenate((first, second)), want, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(X, X_end, rtol=1e-12, atol=1e-12)
