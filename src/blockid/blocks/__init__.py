"""Nonlinear blocks: static curves and the backlash (hysteresis) block."""

from blockid.blocks.backlash import Backlash
from blockid.blocks.base import BLOCK_TYPES, Block, DynamicBlock, StaticBlock, block_from_dict
from blockid.blocks.polynomial import Polynomial, TwoSegmentPolynomial
from blockid.blocks.static import DeadZone, PiecewiseLinear, Saturation

__all__ = [
    "BLOCK_TYPES",
    "Backlash",
    "Block",
    "DeadZone",
    "DynamicBlock",
    "PiecewiseLinear",
    "Polynomial",
    "Saturation",
    "StaticBlock",
    "TwoSegmentPolynomial",
    "block_from_dict",
]
