"""The simulation kernels (blockid._kernels.simulation) against plain-Python twins: the
all-pole recursion of the linear block and the backlash with its parameter sensitivities."""

from __future__ import annotations

import numpy as np

from blockid._kernels.simulation import allpole_run, backlash_sensitivity
from blockid.blocks import Backlash


# ------------------------------------------------------------------ reference twins
def allpole_reference(a, F, S0, n0):
    S = S0.copy()
    for t in range(n0, S.shape[0]):
        S[t] = F[t] - sum(a[j - 1] * S[t - j] for j in range(1, len(a) + 1) if t - j >= 0)
    return S


def backlash_sensitivity_reference(u, theta, x0, dx0):
    """(A3) one sample at a time, carrying the derivative of the active branch."""
    mL, cL, mR, cR = theta
    x_prev, d_prev = x0, np.array(dx0, dtype=float)
    xs, ds = [], []
    for ut in u:
        zL, zR = x_prev / mL - cL, x_prev / mR + cR
        if ut <= zL:
            x, d = (mL * (ut + cL) if ut < zL else x_prev), np.array([ut + cL, mL, 0, 0])
        elif ut >= zR:
            x, d = (mR * (ut - cR) if ut > zR else x_prev), np.array([0, 0, ut - cR, -mR])
        else:
            x, d = x_prev, d_prev.copy()
        xs.append(x)
        ds.append(d)
        x_prev, d_prev = x, d
    return np.array(xs), np.array(ds, dtype=float)


def test_allpole_kernel_matches_reference(rng):
    a = np.array([-1.1, 0.55, -0.125])
    F = rng.standard_normal((200, 4))
    S0 = np.zeros((200, 4))
    S0[:3] = rng.standard_normal((3, 4))
    S = S0.copy()
    allpole_run(a, F, S, 3)
    np.testing.assert_allclose(S, allpole_reference(a, F, S0, 3), rtol=1e-13, atol=1e-13)
    S = np.zeros((200, 4))
    allpole_run(a, F, S, 0)  # from rest: samples before t = 0 count as zero
    np.testing.assert_allclose(
        S, allpole_reference(a, F, np.zeros((200, 4)), 0), rtol=1e-13, atol=1e-13
    )


def test_backlash_sensitivity_kernel_matches_reference_and_block(rng):
    u = 3 * np.sin(np.arange(400) / 15) + 0.3 * rng.standard_normal(400)
    theta = np.array([0.9, 0.4, 1.2, 0.3])
    dx0 = rng.standard_normal(4)
    x, dx = backlash_sensitivity(u, theta, 0.2, dx0)
    x_ref, dx_ref = backlash_sensitivity_reference(u, theta, 0.2, dx0)
    np.testing.assert_array_equal(x, Backlash(*theta).simulate(u, x0=0.2))
    np.testing.assert_allclose(x, x_ref, rtol=0, atol=1e-14)
    np.testing.assert_allclose(dx, dx_ref, rtol=0, atol=1e-14)
