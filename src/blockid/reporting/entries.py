"""The models a report shows, whichever workflow produced them."""

from __future__ import annotations

from dataclasses import dataclass, field
from html import escape
from typing import Any

__all__ = ["Entry", "heading"]


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

    @property
    def model(self) -> Any:
        return getattr(self.fit, "model", None)


def heading(entry: Entry) -> str:
    """The ``<h3>`` that opens a model's part of a section."""
    return f"<h3>{escape(entry.label)}</h3>"
