"""Blocks: static curves, the backlash (hysteresis) block, the linear dynamic block and
the integrator."""

from blockid.blocks.backlash import Backlash
from blockid.blocks.base import (
    BLOCK_TYPES,
    Block,
    DynamicBlock,
    StaticBlock,
    block_from_dict,
    block_template,
)
from blockid.blocks.free_pwl import FreePiecewiseLinear
from blockid.blocks.integrator import Integrator
from blockid.blocks.linear import LinearBlock
from blockid.blocks.polynomial import Polynomial, TwoSegmentPolynomial
from blockid.blocks.static import DeadZone, PiecewiseLinear, Saturation

__all__ = [
    "BLOCK_TYPES",
    "Backlash",
    "Block",
    "DeadZone",
    "DynamicBlock",
    "FreePiecewiseLinear",
    "Integrator",
    "LinearBlock",
    "PiecewiseLinear",
    "Polynomial",
    "Saturation",
    "StaticBlock",
    "TwoSegmentPolynomial",
    "block_from_dict",
    "block_template",
]
