"""The stages of ``identify``'s search, as objects: one class per stage, run in the
order of :data:`STAGES`.

A stage reads what the stages before it found from a :class:`Context` (the structures
asked for, the delays, the ARX orders, the screening iterations), fits and scores its
candidates through the search (``search.run(stage, candidates, screen)``: every fold,
in the workers, results in a fixed order) and leaves what the next stages need in the
context. A new stage is a class with a ``name`` and a ``run(search, context)`` put in
its place in :data:`STAGES`; the search itself (:class:`blockid.workflows.identify._Search`:
folds, scores, ranking, time limit) and the choice after the stages (the selection,
the linear-unless-the-folds-agree rule, the refit) do not change. ``docs/identify.md``
describes each stage and the effort's numbers for it (:mod:`blockid.workflows.effort`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from blockid.data.dataset import Dataset
from blockid.data.folds import Segment, materialise
from blockid.errors import BlockidError, EstimationError
from blockid.fitting.registry import STRUCTURES
from blockid.workflows.effort import Effort
from blockid.workflows.search_space import (
    LINEAR,
    Candidate,
    block_state_candidates,
    delay_candidates,
    grown,
    integrating_candidates,
    n_state_space_parameters,
    order_grid,
    output_error_orders,
    polynomial_state_candidates,
    state_candidates,
    structure_candidates,
)

if TYPE_CHECKING:  # the search and its scores live in identify, which imports this
    from blockid.workflows.identify import Score, _Search

__all__ = [
    "INTEGRATING_POLE",
    "STAGES",
    "BlockStructures",
    "Context",
    "Delays",
    "Finalists",
    "LinearOrders",
    "Nonlinearity",
    "Stage",
    "StateSpaces",
    "run_stages",
]

#: ARX poles this close to +1 suggest an integrating plant (candidates with integrators).
INTEGRATING_POLE = 1e-2
#: A candidate whose score is more than this many times the best model's so far is not
#: fitted again as a finalist: its longer fit would have to cut its error by a third to
#: matter. On the 22 shared sets' standard searches (2026-11-28) none of the 29
#: finalists that started 10 % or more behind the best came closer to it by more than
#: 7 % of its error (the furthest behind, 2.64 times, ended 2.58 times; the one large
#: gain, 2.6 times on the Silverbox, was the best candidate's own), and none was
#: chosen. ``docs/identify.md`` (finalists out of reach) has the study and the record
#: of several inputs and outputs where such finalists took most of the search.
FINALIST_REACH = 1.5


@dataclass
class Context:
    """What the stages pass on to each other (the search holds the scores)."""

    chosen: Sequence[str]  # structures that may be chosen
    recommended: tuple[int, int, int] | None  # the orders test's (na, nb, nk)
    notes: list[str]  # for the user, in the result
    asked: bool = False  # the structures were named by the caller
    delays: list[Any] = field(default_factory=list)  # the delays carried on
    orders: list[tuple[int, Any, Any]] = field(default_factory=list)  # ARX order sets
    screen: dict[str, Any] = field(default_factory=dict)  # iterations of a screening fit

    @property
    def block(self) -> list[str]:
        """The block structures among those chosen."""
        return [s for s in self.chosen if STRUCTURES[s].block_oriented]

    @property
    def states(self) -> list[str]:
        """The state-space structures among those chosen."""
        return [s for s in self.chosen if STRUCTURES[s].orders == "state"]

    @property
    def iterative(self) -> list[str]:
        """The structures fitted by iterations (the finalists and growth stages')."""
        return self.block + self.states


class Stage:
    """One stage of the search: ``run`` scores its candidates through ``search`` and
    updates ``context`` for the stages after it."""

    name: str = ""

    def run(self, search: _Search, context: Context) -> None:  # pragma: no cover
        raise NotImplementedError


class Delays(Stage):
    """1. ARX models with ``na = nb = 4`` over the delays ``0 .. max_delay`` (and, with
    several inputs or outputs, each pair's own delay): the two best delays, and the
    orders test's, carry on."""

    name = "delay"

    def run(self, search: _Search, context: Context) -> None:
        eff = search.effort
        probe = min(4, eff.max_order)
        first = delay_candidates(eff.max_delay, probe)
        per_pair = _per_pair_delays(search, context.notes)
        if per_pair is not None:
            first.append(
                Candidate(LINEAR, {"na": probe, "nb": probe, "nk": per_pair, "center": True})
            )
        by_delay = search.ranked(search.run(self.name, first, False, capped=False))
        delays: list[Any] = []
        for s in by_delay:
            nk = s.candidate.options["nk"]
            if nk not in delays:
                delays.append(nk)
            if len(delays) >= 2:
                break
        recommended = context.recommended
        if recommended is not None and recommended[2] not in delays:
            delays.append(recommended[2])
        context.delays = delays or [1]


class LinearOrders(Stage):
    """2. The ARX order grid at those delays (and, with several inputs or outputs, the
    best ARX with each pair's own ``nb``): the best ``linear_keep`` order sets carry on."""

    name = "linear orders"

    def run(self, search: _Search, context: Context) -> None:
        eff = search.effort
        search.run(self.name, order_grid(context.recommended, context.delays, eff.max_order),
                   False)  # fmt: skip
        arx = search.ranked([s for s in search.order if s.candidate.structure == LINEAR])
        if not arx:
            raise EstimationError(
                "no linear model of any order in the grid simulates stably on the held-back "
                "folds; check the data (input and output columns, sampling) or give more data"
            )
        pairs = _per_pair_orders(search, arx[0], context.notes)
        if pairs is not None:  # the best ARX with each pair's unneeded coefficients dropped
            search.run("per-pair orders", [pairs], False)
            arx = search.ranked([s for s in search.order if s.candidate.structure == LINEAR])
        orders: list[tuple[int, Any, Any]] = []
        for s in arx:
            if _orders_of(s) not in orders:
                orders.append(_orders_of(s))
            if len(orders) >= eff.linear_keep:
                break
        context.orders = orders
        context.screen = _iterations(eff.screen_nfev)


class BlockStructures(Stage):
    """3-4. Output-error orders around the best ARX orders, then every block structure
    with every block family in its slots (and integrators on an integrating plant)."""

    name = "structures"

    def run(self, search: _Search, context: Context) -> None:
        if context.block:
            context.orders = _block_structures(
                search, context.block, context.orders, context.recommended, context.screen,
                context.notes,
            )  # fmt: skip


class StateSpaces(Stage):
    """5. Linear state spaces at every dimension, polynomial ones at ``state_keep`` of
    those dimensions, and block state spaces (several channels, or loop blocks)."""

    name = "state space"

    def run(self, search: _Search, context: Context) -> None:
        if context.states:
            _state_space(search, context.states, context.screen, context.asked)


class Finalists(Stage):
    """6. The best ``finalists`` candidates that iterate, fitted again with
    ``final_nfev`` iterations (new candidates, scored like every other)."""

    name = "finalists"

    def run(self, search: _Search, context: Context) -> None:
        iterative = context.iterative
        if not iterative:
            return
        pool = [s for s in search.order if s.candidate.structure in iterative]
        best = search.ranked(pool)[: search.effort.finalists]
        # out of reach of the best model that may be chosen: no longer fit (FINALIST_REACH);
        # a model scored only to guide the search (an ARX when chains were asked) does not
        # count, or the structures asked for would lose their longer fits to it
        leader = search.ranked([s for s in search.order if s.candidate.structure in context.chosen])
        if leader:
            far = [s for s in best if s.rmse > FINALIST_REACH * leader[0].rmse]
            best = [s for s in best if s not in far]
            if far:
                search.out_of_reach += [
                    {"label": s.candidate.label, "cv_rmse": s.rmse, "best": leader[0].rmse}
                    for s in far
                ]
        final = _iterations(search.effort.final_nfev)
        search.run(self.name, [_with_iterations(s.candidate, final) for s in best], False)


class Nonlinearity(Stage):
    """7. The best candidate with each polynomial degree, block size or state-space
    degree raised (a state-space degree by a climb from the degree below), kept while
    the score falls by more than the tie, up to ``grow_steps`` times."""

    name = "nonlinearity"

    def run(self, search: _Search, context: Context) -> None:
        iterative = context.iterative
        ranked = search.ranked([s for s in search.order if s.candidate.structure in iterative])
        if not ranked:
            return
        eff = search.effort
        current = ranked[0]
        signals = (search.data.n_inputs, search.data.n_outputs)
        for _ in range(eff.grow_steps):
            trials = [
                _climbing(c, signals, eff)
                for c in grown(current.candidate)
                if _affordable(c, signals, eff)
            ]
            if not trials:
                break
            scored = [s for s in search.run(self.name, trials, False) if s.ok]
            better = [s for s in scored if s.rmse < current.rmse * (1.0 - search.tie)]
            if not better:
                break
            current = min(better, key=lambda s: (s.rmse, s.candidate.label))


#: The stages, in the order they run.
STAGES: tuple[Stage, ...] = (
    Delays(),
    LinearOrders(),
    BlockStructures(),
    StateSpaces(),
    Finalists(),
    Nonlinearity(),
)


def run_stages(
    search: _Search,
    chosen: Sequence[str],
    recommended: tuple[int, int, int] | None,
    notes: list[str],
    asked: bool = False,
    stages: Sequence[Stage] | None = None,
) -> Context:
    """Run ``stages`` (default :data:`STAGES`, read when called) in order; every score
    lands in ``search``. ``asked``: the structures were named by the caller (searched
    even where the default search leaves them out). Returns the context the stages
    left."""
    context = Context(chosen, recommended, notes, asked)
    for stage in STAGES if stages is None else stages:
        stage.run(search, context)
    return context


# ----------------------------------------------------------------------------- helpers
def _iterations(nfev: int) -> dict[str, Any]:
    return {"max_nfev": nfev, "tail_fraction": 0.0}


def _integrations(data: Dataset, orders: Sequence[tuple[int, int, int]]) -> int:
    """Integrators the estimation data suggest (0, 1 or 2): the most poles within
    :data:`INTEGRATING_POLE` of +1 of a least-squares ARX of the kept orders."""
    from blockid.fitting.dispatch import fit_model

    count = 0
    for na, nb, nk in orders:
        try:
            with np.errstate(all="ignore"):
                model = fit_model(data, LINEAR, na=na, nb=nb, nk=nk, allow_unstable=True).model
        except BlockidError:
            continue
        poles = np.asarray(model.poles(), dtype=complex)
        count = max(count, int(np.sum(np.abs(poles - 1.0) < INTEGRATING_POLE)))
    return min(count, 2)


def _orders_of(score: Score) -> tuple[int, Any, Any]:
    """``(na, nb, nk)``; ``nb``, ``nk`` per-pair matrices (nested tuples) where they are."""
    o = score.candidate.orders()
    nb, nk = o["nb"], o["nk"]
    nb = nb if isinstance(nb, tuple) else int(nb)
    return int(o["na"]), nb, nk if isinstance(nk, tuple) else int(nk)


def _pair_data(search: _Search) -> Dataset:
    """The data the per-pair scans run their least squares on: a long record's first
    samples (as the screening fits)."""
    data = search.data
    if search.long:
        whole = tuple(Segment(i, 0, e.n_samples) for i, e in enumerate(data.experiments))
        data = materialise(data, whole, search.effort.screen_samples)
    return data


def _per_pair_orders(search: _Search, best: Score, notes: list[str]) -> Candidate | None:
    """With several inputs or outputs, the best ARX candidate with each pair's own
    ``nb`` (:func:`~blockid.fitting.delays.channel_orders`, at most its ``nb``) when the
    pairs differ, else None."""
    if search.data.n_inputs * search.data.n_outputs == 1:
        return None
    na, nb, nk = _orders_of(best)
    if isinstance(nb, tuple):
        return None
    from blockid.fitting.delays import channel_orders

    try:
        found = channel_orders(_pair_data(search), nk, na, nb)
    except BlockidError as exc:
        notes.append(f"per-pair orders not tested: {exc}")
        return None
    option = found.as_option()
    if isinstance(option, int) and option == nb:
        return None
    notes.append(
        f"per-pair orders by the least-squares description length, nb = {found.nb.tolist()} "
        f"(at most the best ARX's {nb}; rows: {', '.join(found.outputs)}; columns: "
        f"{', '.join(found.inputs)}), scored beside it"
    )
    return best.candidate.with_options(nb=option)


def _per_pair_delays(search: _Search, notes: list[str]) -> tuple[tuple[int, ...], ...] | None:
    """With several inputs or outputs, each pair's delay by the least-squares scan
    (:func:`~blockid.fitting.delays.channel_delays`) when the pairs differ, else None."""
    data = search.data
    if data.n_inputs * data.n_outputs == 1:
        return None
    from blockid.fitting.delays import channel_delays

    try:
        found = channel_delays(_pair_data(search), search.effort.max_delay)
    except BlockidError as exc:
        notes.append(f"per-pair delays not scanned: {exc}")
        return None
    option = found.as_option()
    if isinstance(option, int):
        return None
    notes.append(
        f"per-pair delays from the least-squares scan, nk = {found.nk.tolist()} (rows: "
        f"{', '.join(found.outputs)}; columns: {', '.join(found.inputs)}), scored beside "
        "one common delay"
    )
    return option


def _with_iterations(candidate: Candidate, iterations: dict[str, Any]) -> Candidate:
    decl = STRUCTURES[candidate.structure]
    accepted = decl.accepted(None)
    if not decl.block_oriented and "tail_fraction" not in candidate.options:
        accepted = tuple(k for k in accepted if k != "tail_fraction")  # see _state_space
    return candidate.with_options(**{k: v for k, v in iterations.items() if k in accepted})


def _affordable(candidate: Candidate, signals: tuple[int, int], effort: Effort) -> bool:
    """A polynomial state-space candidate within the effort's parameter budget and its
    largest planned degree (every other candidate is). Cross-validation on the
    estimation record cannot see how a higher degree extrapolates beyond its range
    (Silverbox: degree 5 scored 0.39 mV against degree 3's 0.57 on the folds, and its
    free run on the test record that leaves the range was 2.0 mV), so the nonlinearity
    stage does not raise a degree past what the effort plans."""
    o = candidate.options
    if "degree" not in o:
        return True
    if o["degree"] > max(d for d, _ in effort.state_plans):
        return False
    n = n_state_space_parameters(o["nx"], *signals, o["degree"], o.get("monomials", "full"))
    return n <= (effort.climb_parameters if "start_degree" in o else effort.state_parameters)


def _climbing(candidate: Candidate, signals: tuple[int, int], effort: Effort) -> Candidate:
    """A climb (``start_degree``) over the effort's ``state_parameters`` with its top
    degree limited to ``climb_nfev`` iterations: it starts from the model of the degree
    below, near its optimum (WH 2009, 6 states: 1.64 mV at degree 2, 0.604 after 40
    iterations at degree 3, 840 parameters)."""
    o = candidate.options
    if "start_degree" not in o:
        return candidate
    n = n_state_space_parameters(o["nx"], *signals, o["degree"], o.get("monomials", "full"))
    if n <= effort.state_parameters:
        return candidate
    return candidate.with_options(rung_nfev=min(effort.climb_nfev, o.get("max_nfev", 10**9)))


def _block_structures(
    search: _Search,
    block: list[str],
    orders: list[tuple[int, int, int]],
    recommended: tuple[int, int, int] | None,
    screen: dict[str, Any],
    notes: list[str],
) -> list[tuple[int, int, int]]:
    """The output-error orders and the block structures' screening; returns the order
    sets the structures were screened at."""
    eff = search.effort
    oe = output_error_orders(orders[0], eff.max_order, screen)
    best_oe = search.ranked(search.run("output-error orders", oe, True))
    if best_oe and _orders_of(best_oe[0]) not in orders:
        orders = [*orders[: max(eff.linear_keep - 1, 1)], _orders_of(best_oe[0])]
    # the false-nearest-neighbours orders are those of a nonlinear model: the linear
    # part of a block structure may need fewer lags than the best linear approximation
    if recommended is not None:
        na, nb, nk = recommended
        fnn = (max(na, 1), max(nb, 1), nk)
        if fnn not in orders:
            orders.append(fnn)
    integrations = _integrations(search.data, orders)
    candidates = integrating_candidates(block, orders, search.data, screen, integrations)
    if candidates:
        notes.append(
            f"the estimation data suggest a plant that integrates (least-squares ARX poles "
            f"within {INTEGRATING_POLE:g} of 1): {len(candidates)} candidates with up to "
            f"{integrations} integrator(s) tried first"
        )
    candidates += structure_candidates(block, orders, search.data, screen, eff.families)
    search.run("structures", candidates, True, race=True)
    return orders


def _state_space(
    search: _Search, states: list[str], screen: dict[str, Any], asked: bool = False
) -> None:
    """Linear state-space models at every state dimension up to the effort's largest
    order, then polynomial ones at ``state_keep`` of those dimensions: the best (the
    smallest among near-ties), then the largest dimension tied with it whose polynomial
    candidates fit the parameter budget, then the next best. A linear model's free-run
    error cannot tell the dynamic order apart when the nonlinear distortion dominates
    it (Wiener-Hammerstein 2009: every dimension from 4 to 8 within 0.3 %), and the
    polynomial terms need the states the dynamics have: both ends of the tie are tried.

    On a record under ``LONG_RECORD`` samples the state-space candidates keep their
    refinements' early stopping (a held-back tail: :data:`~blockid.defaults.STATE_SPACE_TAIL`),
    which the chains' screening switches off (the folds hold data back already): refined
    to convergence on a few hundred samples they fitted the noise (``docs/identify.md``).
    A long record's keep none: their fits do not fit the noise, and a tail held back in
    a fold's fit but not in the final one made the WH 2009's model worse (0.60 against
    0.57 mV) and its search 120 s longer.
    """
    eff = search.effort
    if not search.long:  # a short record's state spaces keep their early stopping
        screen = {k: v for k, v in screen.items() if k != "tail_fraction"}
    nxs = list(range(1, eff.max_order + 1))  # linear fits are cheap: every dimension
    # the linear state space gives the dimensions even when only models built on it
    # were asked for (its scores are kept, it is chosen only if asked for)
    search.run("state space", state_candidates([*states, "state-space"], nxs, screen), True)
    linear = search.ranked([s for s in search.order if s.stage == "state space"])
    if not linear:
        return
    signals = (search.data.n_inputs, search.data.n_outputs)

    def candidates(dims: list[int]) -> list[Candidate]:
        return polynomial_state_candidates(
            states, dims, eff.state_plans, signals, screen, eff.state_parameters
        )

    ranked = list(dict.fromkeys(s.candidate.options["nx"] for s in linear))
    chosen = ranked[:1]
    tied = [
        s.candidate.options["nx"] for s in linear if s.rmse <= linear[0].rmse * (1 + search.tie)
    ]
    for nx in sorted(set(tied), reverse=True):
        if len(chosen) < eff.state_keep and nx not in chosen and candidates([nx]):
            chosen.append(nx)
            break
    chosen += [nx for nx in ranked if nx not in chosen][: max(0, eff.state_keep - len(chosen))]
    found = candidates(chosen)
    if found:
        search.run("nonlinear state space", found, True)
    several = search.data.n_inputs > 1 or search.data.n_outputs > 1
    if asked or several or eff.loop_single:
        # static blocks per channel: on one input and one output the chain structures
        # (Hammerstein, Wiener, ...) hold these models with polynomial linear blocks, so
        # the default search leaves them out there and tries the loop blocks only, which
        # no chain holds (a static block on a combination of the states)
        plans = eff.block_state_plans if asked or several else ()
        blocks = block_state_candidates(states, chosen, plans, screen, eff.loop_plans)
        if blocks:
            search.run("block state space", blocks, True)
