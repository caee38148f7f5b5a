"""Each block's ``export_source``, the rule the exported module copies
(:func:`blockid.models.export.to_python_module`), gives the block's own numbers bit for
bit: run here on what the module hands it (the block's file entry through JSON)."""

import json
import textwrap

import numpy as np
import pytest

from blockid.blocks import (
    BLOCK_TYPES,
    Backlash,
    DeadZone,
    FreePiecewiseLinear,
    PiecewiseLinear,
    Polynomial,
    Saturation,
    StaticBlock,
    TwoSegmentPolynomial,
)
from blockid.models import _export_runtime as runtime

STATIC = [
    DeadZone(-0.3, 0.5, 0.7, 1.3),
    Saturation(-0.4, 0.9, 1.7),
    PiecewiseLinear([-1.0, 0.0, 0.5, 2.0], [-0.5, 0.0, 0.7, 0.8]),
    FreePiecewiseLinear([-2.0, -0.5, 1.0], [1.0, 0.0, 3.0]),
    Polynomial([0.3, -1.0, 0.5, 0.25]),
    Polynomial([1.0, 0.2, -0.05], constant=False),
    TwoSegmentPolynomial([0.1, 1.0, 0.5], [-0.3, 0.4, 0.2]),
]


def _rule(block):
    """The functions of the block's export_source and its entry as the module reads it."""
    namespace = {"np": np, "_polyval": runtime._polyval, "_derivative": runtime._derivative}
    exec(textwrap.dedent(type(block).export_source), namespace)  # noqa: S102
    return namespace, json.loads(json.dumps(block.to_dict()))


@pytest.mark.parametrize("block", STATIC, ids=lambda b: b.kind)
def test_a_static_rule_evaluates_and_differentiates_as_the_block(block):
    rule, p = _rule(block)
    s = np.concatenate((np.linspace(-3.0, 3.0, 1201), [-0.3, 0.0, 0.5, 1.0]))
    assert np.array_equal(rule["evaluate"](p, s), block(s))
    if type(block).derivative is not StaticBlock.derivative:  # its own derivative
        assert np.array_equal(rule["slope"](p, s), block.derivative(s))
    if "scalar" in rule:  # one float at a time, for a feedback loop: the same numbers
        one = rule["scalar"](p)
        assert np.array_equal(np.array([one(float(v)) for v in s]), block(s))


def test_the_backlash_rule_runs_as_the_block_from_rest():
    block = Backlash(0.9, 0.3, 1.1, 0.25)
    rule, p = _rule(block)
    u = 2.0 * np.sin(np.linspace(0.0, 12.0, 500)) + 0.1 * np.cos(np.linspace(0.0, 90.0, 500))
    assert np.array_equal(rule["run"](p, u), block.run(u))
    assert rule["run"](p, np.zeros(0)).shape == (0,)


def test_every_built_in_block_but_the_integrator_gives_its_rule():
    """A block without one is refused at export (tests/models/test_export.py)."""
    missing = {kind for kind, cls in BLOCK_TYPES.items()
               if cls.__module__.startswith("blockid.") and cls.export_source is None}  # fmt: skip
    assert missing == {"linear", "integrator"}  # the linear block is the runtime's own
