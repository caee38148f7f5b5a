"""Derivatives of a chain's free-run simulation with respect to its parameters.

:meth:`ChainModel.simulate_with_sensitivities` is :func:`chain_sensitivities`: the
sensitivities travel down the chain with the signal, each block contributing its own
``forward``. :func:`sensitivity_chunks` gives the same values piece by piece for long
records. The fitters (:mod:`blockid.fitting.simulation_error`) and the standard errors
(:mod:`blockid.evaluation.uncertainty`) both read them from the model.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

import numpy as np

from blockid.config import get_config
from blockid.errors import ParameterError

if TYPE_CHECKING:  # the chain imports this module; a type, not an import circle
    from blockid.models.block import ChainModel

__all__ = ["chain_sensitivities", "sensitivity_chunks"]


def chain_sensitivities(
    model: ChainModel, u: Any, y_initial: Any = None
) -> tuple[np.ndarray, np.ndarray]:
    """Free-run simulation and its derivative with respect to :meth:`free_parameters`.

    Parameters
    ----------
    model : ChainModel
        Any chain of blocks.
    u : array_like, shape (N,) or (N, 1)
        Input.
    y_initial : array_like, optional
        Measured outputs whose first ``max_lag`` samples start the simulation, as in
        :meth:`ChainModel.simulate` given ``max_lag`` of them (later samples are not
        used: the start a chain estimates from more is not differentiated here).

    Returns
    -------
    y : ndarray, shape (N,)
        Equal to ``model.simulate(u, y_initial[:max_lag])[:, 0]`` (up to rounding).
    dy : ndarray, shape (N, n_free)
        ``dy[k, i] = ∂y(k)/∂θ_i``.

    Notes
    -----
    The sensitivities travel down the chain with the signal: every block maps its
    input and the input's sensitivities to its output and the output's sensitivities
    (``forward`` of each block). A static block multiplies by ``N'(s)`` and adds its own
    parameter Jacobian; a linear block filters every column through ``z^-nk B/A`` and
    adds the forcing of its own parameters,

    .. math::

        A(z^{-1}) s_i(k) = \\begin{cases}
            z^{-n_k} B(z^{-1})\\, \\partial w(k)/\\partial \\theta_i & \\text{upstream} \\\\
            -x(k - j) & \\theta_i = a_j \\\\
            w(k - n_k - j) & \\theta_i = b_j
        \\end{cases}

    (B2). When the last linear block starts from ``x = N^{-1}(y)`` of the measured
    outputs, the dependence of that start on the parameters of the blocks after it is
    included: ``dx/dθ = -(∂N/∂θ) / N'(x)``.
    """
    u_arr, _ = model._check_signals(u)
    s = np.ascontiguousarray(u_arr[:, 0] - model.input_offset)
    columns = model.block_columns()
    n_par = int(sum(int((c >= 0).sum()) for c in columns))
    S = np.zeros((s.shape[0], n_par))
    last = model.last_linear_index
    init = _initial_state(model, columns, y_initial, n_par)
    for i, block in enumerate(model.blocks):
        s, S = block.forward(s, S, columns[i], init if i == last else None)
    return s + model.output_offset, S


def _initial_state(
    model: ChainModel, columns: list[np.ndarray], y_initial: Any, n_par: int
) -> tuple[np.ndarray, np.ndarray] | None:
    """The last linear block's start from measured outputs, and its sensitivities."""
    x0 = model.initial_state(y_initial)
    if x0 is None:
        return None
    tail = range(model.last_linear_index + 1, len(model.blocks))
    signals = [x0]
    for i in tail:  # the signal entering every tail block, from x0 forwards
        signals.append(np.asarray(model.blocks[i](signals[-1]), dtype=float))
    S0 = np.zeros((x0.shape[0], n_par))
    for k in reversed(range(len(tail))):  # x_k = N_k^{-1}(x_{k+1}), chain rule backwards
        block, x = model.blocks[tail[k]], signals[k]
        slope = block.derivative(x)
        own, free = columns[tail[k]], columns[tail[k]] >= 0
        S0 = S0 / slope[:, None]
        if free.any():
            S0[:, own[free]] -= block.jacobian(x)[:, free] / slope[:, None]
    return x0, S0


def sensitivity_chunks(
    model: ChainModel, u: Any, y_initial: Any = None, rows: int | None = None
) -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
    """:func:`chain_sensitivities` in pieces of at most ``rows`` samples (default: the
    ``sensitivity_rows`` of :func:`blockid.config.get_config`).

    Yields ``(start, y, dy)`` for consecutive samples ``start .. start + len(y)``: the
    same values as the whole-record function, holding one piece at a time. A linear
    block continues from its last ``max_lag`` inputs and outputs (and their
    sensitivities) of the previous piece, which is exactly the recursion's state; a
    static block needs no state. Only for a chain of static and linear blocks
    (:func:`blockid.fitting.simulation_error.chunkable`).
    """
    blocks = getattr(model, "blocks", None)
    if blocks is None or not all(b.role in ("static", "linear") for b in blocks):
        raise ParameterError("sensitivity_chunks needs a chain of static and linear blocks")
    u_arr, _ = model._check_signals(u)
    signal = u_arr[:, 0] - model.input_offset
    columns = model.block_columns()
    n_par = int(sum(int((c >= 0).sum()) for c in columns))
    last = model.last_linear_index
    init = _initial_state(model, columns, y_initial, n_par)
    rows = get_config()["sensitivity_rows"] if rows is None else rows
    rows = max(int(rows), max(b.max_lag for b in model.linear_blocks), 1)
    state: dict[int, tuple[np.ndarray, ...]] = {}
    for start in range(0, signal.shape[0], rows):
        s = np.ascontiguousarray(signal[start : start + rows])
        S = np.zeros((s.shape[0], n_par))
        for i, block in enumerate(model.blocks):
            if block.role != "linear":
                s, S = block.forward(s, S, columns[i], None)
                continue
            lag = block.max_lag
            if start == 0:
                w_all, Sw_all = s, S
                x_all, Sx_all = block.forward(s, S, columns[i], init if i == last else None)
                x, Sx = x_all, Sx_all
            else:  # the previous piece's last inputs and outputs start this one
                w_prev, Sw_prev, x_prev, Sx_prev = state[i]
                w_all = np.concatenate((w_prev, s))
                Sw_all = np.vstack((Sw_prev, S))
                x_all, Sx_all = block.forward(w_all, Sw_all, columns[i], (x_prev, Sx_prev))
                x, Sx = x_all[lag:], Sx_all[lag:]
            if lag:
                state[i] = (w_all[-lag:], Sw_all[-lag:], x_all[-lag:], Sx_all[-lag:])
            s, S = x, Sx
        yield start, s + model.output_offset, S
