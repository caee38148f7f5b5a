import numpy as np
import pytest

from blockid import errors
from blockid.estimators import HierarchicalRLS, RecursiveLeastSquares

import reference


def test_matches_reference_with_arbitrary_groups(rng):
    Phi = rng.standard_normal((400, 5))
    y = Phi @ rng.standard_normal(5) + 0.1 * rng.standard_normal(400)
    groups = [[4, 1], [0, 3, 2]]
    h = HierarchicalRLS(groups=groups, forgetting=0.99, initial_covariance=1e4).fit(Phi, y)
    theta_ref, _ = reference.hierarchical_rls(Phi, y, groups, np.full(400, 0.99), 1e4)
    np.testing.assert_allclose(h.coef_, theta_ref[:, 0], rtol=1e-8)
    np.testing.assert_allclose(h.predict(Phi), Phi @ theta_ref[:, 0], rtol=1e-8)


def test_converges_to_full_rls_on_noise_free_data(rng):
    Phi = rng.standard_normal((5000, 8))
    Y = Phi @ rng.standard_normal((8, 2))
    h = HierarchicalRLS(groups=2, forgetting=0.99).fit(Phi, Y)
    full = RecursiveLeastSquares().fit(Phi, Y)
    np.testing.assert_allclose(h.coef_, full.coef_, atol=1e-10)


def test_without_forgetting_converges_only_like_one_over_t(rng):
    Phi = rng.standard_normal((20000, 8))
    Y = Phi @ rng.standard_normal((8, 1))
    errs = [
        np.abs(
            HierarchicalRLS().fit(Phi[:n], Y[:n]).coef_
            - RecursiveLeastSquares().fit(Phi[:n], Y[:n]).coef_
        ).max()
        for n in (2000, 20000)
    ]
    assert 1e-5 < errs[1] < errs[0] / 3


def test_chunks_equal_one_fit(rng):
    Phi = rng.standard_normal((300, 4))
    y = Phi @ [1.0, 2.0, 3.0, 4.0]
    whole = HierarchicalRLS(groups=[[0, 2], [1, 3]]).fit(Phi, y)
    chunked = HierarchicalRLS(groups=[[0, 2], [1, 3]])
    for s in range(0, 300, 7):
        chunked.partial_fit(Phi[s : s + 7], y[s : s + 7])
    assert np.array_equal(chunked.coef_, whole.coef_)


def test_bad_groups():
    with pytest.raises(errors.ParameterError, match="exactly once"):
        HierarchicalRLS(groups=[[0, 1], [1, 2]]).fit(np.ones((5, 3)), np.ones(5))
