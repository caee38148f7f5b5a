"""One-command identification: search structures, orders, delays and nonlinearities.

``identify(data)`` chooses a model for a user's record using **only the estimation
data**, scored as the user will use the model: by free-run simulation.

1. **Hold-out.** With several experiments the last one is held out; with one, the last
   ``holdout`` fraction of it (default 25 %). Candidates are fitted on the rest and
   scored by the RMSE of their free-run simulation on the held-out part (a tail is
   simulated from the start of its experiment, so it starts from the model's own state;
   a held-out experiment from its first measured outputs).
2. **Linear orders.** Least-squares ARX models over a grid of ``na, nb, nk`` (centred
   on the false-nearest-neighbours recommendation, :mod:`blockid.fitting.orders`, when
   the record allows it), scored on the hold-out; the best few order sets (stable ones
   only) carry on.
3. **Structures.** With the best orders: output-error, Hammerstein (polynomial,
   two-segment polynomial and piecewise-linear input blocks), Wiener, Hammerstein-Wiener,
   Wiener-Hammerstein (from the BLA), linear with static feedback, backlash — each fitted
   by the simulation-error method with a short iteration budget (long records are
   screened on their first ``screen_samples``), centred or not where that matters (the
   two-segment polynomial's break sits at ``u = 0``). A candidate that fails, is
   unstable or does not simulate finitely is **rejected with its reason**, not ranked.
   When the estimation data suggest a plant that integrates (the best least-squares ARX
   models have poles within ``INTEGRATING_POLE`` of +1), the structures that take an
   integrator are tried first with one (and, for two such poles, two) integrators
   after their linear block, which then has ``n`` fewer poles and one sample less delay.
4. **Selection.** Ranked by hold-out RMSE; among near-ties (within ``tie`` = 2 % of the
   best RMSE) the one with the fewest parameters wins. The best few are fitted again
   with the full iteration budget, re-scored, and the winner (again parsimonious among
   near-ties) is offered a richer nonlinearity (each polynomial degree + 2, kept only
   when the hold-out error falls by more than ``tie``) and refitted on **all**
   estimation data, starting from its estimate.

Validation data, when given, are used only after the choice, to report.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from blockid.data.dataset import Dataset, Experiment
from blockid.errors import BlockidError, DataError, ParameterError
from blockid.fitting.registry import STRUCTURES

__all__ = ["Candidate", "Score", "IdentifyResult", "identify", "DEFAULT_SEARCH", "INTEGRATING_POLE"]

#: Structures searched by default (when registered).
DEFAULT_SEARCH = (
    "arx",
    "output-error",
    "feedback",
    "hammerstein",
    "wiener",
    "hammerstein-wiener",
    "wiener-hammerstein",
    "backlash",
)

Progress = Callable[[str, int, int, str], None]

#: Options that set how long a fit iterates, not which model it is.
_ITERATION_SETTINGS = ("max_nfev", "tail_fraction", "patience")

#: The linear structure of the order search (least squares: fast over a grid).
LINEAR = "arx"
OUTPUT_ERROR = "output-error"

#: A least-squares ARX pole this close to +1 suggests that the plant integrates.
INTEGRATING_POLE = 1e-2


@dataclass(frozen=True)
class Candidate:
    """A structure and its fit options (orders, blocks, centring)."""

    structure: str
    options: dict[str, Any]

    @property
    def label(self) -> str:
        shown = ", ".join(
            f"{k}={v}" for k, v in self.options.items() if k not in _ITERATION_SETTINGS
        )
        return f"{self.structure}({shown})"

    def orders(self) -> dict[str, Any]:
        return {k: self.options[k] for k in ("na", "nb", "nk") if k in self.options}


@dataclass
class Score:
    """A candidate's result on the hold-out (or why it was rejected)."""

    candidate: Candidate
    rmse: float = np.inf
    fit_percent: float = -np.inf
    n_parameters: int = 0
    seconds: float = 0.0
    stage: str = ""
    reason: str = ""
    model: Any = None

    @property
    def ok(self) -> bool:
        return not self.reason

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "structure": self.candidate.structure,
            "options": _jsonable(self.candidate.options),
            "stage": self.stage,
            "seconds": round(self.seconds, 3),
        }
        if self.reason:
            out["rejected"] = self.reason
        else:
            out.update(
                holdout_rmse=self.rmse, holdout_fit_percent=self.fit_percent,
                n_parameters=self.n_parameters,
            )  # fmt: skip
        return out


