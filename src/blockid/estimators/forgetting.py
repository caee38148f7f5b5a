"""Forgetting factors: a constant or a piecewise-constant schedule.

Paper B runs its recursive estimator with lambda = 0.98 for the first 200 samples and
lambda = 1 afterwards; that schedule is written ``"0.98:200,1"``. The general form is
``"l1:n1,l2:n2,...,lK"``: ``l1`` for ``n1`` samples, then ``l2`` for ``n2`` samples, ...,
then ``lK`` for ever. A bare number is a constant factor.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blockid.errors import ParameterError

__all__ = ["ForgettingSchedule"]

_FORM = "a number in (0, 1] such as 0.99, or a schedule such as 0.98:200,1"


@dataclass(frozen=True)
class ForgettingSchedule:
    """Piecewise-constant forgetting factor over the sample count.

    Parameters
    ----------
    values : tuple of float
        Factors, each in (0, 1]; the last one holds for ever.
    durations : tuple of int
        Number of samples each factor but the last is used for (``len(values) - 1``).

    Examples
    --------
    >>> s = ForgettingSchedule.parse("0.98:200,1")
    >>> s.factors(198, 4).tolist()
    [0.98, 0.98, 1.0, 1.0]
    >>> str(s)
    '0.98:200,1'
    """

    values: tuple[float, ...]
    durations: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        if len(self.values) != len(self.durations) + 1:
            raise ParameterError(
                "forgetting schedule needs one duration for every factor but the last; "
                f"expected {_FORM}"
            )
        for v in self.values:
            if not (0.0 < v <= 1.0):
                raise ParameterError(f"forgetting factor {v} is outside (0, 1]; expected {_FORM}")
        for d in self.durations:
            if d <= 0:
                raise ParameterError(f"forgetting duration {d} must be a positive sample count")

    @classmethod
    def parse(cls, spec: str | float | ForgettingSchedule) -> ForgettingSchedule:
        """Build a schedule from a number, a spec string, or return a schedule as is."""
        if isinstance(spec, ForgettingSchedule):
            return spec
        if isinstance(spec, int | float | np.floating):
            return cls((float(spec),))
        text = str(spec).strip()
        values: list[float] = []
        durations: list[int] = []
        parts = [p.strip() for p in text.split(",")]
        try:
            for i, part in enumerate(parts):
                if ":" in part:
                    v, d = part.split(":")
                    values.append(float(v))
                    durations.append(int(d))
                elif i == len(parts) - 1:
                    values.append(float(part))
                else:
                    raise ValueError(part)
        except ValueError:
            raise ParameterError(f"cannot read forgetting {text!r}; expected {_FORM}") from None
        if len(values) == len(durations):  # "0.98:200" alone: hold the last value
            values.append(values[-1])
        return cls(tuple(values), tuple(durations))

    @property
    def is_constant_one(self) -> bool:
        """True when every factor is 1 (no forgetting)."""
        return all(v == 1.0 for v in self.values)

    @property
    def settled_after(self) -> int:
        """Samples after which every factor is the last value."""
        return int(sum(self.durations))

    def factors(self, start: int, n: int) -> np.ndarray:
        """Factors for samples ``start .. start + n - 1`` (sample count since the start)."""
        out = np.full(n, self.values[-1])
        edge = 0
        for v, d in zip(self.values[:-1], self.durations, strict=True):
            lo, hi = max(edge - start, 0), min(edge + d - start, n)
            if hi > lo:
                out[lo:hi] = v
            edge += d
        return out

    def __str__(self) -> str:
        parts = [f"{v:g}:{d}" for v, d in zip(self.values[:-1], self.durations, strict=True)]
        return ",".join([*parts, f"{self.values[-1]:g}"])
