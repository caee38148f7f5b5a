"""One-command identification: choose delay, orders, structure and nonlinearity.

``identify(data)`` chooses a model for a record using **only the estimation data**,
scored the way the model will be used: by free-run simulation. It runs as named stages,
every candidate of every stage judged by one criterion:

**The criterion: blocked cross-validation.** The estimation data are cut into
contiguous folds (:func:`~blockid.data.folds.fold_plan`: 4 blocks for a single record
under :data:`LONG_RECORD` samples, 3 above; with three or more experiments, leave a
group of experiments out). For each fold a candidate is fitted on the other folds and
simulated free-run on the held-back one from the fold's start, its initial state
estimated from the fold's first ``n_init`` measured outputs
(:func:`~blockid.evaluation.validate.evaluate` with ``initial_samples``, the function
``compare`` scores with), and scored on the rest of the fold. A fold's RMSE is divided
by the spread of its output; the candidate's score is the **geometric mean** over the
folds (``rule``), in units of the output's spread over all estimation data (so it reads
as an RMSE): every fold counts, none by its size alone. A single held-back tail of
100-250 samples was too noisy a judge on short records, and the plain mean lets one
unusual fold decide (``docs/identify.md`` has the study that chose the rule). A
candidate that fails, is unstable, does not simulate finitely or is not trusted
(:mod:`blockid.evaluation.trust`) on any fold is **rejected with its reason**.

**The stages** (``effort`` sets their sizes, :data:`EFFORTS`):

1. ``delay`` -- ARX models with ``na = nb = 4`` over the delays ``0 .. max_delay``
   (with several inputs or outputs, also with each pair's own delay where the pairs'
   differ, :func:`~blockid.fitting.delays.channel_delays`); the two best delays and the
   false-nearest-neighbours test's
   (:mod:`blockid.fitting.orders`, noise allowance estimated) carry on.
2. ``linear orders`` -- ARX ``na = 1 .. max_order``, ``nb <= na + 1`` at those delays
   (with several inputs or outputs, then ``per-pair orders``: the best of them with
   each pair's own ``nb``, at most its own, by the minimum description length of the
   least-squares residual, :func:`~blockid.fitting.delays.channel_orders`); the best order sets
   carry on, and output-error models around the best one (the best linear
   approximation's orders) replace the last.
3. ``structures`` -- every searched structure (the registry's ``search_rank``) with
   every block family in its slots (:mod:`blockid.workflows.search_space`), centring
   decided from the data, fitted by simulation error with ``screen_nfev`` iterations
   (long records on the first ``screen_samples`` of each fold's training data); with
   an integrating plant (ARX poles within :data:`INTEGRATING_POLE` of 1) also with
   integrators. A long record's structures are raced (``_Search._race``): all on the
   first fold, the best ``1 / race`` of them on the others.
4. ``finalists`` -- the best ``finalists`` candidates again with ``final_nfev``
   iterations on the whole training folds: new candidates, scored like the rest (a
   longer fit never replaces a shorter one that scored better); one more than
   :data:`~blockid.workflows.stages.FINALIST_REACH` times the best score so far is not
   fitted again (``search.out_of_reach``).
5. ``nonlinearity`` -- the best candidate with each polynomial degree or block size
   raised by 2 (a state-space model's monomial degree by 1), while the score falls by
   more than ``tie``.
6. ``refit`` -- the chosen candidate (ranked by score; among near-ties, within ``tie``,
   the fewest parameters; a model beyond linear only if it earned it, below) fitted
   with its own options on **all** estimation data, and checked once more (free run
   from rest). If that fails, the next one. A refit stopped by its evaluation limit
   more than ``REFIT_SLACK`` (:mod:`blockid.workflows.refit`) worse on its own data than
   the candidate's cross-validated score is fitted again with ``REFIT_MORE`` times the
   evaluations, and the better kept; one still more than ``refit_failed`` times worse
   than the folds' pooled error (whatever stopped it) is refused, with a note, and the
   next candidate fitted (if all are, the first of them is returned, with a note).
   **Warm starts**: a fit by simulation error is a nonconvex optimisation and the refit
   one start of it. A refit still more than ``REFIT_SLACK`` worse on its own data than
   the folds' pooled error on data they never saw found a worse optimum than they did:
   the candidate is then also fitted on the training data of its ``warm_starts`` best
   folds, each model refined on all estimation data
   (:func:`~blockid.fitting.dispatch.refine_from`), in the workers; the start with the
   lowest free-run error from the start of every fold's held-back part (initial state
   from its first ``n_init`` outputs, as the search scores) replaces the direct fit when
   it beats it by more than ``tie``. (EMPS: the direct refit stalled at 10.1 mm on its
   own data, its folds at 5.2 mm; the start from the model fitted without fold 1 tests
   3.4 mm against 13.3. Run on every refit, starts better in-sample by 0.1-2 % tested
   worse on the Silverbox and the ball and beam.)

**Linear unless the folds agree.** A model beyond linear (a static block, state
monomials, or an integrator) is chosen over the best-ranked linear model without
integrator (ARX, output-error, linear state space) only if it wins *consistently*: the
mean over the folds of the log ratio of their errors, fold by fold, must lie below
zero by more than ``LINEAR_MARGIN`` (0.75) times its standard error (after the
one-standard-error rule of cross-validation, Breiman et al. 1984, Hastie et al. 2009
sec. 7.10, paired over the folds the two share; the margin chosen on the shared
benchmark sets with each set left out in turn, ``docs/identify.md``). Otherwise the
linear model is chosen, with a note giving the numbers. (EMPS, with a fixed stability
margin: an integrating Hammerstein model scored 18.2 mm against the ARX's 21.3, but
its folds' errors were 12, 28 and 16 mm against 49,
7 and 27: mean log ratio -0.16, standard error 0.82; it tested 47.7 mm against the
ARX's 8.8.)

**An integrator at the longer horizon too.** An integrator's free-run error grows
with the horizon without bound (an offset in its input is summed), so folds a quarter of
the record long understate it. A best candidate with an integrator (and the first
linear model without one, above) is therefore scored once more, over the estimation
data's two halves (each fitted on one half and simulated over the other, the same
rule); unless it is then better, the candidates with an integrator are put after the
others, with a note. (DaISy ball and beam: an output-error model with an integrator beat
every linear one on all four folds of 125 samples, but erred 0.145 and 0.133 over the
halves against 0.095 and 0.084 without integrator (combined: 0.158 against 0.101); it
drifted to 0.232 on the test half against the ARX's 0.071.) Four fits, only when an
integrator would be chosen, and only when the folds are not already the halves or
whole experiments.

**Deterministic.** The search is a fixed amount of work: no stage depends on the
clock, so the same data, options and version give the same model, bit for bit, on a
busy or an idle machine, with any number of ``jobs`` and on a dask cluster
(``scheduler``; :mod:`blockid.workflows.parallel`: results merged in a fixed order, every
fit with a single BLAS thread). ``time_limit`` is a safety cap only: when it cuts a stage the
result says so (``cut_by_time_limit``) and is no longer reproducible.

Validation data, when given, are used only after the choice, to report.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from blockid.data.dataset import Dataset
from blockid.data.folds import Fold, FoldPlan, fold_plan, materialise
from blockid.defaults import TIE
from blockid.errors import BlockidError, DataError, EstimationError, ParameterError
from blockid.evaluation.trust import assess
from blockid.fitting.checks import refuse_constant_inputs
from blockid.fitting.registry import STRUCTURES, searched_structures
from blockid.workflows.distortion import distortion_record
from blockid.workflows.effort import (
    EFFORTS,
    LONG_RECORD,
    RULES,
    Effort,
    check_search,
)
from blockid.workflows.parallel import TaskRunner
from blockid.workflows.refit import (
    REFIT_FAILED,
    REFIT_SLACK,
    RefitFellShort,
    _final,
    _final_fit,
    _fold_rmse,
    _pooled,
    _reason,
    _segment_rmse,
    _Start,
    _Started,
)
from blockid.workflows.scores import FoldScore, IdentifyResult, Score
from blockid.workflows.search_space import (
    LINEAR,
    Candidate,
    climb_base,
    keeps_fold_models,
    unique,
)
from blockid.workflows.stages import FINALIST_REACH, INTEGRATING_POLE, Stage, run_stages

__all__ = [
    "EFFORTS",
    "INTEGRATING_POLE",
    "LONG_RECORD",
    "RULES",
    "Candidate",
    "Effort",
    "FoldScore",
    "IdentifyResult",
    "Score",
    "identify",
]

Progress = Callable[[str, int, int, str], None]

#: Standard errors by which a model beyond linear must beat the best linear one over
#: the folds (mean log error ratio < -LINEAR_MARGIN * its standard error). Chosen by
#: ``benchmarks/real/linear_rule_study.py`` on the 15 shared sets whose searches compared
#: the two, each set left out in turn: 0.75 in 13 of the 15 runs (0.5 and 1.0 in the
#: others); test error over the better pick, geometric mean: 1.0003 at 0.75, 1.0005 at
#: 1.0, 1.008 at 0.5, 1.020 at 0, 1.157 at 1.5 (``docs/identify.md`` has the table).
LINEAR_MARGIN = 0.75
#: A race (``_Search._race``) carries on at least this many candidates, and a stage of
#: fewer new candidates is not raced.
RACE_MIN = 8


# ----------------------------------------------------------------------------- one fit
@dataclass(frozen=True)
class _Task:
    """Fit ``candidate`` on ``fold``'s training data (the first ``limit`` samples when
    given) and score it on the held-back data from ``n_init`` measured outputs."""

    candidate: Candidate
    fold: Fold
    limit: int | None
    n_init: int
    #: the fold's model of the candidate below this climb's top degree, and that degree
    start: Any = None
    done: int = 0


def _fit_and_score(data: Dataset, task: _Task) -> FoldScore:
    """One candidate on one fold (runs in a worker process or here); a climb given the
    fold's model of the degree below continues from it (the same model, bit for bit)."""
    from blockid.evaluation.validate import evaluate
    from blockid.fitting.dispatch import climb_from, fit_model

    t0 = time.perf_counter()
    train = materialise(data, task.fold.train, task.limit)
    test = materialise(data, task.fold.test)
    cand = task.candidate
    try:
        with np.errstate(all="ignore"):
            if task.start is not None:
                fit = climb_from(task.start, task.done, train, cand.structure, **cand.options)
            else:
                fit = fit_model(train, cand.structure, **cand.options)
            model = fit.model
            if not model.is_stable():
                raise EstimationError("unstable")
            scored = evaluate(model, test, "simulation", initial_samples=task.n_init)
            rmse, relative = _pooled(scored, test)
            if not math.isfinite(rmse):
                raise EstimationError("its free-run simulation of the held-back fold is not finite")
            trust = assess(model, train, test)
        reasons = trust.reasons
        if reasons:
            raise EstimationError(reasons[0])
        n_par = model.n_free_parameters
    except Exception as exc:  # noqa: BLE001 - one candidate must not end the search
        return FoldScore(reason=_reason(exc), seconds=time.perf_counter() - t0)
    kept = model if keeps_fold_models(cand) else None
    return FoldScore(rmse, relative, n_par, "", trust, time.perf_counter() - t0, kept)


