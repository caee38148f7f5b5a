"""Plots of blocks, models and results. matplotlib is imported only when a plot is drawn."""

from blockid.plotting.backlash import plot_backlash, triangular_sweep
from blockid.plotting.blocks import plot_block
from blockid.plotting.figures import (
    fit_figures,
    plot_blocks,
    plot_model_output,
    plot_parameter_history,
)

__all__ = [
    "fit_figures",
    "plot_backlash",
    "plot_block",
    "plot_blocks",
    "plot_model_output",
    "plot_parameter_history",
    "triangular_sweep",
]