@dataclass(frozen=True)
class IdentifyResult:
    """What :func:`identify` chose and everything it tried.

    Attributes
    ----------
    selected : Score
        The chosen candidate (its hold-out score).
    fit : FitResult
        The chosen candidate refitted on all estimation data; ``fit.model`` is the model.
    ranked : list of Score
        Candidates that were scored, best first (the selected one first).
    rejected : list of Score
        Candidates that failed, with their reasons.
    simulation, one_step : ModelOutput or None
        Scores of the model on the validation data (or on the estimation data when no
        validation data were given: see ``on``).
    on : str
        ``"validation"`` or ``"estimation"``.
    seconds : float
    holdout : str
        How the estimation data were split for choosing.
    """

    selected: Score
    fit: Any
    ranked: list[Score]
    rejected: list[Score]
    simulation: Any
    one_step: Any
    one_step_error: str | None
    on: str
    seconds: float
    holdout: str
    orders_evidence: Any = None
    notes: list[str] = field(default_factory=list)

    @property
    def model(self) -> Any:
        return self.fit.model

    def to_dict(self) -> dict[str, Any]:
        sel = self.selected.candidate
        selected: dict[str, Any] = {
            "structure": sel.structure,
            "orders": sel.orders(),
            "options": _jsonable({k: v for k, v in sel.options.items() if k not in sel.orders()}),
            "method": self.fit.method,
            "holdout_rmse": self.selected.rmse,
            "scored_on": self.on,
            "simulation": _flat(self.simulation.metrics) if self.simulation else None,
            "one_step": _flat(self.one_step.metrics) if self.one_step else None,
        }
        if self.one_step_error:
            selected["one_step_error"] = self.one_step_error
        return {
            "selected": selected,
            "models": [s.to_dict() for s in self.ranked],
            "search": {
                "candidates": len(self.ranked) + len(self.rejected),
                "rejected": [s.to_dict() for s in self.rejected],
                "holdout": self.holdout,
                "seconds": round(self.seconds, 3),
                "notes": self.notes,
            },
        }


def _flat(metrics: dict[str, dict[str, float]]) -> dict[str, Any]:
    """``{"rmse": {"y": v}}`` -> ``{"rmse": v}`` for one output, unchanged for several."""
    if all(len(v) == 1 for v in metrics.values()):
        return {k: next(iter(v.values())) for k, v in metrics.items()}
    return metrics


def _jsonable(options: dict[str, Any]) -> dict[str, Any]:
    return {k: v if isinstance(v, int | float | str | bool) else str(v) for k, v in options.items()}


# ----------------------------------------------------------------------------- hold-out
@dataclass(frozen=True)
class _Split:
    fit: Dataset
    #: (u, y, first scored sample) per held-out record, each simulated from its start
    scored: list[tuple[np.ndarray, np.ndarray, int]]
    text: str


def _split(data: Dataset, holdout: float) -> _Split:
    exps = data.experiments
    if len(exps) >= 2:
        fit = Dataset(data.inputs, data.outputs, data.sampling_time, exps[:-1], data.source)
        last = exps[-1]
        return _Split(fit, [(last.u, last.y, 0)], f"last experiment {last.name!r} held out")
    e = exps[0]
    cut = int(round((1.0 - holdout) * e.n_samples))
    fit_exp = Experiment(e.name, e.u[:cut], e.y[:cut])
    fit = Dataset(data.inputs, data.outputs, data.sampling_time, [fit_exp], data.source)
    return _Split(
        fit, [(e.u, e.y, cut)], f"last {100 * holdout:.0f} % of the record held out ({cut}:)"
    )


