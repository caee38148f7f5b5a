"""Records of the built-in simulated plants, to try the library and the command line on.

``blockid example-data NAME -o FILE`` writes :func:`example_record` ``(NAME).frame``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from blockid.errors import ParameterError

__all__ = ["EXAMPLES", "ExampleRecord", "check_example", "example_record"]

#: The example records, by name.
EXAMPLES = ("electrohydraulic", "windtunnel-110kPa", "windtunnel-130kPa")


@dataclass(frozen=True)
class ExampleRecord:
    """One continuous record: an estimation experiment followed by a validation one.

    ``estimation`` and ``validation`` are the half-open sample ranges ``(start, stop)``
    of the two experiments in ``frame``, whose time column ``t`` runs on without a
    jump from the first into the second.
    """

    name: str
    seed: int | None
    frame: Any  # pandas.DataFrame
    estimation: tuple[int, int]
    validation: tuple[int, int]


def check_example(name: str) -> None:
    """Refuse a name that is not one of :data:`EXAMPLES` (needs no numerical library)."""
    if name not in EXAMPLES:
        raise ParameterError(
            f"unknown example {name!r}; choose one of {', '.join(EXAMPLES)}", parameter="name"
        )


def example_record(name: str, seed: int | None = 0) -> ExampleRecord:
    """Simulate the plant of example ``name`` and join its two experiments.

    ``electrohydraulic`` (paper B): columns ``t, current, velocity``; estimation: the
    averaged multisine runs, validation: a general trajectory. ``windtunnel-110kPa`` and
    ``windtunnel-130kPa`` (paper A): ``t, u1, u2, v1, v2, y1, y2`` at that operating
    condition. The same seed gives the same record.

    >>> record = example_record("windtunnel-110kPa", seed=0)
    >>> record.estimation, record.validation, list(record.frame.columns)
    ((0, 1200), (1200, 2400), ['t', 'u1', 'u2', 'v1', 'v2', 'y1', 'y2'])
    """
    import numpy as np
    import pandas as pd

    check_example(name)
    if name == "electrohydraulic":
        from blockid.plants.electrohydraulic import electrohydraulic_experiment

        exp = electrohydraulic_experiment(seed=seed)
        parts = [exp[k][["t", "current", "velocity"]] for k in ("estimation", "validation")]
    else:
        from blockid.plants.windtunnel import windtunnel_experiment

        condition = name.split("-", 1)[1]
        parts = [
            windtunnel_experiment(condition, seed=seed, kind=k).drop(columns=["x_true"])
            for k in ("estimation", "validation")
        ]
    frame = pd.concat(parts, ignore_index=True)
    dt = float(parts[0]["t"].iloc[1] - parts[0]["t"].iloc[0])
    frame["t"] = np.arange(len(frame)) * dt
    n_est = len(parts[0])
    return ExampleRecord(name, seed, frame, (0, n_est), (n_est, len(frame)))
