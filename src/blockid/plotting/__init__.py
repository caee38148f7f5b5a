"""Plots of blocks, models and results. matplotlib is imported only when a plot is drawn."""

from blockid.plotting.blocks import plot_block

__all__ = ["plot_block"]