def _holdout_score(model: Any, split: _Split) -> tuple[float, float]:
    """Free-run RMSE and fit percent on the held-out parts (all outputs pooled)."""
    errs, ys = [], []
    for u, y, start in split.scored:
        n0 = model.max_lag
        with np.errstate(all="ignore"):
            sim = model.simulate(u, y[:n0])
        first = max(start, n0)
        errs.append(y[first:] - sim[first:])
        ys.append(y[first:])
    err, y_all = np.concatenate(errs), np.concatenate(ys)
    if not np.all(np.isfinite(err)):
        return np.inf, -np.inf
    rmse = float(np.sqrt(np.mean(err**2)))
    spread = float(np.linalg.norm(y_all - y_all.mean(axis=0)))
    fit = 100.0 * (1.0 - float(np.linalg.norm(err)) / spread) if spread > 0 else -np.inf
    return rmse, fit


def _n_parameters(model: Any) -> int:
    if hasattr(model, "free_parameters"):
        return int(model.free_parameters().size)
    return int(sum(model.n_parameters(i) for i in range(len(model.outputs))))


# ----------------------------------------------------------------------------- stages
class _Search:
    def __init__(self, split: _Split, budget: float, progress: Progress | None) -> None:
        self.split = split
        self.t0 = time.perf_counter()
        self.budget = budget
        self.progress = progress
        self.scores: list[Score] = []
        self.notes: list[str] = []

    def left(self) -> float:
        return self.budget - (time.perf_counter() - self.t0)

    def tell(self, stage: str, done: int, total: int, label: str) -> None:
        if self.progress is not None:
            self.progress(stage, done, total, label)

    def run(self, candidate: Candidate, data: Dataset, stage: str) -> Score:
        from blockid.fitting.dispatch import fit_model

        score = Score(candidate, stage=stage)
        t = time.perf_counter()
        try:
            with np.errstate(all="ignore"):
                fit = fit_model(data, candidate.structure, **candidate.options)
            model = fit.model
            if hasattr(model, "is_stable") and not model.is_stable():
                raise ParameterError("unstable")
            score.rmse, score.fit_percent = _holdout_score(model, self.split)
            if not np.isfinite(score.rmse):
                raise ParameterError("its free-run simulation of the hold-out is not finite")
            score.model = model
            score.n_parameters = _n_parameters(model)
        except BlockidError as exc:
            score.reason = str(exc).split(". ")[0][:300] or type(exc).__name__
        except Exception as exc:  # noqa: BLE001 - one candidate must not end the search
            score.reason = f"{type(exc).__name__}: {exc}"[:300]
        score.seconds = time.perf_counter() - t
        self.scores.append(score)
        return score


def _ranked(scores: Sequence[Score], tie: float) -> list[Score]:
    """Best first; among near-ties of the best, the fewest parameters first."""
    ok = sorted((s for s in scores if s.ok), key=lambda s: s.rmse)
    if not ok:
        return []
    best = ok[0].rmse
    near = [s for s in ok if s.rmse <= best * (1.0 + tie)]
    near.sort(key=lambda s: (s.n_parameters, s.rmse))
    rest = [s for s in ok if s not in near]
    return near + rest


def _order_grid(
    recommended: tuple[int, int, int] | None, delays: Sequence[int], max_order: int
) -> list[tuple[int, int, int]]:
    """``(na, nb, nk)`` with ``nb <= na + 1`` for the given delays; the FNN recommendation's
    neighbourhood first."""
    grid = [
        (na, nb, nk) for nk in delays for na in range(1, max_order + 1) for nb in range(1, na + 2)
    ]
    if recommended is not None:
        na0, nb0, _ = recommended
        near = [g for g in grid if abs(g[0] - na0) <= 2 and abs(g[1] - nb0) <= 2]
        grid = near + [g for g in grid if g not in near]
    return grid


def _output_error_orders(arx: tuple[int, int, int], max_order: int, nfev: int) -> list[Candidate]:
    """Output-error candidates around the best ARX orders ``(na, nb, nk)``: ``na - 1`` to
    ``na + 1``, ``nb = na + 1`` (a proper best linear approximation) and the delays from
    ``nk`` down to ``max(nk - 3, 0)`` (equation error overestimates delays under output
    noise); the ARX orders themselves are scored by the structure screening."""
    na0, _, nk0 = arx
    out = []
    for nk in range(nk0, max(nk0 - 3, 0) - 1, -1):
        for na in range(max(na0 - 1, 1), min(na0 + 1, max_order) + 1):
            options = {"na": na, "nb": na + 1, "nk": nk, "max_nfev": nfev, "tail_fraction": 0.0}
            out.append(Candidate(OUTPUT_ERROR, options))
    return out


