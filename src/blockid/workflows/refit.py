"""The refit of ``identify``'s chosen candidate on all estimation data, and its checks.

The search scores candidates on folds; the one it chooses is fitted once more on all
the estimation data (:func:`_final_fit`, run here or, for the warm starts from the
folds' models, in the search's workers) and checked against what its folds found: a
refit that stopped at its evaluation limit short of them is fitted again with more
evaluations; one still far short is refused (:class:`RefitFellShort`) and the next
candidate is tried (:func:`_final`). ``docs/identify.md`` (step 8, refit) has the rules
and the measurements behind the factors.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from blockid.data.dataset import Dataset
from blockid.data.folds import Fold, Segment, materialise
from blockid.errors import BlockidError, EstimationError
from blockid.evaluation.trust import assess
from blockid.workflows.search_space import Candidate

if TYPE_CHECKING:  # the search and its scores live in identify, which imports this
    from blockid.workflows.identify import Score, _Search

__all__ = ["REFIT_FAILED", "REFIT_MORE", "REFIT_SLACK", "RefitFellShort"]

#: A refit on all estimation data that stopped at its evaluation limit and simulates its
#: own data more than this factor worse than its candidate's cross-validated score (on
#: data its fold fits never saw) has not converged: it is fitted again with
#: ``REFIT_MORE`` times the evaluations, and the better of the two kept.
REFIT_SLACK = 1.1
REFIT_MORE = 3
#: A refit whose free run on its own data is still more than this factor worse than its
#: candidate's cross-validated score has not found what the folds found (whatever made
#: it stop): it is refused, and the next candidate is fitted (``identify``'s
#: ``refit_failed``, whose default this is). (Bouc-Wen, a degree-2
#: polynomial state space: the folds reached 15 um on held-back data, the refit on all
#: 40 960 samples stalled at its linear start's 164 um, every step that moved a pole
#: sitting at the stability margin refused; it tested 150 um.)
REFIT_FAILED = 2.0


def _reason(exc: BaseException) -> str:
    """Why a fit failed: a blockid error's first sentence, another error's type and
    message, shortened at a word (never cut mid-word) beyond 600 characters."""
    import textwrap

    text = str(exc).split(". ")[0] if isinstance(exc, BlockidError) else f"{exc}"
    if not isinstance(exc, BlockidError) or not text:
        text = f"{type(exc).__name__}: {text}" if text else type(exc).__name__
    return textwrap.shorten(text, 600, placeholder=" [...]")


def _pooled(scored: Any, test: Dataset) -> tuple[float, float]:
    """RMSE over all outputs (data units) and the mean over outputs of RMSE / spread."""
    rmse = scored.metrics["rmse"]
    values = np.array([rmse[name] for name in test.outputs], dtype=float)
    if not np.all(np.isfinite(values)):
        return math.inf, math.inf
    y = np.vstack([e.y[scored.skip :] for e in test.experiments])
    spread = y.std(axis=0)
    spread[spread == 0] = 1.0
    return float(np.sqrt(np.mean(values**2))), float(np.mean(values / spread))


def _refit(
    candidate: Candidate, data: Dataset, cv_rmse: float, n_init: int, notes: list[str]
) -> tuple[Any, float | None]:
    """The candidate fitted with its own options on all estimation data, and checked;
    with its free-run RMSE on those data (None for a fit without an evaluation limit,
    least squares, whose optimum is unique).

    A fit stopped by its evaluation limit whose free run on its own data is more than
    ``REFIT_SLACK`` times the candidate's cross-validated RMSE is fitted again with
    ``REFIT_MORE`` times the evaluations (the folds showed what the structure reaches;
    a longer record can need more iterations to get there), and the better kept."""
    from blockid.fitting.dispatch import fit_model

    with np.errstate(all="ignore"):
        fit = fit_model(data, candidate.structure, **candidate.options)
        nfev = candidate.options.get("max_nfev")
        stopped = "max_nfev" in str(fit.settings.get("stop_reason", ""))
        first = _own_rmse(fit.model, data, n_init) if nfev is not None else None
        if stopped and first is not None and math.isfinite(cv_rmse):
            if first > REFIT_SLACK * cv_rmse:
                more = {**candidate.options, "max_nfev": REFIT_MORE * int(nfev)}
                longer = fit_model(data, candidate.structure, **more)
                second = _own_rmse(longer.model, data, n_init)
                if second < first:
                    fit = longer
                notes.append(
                    f"the refit of {candidate.label} on all estimation data stopped at "
                    f"max_nfev = {nfev} with a free-run RMSE of {first:.4g} on its own data "
                    f"against {cv_rmse:.4g} cross-validated; fitted again with max_nfev = "
                    f"{more['max_nfev']}: {second:.4g}"
                    + ("" if second < first else " (not better: the first fit kept)")
                )
                first = min(first, second)
        trust = assess(fit.model, data)
    if trust.reasons:
        raise EstimationError(trust.reasons[0])
    return fit, first


def _own_rmse(model: Any, data: Dataset, n_init: int) -> float:
    """A model's free-run RMSE on the data it was fitted on (pooled over the outputs)."""
    from blockid.evaluation.validate import evaluate

    return _pooled(evaluate(model, data, "simulation", initial_samples=n_init), data)[0]


def _segment_rmse(model: Any, data: Dataset, segments: Sequence[Segment], n_init: int) -> float:
    """A model's free-run RMSE from the start of each of ``segments`` (its initial state
    from each one's first ``n_init`` outputs), pooled: how the search scores a fold."""
    return _own_rmse(model, materialise(data, segments), n_init)


