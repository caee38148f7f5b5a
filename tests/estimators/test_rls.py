"""RecursiveLeastSquares against exact (weighted) least squares, chunking and long runs."""

import numpy as np
import pytest

from blockid import errors
from blockid.estimators import BatchLeastSquares, ForgettingSchedule, RecursiveLeastSquares

import reference


def _problem(rng, N=1500, n=6, noise=0.1, m=1):
    Phi = rng.standard_normal((N, n))
    theta = rng.uniform(-2, 2, size=(n, m))
    Y = Phi @ theta + noise * rng.standard_normal((N, m))
    return Phi, (Y[:, 0] if m == 1 else Y), theta


def test_default_rls_equals_batch_least_squares(rng):
    Phi, y, _ = _problem(rng)
    rls = RecursiveLeastSquares(forgetting=1).fit(Phi, y)
    batch = BatchLeastSquares().fit(Phi, y)
    np.testing.assert_allclose(rls.coef_, batch.coef_, rtol=1e-8)
    np.testing.assert_allclose(rls.coef_, np.linalg.lstsq(Phi, y, rcond=None)[0], rtol=1e-8)


def test_forgetting_gives_exponentially_weighted_least_squares(rng):
    Phi, y, _ = _problem(rng, N=800)
    lam, mu = 0.97, 1e3
    rls = RecursiveLeastSquares(forgetting=lam, initial_covariance=mu).fit(Phi, y)
    N = len(y)
    w = lam ** np.arange(N - 1, -1, -1.0)
    exact = reference.weighted_least_squares(Phi, y, w, prior_weight=lam**N / mu)
    np.testing.assert_allclose(rls.coef_, exact[:, 0], rtol=1e-8)


def test_forgetting_schedule_of_paper_b(rng):
    Phi, y, _ = _problem(rng, N=600)
    mu = 1e2
    rls = RecursiveLeastSquares(forgetting="0.98:200,1", initial_covariance=mu).fit(Phi, y)
    lam = ForgettingSchedule.parse("0.98:200,1").factors(0, len(y))
    # weight of sample t is the product of the factors applied after it
    after = np.concatenate([np.cumprod(lam[::-1])[::-1][1:], [1.0]])
    exact = reference.weighted_least_squares(Phi, y, after, prior_weight=np.prod(lam) / mu)
    np.testing.assert_allclose(rls.coef_, exact[:, 0], rtol=1e-8)


@pytest.mark.parametrize("m", [1, 2])
def test_chunks_equal_one_fit(rng, m):
    Phi, y, _ = _problem(rng, m=m)
    whole = RecursiveLeastSquares(forgetting="0.95:300,0.999").fit(Phi, y)
    chunked = RecursiveLeastSquares(forgetting="0.95:300,0.999")
    for start in range(0, len(Phi), 97):
        chunked.partial_fit(Phi[start : start + 97], y[start : start + 97])
    assert np.array_equal(chunked.coef_, whole.coef_)
    assert np.array_equal(chunked.covariance_, whole.covariance_)
    assert chunked.n_samples_seen_ == len(Phi)
    assert whole.coef_.shape == ((6,) if m == 1 else (2, 6))


def test_sample_by_sample_equals_one_fit(rng):
    Phi, y, _ = _problem(rng, N=200)
    whole = RecursiveLeastSquares(forgetting=0.99).fit(Phi, y)
    single = RecursiveLeastSquares(forgetting=0.99)
    for t in range(len(y)):
        single.partial_fit(Phi[t : t + 1], y[t : t + 1])
    assert np.array_equal(single.coef_, whole.coef_)


def test_ten_million_samples_with_dead_stretches_stay_bounded():
    """lambda = 0.98, 10^7 samples, 80 % of them without excitation (anti-wind-up)."""
    rng = np.random.default_rng(7)
    theta = np.array([0.5, -1.0, 2.0])
    rls = RecursiveLeastSquares(forgetting=0.98, initial_covariance=1e4)
    trace_max = 3 * 1e4
    max_trace = 0.0
    chunk = 500_000
    for c in range(20):
        Phi = rng.standard_normal((chunk, 3))
        # long stretches (hundreds of thousands of samples) of zero excitation
        if c % 5 != 0:
            Phi[:] = 0.0
        y = Phi @ theta + 0.01 * rng.standard_normal(chunk)
        rls.partial_fit(Phi, y)
        max_trace = max(max_trace, np.trace(rls.covariance_))
        assert np.all(np.isfinite(rls.coef_)) and np.all(np.isfinite(rls.covariance_))
    assert rls.n_samples_seen_ == 10_000_000
    assert max_trace <= trace_max * (1 + 1e-12)
    np.testing.assert_allclose(rls.coef_, theta, atol=0.01)


def test_divergence_is_reported_and_state_kept(rng):
    Phi, y, _ = _problem(rng, N=100)
    rls = RecursiveLeastSquares().fit(Phi[:50], y[:50])
    before = rls.coef_.copy()
    bad = Phi[50:].copy()
    bad[10] = 1e300
    with pytest.raises(errors.EstimationError, match="diverged at sample 60"):
        rls.partial_fit(bad, y[50:])
    assert np.array_equal(rls.coef_, before)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"forgetting": 1.5}, r"forgetting factor 1.5 is outside \(0, 1\]"),
        ({"forgetting": "0.9:abc"}, "cannot read forgetting"),
        ({"initial_covariance": -1.0}, "initial_covariance=-1.0 is outside"),
        ({"initial_parameters": [1.0, 2.0]}, r"initial_parameters has shape \(2,\)"),
    ],
)
def test_bad_parameters_are_named(rng, kwargs, match):
    Phi, y, _ = _problem(rng, N=20)
    with pytest.raises(errors.BlockidError, match=match):
        RecursiveLeastSquares(**kwargs).fit(Phi, y)


def test_bad_data_is_named(rng):
    Phi, y, _ = _problem(rng, N=20)
    Phi[7, 2] = np.nan
    with pytest.raises(errors.DataError, match="NaN or inf.*row 7"):
        RecursiveLeastSquares().fit(Phi, y)
    with pytest.raises(errors.DataError, match="20 rows but y has 19"):
        RecursiveLeastSquares().fit(np.ones((20, 2)), np.ones(19))
    rls = RecursiveLeastSquares().fit(np.ones((20, 2)), np.ones(20))
    with pytest.raises(errors.DataError, match="call fit\\(\\) to start over"):
        rls.partial_fit(np.ones((5, 3)), np.ones(5))
