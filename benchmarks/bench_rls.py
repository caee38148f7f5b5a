"""RLS kernel speed: compiled kernel against a plain NumPy per-sample loop, same run.

Usage: ``python benchmarks/bench_rls.py [--samples N] [--write-docs]``

Both implement the same algorithm (A2 with lambda = 0.99, symmetric covariance update,
trace bound) on the same data with 10 parameters. The NumPy loop is timed on a prefix
of the record (it is ~100x slower) and reported per sample. Targets (2-core machine):
<= 150 ns/sample and >= 80x the NumPy loop.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _report import machine, write_section

from blockid import HierarchicalRLS, RecursiveLeastSquares
from blockid._kernels import rls as kernels


def numpy_loop(Phi, y, lam, mu, trace_max):
    """The same update, one sample at a time in NumPy (the reference a user would write)."""
    n = Phi.shape[1]
    theta = np.zeros(n)
    P = mu * np.eye(n)
    for t in range(Phi.shape[0]):
        phi = Phi[t]
        g = P @ phi
        denom = lam + phi @ g
        theta += g * (y[t] - phi @ theta) / denom
        P = (P - np.outer(g, g) / denom) / lam
        tr = np.trace(P)
        if tr > trace_max:
            P *= trace_max / tr
    return theta


def best_of(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=2_000_000)
    ap.add_argument("--numpy-samples", type=int, default=40_000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--write-docs", action="store_true")
    args = ap.parse_args()

    n, N = 10, args.samples
    rng = np.random.default_rng(0)
    Phi = rng.standard_normal((N, n))
    y = Phi @ rng.standard_normal(n) + 0.1 * rng.standard_normal(N)
    lam = np.full(N, 0.99)
    E = np.empty(N)
    mu, trace_max = 1e4, 1e4 * n

    def kernel():
        theta, P = np.zeros(n), mu * np.eye(n)
        assert kernels.rls_run(theta, P, Phi, y, lam, trace_max, E) == kernels.OK

    kernel()  # compile (or load from cache)
    t_kernel = best_of(kernel, args.repeats) / N

    est = RecursiveLeastSquares(forgetting=0.99, initial_covariance=mu)
    est.fit(Phi[:100], y[:100])
    t_class = best_of(lambda: est.fit(Phi, y), args.repeats) / N

    hier = HierarchicalRLS(groups=2, forgetting=0.99, initial_covariance=mu)
    hier.fit(Phi[:100], y[:100])
    t_hier = best_of(lambda: hier.fit(Phi, y), args.repeats) / N

    M = args.numpy_samples
    t_numpy = best_of(lambda: numpy_loop(Phi[:M], y[:M], 0.99, mu, trace_max), 2) / M

    # same answer on the common prefix
    theta_k, P_k = np.zeros(n), mu * np.eye(n)
    kernels.rls_run(theta_k, P_k, Phi[:M], y[:M], lam[:M], trace_max, E[:M])
    agree = float(np.max(np.abs(theta_k - numpy_loop(Phi[:M], y[:M], 0.99, mu, trace_max))))

    rows = [
        ("RLS kernel (`rls_run`)", t_kernel),
        ("`RecursiveLeastSquares.fit` (kernel + checks)", t_class),
        ("`HierarchicalRLS.fit`, two groups of 5", t_hier),
        ("NumPy per-sample loop, same algorithm", t_numpy),
    ]
    lines = [
        "## Recursive least squares (issue: core)",
        "",
        f"`python benchmarks/bench_rls.py` — 10 parameters, lambda = 0.99, {N:,} samples "
        f"(NumPy loop: first {M:,}), best of {args.repeats}. Machine: {machine()}.",
        "",
        "| implementation | ns/sample | speed-up over NumPy loop |",
        "|---|---:|---:|",
    ]
    for label, t in rows:
        lines.append(f"| {label} | {t * 1e9:,.0f} | {t_numpy / t:,.0f}x |")
    lines += [
        "",
        f"Kernel and NumPy loop agree to {agree:.1e} (max abs parameter difference) on the "
        "common prefix. Targets: <= 150 ns/sample and >= 80x the NumPy loop.",
    ]
    report = "\n".join(lines)
    print(report)
    if args.write_docs:
        write_section("bench-rls", report)


if __name__ == "__main__":
    main()