def _fell_short(fit: Any, own: float | None, fold_rmse: float, factor: float) -> None:
    """Refuse a refit whose own-data error is more than ``factor`` times the folds'
    pooled error on data they never saw (:class:`RefitFellShort`)."""
    if own is not None and own > factor * fold_rmse:
        raise RefitFellShort(
            f"its fit on all estimation data simulates its own data with an RMSE of "
            f"{own:.4g}, more than {factor:g} times the folds' {fold_rmse:.4g} on "
            f"data they never saw (stopped: {fit.settings.get('stop_reason', '?')}): the "
            "fit did not find what the folds found",
            fit,
        )


@dataclass(frozen=True)
class _Start:
    """The final fit of ``candidate`` on all estimation data: directly (``fold`` None,
    :func:`_refit`) or refined from its model fitted on ``fold``'s training data (the
    first ``limit`` samples when given)."""

    candidate: Candidate
    fold: Fold | None
    limit: int | None
    n_init: int
    cv_rmse: float
    segments: tuple[Segment, ...] = ()  # a warm start's: the folds' held-back parts


@dataclass
class _Started:
    """What one :class:`_Start` gave: the fit, its free-run RMSE on all estimation data
    (None: a fit without an evaluation limit) and, once there are warm starts to compare
    it with, from the start of every fold's held-back part (:func:`_segment_rmse`), or
    why it failed."""

    fit: Any = None
    rmse: float | None = math.inf
    segment_rmse: float = math.inf
    reason: str = ""
    notes: list[str] = field(default_factory=list)


def _final_fit(data: Dataset, task: _Start) -> _Started:
    """One :class:`_Start` (in a worker process or here)."""
    from blockid.fitting.dispatch import fit_model, refine_from

    cand = task.candidate
    out = _Started()
    try:
        if task.fold is None:
            out.fit, out.rmse = _refit(cand, data, task.cv_rmse, task.n_init, out.notes)
        else:
            train = materialise(data, task.fold.train, task.limit)
            with np.errstate(all="ignore"):
                start = fit_model(train, cand.structure, **cand.options).model
                fit = refine_from(start, data, cand.structure, **cand.options)
                if not fit.model.is_stable():
                    raise EstimationError("unstable")
                rmse = _own_rmse(fit.model, data, task.n_init)
                if not math.isfinite(rmse):
                    raise EstimationError("its free-run simulation of the data is not finite")
                trust = assess(fit.model, data)
            if trust.reasons:
                raise EstimationError(trust.reasons[0])
            out.fit, out.rmse = fit, rmse
            with np.errstate(all="ignore"):
                out.segment_rmse = _segment_rmse(fit.model, data, task.segments, task.n_init)
    except Exception as exc:  # noqa: BLE001 - one start must not end the search
        out.fit, out.reason = None, _reason(exc)
    return out


def _final(search: _Search, score: Score, notes: list[str]) -> tuple[Any, dict[str, Any] | None]:
    """The candidate of ``score`` fitted on all estimation data (module docstring, step
    6): the direct fit, or the best of it and the folds' models refined on all the data,
    and what was tried (None when only the direct fit was). Raises the direct fit's
    error when every start failed, :class:`RefitFellShort` when the best falls short
    of the folds."""
    results = search.final_fits(score)
    (_, direct), warm = results[0], results[1:]
    notes.extend(direct.notes)
    ok = [(name, r) for name, r in results if r.fit is not None and not r.reason]
    if not ok:
        raise EstimationError(direct.reason)
    best_name, best = min(ok, key=lambda nr: nr[1].segment_rmse)
    if direct.fit is not None and not direct.segment_rmse > (1.0 + search.tie) * best.segment_rmse:
        best_name, best = results[0]  # near-ties (and a fit without warm starts): the direct fit
    info = None
    if warm:
        info = {
            "candidate": score.candidate.label,
            "fold_rmse": _fold_rmse(score),
            "starts": [
                {
                    "start": name,
                    "rmse": None if r.reason else r.rmse,
                    "fold_starts_rmse": _finite(r.segment_rmse) if not r.reason else None,
                    "failed": r.reason or None,
                }
                for name, r in results
            ],
            "chosen": best_name,
            "fold_starts_rmse": _finite(best.segment_rmse),
        }
    fit = best.fit
    if best is not direct:
        from dataclasses import replace

        base = direct.fit.settings if direct.fit is not None else {}
        fit = replace(fit, settings={**base, **fit.settings, "initial": best_name})
        shown = "; ".join(
            f"{name}: {r.segment_rmse:.4g}" if not r.reason else f"{name}: failed ({r.reason})"
            for name, r in results
        )
        notes.append(
            f"{score.candidate.label} was fitted on all estimation data directly and refined "
            f"on all of them from its models of the folds; simulated from the start of "
            f"every fold (as the search scores) they err {shown}: {best_name} is returned"
        )
    _fell_short(fit, best.rmse, _fold_rmse(score), search.refit_failed)
    return fit, info


def _finite(value: float) -> float | None:
    """``value``, or None where it is not finite (strict JSON)."""
    return value if math.isfinite(value) else None


class RefitFellShort(EstimationError):
    """A refit that simulates its own data far worse than the folds simulated data they
    never saw (:data:`REFIT_FAILED`); ``fit`` is kept, for when every candidate's does."""

    def __init__(self, message: str, fit: Any) -> None:
        super().__init__(message)
        self.fit = fit


def _fold_rmse(score: Score) -> float:
    """The folds' errors pooled (root mean square): the held-back error a refit's error
    on its own data is compared with (the score's geometric mean weighs a poor fold less,
    and a refit's pooled error does not)."""
    return float(np.sqrt(np.mean([f.rmse**2 for f in score.folds]))) if score.folds else math.inf
