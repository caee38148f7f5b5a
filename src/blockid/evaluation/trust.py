"""Whether a fitted model can be trusted beyond the samples that scored it.

A model can simulate the data it was scored on well and still be one nobody should
use: its internal signals may run far outside the ranges it was estimated on when the
input does not, it may diverge when started from rest, or its linear blocks may hold
poles and zeros that cancel each other with large coefficients (the cancellation is
exact only on the estimation data's spectrum). :func:`assess` measures each of these on
a model and data; :class:`Trust` says which are reasons to reject the model and which
are worth a flag. ``identify`` runs it on every candidate's held-back fold
(:mod:`blockid.workflows.identify`).

The limits (module constants, documented in ``docs/identify.md``):

* **range excess** -- the largest excursion of an internal signal (the input of a
  nonlinear block, or the fed-back output) beyond its estimation range, *minus* the
  input's own excursion beyond its range, as a fraction of the range's width. A
  well-posed model's internal signals leave their ranges about as far as the input
  leaves its own; one whose ``x`` leaves by 170 % while ``u`` stays inside extrapolates
  a nonlinearity it never saw. Rejected above :data:`MAX_RANGE_EXCESS` (0.5).
* **free run from rest** -- how far the free run from rest (the model's zero state)
  strays from the measured output, over their difference at the first sample plus the
  measured output's largest deviation from its mean (:func:`rest_ratio`). A run from
  rest that settles onto the data gives about 1; a WH fit that spikes to 96 V from rest
  on a 2-10 V record about 20. Rejected above :data:`MAX_REST_RATIO` (5) or when not
  finite.
* **conditioning** (flags only) -- a linear block with a pole and a zero closer than
  :data:`CANCELLATION` (both outside the circle of radius 0.2, where cancellation
  matters), or whose coefficients ``sum |b_i|`` exceed :data:`COEFFICIENT_RATIO` (100)
  times the block's gain on the data (the spread of its output over that of its input):
  large coefficients that cancel on the data and not on other inputs.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from blockid.data.dataset import Dataset

__all__ = [
    "CANCELLATION",
    "COEFFICIENT_RATIO",
    "MAX_RANGE_EXCESS",
    "MAX_REST_RATIO",
    "Trust",
    "assess",
    "rest_ratio",
]

#: Internal signals may leave their estimation ranges by at most this fraction of the
#: range's width more than the input leaves its own.
MAX_RANGE_EXCESS = 0.5
#: A free run from rest may stray from the measured output at most this many times
#: their difference at the first sample plus the output's largest deviation.
MAX_REST_RATIO = 5.0
#: A pole and a zero of a linear block closer than this are flagged as cancelling.
CANCELLATION = 1e-2
#: A linear block whose ``sum |b_i|`` exceeds this many times its gain on the data is
#: flagged.
COEFFICIENT_RATIO = 100.0


@dataclass(frozen=True)
class Trust:
    """What :func:`assess` measured, and what follows from it.

    Attributes
    ----------
    range_excess : float
        Internal signals' excursion beyond their ranges minus the input's (fraction of
        the range width); 0 for models without recorded ranges.
    rest_ratio : float
        Peak deviation of the free run from rest over that of the measured output.
    flags : list of str
        Conditioning notes (not reasons to reject).
    """

    range_excess: float = 0.0
    rest_ratio: float = 0.0
    flags: list[str] = field(default_factory=list)

    @property
    def reasons(self) -> list[str]:
        """Why the model should be rejected (empty: trusted)."""
        out = []
        if not self.range_excess <= MAX_RANGE_EXCESS:
            out.append(
                f"on held-back data an internal signal leaves its estimation range by "
                f"{_percent(self.range_excess)} of that range more than the input leaves "
                f"its own (limit {100 * MAX_RANGE_EXCESS:.0f} %)"
            )
        if not self.rest_ratio <= MAX_REST_RATIO:
            how = (
                "is not finite"
                if not np.isfinite(self.rest_ratio)
                else f"strays {self.rest_ratio:.3g} times further from the measured "
                f"output than its start and the output's range explain "
                f"(limit {MAX_REST_RATIO:g})"
            )
            out.append(f"its free run from rest {how}")
        return out

    def worst(self, other: Trust) -> Trust:
        """The worse of two assessments, measure by measure (flags of both)."""
        return Trust(
            _worse(self.range_excess, other.range_excess),
            _worse(self.rest_ratio, other.rest_ratio),
            [*self.flags, *(f for f in other.flags if f not in self.flags)],
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "range_excess": _finite(self.range_excess),
            "rest_ratio": _finite(self.rest_ratio),
            "flags": list(self.flags),
            "reasons": self.reasons,
        }


def _worse(a: float, b: float) -> float:
    if not np.isfinite(a) or not np.isfinite(b):
        return float("inf")
    return max(a, b)


def _finite(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None


def _percent(value: float) -> str:
    return f"{100 * value:.0f} %" if np.isfinite(value) else "an unbounded amount"


def assess(model: Any, estimation: Dataset, held_back: Dataset | None = None) -> Trust:
    """Measure ``model`` (fitted on ``estimation``) for :class:`Trust`.

    Parameters
    ----------
    model : Model
        Any blockid model (linear models have no internal ranges or blocks to check;
        their free run from rest is checked all the same).
    estimation : Dataset
        The data the model was fitted on: the free run from rest and the blocks' gains
        are measured on them.
    held_back : Dataset, optional
        Data the model was not fitted on: the range excess is measured on them.
    """
    with np.errstate(all="ignore"):
        excess = 0.0
        if held_back is not None:
            for exp in held_back.experiments:
                excess = _worse(excess, _range_excess(model.range_excursion(exp.u)))
        rest = 0.0
        flags: list[str] = []
        for exp in estimation.experiments:
            rest = _worse(rest, rest_ratio(model, exp.u, exp.y))
        first = estimation.experiments[0]
        for i, (block, w, x) in enumerate(model.linear_signals(first.u)):
            if not block.integrates:  # an integrator's poles are its purpose
                flags += _conditioning(block, w, x, i, len(model.linear_blocks))
    return Trust(excess, rest, flags)


def _range_excess(excursions: dict[str, float]) -> float:
    """Internal signals' excursion minus the input's (0 when nothing is recorded)."""
    inner = [v for k, v in excursions.items() if k != "u"]
    if not inner:
        return 0.0
    worst = max(inner)
    if not np.isfinite(worst):
        return float("inf")
    return max(worst - excursions.get("u", 0.0), 0.0)


def rest_ratio(model: Any, u: np.ndarray, y: np.ndarray) -> float:
    """How far the free run from rest strays from the measured output, beyond where it
    started: ``max |ŷ_rest - y|`` over ``|ŷ_rest(0) - y(0)|`` plus the measured output's
    largest deviation from its mean.

    A model started from rest away from the data (an uncentred model at 0 when the data
    sit at 355 mm) settles onto them: about 1. One whose transient from rest swings far
    beyond both (a Wiener-Hammerstein fit with ``b = [-9.5, 35, -51, 33, -8.5]`` spiking
    to 96 V on a 2-10 V record) gives 10 or more. 0 for a model that integrates:
    started from rest, it drifts with the input's offset, which says nothing about its
    trustworthiness.
    """
    if any(block.integrates for block in model.linear_blocks):
        return 0.0
    rest = np.asarray(model.simulate(u), dtype=float)
    if not np.all(np.isfinite(rest)):
        return float("inf")
    gap = np.abs(rest - y)
    scale = float(np.max(gap[0])) + float(np.max(np.abs(y - y.mean(axis=0))))
    return float(np.max(gap)) / scale if scale > 0 else 0.0


def _conditioning(block: Any, w: np.ndarray, x: np.ndarray, i: int, n: int) -> list[str]:
    name = "the linear block" if n == 1 else f"linear block {i + 1}"
    out = []
    poles, zeros = block.poles(), block.zeros()
    poles, zeros = poles[np.abs(poles) > 0.2], zeros[np.abs(zeros) > 0.2]
    if poles.size and zeros.size:
        gap = np.abs(poles[:, None] - zeros[None, :])
        k = np.unravel_index(np.argmin(gap), gap.shape)
        if gap[k] < CANCELLATION:
            out.append(
                f"{name} has a pole ({poles[k[0]]:.4g}) and a zero ({zeros[k[1]]:.4g}) "
                f"{gap[k]:.2g} apart: they nearly cancel (fewer orders may do)"
            )
    spread_w, spread_x = float(np.std(w)), float(np.std(x))
    size = float(np.sum(np.abs(block.b)))
    if spread_w > 0 and np.isfinite(spread_x) and size > COEFFICIENT_RATIO * spread_x / spread_w:
        gain = spread_x / spread_w
        out.append(
            f"{name}'s coefficients (sum |b| = {size:.3g}) are {size / max(gain, 1e-300):.3g} "
            f"times its gain on the data ({gain:.3g}): they cancel on these data and may not "
            "on others"
        )
    return out
