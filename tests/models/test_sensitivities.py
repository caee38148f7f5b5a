"""A chain's free-run sensitivities (models/sensitivities.py), through
simulate_with_sensitivities: equal to simulate and to central differences for every
kind of block, from rest and from measured outputs. The piecewise walk
(sensitivity_chunks) is checked in tests/fitting/test_long_records.py."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from blockid.blocks import (
    Backlash,
    DeadZone,
    PiecewiseLinear,
    Polynomial,
    Saturation,
    TwoSegmentPolynomial,
)
from blockid.blocks.base import StaticBlock
from blockid.fitting.simulation_error import simulate_with_sensitivities
from blockid.models.block import BacklashModel, Hammerstein, HammersteinWiener, Wiener

A3 = [-1.1, 0.55, -0.125]  # poles 0.5 and 0.3 +- 0.4j


# ------------------------------------------------------------------ Jacobian
class _Tanh(StaticBlock):
    """A block the refinement has no analytic derivative for (numerical fallback)."""

    kind = ""

    def __init__(self, gain: float, scale: float) -> None:
        self.gain = gain
        self.scale = scale

    @property
    def parameters(self) -> dict[str, Any]:
        return {"gain": self.gain, "scale": self.scale}

    def __call__(self, u):
        return self.gain * np.tanh(self.scale * np.asarray(u, dtype=float))


SENSITIVITY_MODELS = {
    "hammerstein-wiener with offsets": lambda: HammersteinWiener(
        "u",
        "y",
        input_block=TwoSegmentPolynomial([0.2, 1, 0.4, -0.3], [-0.3, -0.5, 0.6, 0.4]),
        output_block=Polynomial([1, 0.2, 0.05], constant=False),
        na=3,
        nb=3,
        nk=2,
        a=A3,
        b=[1, 0.4, 0.2],
        input_offset=0.1,
        output_offset=0.3,
    ),
    "backlash": lambda: BacklashModel(
        "u",
        "y",
        input_block=Backlash(0.9, 0.2, 0.8, 0.3),
        na=2,
        nb=2,
        nk=1,
        a=[-1, 0.3],
        b=[1, 0.5],
    ),
    "dead zone": lambda: Hammerstein(
        "u",
        "y",
        input_block=DeadZone(-0.2, 0.3, 1.2, 0.8),
        na=2,
        nb=2,
        nk=0,
        a=[-1, 0.3],
        b=[1, 0.5],
    ),
    "saturation": lambda: Hammerstein(
        "u", "y", input_block=Saturation(-0.5, 0.7, 1.3), na=2, nb=1, nk=1, a=[-1, 0.3]
    ),
    "piecewise linear": lambda: Hammerstein(
        "u",
        "y",
        input_block=PiecewiseLinear([-1, 0, 1], [-0.5, 0.1, 0.8]),
        na=1,
        nb=2,
        nk=1,
        a=[-0.7],
        b=[1, 0.5],
    ),
    "wiener": lambda: Wiener(
        "u",
        "y",
        output_block=Polynomial([1, 0.2, 0.05], constant=False),
        na=2,
        nb=2,
        nk=3,
        a=[-1, 0.3],
        b=[0.5, 0.5],
    ),
    "numerical block derivative": lambda: Hammerstein(
        "u", "y", input_block=_Tanh(1.5, 0.8), na=2, nb=2, nk=1, a=[-1, 0.3], b=[1, 0.5]
    ),
}


@pytest.mark.parametrize("name", list(SENSITIVITY_MODELS))
@pytest.mark.parametrize("measured_start", [False, True])
def test_sensitivities_match_simulate_and_finite_differences(name, measured_start, rng):
    model = SENSITIVITY_MODELS[name]()
    t = np.arange(300)
    u = np.sin(t / 10) + 0.1 * rng.standard_normal(300)
    y0 = 0.5 + 0.1 * rng.standard_normal(model.max_lag) if measured_start else None
    y, J = simulate_with_sensitivities(model, u, y0)
    np.testing.assert_allclose(y, model.simulate(u, y0)[:, 0], rtol=1e-12, atol=1e-12)
    theta = model.free_parameters()
    J_fd = np.empty_like(J)
    for k in range(theta.size):
        h = 1e-6 * max(1.0, abs(theta[k]))
        up, down = theta.copy(), theta.copy()
        up[k] += h
        down[k] -= h
        J_fd[:, k] = (
            model.with_free_parameters(up).simulate(u, y0)[:, 0]
            - model.with_free_parameters(down).simulate(u, y0)[:, 0]
        ) / (2 * h)
    np.testing.assert_allclose(J, J_fd, rtol=0, atol=1e-6 * np.max(np.abs(J_fd)))
