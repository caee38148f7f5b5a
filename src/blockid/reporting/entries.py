"""The models a report shows, whichever workflow produced them."""

from __future__ import annotations

from dataclasses import dataclass, field
from html import escape
from typing import Any

import numpy as np

__all__ = ["Entry", "heading", "predicts_by_free_run"]


@dataclass
class Entry:
    """One model of the report: its label, fit and scores (or why it failed)."""

    label: str
    method: str
    fit: Any
    simulation: Any
    one_step: Any
    error: str | None = None
    one_step_error: str | None = None
    on: str = "validation"
    notes: list[str] = field(default_factory=list)
    row: str | None = None  # the class of its rows in the comparison ("baseline")
    residuals: Any = None  # compare's residual analysis on the validation data, if made

    @property
    def model(self) -> Any:
        return getattr(self.fit, "model", None)


def heading(entry: Entry) -> str:
    """The ``<h3>`` that opens a model's part of a section."""
    return f"<h3>{escape(entry.label)}</h3>"


def predicts_by_free_run(simulation: Any, one_step: Any) -> bool:
    """Whether a model's one-step prediction is its free-run simulation, sample for
    sample (two :class:`~blockid.evaluation.ModelOutput` of the same data): a model
    without a noise model (a state space fitted as output error, without a predictor
    gain ``K``) has no one-step predictor but its free run, and the report says so
    instead of repeating the free-run numbers as one-step ones."""
    if one_step is None or simulation is None:
        return False
    pairs = zip(one_step.outputs, simulation.outputs, strict=True)
    return all(np.array_equal(a, b, equal_nan=True) for a, b in pairs)
