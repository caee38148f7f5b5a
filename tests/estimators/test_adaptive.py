import numpy as np

from blockid.estimators import AdaptiveWeightedRLS

import reference


def test_aw_rls_is_weighted_least_squares_with_its_weights(rng):
    Phi = rng.standard_normal((600, 4))
    y = Phi @ [0.9, 0.72, 0.9, 0.765] + 0.05 * rng.standard_normal(600)
    aw = AdaptiveWeightedRLS(eps1=1.0, eps2=0.1, initial_covariance=1e5).fit(Phi, y)
    exact = reference.weighted_least_squares(
        Phi, y, 1.0 / aw.weights_, prior_weight=1e-5, theta0=0.01
    )
    np.testing.assert_allclose(aw.coef_, exact[:, 0], rtol=1e-7)
    # the eps1 term vanishes as P shrinks: late weights tend to eps2
    assert aw.weights_[0] > 1e4 and abs(aw.weights_[-1] - 0.1) < 1e-3


def test_aw_rls_chunks_equal_one_fit(rng):
    Phi = rng.standard_normal((300, 3))
    y = Phi @ [1.0, 2.0, 3.0]
    whole = AdaptiveWeightedRLS().fit(Phi, y)
    chunked = AdaptiveWeightedRLS()
    for s in range(0, 300, 41):
        chunked.partial_fit(Phi[s : s + 41], y[s : s + 41])
    assert np.array_equal(chunked.coef_, whole.coef_)
