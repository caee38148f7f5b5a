"""The backlash kernels (blockid._kernels.backlash, SPEC (A3), (A4)): the one-sample step
and the run over a record; the block's tests (tests/blocks/test_backlash.py) check the
run against a plain-Python reference."""

from __future__ import annotations

import numpy as np

from blockid._kernels.backlash import backlash_run, backlash_step


def test_step_kernel_is_the_run_kernel():
    u = np.array([0.0, 2.0, 1.0, -3.0])
    theta = np.array([0.9, 0.8, 0.9, 0.85])
    x, f1, f2 = backlash_run(u, theta, 0.0)
    x_prev = 0.0
    for t in range(u.size):
        assert backlash_step(u[t], x_prev, *theta) == (x[t], f1[t], f2[t])
        x_prev = x[t]


def test_run_follows_the_dead_band_and_both_branches_by_hand():
    # paper A's block from x0 = 0: u = 0 sits in the band [-0.8, 0.85]; u = 2 drives
    # right, x = 0.9 (2 - 0.85); u = 1 is inside the new band [x/0.9 - 0.8, x/0.9 + 0.85]
    # = [0.35, 2.0]; u = -3 drives left, x = 0.9 (-3 + 0.8)
    x, f1, f2 = backlash_run(np.array([0.0, 2.0, 1.0, -3.0]), np.array([0.9, 0.8, 0.9, 0.85]), 0.0)
    np.testing.assert_allclose(x, [0.0, 1.035, 1.035, -1.98], rtol=0, atol=1e-14)
    np.testing.assert_array_equal(f1, [0.0, 0.0, 0.0, 1.0])
    np.testing.assert_array_equal(f2, [0.0, 1.0, 0.0, 0.0])
