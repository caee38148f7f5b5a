"""The size of ``identify``'s search, and the checks of its arguments.

An :class:`Effort` counts work — folds, orders, candidates, iterations — never seconds,
so that the same data, effort and version give the same model on any machine at any
load (``docs/identify.md`` lists the counts). This module needs no numerical library:
the command line checks ``--effort``, ``--structures``, ``--jobs`` and ``--time-limit``
with :func:`check_search` before it imports NumPy.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from blockid.errors import ParameterError
from blockid.fitting.registry import STRUCTURES

__all__ = ["EFFORTS", "LONG_RECORD", "MAX_JOBS", "RULES", "Effort", "check_jobs", "check_search"]

#: Records of at least this many samples get fewer folds and screening on a part.
LONG_RECORD = 20_000
#: The most worker processes a search starts on one machine (each holds the record and
#: a fit): more is refused, not cut silently; a dask cluster (``scheduler``) has more.
MAX_JOBS = 64
#: How fold scores are combined into a candidate's score (``docs/identify.md`` has the
#: study that chose the first).
RULES = ("geometric-mean", "median", "mean")


@dataclass(frozen=True)
class Effort:
    """The sizes of the search's stages (:mod:`blockid.workflows.identify`)."""

    name: str
    folds: int  # folds of a record shorter than LONG_RECORD samples
    folds_long: int  # folds of a longer one
    max_order: int  # largest na of the ARX order grid
    max_delay: int  # largest delay scanned
    linear_keep: int  # ARX order sets carried to the structures
    families: int | None  # block families per slot (None: all)
    screen_nfev: int  # simulation-error iterations of a screening fit
    screen_samples: int  # training samples of a screening fit (long records)
    finalists: int  # candidates fitted again with final_nfev
    final_nfev: int  # iterations of a finalist's fit
    grow_steps: int  # richer-nonlinearity steps
    #: (degree, monomials) of the polynomial state-space candidates
    state_plans: tuple[tuple[int, str], ...] = ((3, "states"),)
    #: largest number of parameters of a polynomial state-space candidate
    state_parameters: int = 100
    #: state dimensions carried from the linear state-space stage to the polynomial one
    state_keep: int = 1
    #: training samples of the finalists' and later fits on a long record (None: all)
    final_samples: int | None = None
    #: (input block, output block) of the block state-space candidates, searched on data
    #: of several inputs or outputs (one family on every channel; None: no block there)
    block_state_plans: tuple[tuple[str | None, str | None], ...] = (
        ("polynomial:degree=3", None),
        (None, "polynomial:degree=3"),
        ("polynomial:degree=3", "polynomial:degree=3"),
    )
    #: loop-block families of the block state-space candidates (a loop per output, one
    #: family for all): searched on data of several inputs or outputs, and with
    #: ``loop_single`` on one input and one output too, where no chain structure holds
    #: a static block on a combination of the states
    loop_plans: tuple[str, ...] = ("saturation", "dead-zone")
    loop_single: bool = False
    #: folds whose models are refined on all estimation data beside the chosen
    #: candidate's direct refit (its warm starts), on a record shorter than
    #: LONG_RECORD samples and on a longer one
    warm_starts: int = 4
    warm_starts_long: int = 3
    #: largest number of parameters of a polynomial state-space candidate whose degree
    #: the nonlinearity stage raises by a climb from the degree below (``start_degree``),
    #: and the iterations of the climbed degree when it is over ``state_parameters``
    climb_parameters: int = 900
    climb_nfev: int = 40
    #: on a long record, the block structures' screening is raced: every candidate on
    #: the first fold, the best ``1 / race`` of them on the others (1: no race)
    race: int = 3

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


#: The efforts ``identify`` offers: the same data and effort give the same model.
EFFORTS: dict[str, Effort] = {
    e.name: e
    for e in (
        Effort(
            name="quick", folds=3, folds_long=2, max_order=5, max_delay=10, linear_keep=1,
            families=3, screen_nfev=15, screen_samples=10_000, finalists=2, final_nfev=60,
            grow_steps=1, state_plans=((2, "full"), (3, "states"), (3, "full")),
            state_parameters=300,
            state_keep=2, final_samples=20_000, warm_starts=2,
            warm_starts_long=1, climb_parameters=600, climb_nfev=20,
            block_state_plans=(
                ("polynomial:degree=3", None), (None, "polynomial:degree=3"),
                ("polynomial:degree=3", "polynomial:degree=3"),
            ),
        ),
        Effort(
            name="standard", folds=4, folds_long=3, max_order=8, max_delay=20, linear_keep=2,
            families=None, screen_nfev=30, screen_samples=20_000, finalists=3,
            final_nfev=150, grow_steps=3,
            state_plans=((2, "full"), (3, "states"), (3, "full")), state_parameters=300,
            state_keep=2, final_samples=50_000, loop_single=True,
        ),
        Effort(
            name="thorough", folds=5, folds_long=3, max_order=10, max_delay=30, linear_keep=3,
            families=None, screen_nfev=60, screen_samples=50_000, finalists=5,
            final_nfev=300, grow_steps=4,
            state_plans=((2, "full"), (3, "states"), (3, "full"), (4, "states")),
            state_parameters=1200, state_keep=3, final_samples=None, loop_single=True,
            warm_starts=5, climb_parameters=1800, climb_nfev=60, race=2,
        ),
    )
}  # fmt: skip


def check_jobs(jobs: int | None) -> int | None:
    """``jobs``, the worker processes of one machine (``identify``'s and ``fleet``'s one
    name for them), checked: a whole number from 1 to :data:`MAX_JOBS`, or None (every
    core, at most ``MAX_JOBS``)."""
    if jobs is not None and (isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1):
        raise ParameterError(f"jobs must be a whole number >= 1, got {jobs!r}", parameter="jobs")
    if jobs is not None and jobs > MAX_JOBS:
        raise ParameterError(
            f"jobs={jobs} is more worker processes than blockid starts on one machine "
            f"({MAX_JOBS}); give {MAX_JOBS} or fewer, or a dask cluster (scheduler) for more",
            parameter="jobs",
        )
    return jobs


def check_search(
    structures: Sequence[str] | None,
    effort: str | Effort,
    rule: str = RULES[0],
    jobs: int | None = None,
    time_limit: float | None = None,
    scheduler: Any = None,
) -> tuple[Effort, list[str] | None]:
    """Check ``identify``'s search arguments; return the effort and the structures asked
    for (None: the registry's searched ones)."""
    if not isinstance(effort, Effort) and effort not in EFFORTS:
        raise ParameterError(
            f"effort={effort!r} is unknown; choose one of {', '.join(EFFORTS)}", parameter="effort"
        )
    if rule not in RULES:
        raise ParameterError(f"rule={rule!r}: choose one of {', '.join(RULES)}", parameter="rule")
    check_jobs(jobs)
    if scheduler is not None and jobs is not None:
        raise ParameterError(
            "give jobs (worker processes here) or scheduler (a dask cluster), not both",
            parameter="scheduler",
        )
    if time_limit is not None and not time_limit > 0:
        raise ParameterError(
            f"time_limit must be a positive number of seconds, got {time_limit!r}",
            parameter="time_limit",
        )
    asked = list(structures) if structures else None
    unknown = [s for s in asked or () if s not in STRUCTURES]
    if unknown:
        raise ParameterError(
            f"structures {unknown} are unknown; choose among {', '.join(STRUCTURES)}",
            parameter="structures",
        )
    return effort if isinstance(effort, Effort) else EFFORTS[effort], asked
