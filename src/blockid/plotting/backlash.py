"""Hysteresis-loop plot of a backlash block (SPEC.md (A3)).

matplotlib is imported inside the function only.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from blockid.blocks.backlash import Backlash

__all__ = ["plot_backlash", "triangular_sweep"]


def triangular_sweep(amplitude: float, n_per_leg: int = 100) -> np.ndarray:
    """Input ``0 -> +A -> -A -> +A`` in straight legs, for drawing a hysteresis loop.

    Examples
    --------
    >>> triangular_sweep(2.0, n_per_leg=1)
    array([ 0.,  2.,  0., -2.,  0.,  2.])
    """
    a = float(amplitude)
    up = np.linspace(0.0, a, n_per_leg + 1)
    down = np.linspace(a, -a, 2 * n_per_leg + 1)[1:]
    back = np.linspace(-a, a, 2 * n_per_leg + 1)[1:]
    return np.concatenate([up, down, back])


def plot_backlash(
    block: Backlash,
    ax: Any = None,
    u: np.ndarray | None = None,
    truth: Backlash | None = None,
) -> Any:
    """Draw ``x`` against ``u`` for a backlash, with its two branch lines dashed.

    Parameters
    ----------
    block : Backlash
        The (estimated) block to draw.
    ax : matplotlib Axes, optional
        Where to draw; a new figure is made when omitted.
    u : array, optional
        Input sequence to drive the block with. Default: a triangular sweep
        ``0 -> +A -> -A -> +A`` with ``A = 4 (c_left + c_right)`` (1.0 if that is 0).
    truth : Backlash, optional
        A reference block (e.g. the true one in a simulation), drawn dotted on the
        same input.

    Returns
    -------
    matplotlib Axes
    """
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(5.0, 4.0))
    if u is None:
        width = block.c_left + block.c_right
        u = triangular_sweep(4.0 * width if width > 0 else 1.0)
    u = np.asarray(u, dtype=float)
    grid = np.linspace(u.min(), u.max(), 2)

    ax.plot(u, block.simulate(u), color="C0", lw=1.8, label="backlash loop")
    ax.plot(
        grid, block.m_left * (grid + block.c_left), "--", color="C1", lw=1.0, label="left branch"
    )
    ax.plot(
        grid,
        block.m_right * (grid - block.c_right),
        "--",
        color="C2",
        lw=1.0,
        label="right branch",
    )
    if truth is not None:
        ax.plot(u, truth.simulate(u), ":", color="k", lw=1.5, label="truth")
    ax.set_xlabel("input u")
    ax.set_ylabel("output x")
    ax.set_title(
        f"backlash m_L={block.m_left:.4g}, c_L={block.c_left:.4g}, "
        f"m_R={block.m_right:.4g}, c_R={block.c_right:.4g}",
        fontsize="medium",
    )
    ax.legend(loc="upper left", fontsize="small")
    return ax
