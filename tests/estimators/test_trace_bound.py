"""The anti-wind-up trace bound of hierarchical RLS while it is active.

With forgetting ``lambda < 1`` and no excitation (regressor rows of zeros) ``P`` grows
like ``lambda^-t``; blockid scales it back to a bounded trace after every step, each
group's block to its share ``trace_max * n_g / n`` (``blockid._kernels.rls``). The
records below hold long unexcited stretches, so the bound binds for hundreds of
samples, and excitation resumes afterwards, so the bounded ``P`` decides the estimates
that follow. The reference is a textbook H-RLS (A10) in NumPy with the bound applied
as documented.
"""

from __future__ import annotations

import numpy as np
import pytest

from blockid.estimators import HierarchicalRLS

GROUPS = [[0], [1, 2]]
MU = 100.0
LAM = 0.95
TRUTH = np.array([1.0, -2.0, 0.5])


def hrls_reference(Phi, y, groups, lam, mu, trace_max):
    """H-RLS (A10): common error, one RLS step per group, each group's ``P`` scaled
    down to ``trace_max * n_g / n`` when its trace exceeds that (only for lam < 1).
    Returns the final estimate, the final block-diagonal P and the trace of every
    group after every sample."""
    N, n = Phi.shape
    theta = np.zeros(n)
    Ps = [mu * np.eye(len(g)) for g in groups]
    traces = np.empty((N, len(groups)))
    for t in range(N):
        e = y[t] - Phi[t] @ theta
        for gi, g in enumerate(groups):
            phi, Pg = Phi[t, g], Ps[gi]
            denom = lam + phi @ Pg @ phi
            theta[g] = theta[g] + Pg @ phi * e / denom
            Pg = (Pg - np.outer(Pg @ phi, phi @ Pg) / denom) / lam
            share = trace_max * len(g) / n
            if lam < 1.0 and np.trace(Pg) > share:
                Pg = Pg * (share / np.trace(Pg))
            Ps[gi] = Pg
            traces[t, gi] = np.trace(Pg)
    P = np.zeros((n, n))
    for g, Pg in zip(groups, Ps, strict=True):
        P[np.ix_(g, g)] = Pg
    return theta, P, traces


@pytest.fixture(scope="module")
def record():
    """1200 samples; rows 200..699 and 900..1099 carry no excitation (all zero), while
    the output keeps its noise."""
    rng = np.random.default_rng(0)
    Phi = rng.standard_normal((1200, 3))
    Phi[200:700] = 0.0
    Phi[900:1100] = 0.0
    y = Phi @ TRUTH + 0.1 * rng.standard_normal(1200)
    return Phi, y


def test_the_bound_binds_and_the_trace_never_exceeds_it(record):
    Phi, y = record
    trace_max = 3 * MU  # the default: n * initial_covariance
    est = HierarchicalRLS(groups=GROUPS, forgetting=LAM, initial_covariance=MU)
    traces, coefs = [], []
    for t in range(Phi.shape[0]):  # sample by sample, to see P after every step
        est.partial_fit(Phi[t : t + 1], y[t : t + 1])
        P = est.covariance_
        traces.append([P[0, 0], P[1, 1] + P[2, 2]])
        coefs.append(est.coef_.copy())
    traces, coefs = np.array(traces), np.array(coefs)
    shares = np.array([trace_max / 3, 2 * trace_max / 3])
    assert np.all(traces <= shares * (1 + 1e-12))
    # active: at the end of each unexcited stretch every group sits on its share
    for t in (699, 1099):
        np.testing.assert_allclose(traces[t], shares, rtol=1e-12)
    # without the bound the same stretch would have grown P by 0.95^-500 ~ 1e11
    free = HierarchicalRLS(
        groups=GROUPS, forgetting=LAM, initial_covariance=MU, max_covariance_trace=1e300
    ).fit(Phi[:700], y[:700])
    assert np.trace(free.covariance_) > 1e6 * trace_max
    # no excitation, no update: the estimate is frozen over the stretch, and finite
    assert np.all(coefs[200:700] == coefs[199])
    assert np.all(np.isfinite(coefs))
    # the reference gives the same trajectory of traces
    _, _, ref_traces = hrls_reference(Phi, y, GROUPS, LAM, MU, trace_max)
    np.testing.assert_allclose(traces, ref_traces, rtol=1e-10)


@pytest.mark.parametrize("trace_max", [None, 30.0])
def test_estimates_after_the_bound_was_active_equal_the_reference(record, trace_max):
    Phi, y = record
    est = HierarchicalRLS(
        groups=GROUPS, forgetting=LAM, initial_covariance=MU, max_covariance_trace=trace_max
    ).fit(Phi, y)
    bound = 3 * MU if trace_max is None else trace_max
    theta, P, _ = hrls_reference(Phi, y, GROUPS, LAM, MU, bound)
    np.testing.assert_allclose(est.coef_, theta, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(est.covariance_, P, rtol=1e-10, atol=1e-12 * bound)
    assert np.trace(est.covariance_) <= bound * (1 + 1e-12)
    # the estimate is the truth within the noise
    np.testing.assert_allclose(est.coef_, TRUTH, atol=0.1)


def test_chunked_and_whole_record_agree_while_the_bound_is_active(record):
    Phi, y = record
    whole = HierarchicalRLS(groups=GROUPS, forgetting=LAM, initial_covariance=MU).fit(Phi, y)
    chunked = HierarchicalRLS(groups=GROUPS, forgetting=LAM, initial_covariance=MU)
    for lo in range(0, 1200, 170):  # chunk edges inside the unexcited stretches
        chunked.partial_fit(Phi[lo : lo + 170], y[lo : lo + 170])
    assert np.array_equal(chunked.coef_, whole.coef_)
    assert np.array_equal(chunked.covariance_, whole.covariance_)