def _screen(data: Dataset, samples: int) -> Dataset:
    """The first ``samples`` of each experiment (long records are screened on a part)."""
    if all(e.n_samples <= samples for e in data.experiments):
        return data
    exps = [Experiment(e.name, e.u[:samples], e.y[:samples]) for e in data.experiments]
    return Dataset(data.inputs, data.outputs, data.sampling_time, exps, data.source)


def _nonlinear_candidates(
    structures: Sequence[str], orders: list[tuple[int, int, int]], nfev: int
) -> list[Candidate]:
    """The structures' search plans (``Structure.search`` in the registry) on every order
    set: each structure's first plan before any second one, so that a short budget still
    sees every structure once."""
    fast = {"max_nfev": nfev, "tail_fraction": 0.0}
    out: list[Candidate] = []
    usable = [STRUCTURES[s] for s in structures if s in STRUCTURES]
    usable = [d for d in usable if d.block_oriented]
    rounds = max((len(d.search) for d in usable), default=0)
    for na, nb, nk in orders:
        for r in range(rounds):
            for decl in usable:
                if r >= len(decl.search):
                    continue
                o = {"na": na, "nb": na + 1 if decl.proper else nb, "nk": max(nk, decl.min_delay)}
                accepted = decl.accepted(None)
                opts = {k: v for k, v in {**o, **decl.search[r], **fast}.items() if k in accepted}
                out.append(Candidate(decl.name, opts))
    unique, seen = [], set()
    for c in out:
        key = (c.structure, tuple(sorted(c.options.items())))
        if key not in seen:
            seen.add(key)
            unique.append(c)
    return unique


def _integrations(linear: Sequence[Score], orders: list[tuple[int, int, int]]) -> int:
    """Integrators the estimation data suggest (0, 1 or 2): the most poles within
    :data:`INTEGRATING_POLE` of +1 of the best ARX model of any kept order set (each
    fitted on the estimation data's fit part)."""
    count, seen = 0, set()
    for s in sorted(linear, key=lambda s: s.rmse):
        o = s.candidate.orders()
        key = (o["na"], o["nb"], o["nk"])
        if key not in orders or key in seen or not hasattr(s.model, "poles"):
            continue
        seen.add(key)
        poles = np.asarray(s.model.poles(), dtype=complex)
        count = max(count, int(np.sum(np.abs(poles - 1.0) < INTEGRATING_POLE)))
    return min(count, 2)


def _integrating_candidates(
    structures: Sequence[str], orders: list[tuple[int, int, int]], nfev: int, integrations: int
) -> list[Candidate]:
    """The first search plan of every structure that takes an integrator, with ``n = 1 ..
    integrations`` integrators: the linear block before them gets ``na - n`` poles and
    ``nk - 1`` delay (the integrator's sample)."""
    fast = {"max_nfev": nfev, "tail_fraction": 0.0}
    usable = [STRUCTURES[s] for s in structures if s in STRUCTURES]
    usable = [d for d in usable if "integrator" in d.accepted(None)]
    out: list[Candidate] = []
    for n in range(1, integrations + 1):
        for na, nb, nk in orders:
            for decl in usable:
                na_n = max(na - n, 1)
                o = {
                    "na": na_n,
                    "nb": na_n + 1 if decl.proper else nb,
                    "nk": max(nk - 1, decl.min_delay),
                    "integrator": n,
                }
                accepted = decl.accepted(None)
                opts = {k: v for k, v in {**o, **decl.search[0], **fast}.items() if k in accepted}
                candidate = Candidate(decl.name, opts)
                if candidate not in out:
                    out.append(candidate)
    return out


def _patient(structure: str) -> dict[str, Any]:
    """Full fits stop early only on a real rise of the held-out error: a patience of 20
    iterations where the method takes one (5 stopped long records while they improved)."""
    return {"patience": 20} if "patience" in STRUCTURES[structure].accepted(None) else {}


