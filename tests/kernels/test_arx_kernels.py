"""The compiled ARX simulation (blockid._kernels.arx) against a plain loop."""


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