# ----------------------------------------------------------------------------- the search
class _Search:
    """The fold plan, the runner, every score so far, and the rules that rank them."""

    def __init__(
        self,
        data: Dataset,
        plan: FoldPlan,
        runner: TaskRunner,
        effort: Effort,
        rule: str,
        tie: float,
        deadline: float | None,
        progress: Progress | None,
        refit_failed: float,
    ) -> None:
        self.data = data
        self.plan = plan
        self.runner = runner
        self.effort = effort
        self.rule = rule
        self.tie = tie
        self.refit_failed = refit_failed
        self.deadline = deadline
        self.progress = progress
        self.scores: dict[tuple[Any, ...], Score] = {}
        self.order: list[Score] = []
        self.cut = False
        self.stages: list[dict[str, Any]] = []
        self.raced: list[dict[str, Any]] = []  # candidates a race left out (:meth:`_race`)
        #: finalists left unfitted, too far behind the best (``stages.FINALIST_REACH``)
        self.out_of_reach: list[dict[str, Any]] = []
        #: (candidate key, training segments, limit) -> that fit's model, for a climb
        self.fold_models: dict[tuple[Any, ...], Any] = {}
        shortest = min(s.n_samples for f in plan.folds for s in f.test)
        self.n_init = int(min(50, max(10, shortest // 10)))
        y = np.vstack([e.y for e in data.experiments])
        self.spread = float(np.mean(np.where(y.std(axis=0) > 0, y.std(axis=0), 1.0)))
        self.long = sum(e.n_samples for e in data.experiments) >= LONG_RECORD

    def expired(self) -> bool:
        return self.deadline is not None and time.monotonic() > self.deadline

    def run(
        self,
        stage: str,
        candidates: Sequence[Candidate],
        screen: bool,
        capped: bool = True,
        race: bool = False,
    ) -> list[Score]:
        """Score ``candidates`` (each fit once: a candidate scored before is not fitted
        again) on every fold; returns their scores in order (the new and the old).
        ``capped=False``: the time limit does not apply (the delay scan, so that a cut
        search still has a model). ``race``: on a long record, the new candidates are
        raced (:meth:`_race`): only those that lead on the first fold are scored on
        the others."""
        candidates = unique(candidates)
        new = [c for c in candidates if c.key not in self.scores]
        limit = None
        if self.long:
            limit = self.effort.screen_samples if screen else self.effort.final_samples
        raced = race and self.long and self.effort.race > 1 and len(self.plan) > 1
        if raced and len(new) >= RACE_MIN:
            scored = self._race(stage, new, limit, capped)
        else:
            scored = self._fold_scores(stage, new, self.plan, limit, capped)
        for cand, folds in zip(new, scored, strict=True):
            if folds is None:
                continue  # cut by the time limit (or raced out): not scored
            score = self._combine(cand, stage, folds)
            self.scores[cand.key] = score
            self.order.append(score)
        return [self.scores[c.key] for c in candidates if c.key in self.scores]

    def _race(
        self, stage: str, candidates: list[Candidate], limit: int | None, capped: bool
    ) -> list[list[FoldScore] | None]:
        """Successive halving in one round: every candidate fitted and scored on the
        first fold; the best ``1 / effort.race`` of them (at least ``RACE_MIN``, ties by
        label) on the other folds as well, and with them every candidate within the
        search's ``tie`` of the best first fold (one fold does not tell near-ties apart,
        and among them the simplest is chosen) and every linear one (the comparators of
        the rule that keeps a model beyond linear). Each fold's fit is the one the full stage
        would make, so a candidate that carries on gets the very score it would have
        had; one that fails the first fold is rejected with its reason, as before; the
        others are left out, recorded in :attr:`raced` with their first fold's error.
        ``docs/identify.md`` (racing) has the study behind the rule."""
        first_plan = FoldPlan(self.plan.folds[:1], self.plan.text)
        rest_plan = FoldPlan(self.plan.folds[1:], self.plan.text)
        first = self._fold_scores(stage, candidates, first_plan, limit, capped)
        record = self.stages.pop()
        ok = [j for j, f in enumerate(first) if f is not None and not f[0].reason]
        ok.sort(key=lambda j: (first[j][0].relative, candidates[j].label))  # type: ignore[index]
        keep = max(RACE_MIN, math.ceil(len(candidates) / self.effort.race))
        best = first[ok[0]][0].relative if ok else math.inf  # type: ignore[index]
        kept = [
            j
            for rank, j in enumerate(ok)
            if rank < keep
            or first[j][0].relative <= best * (1.0 + self.tie)  # type: ignore[index]
            or STRUCTURES[candidates[j].structure].linear  # the linear rule's comparators
        ]
        carried = set(kept)
        dropped = [j for j in ok if j not in carried]
        rest = self._fold_scores(stage, [candidates[j] for j in kept], rest_plan, limit, capped)
        second = self.stages.pop()
        out: list[list[FoldScore] | None] = [
            f if f is not None and f[0].reason else None for f in first
        ]
        for j, more in zip(kept, rest, strict=True):
            out[j] = None if more is None else [*first[j], *more]  # type: ignore[misc]
        for j in dropped:
            self.raced.append(
                {
                    "candidate": candidates[j].label,
                    "stage": stage,
                    "fold": self.plan.folds[0].name,
                    "relative": first[j][0].relative,  # type: ignore[index]
                }
            )
        self.stages.append(
            {
                "stage": stage,
                "candidates": len(candidates),
                "fits": record["fits"] + second["fits"],
                "seconds": round(record.get("seconds", 0.0) + second.get("seconds", 0.0), 3),
                "raced": {
                    "first_fold": self.plan.folds[0].name,
                    "carried_on": len(kept),
                    "left_out": len(dropped),
                },
            }
        )
        return out

    def score_on(
        self, plan: FoldPlan, stage: str, candidates: Sequence[Candidate]
    ) -> list[list[FoldScore]] | None:
        """Every candidate's fold scores on another fold ``plan`` (with the training
        limit of a finalist), in the order given; not kept among the search's scores.
        None when the time limit cuts it."""
        limit = self.effort.final_samples if self.long else None
        results = self._fold_scores(stage, candidates, plan, limit)
        if any(r is None for r in results):
            return None
        return [r for r in results if r is not None]

    def _fold_scores(
        self,
        stage: str,
        candidates: Sequence[Candidate],
        plan: FoldPlan,
        limit: int | None,
        capped: bool = True,
    ) -> list[list[FoldScore] | None]:
        """Each candidate fitted and scored on every fold of ``plan`` (in a worker, the
        stage recorded with its time, progress reported): its fold scores in order, or
        None where the time limit (when ``capped``) cut it, and ``cut`` is then set."""
        tasks = [self._task(c, fold, limit) for c in candidates for fold in plan.folds]
        t0 = time.perf_counter()
        self.stages.append({"stage": stage, "candidates": len(candidates), "fits": len(tasks)})
        if capped and self.expired():
            tasks = []
        continued = sum(t.start is not None for t in tasks)
        if continued:  # fits that start from the fold's model of the degree below
            self.stages[-1]["continued"] = continued
        count = [0]
        k = len(plan)

        def done(i: int, result: FoldScore) -> None:
            count[0] += 1
            if self.progress is not None:
                self.progress(stage, count[0], len(tasks), candidates[i // k].label)

        deadline = self.deadline if capped else None
        results = self.runner.map(_fit_and_score, tasks, done=done, deadline=deadline)
        out: list[list[FoldScore] | None] = []
        for i, result in enumerate(results):
            if result is not None and result.model is not None:  # a climb's start, kept here
                task = tasks[i]
                self.fold_models[task.candidate.key, task.fold.train, limit] = result.model
                results[i] = replace(result, model=None)
        for j in range(len(candidates)):
            folds = results[j * k : (j + 1) * k]
            complete = len(folds) == k and all(f is not None for f in folds)
            out.append(list(folds) if complete else None)
        if any(f is None for f in out):
            self.cut = True
        self.stages[-1]["seconds"] = round(time.perf_counter() - t0, 3)
        return out

    def _task(self, cand: Candidate, fold: Fold, limit: int | None) -> _Task:
        """The fit of ``cand`` on ``fold``: a climb whose degree below was fitted on the
        same training data continues from that model (:func:`climb_base`)."""
        base = climb_base(cand)
        start = None if base is None else self.fold_models.get((base[0], fold.train, limit))
        if start is None:
            return _Task(cand, fold, limit, self.n_init)
        return _Task(cand, fold, limit, self.n_init, start, base[1])

    def final_fits(self, score: Score) -> list[tuple[str, _Started]]:
        """The candidate of ``score`` fitted on all estimation data directly (here, on as
        many threads as there are workers) and, when that fit
        simulates its own data more than ``REFIT_SLACK`` times worse than the folds
        simulated data they never saw (pooled), from its models of its
        ``warm_starts`` best folds (by held-back error), in the workers: each start's
        name and result, the direct fit first. The time limit cuts the warm starts,
        never the direct fit (a cut search still returns a model)."""
        from blockid.fitting.threads import fit_threads
        from blockid.workflows.parallel import _single_threaded

        cand = score.candidate
        limit = self.effort.final_samples if self.long else None
        parts = tuple(s for f in self.plan.folds for s in f.test)
        t0 = time.perf_counter()
        self.stages.append({"stage": "refit", "candidates": 1, "fits": 1})
        with _single_threaded(), fit_threads(self.runner.local_threads):
            direct = _final_fit(self.data, _Start(cand, None, limit, self.n_init, score.rmse))
        out = [("the direct fit", direct)]
        eff = self.effort
        count = min(eff.warm_starts_long if self.long else eff.warm_starts, len(score.folds))
        if direct.rmse is None or not direct.rmse > REFIT_SLACK * _fold_rmse(score) or count < 1:
            self.stages[-1]["seconds"] = round(time.perf_counter() - t0, 3)
            return out  # least squares (one optimum), or the fit found what the folds did
        if direct.fit is not None:  # scored as the warm starts are (one BLAS thread)
            with _single_threaded(), np.errstate(all="ignore"):
                direct.segment_rmse = _segment_rmse(direct.fit.model, self.data, parts, self.n_init)
        best = sorted(range(len(score.folds)), key=lambda i: (score.folds[i].relative, i))
        folds = [self.plan.folds[i] for i in best[:count]]
        tasks = [_Start(cand, fold, limit, self.n_init, score.rmse, parts) for fold in folds]
        self.stages[-1]["fits"] += len(tasks)
        count_done = [0]

        def done(i: int, result: Any) -> None:
            count_done[0] += 1
            if self.progress is not None:
                self.progress("warm starts", count_done[0], len(tasks), cand.label)

        results = self.runner.map(_final_fit, tasks, done=done, deadline=self.deadline)
        self.stages[-1]["seconds"] = round(time.perf_counter() - t0, 3)
        if any(r is None for r in results):
            self.cut = True  # the warm starts the limit cut are left out
        return out + [
            (f"the model fitted without {f.name}", r)
            for f, r in zip(folds, results, strict=True)
            if r is not None
        ]

    def _combine(self, cand: Candidate, stage: str, folds: list[FoldScore]) -> Score:
        score = Score(cand, stage, list(folds), seconds=sum(f.seconds for f in folds))
        failed = [(i, f) for i, f in enumerate(folds) if f.reason]
        if failed:
            i, f = failed[0]
            score.reason = f"{f.reason} ({self.plan.folds[i].name})"
            return score
        rel = np.array([f.relative for f in folds])
        agg = _combine_folds(rel, self.rule)
        score.rmse = agg * self.spread
        score.fit_percent = 100.0 * (1.0 - agg)
        score.n_parameters = max(f.n_parameters for f in folds)
        flags: list[str] = []
        for f in folds:
            for note in f.trust.flags if f.trust is not None else []:
                if note not in flags:
                    flags.append(note)
        score.flags = flags
        return score

    def ranked(self, scores: Sequence[Score] | None = None) -> list[Score]:
        """Best first; among near-ties of the best, the fewest parameters first; flagged
        candidates after the unflagged ones of the same tie group."""
        pool = [s for s in (self.order if scores is None else scores) if s.ok]
        ordered = sorted(pool, key=lambda s: (s.rmse, s.n_parameters, s.candidate.label))
        if not ordered:
            return []
        best = ordered[0].rmse
        near = [s for s in ordered if s.rmse <= best * (1.0 + self.tie)]
        # then the longer delay: a delay too short adds a coefficient the data set to 0
        near.sort(
            key=lambda s: (bool(s.flags), s.n_parameters, -_delay(s), s.rmse, s.candidate.label)
        )
        return near + [s for s in ordered if s not in near]


def _logs(relative: Any) -> np.ndarray:
    """The logs of the folds' relative errors (an exact fit counts as 1e-300)."""
    return np.log(np.maximum(relative, 1e-300))


def _combine_folds(relative: np.ndarray, rule: str) -> float:
    """One number from the folds' relative errors (:data:`RULES`)."""
    if rule == "geometric-mean":
        return float(np.exp(np.mean(_logs(relative))))
    if rule == "median":
        return float(np.median(relative))
    return float(np.mean(relative))


def _delay(score: Score) -> int:
    nk = score.candidate.options.get("nk", 0)
    return int(nk) if isinstance(nk, int) else int(np.min(nk)) if isinstance(nk, tuple) else 0


def _beyond_linear(score: Score) -> bool:
    return not STRUCTURES[score.candidate.structure].linear or bool(
        score.candidate.options.get("integrator")
    )


def _earned(eligible: list[Score]) -> tuple[list[Score], dict[str, Any] | None]:
    """``eligible`` with the best linear candidate first when the best candidate is
    beyond linear but does not beat it consistently over the folds (module docstring),
    and the comparison's numbers (None when the order stands or there is nothing to
    compare with)."""
    best = eligible[0]
    if not _beyond_linear(best):
        return eligible, None
    base = next((s for s in eligible if not _beyond_linear(s)), None)
    if base is None or len(best.folds) != len(base.folds) or len(best.folds) < 2:
        return eligible, None
    d = _logs([f.relative for f in best.folds]) - _logs([f.relative for f in base.folds])
    mean, se = float(np.mean(d)), float(np.std(d, ddof=1) / math.sqrt(len(d)))
    wins = int(np.sum(d < 0))
    kept = mean < -LINEAR_MARGIN * se
    info = {
        "best": best.candidate.label,
        "linear": base.candidate.label,
        "mean_log_ratio": mean,
        "standard_error": se,
        "folds_won": wins,
        "folds": len(d),
        "margin": LINEAR_MARGIN,
        "linear_chosen": not kept,
    }
    if kept:
        return eligible, info
    return [base] + [s for s in eligible if s is not base], info


def _integrating(score: Score) -> bool:
    return bool(score.candidate.options.get("integrator"))


def _long_horizon(
    search: _Search, eligible: list[Score], notes: list[str]
) -> tuple[list[Score], dict[str, Any] | None]:
    """``eligible`` with the integrating candidates put last when the first is one and it
    does not beat the best linear model without integrator over the estimation data's
    two halves as well (module docstring), and the check's numbers. None when the first
    candidate has no integrator, there is no linear model to compare it with, the folds
    already are the halves or whole experiments (no longer horizon to check), or the
    time limit cut the check. A fit that fails on a half counts against its model; when
    the linear model's does, the order stands (``checked`` False)."""
    best = eligible[0]
    if not _integrating(best):
        return eligible, None
    base = next((s for s in eligible if not _beyond_linear(s)), None)
    if base is None or len(search.plan) <= 2 or len(search.data.experiments) >= 3:
        return eligible, None
    halves = fold_plan(search.data, 2)
    pair = search.score_on(halves, "long horizon", [best.candidate, base.candidate])
    if pair is None:
        return eligible, None
    failed = [next((f.reason for f in folds if f.reason), None) for folds in pair]
    scores = [
        None
        if why
        else _combine_folds(np.array([f.relative for f in folds]), search.rule) * search.spread
        for folds, why in zip(pair, failed, strict=True)
    ]
    info: dict[str, Any] = {
        "integrating": best.candidate.label,
        "linear": base.candidate.label,
        "folds": halves.text,
        "integrating_rmse": scores[0],
        "linear_rmse": scores[1],
        "integrating_fold_rmse": [None if f.reason else f.rmse for f in pair[0]],
        "linear_fold_rmse": [None if f.reason else f.rmse for f in pair[1]],
        "integrating_failed": failed[0],
        "linear_failed": failed[1],
        "checked": scores[1] is not None,
    }
    if scores[1] is None:  # no linear yardstick over the halves: the order stands
        info["integrator_kept"] = True
        return eligible, info
    kept = scores[0] is not None and scores[0] < scores[1]
    info["integrator_kept"] = kept
    if kept:
        return eligible, info
    how = f"its fit on a half failed ({failed[0]})" if failed[0] else f"it erred {scores[0]:.4g}"
    notes.append(
        f"{best.candidate.label} scored best, but an integrator's free-run error grows with "
        f"the horizon: fitted on one half of the estimation data and simulated over the "
        f"other, {how}, against {scores[1]:.4g} for the linear {base.candidate.label}, so "
        "the candidates with an integrator were put after the others"
    )
    return [s for s in eligible if not _integrating(s)] + [
        s for s in eligible if _integrating(s)
    ], info


def one_record_note(data: Dataset, folds: int) -> list[str]:
    """The note of a model beyond linear chosen on the folds of one short record: more
    experiments would test the choice on records it has not seen (``docs/identify.md``,
    the tanks study)."""
    n = data.experiments[0].n_samples
    if len(data.experiments) > 1 or n >= LONG_RECORD:
        return []
    return [
        f"chosen beyond linear on {folds} folds of one record of {n} samples: on a short "
        "record, one record's folds can favour a model that does worse on another record "
        "of the same plant (docs/identify.md, the tanks study); give every estimation "
        "experiment you have (several files, or --experiment-column): with three or more, "
        "each fold holds a whole experiment back"
    ]


def identify(
    data: Dataset,
    validation: Dataset | None = None,
    *,
    structures: Sequence[str] | None = None,
    effort: str | Effort = "standard",
    jobs: int | None = None,
    scheduler: Any = None,
    time_limit: float | None = None,
    rule: str = "geometric-mean",
    tie: float = TIE,
    refit_failed: float = REFIT_FAILED,
    use_orders_test: bool = True,
    progress: Progress | None = None,
    stages: Sequence[Stage] | None = None,
) -> IdentifyResult:
    """Choose and fit a model for ``data`` by cross-validated free-run simulation (module
    docstring).

    Parameters
    ----------
    data : Dataset
        Estimation data (the only data used to choose).
    validation : Dataset, optional
        Reported on after the choice; never used to choose.
    structures : sequence of str, optional
        Structures that may be chosen (default: the registry's searched ones). With
        structures given, the result is one of them, or an error that says why none
        could be fitted. ARX fits choose the delay and orders in any case. Block
        structures need one input and one output; with several, ARX is searched.
    effort : {"quick", "standard", "thorough"} or Effort
        The search's size (:data:`EFFORTS`, or an :class:`Effort` of one's own): the
        same effort on the same data gives the same model on any machine.
    jobs : int, optional
        Worker processes, at most 64 (default: every core this process may use, at most 64).
    scheduler : str or distributed.Client or cluster, optional
        Fit the candidates on this dask cluster instead of local worker processes (an
        address such as ``tcp://host:8786``, a client or a cluster): the record is sent
        to each worker once, and the model is the one ``jobs=1`` gives, bit for bit. The
        refit on all the data runs here. Not with ``jobs``.
    time_limit : float, optional
        Seconds after which no new fit starts (a safety cap; the result then says it was
        cut and may differ from an uncut run). None: no cap.
    rule : {"geometric-mean", "median", "mean"}
        How a candidate's fold scores are combined (module docstring).
    tie : float
        Relative score within which the candidate with fewer parameters wins.
    refit_failed : float
        A chosen candidate whose fit on all estimation data simulates those data more
        than this factor worse than its folds simulated data they never saw is refused,
        and the next one fitted (:data:`~blockid.workflows.refit.REFIT_FAILED`).
    use_orders_test : bool
        Add the false-nearest-neighbours delay and centre the order grid on its orders.
    progress : callable, optional
        ``progress(stage, done, total, label)`` after every fit.
    stages : sequence of Stage, optional
        The search's stages, run in order (default:
        :data:`blockid.workflows.stages.STAGES`): a search of one's own adds or leaves
        out a :class:`~blockid.workflows.stages.Stage`. Every candidate a stage scores is
        ranked, chosen among and reported like the others.

    Returns
    -------
    IdentifyResult
    """
    t_start = time.perf_counter()
    if not isinstance(data, Dataset):
        raise DataError(f"identify needs a blockid Dataset, got {type(data).__name__}")
    eff, asked = check_search(structures, effort, rule, jobs, time_limit, scheduler)
    if not refit_failed > 0:
        raise ParameterError(
            f"refit_failed must be a positive factor, got {refit_failed!r}",
            parameter="refit_failed",
        )
    refuse_constant_inputs(data)  # before any fold: it names the input, they would not
    chosen = asked or list(searched_structures())
    notes: list[str] = []
    if data.n_inputs != 1 or data.n_outputs != 1:
        block = [s for s in chosen if STRUCTURES[s].block_oriented]
        if block and asked:
            multi = [s for s in STRUCTURES if not STRUCTURES[s].block_oriented]
            raise ParameterError(
                f"{', '.join(block)} take one input and one output; the data have "
                f"{data.n_inputs} input(s) and {data.n_outputs} output(s): search "
                f"{', '.join(multi)}",
                parameter="structures",
            )
        if block:
            notes.append(
                "several inputs or outputs: the chain structures (one input, one output) "
                "are not searched; the block models of several inputs and outputs "
                "(block-state-space) are"
            )
        chosen = [s for s in chosen if not STRUCTURES[s].block_oriented] or [LINEAR]
    n_samples = sum(e.n_samples for e in data.experiments)
    plan = fold_plan(data, eff.folds if n_samples < LONG_RECORD else eff.folds_long)
    deadline = None if time_limit is None else time.monotonic() + float(time_limit)

    evidence, recommended = None, None
    if use_orders_test and data.n_outputs == 1:
        try:
            from blockid.fitting.orders import false_nearest_neighbours

            evidence = false_nearest_neighbours(data)
            recommended = tuple(int(v) for v in evidence.recommended)
        except (BlockidError, ImportError) as exc:
            notes.append(f"orders test skipped: {exc}")

    distortion = distortion_record(data, notes)  # periodic data: the BLA's distortion
    horizon: dict[str, Any] | None = None
    warm: list[dict[str, Any]] = []
    fit, selected = None, None
    short: tuple[Score, Any] | None = None  # the first refit that fell short, kept
    with TaskRunner(data, jobs, scheduler) as runner:
        search = _Search(data, plan, runner, eff, rule, tie, deadline, progress, refit_failed)
        run_stages(search, chosen, recommended, notes, asked=bool(asked), stages=stages)
        for raced in (r["raced"] for r in search.stages if "raced" in r):
            notes.append(
                f"a long record: the structures were raced, each scored on "
                f"{raced['first_fold']} first and the best {raced['carried_on']} on every "
                f"fold; {raced['left_out']} were left out there (search.raced_out in the "
                "JSON lists them with that fold's error)"
            )
        if search.out_of_reach:
            far = search.out_of_reach
            notes.append(
                f"{len(far)} finalist(s) not fitted again, more than {FINALIST_REACH:g} times "
                f"the best model's cross-validated error ({far[0]['best']:.4g}): "
                + ", ".join(f"{f['label']} ({f['cv_rmse']:.4g})" for f in far)
            )
        ranked_all = search.ranked()
        eligible = [s for s in ranked_all if s.candidate.structure in chosen]
        if not eligible:
            raise EstimationError(_nothing_fitted(search, chosen))
        eligible, earned = _earned(eligible)
        eligible, horizon = _long_horizon(search, eligible, notes)
        if horizon is not None and not horizon["integrator_kept"]:
            eligible, earned = _earned(eligible)
        for s in eligible:
            if progress is not None:
                progress("refit", 0, 1, s.candidate.label)
            try:
                fit, tried = _final(search, s, notes)
                if tried is not None:
                    warm.append(tried)
            except BlockidError as exc:
                fit = None
                if isinstance(exc, RefitFellShort) and short is None:
                    short = (s, exc.fit)
                notes.append(f"{s.candidate.label} failed on all estimation data ({_reason(exc)}); "
                             "the next candidate was fitted instead")  # fmt: skip
                continue
            selected = s
            break
    if (fit is None or selected is None) and short is not None:
        selected, fit = short
        notes.append(
            f"every candidate's refit failed; {selected.candidate.label}'s, which fell short "
            "of its folds but was trusted, is returned"
        )
    if fit is None or selected is None:
        raise EstimationError(_nothing_fitted(search, chosen))
    if earned is not None and earned["linear_chosen"]:
        chose = selected is eligible[0]
        notes.append(
            f"{earned['best']} scored best but did not beat the linear {earned['linear']} "
            f"consistently over the folds (it won {earned['folds_won']} of "
            f"{earned['folds']}; mean log error ratio {earned['mean_log_ratio']:+.3f}, "
            f"standard error {earned['standard_error']:.3f}, needed below "
            f"-{earned['margin']:g} standard errors): "
            + (
                "the linear model is chosen"
                if chose
                else "the linear model was put first, but its refit failed"
            )  # fmt: skip
        )
    if _beyond_linear(selected):
        notes += one_record_note(data, len(plan))
    if progress is not None:
        progress("refit", 1, 1, selected.candidate.label)

    from blockid.evaluation.validate import score_model

    target, on = (validation, "validation") if validation is not None else (data, "estimation")
    simulation, one_step, one_step_error = score_model(fit.model, target)
    if validation is None:
        notes.append(
            "no validation data: the scores are on the estimation data, which also chose "
            "the model (optimistic)"
        )
    if search.cut:
        notes.append(
            f"the time limit ({time_limit:g} s) cut the search: candidates not fitted by then "
            "were left out, and another run may choose differently"
        )
    ranked = [selected] + [s for s in ranked_all if s is not selected]
    rejected = [s for s in search.order if not s.ok]
    info = {
        "effort": eff.name,
        "effort_settings": eff.to_dict(),
        "jobs": runner.jobs,
        "scheduler": runner.address,
        "rule": rule,
        "folds": plan.to_dict(data),
        "initial_samples": search.n_init,
        "stages": search.stages,
        "raced_out": search.raced,
        "out_of_reach": search.out_of_reach,
        "cut_by_time_limit": search.cut,
        "time_limit": time_limit,
        "beyond_linear": earned,
        "long_horizon": horizon,
        "warm_starts": warm,
        "distortion": distortion,
    }
    return IdentifyResult(
        selected=selected,
        fit=fit,
        ranked=ranked,
        rejected=rejected,
        simulation=simulation,
        one_step=one_step,
        one_step_error=one_step_error,
        on=on,
        seconds=time.perf_counter() - t_start,
        holdout=f"{plan.text}, each scored by free run from its first {search.n_init} samples",
        orders_evidence=evidence,
        notes=notes,
        search=info,
    )


def _nothing_fitted(search: _Search, chosen: Sequence[str]) -> str:
    failed = [s for s in search.order if s.candidate.structure in chosen and not s.ok]
    why = "; ".join(f"{s.candidate.label}: {s.reason}" for s in failed[:3])
    return (
        f"no candidate of {', '.join(chosen)} could be fitted and trusted on these data"
        + (f" ({why})" if why else "")
        + "; try other structures, or more data"
    )