def _grow(winner: Score, search: _Search, data: Dataset, tie: float) -> Score:
    """Try the winner with a richer nonlinearity (each polynomial degree + 2, up to 9,
    again while it helps); keep a step only when the hold-out RMSE falls by more than
    ``tie``."""
    best = winner
    for key in ("r1", "r2", "r"):
        while True:
            degree = best.candidate.options.get(key)
            # the first step is tried even when the budget is spent: the search found
            # the structure, and its nonlinearity may be too poor (a polynomial of the
            # winner's screening degree); further steps only within the budget
            if not isinstance(degree, int) or degree + 2 > 9:
                break
            if best is not winner and search.left() <= 0:
                break
            structure = best.candidate.structure
            opts = {**best.candidate.options, key: degree + 2, **_patient(structure)}
            trial = search.run(Candidate(structure, opts), data, "grow")
            search.tell("nonlinearity", 1, 1, trial.candidate.label)
            if not (trial.ok and trial.rmse < best.rmse * (1.0 - tie)):
                break
            best = trial
    return best


def _key(candidate: Candidate) -> tuple:
    """A candidate without its iteration settings (a screened and a final fit of the same
    candidate share it)."""
    opts = {k: v for k, v in candidate.options.items() if k not in _ITERATION_SETTINGS}
    return candidate.structure, tuple(sorted(opts.items()))


def _refit(winner: Score, data: Dataset) -> Any:
    """The winner fitted on all estimation data.

    A block-oriented model is refined on simulation error from the finalist's estimate
    (its offsets kept): the search already paid for the start. ARX is refitted.
    """
    from blockid.fitting.dispatch import fit_model

    structure = winner.candidate.structure
    if STRUCTURES[structure].block_oriented and winner.model is not None:
        from dataclasses import replace

        from blockid.fitting.simulation_error import refine

        try:  # a warm start on more data: let it run (early stopping on a real rise only)
            fit = refine(winner.model, data, max_nfev=300, patience=20)
            settings = {**fit.settings, "started_from": "the search's finalist"}
            return replace(fit, settings=settings)
        except BlockidError:
            pass  # fall back to a fit from scratch
    opts = {k: v for k, v in winner.candidate.options.items() if k not in ("max_nfev",)}
    opts.pop("tail_fraction", None)
    return fit_model(data, structure, **opts)


