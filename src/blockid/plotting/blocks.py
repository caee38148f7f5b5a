"""Input-output curves of static blocks.

Blocks' :meth:`plot` methods hand off to :func:`plot_block`; matplotlib is imported
inside it, so importing blockid never pulls in matplotlib.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from blockid.blocks.base import StaticBlock
from blockid.blocks.static import _check_range
from blockid.errors import ParameterError

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["block_name", "default_range", "plot_block"]

#: Kinds whose name reads better than its hyphens replaced by spaces.
_READABLE = {
    "two-segment-polynomial": "two-segment polynomial",
    "piecewise-linear-free": "piecewise-linear (free knots)",
}


def block_name(block: Any) -> str:
    """How figures and tables name a block: its ``label`` if it has one, else its kind
    in words (never the class name).

    >>> from blockid.blocks.polynomial import TwoSegmentPolynomial
    >>> block_name(TwoSegmentPolynomial.from_segments([0.0, 1.0], [0.0, 0.5]))
    'two-segment polynomial'
    >>> from blockid.blocks.static import DeadZone
    >>> block_name(DeadZone(-0.5, 0.5))
    'dead zone'
    """
    label = getattr(block, "label", None)
    if isinstance(label, str) and label:
        return label
    kind = str(getattr(block, "kind", "") or type(block).__name__)
    return _READABLE.get(kind, kind.replace("-", " "))


def default_range(block: Any) -> tuple[float, float]:
    """The block's own plotting range, or ``(-1, 1)`` if it does not offer one."""
    default = getattr(block, "default_u_range", None)
    return default() if callable(default) else (-1.0, 1.0)


def _check_static(name: str, block: Any) -> None:
    if getattr(block, "role", None) != "static":
        raise ParameterError(
            f"{name} must be a static block (w = N(u)), got {type(block).__name__}; "
            "blocks with memory such as backlash are plotted by simulating them"
        )


def plot_block(
    block: StaticBlock,
    ax: Axes | None = None,
    u_range: tuple[float, float] | None = None,
    truth: StaticBlock | None = None,
    *,
    n_points: int = 501,
    **kwargs: Any,
) -> Axes:
    """Draw the input-output curve ``w = N(u)`` of a static block.

    Parameters
    ----------
    block : StaticBlock
        The block to draw (typically an estimate).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure is made if omitted.
    u_range : (float, float), optional
        Input interval. Default: the block's ``default_u_range()``, widened to cover
        the truth's when ``truth`` is given.
    truth : StaticBlock, optional
        The true block, drawn dashed for comparison; a legend is added.
    n_points : int, default 501
        Number of evenly spaced inputs.
    **kwargs
        Passed to ``Axes.plot`` for the block's curve (e.g. ``color``, ``label``).

    Returns
    -------
    matplotlib.axes.Axes
        The axes, with one line for the block and one more for the truth.
    """
    _check_static("block", block)
    if truth is not None:
        _check_static("truth", truth)
    if int(n_points) < 2:
        raise ParameterError(f"n_points must be at least 2, got {n_points}")
    if u_range is None:
        ranges = [default_range(b) for b in (block, truth) if b is not None]
        u_range = (min(r[0] for r in ranges), max(r[1] for r in ranges))
    low, high = _check_range("u_range", u_range)

    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots()
    u = np.linspace(low, high, int(n_points))
    kwargs.setdefault("label", "estimate" if truth is not None else block_name(block))
    ax.plot(u, block(u), **kwargs)
    if truth is not None:
        ax.plot(u, truth(u), linestyle="--", color="black", label="true")
        ax.legend()
    ax.set_xlabel("input u")
    ax.set_ylabel("output w = N(u)")
    return ax
