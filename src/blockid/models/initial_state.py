"""The initial state of a chain model estimated from its first measured outputs.

Given ``n > max_lag`` measured outputs, :meth:`ChainModel.simulate
<blockid.models.block.ChainModel.simulate>` starts every linear block from estimated
first outputs instead of starting the last one from the measurement and the others at
rest:

.. math::

    \\hat x_0 = \\arg\\min_{x_0} \\sum_{t=0}^{n-1} \\bigl(y(t) - \\hat y(t; x_0)\\bigr)^2,
    \\qquad x_0 = \\bigl(x_i(0), \\dots, x_i(m_i - 1)\\bigr)_{i \\text{ linear}},
    \\quad m_i = \\text{max\\_lag}_i

where ``x_i`` is the output of linear block ``i`` and ``ŷ`` the chain's output. Given
its first ``m_i`` outputs and its input from ``t = 0``, a linear block's recursion from
``k = m_i`` reads no sample before 0
(:meth:`~blockid.blocks.linear.LinearBlock.simulate`), so ``x_0`` represents every
state the chain can be in when it starts, possibly with more unknowns than the state
has (over-parameterised: the trust region leaves directions the data do not see where
they start). Not estimated: a linear block that looks back ``n`` samples or more
starts at rest, and so does a dynamic block (backlash).

The solver starts from the start given ``max_lag`` outputs (the last linear block from
``N^{-1}(y)`` where the blocks after it are invertible, else at rest; every other
block at rest, i.e. its first outputs from rest), so the estimate never fits the ``n``
samples worse. The problem is solved on the first ``n`` samples only
(``scipy.optimize.least_squares``, trust-region reflective), so each evaluation costs
``O(n · unknowns)`` whatever the record's length, with the exact Jacobian: every
linear block's output is affine in its own start,

.. math::

    \\frac{\\partial x_i(k)}{\\partial x_i(j)} = \\delta_{kj} \\; (k < m_i), \\qquad
    A_i(z^{-1}) \\frac{\\partial x_i(k)}{\\partial \\theta} =
        z^{-n_{k,i}} B_i(z^{-1}) \\frac{\\partial w_i(k)}{\\partial \\theta} \\; (k \\ge m_i)

(:meth:`~blockid.blocks.linear.LinearBlock.forward` from that start), and a static
block multiplies by its slope (held at the range's end where it continues along its
tangent).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from blockid.models.block import ChainModel

__all__ = ["estimated_starts"]

#: Residual evaluations allowed to the estimate (each one simulation of ``n`` samples).
MAX_NFEV = 100


def _layout(model: ChainModel, n: int) -> list[tuple[int, int, int]]:
    """``(block index, first column, m_i)`` of every linear block whose start is
    estimated: those that look back fewer than ``n`` samples. In a chain that
    integrates, only the integrator's start (the output's level) is estimated: the
    start of a block before it, fitted to the window's noise and model error, would be
    summed by the integrator into a lasting offset or drift (an EMPS model started from
    20 measured samples drifted 0.2 m on a 0.25 m stroke; from 1, 4.4 mm)."""
    integrating = any(getattr(b, "integrates", 0) for b in model.blocks)
    out, col = [], 0
    for i, block in enumerate(model.blocks):
        if block.role != "linear" or block.max_lag >= n:
            continue
        if integrating and not getattr(block, "integrates", 0):
            continue
        out.append((i, col, block.max_lag))
        col += block.max_lag
    return out


def _walk(
    model: ChainModel,
    s: np.ndarray,
    starts: dict[int, np.ndarray],
    layout: list[tuple[int, int, int]],
) -> tuple[np.ndarray, np.ndarray]:
    """The chain's output on ``s`` (as :meth:`ChainModel._run_started`) and its
    derivative with respect to the stacked starts of ``layout``."""
    n = s.shape[0]
    p = sum(m for _, _, m in layout)
    S = np.zeros((n, p))  # d(signal)/d(x_0); the measured input does not depend on it
    own = {i: (col, m) for i, col, m in layout}
    for i, block in enumerate(model.blocks):
        if block.role == "static":
            S = model._slope_at(i, s)[:, None] * S
            s = model._apply_at(i, s)
        elif block.role == "linear":
            init = None  # a block that looks back n samples or more starts at rest
            if i in own:  # d x_i(k) / d x_i(j) = 1 for k = j < m_i
                col, m = own[i]
                S0 = np.zeros((m, p))
                S0[np.arange(m), col + np.arange(m)] = 1.0
                init = (starts[i], S0)
            no_parameters = np.full(block.to_vector().size, -1)
            _, S = block.forward(s, S, no_parameters, init)
            s = block.simulate(s, starts.get(i))
        else:  # a dynamic block: first in the chain, so S is still zero
            s = model._apply_at(i, s)
    return s, S


def estimated_starts(
    model: ChainModel, s: np.ndarray, y: np.ndarray, start: dict[int, np.ndarray]
) -> dict[int, np.ndarray] | None:
    """First outputs of every linear block fitted to the measured outputs ``y``.

    Parameters
    ----------
    model : ChainModel
    s : ndarray, shape (N,)
        The chain's input, relative to the input offset.
    y : ndarray, shape (n,)
        Measured outputs relative to the output offset, ``n > model.max_lag``; only the
        first ``min(n, N)`` are fitted.
    start : dict
        The start from ``max_lag`` outputs (``{last linear block: its first outputs}``,
        or empty when the blocks after it cannot be inverted): the solver's start.

    Returns
    -------
    dict or None
        ``{block index: first outputs}`` for :meth:`ChainModel._run_started`, or None
        when the estimate fails or is not finite (the caller keeps ``start``).
    """
    from scipy.optimize import least_squares  # imported when a start is estimated

    n = min(y.shape[0], s.shape[0])
    layout = _layout(model, n)
    if not layout:
        return None
    s, y = s[:n], y[:n]
    # the solver's start: the given start, every other block's first outputs from rest
    starts = dict(start)
    signal = s
    for i, block in enumerate(model.blocks):
        if block.role != "linear":
            signal = model._apply_at(i, signal)
            continue
        signal = block.simulate(signal, starts.get(i))
        if block.max_lag < n:
            starts.setdefault(i, signal[: block.max_lag])
    x0 = np.concatenate([starts[i] for i, _, _ in layout])

    def unpack(x: np.ndarray) -> dict[int, np.ndarray]:
        out = dict(starts)
        for i, col, m in layout:
            out[i] = x[col : col + m]
        return out

    def residuals(x: np.ndarray) -> np.ndarray:
        return y - _walk(model, s, unpack(x), layout)[0]

    def jacobian(x: np.ndarray) -> np.ndarray:
        return -_walk(model, s, unpack(x), layout)[1]

    with np.errstate(all="ignore"):
        try:
            if not np.all(np.isfinite(residuals(x0))):
                return None
            sol = least_squares(
                residuals,
                x0,
                jac=jacobian,
                method="trf",
                x_scale="jac",
                ftol=1e-12,
                xtol=1e-12,
                gtol=1e-12,
                max_nfev=MAX_NFEV,
            )
        except (ValueError, np.linalg.LinAlgError):
            return None
    if not (np.all(np.isfinite(sol.x)) and np.isfinite(sol.cost)):
        return None
    return unpack(sol.x)