def identify(
    data: Dataset,
    validation: Dataset | None = None,
    *,
    structures: Sequence[str] | None = None,
    budget: float = 600.0,
    holdout: float = 0.25,
    max_order: int = 8,
    max_delay: int = 20,
    linear_keep: int = 2,
    screen_samples: int = 30_000,
    screen_nfev: int = 30,
    finalists: int = 3,
    tie: float = 0.02,
    use_orders_test: bool = True,
    progress: Progress | None = None,
) -> IdentifyResult:
    """Choose and fit a model for ``data`` by free-run simulation (module docstring).

    Parameters
    ----------
    data : Dataset
        Estimation data (the only data used to choose).
    validation : Dataset, optional
        Reported on after the choice; never used to choose.
    structures : sequence of str, optional
        Structures to search (default :data:`DEFAULT_SEARCH`; block structures need one
        input and one output, otherwise only ARX is searched).
    budget : float, default 600
        Seconds for the search; stages stop starting new candidates when it is spent,
        and a refinement running when it is spent returns its best iterate so far
        (:func:`~blockid.fitting.simulation_error.time_limit`). The finalists and the
        richer-nonlinearity trial get at least a tenth of it, the final refit (which
        always runs) at least a fifth: a search ends within about 1.3 times the budget
        plus the initial estimates running at that moment.
    holdout : float, default 0.25
        Fraction of a single record held out for scoring.
    max_order, max_delay : int
        Largest ``na`` (``nb <= na + 1``) of the linear order grid, and largest delay
        ``nk`` scanned (with ``na = nb = 4``) before it: the two best delays (and the
        false-nearest-neighbours one) enter the grid.
    linear_keep : int
        Best linear order sets carried to the nonlinear structures.
    screen_samples, screen_nfev : int
        Samples and simulation-error iterations of the screening fits.
    finalists : int
        Best candidates fitted again with the full iteration budget.
    tie : float
        Relative hold-out RMSE within which the simpler candidate wins.
    use_orders_test : bool
        Centre the order grid on the false-nearest-neighbours recommendation.
    progress : callable, optional
        ``progress(stage, done, total, label)`` after every candidate.

    Returns
    -------
    IdentifyResult
    """

    from blockid.fitting.simulation_error import time_limit

    if not isinstance(data, Dataset):
        raise DataError(f"identify needs a blockid Dataset, got {type(data).__name__}")
    if not budget > 0:
        raise ParameterError(f"budget must be a positive number of seconds, got {budget!r}")
    if not 0.05 <= holdout <= 0.5:
        raise ParameterError(f"holdout must be between 0.05 and 0.5, got {holdout!r}")
    chosen = list(structures or [s for s in DEFAULT_SEARCH if s in STRUCTURES])
    unknown = [s for s in chosen if s not in STRUCTURES]
    if unknown:
        raise ParameterError(
            f"structures {unknown} are unknown; choose among {', '.join(STRUCTURES)}",
            parameter="structures",
        )
    notes: list[str] = []
    if data.n_inputs != 1 or data.n_outputs != 1:
        if any(STRUCTURES[s].block_oriented for s in chosen):
            notes.append("several inputs or outputs: only ARX models are searched")
        chosen = [s for s in chosen if not STRUCTURES[s].block_oriented] or [LINEAR]
    split = _split(data, holdout)
    search = _Search(split, float(budget), progress)
    search.notes = notes

    # orders: the false-nearest-neighbours test centres the grid
    evidence, recommended = None, None
    if use_orders_test and data.n_outputs == 1:
        try:
            from blockid.fitting.orders import false_nearest_neighbours

            # its default grid (na, nb <= 4, nk <= 3): a centre for the search, in seconds;
            # a grid as wide as the search's costs minutes on long records
            evidence = false_nearest_neighbours(split.fit)
            recommended = tuple(int(v) for v in evidence.recommended)
        except (BlockidError, ImportError) as exc:
            notes.append(f"orders test skipped: {exc}")

    # stage 1a: the delay, with a moderate fixed order (and the FNN's delay)
    probe = min(4, max_order)
    delay_scores = []
    for nk in range(0, max_delay + 1):
        cand = Candidate(LINEAR, {"na": probe, "nb": probe, "nk": nk, "center": True})
        delay_scores.append(search.run(cand, split.fit, "orders"))
        search.tell("delay", nk + 1, max_delay + 1, cand.label)
    by_delay = sorted((s for s in delay_scores if s.ok), key=lambda s: s.rmse)
    delays = [s.candidate.options["nk"] for s in by_delay[:2]]
    if recommended is not None and recommended[2] not in delays:
        delays.append(recommended[2])
    delays = delays or [1]
    # stage 1b: linear ARX orders at those delays
    grid = _order_grid(recommended, delays, max_order)
    arx_scores = list(delay_scores)
    for i, (na, nb, nk) in enumerate(grid):
        if search.left() < 0.6 * budget and len(arx_scores) >= 10:
            notes.append(f"order grid cut at {i} of {len(grid)} by the budget")
            break
        cand = Candidate(LINEAR, {"na": na, "nb": nb, "nk": nk, "center": True})
        arx_scores.append(search.run(cand, split.fit, "orders"))
        search.tell("linear orders", i + 1, len(grid), cand.label)
    best_linear = _ranked(arx_scores, tie)
    if not best_linear:
        raise ParameterError(
            "no linear model of any order in the grid simulates stably on the hold-out; "
            "check the data (input and output columns, sampling) or give more data"
        )
    orders = []
    for s in sorted(best_linear, key=lambda s: s.rmse):
        o = s.candidate.orders()
        key = (o["na"], o["nb"], o["nk"])
        if key not in orders:
            orders.append(key)
        if len(orders) >= linear_keep:
            break
    screen = _screen(split.fit, screen_samples)

    # stage 1c: the orders of the best linear approximation. ARX minimises the equation
    # error, which with output noise favours other delays and orders than the dynamics
    # a block structure's linear part needs; an output-error model is the best linear
    # approximation itself, scored by free-run simulation like everything else. Its best
    # orders near the ARX ones replace the last ARX order set carried on.
    if OUTPUT_ERROR in chosen and len(orders) >= 1 and search.left() >= 0.6 * budget:
        oe = _output_error_orders(orders[0], max_order, screen_nfev)
        for i, cand in enumerate(oe):
            if search.left() < 0.5 * budget:
                notes.append(f"output-error order scan cut at {i} of {len(oe)} by the budget")
                break
            search.run(cand, screen, "screen")
            search.tell("output-error orders", i + 1, len(oe), cand.label)
        best_oe = _ranked([s for s in search.scores if s.candidate in oe], tie)
        if best_oe:
            o = best_oe[0].candidate.orders()
            key = (o["na"], o["nb"], o["nk"])
            if key not in orders:
                orders = [*orders[: max(linear_keep - 1, 1)], key]

    # stage 2: structures on the best orders, screened
    integrations = _integrations(best_linear, orders)
    candidates = _integrating_candidates(chosen, orders, screen_nfev, integrations)
    if candidates:
        notes.append(
            f"the estimation data suggest a plant that integrates (least-squares ARX poles "
            f"within {INTEGRATING_POLE:g} of 1): {len(candidates)} candidates with up to "
            f"{integrations} integrator(s) tried first"
        )
    candidates += _nonlinear_candidates(chosen, orders, screen_nfev)
    with time_limit(search.left()):  # a refinement stops when the budget is spent
        for i, cand in enumerate(candidates):
            if search.left() < 0.35 * budget:
                notes.append(f"{len(candidates) - i} structure candidates skipped by the budget")
                break
            search.run(cand, screen, "screen")
            search.tell("structures", i + 1, len(candidates), cand.label)

    # stage 3: finalists with the full iteration budget, on the whole fit part
    screened = _ranked([s for s in search.scores if s.stage in ("screen", "orders")], tie)
    finals = []
    # the finalists and the richer nonlinearity get what is left, at least a tenth of
    # the budget; the refit at least a fifth (it always runs): past these limits a
    # refinement returns its best iterate so far
    with time_limit(max(search.left(), 0.1 * budget)):
        for i, s in enumerate(screened[:finalists]):
            cheap = not STRUCTURES[s.candidate.structure].block_oriented  # ARX: nothing to add
            if cheap or search.left() < 0.15 * budget and finals:
                finals.append(s)
                continue
            opts = {k: v for k, v in s.candidate.options.items() if k != "max_nfev"}
            opts.pop("tail_fraction", None)
            opts.update(_patient(s.candidate.structure))
            finals.append(search.run(Candidate(s.candidate.structure, opts), split.fit, "final"))
            search.tell("finalists", i + 1, min(finalists, len(screened)), s.candidate.label)
        # a full refit can score worse on the hold-out than its screening fit: rank both
        ranked_final = _ranked(finals + screened[:finalists], tie) or screened
        winner = ranked_final[0]
        if STRUCTURES[winner.candidate.structure].block_oriented:
            winner = _grow(winner, search, split.fit, tie)

    # refit on all estimation data: block models start from the finalist (warm start)
    search.tell("refit", 0, 1, winner.candidate.label)
    with time_limit(max(search.left(), 0.2 * budget)):
        fit = _refit(winner, data)
    search.tell("refit", 1, 1, winner.candidate.label)

    from blockid.evaluation.validate import evaluate

    target, on = (validation, "validation") if validation is not None else (data, "estimation")
    simulation = evaluate(fit.model, target, "simulation")
    one_step, one_step_error = None, None
    try:
        one_step = evaluate(fit.model, target, "one-step")
    except BlockidError as exc:
        one_step_error = str(exc)
    if validation is None:
        notes.append(
            "no validation data: the scores are on the estimation data, which also chose "
            "the model (optimistic)"
        )
    ok = _ranked(search.scores, tie)
    finals_seen = {_key(s.candidate) for s in ok if s.stage in ("final", "grow")}
    ok = [s for s in ok if s.stage in ("final", "grow") or _key(s.candidate) not in finals_seen]
    ranked = [winner] + [s for s in ok if s is not winner]
    rejected = [s for s in search.scores if not s.ok]
    return IdentifyResult(
        selected=winner,
        fit=fit,
        ranked=ranked,
        rejected=rejected,
        simulation=simulation,
        one_step=one_step,
        one_step_error=one_step_error,
        on=on,
        seconds=time.perf_counter() - search.t0,
        holdout=split.text,
        orders_evidence=evidence,
        notes=notes,
    )
