import numpy as np
import pytest

from blockid import errors
from blockid.estimators import BatchLeastSquares


def test_matches_lstsq_and_covariance(rng):
    Phi = rng.standard_normal((300, 4)) * [1, 100, 1e-3, 1]
    y = Phi @ [1.0, 0.02, 300.0, -1.0] + 0.01 * rng.standard_normal(300)
    est = BatchLeastSquares().fit(Phi, y)
    np.testing.assert_allclose(est.coef_, np.linalg.lstsq(Phi, y, rcond=None)[0], rtol=1e-10)
    np.testing.assert_allclose(est.covariance_, np.linalg.inv(Phi.T @ Phi), rtol=1e-8)
    resid = y - Phi @ est.coef_
    np.testing.assert_allclose(est.noise_variance_[0], resid @ resid / 296, rtol=1e-8)


def test_chunks_equal_one_fit_and_weights(rng):
    Phi = rng.standard_normal((500, 3))
    Y = Phi @ rng.standard_normal((3, 2)) + 0.1 * rng.standard_normal((500, 2))
    w = rng.uniform(0.1, 2.0, 500)
    whole = BatchLeastSquares().fit(Phi, Y, sample_weight=w)
    chunked = BatchLeastSquares()
    for s in range(0, 500, 2):  # chunks smaller than the number of columns
        chunked.partial_fit(Phi[s : s + 2], Y[s : s + 2], sample_weight=w[s : s + 2])
    np.testing.assert_allclose(chunked.coef_, whole.coef_, rtol=1e-10)
    W = np.sqrt(w)[:, None]
    exact = np.linalg.lstsq(W * Phi, W * Y, rcond=None)[0].T
    np.testing.assert_allclose(whole.coef_, exact, rtol=1e-10)


def test_rank_deficiency_is_reported(rng):
    Phi = rng.standard_normal((100, 3))
    Phi[:, 2] = 2 * Phi[:, 0] - Phi[:, 1]
    with pytest.raises(
        errors.EstimationError, match=r"rank deficient: regressor column\(s\) \[2\]"
    ):
        BatchLeastSquares().fit(Phi, Phi[:, 0])


def test_fit_chunks_with_normalised_columns_matches_least_squares_and_scales_the_rank_test():
    """normalise solves on unit-RMS columns in one pass (the scales are read off R): the
    estimate and its covariance are those of least squares on the data as given, a
    column of tiny but real scale is not mistaken for an unexcited one, and a truly
    dependent column still is."""
    import numpy as np
    import pytest

    from blockid.errors import EstimationError
    from blockid.estimators import BatchLeastSquares

    rng = np.random.default_rng(7)
    u = rng.uniform(-1, 1, 600)
    Phi = np.column_stack([np.ones(600), 1e-9 * u, u**2, 1e6 * u**3])
    theta = np.array([0.5, 2e9, -1.0, 3e-7])
    y = Phi @ theta + 1e-3 * rng.standard_normal(600)
    chunks = [(Phi[i : i + 97], y[i : i + 97]) for i in range(0, 600, 97)]
    est = BatchLeastSquares().fit_chunks(chunks, normalise=True)
    d = 1.0 / np.sqrt(np.mean(Phi**2, axis=0))  # least squares on scaled columns
    exact = np.linalg.lstsq(Phi * d, y, rcond=None)[0] * d
    np.testing.assert_allclose(est.coef_, exact, rtol=1e-8)
    np.testing.assert_allclose(est.coef_, theta, rtol=1e-2)
    scaled_cov = np.linalg.inv((Phi * d).T @ (Phi * d))
    np.testing.assert_allclose(est.covariance_, scaled_cov * np.outer(d, d), rtol=1e-6)
    with pytest.raises(EstimationError, match="rank deficient"):
        BatchLeastSquares().fit_chunks(chunks)  # unscaled: the 1e-9 column looks dead
    dependent = np.column_stack([Phi, 2.0 * Phi[:, 2]])
    with pytest.raises(EstimationError, match=r"column\(s\) \[4\]"):
        BatchLeastSquares().fit_chunks([(dependent, y)], normalise=True)
    # an all-zero column (an input that never moved) is named, not divided by zero
    dead = np.column_stack([Phi[:, :2], np.zeros(600), Phi[:, 2:]])
    with pytest.raises(EstimationError, match=r"column\(s\) \[2\] \(constant"):
        BatchLeastSquares().fit_chunks(
            [(dead[:300], y[:300]), (dead[300:], y[300:])], normalise=True
        )
