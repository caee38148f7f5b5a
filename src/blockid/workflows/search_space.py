"""The candidates ``identify`` fits, generated from the registry and the block families.

Nothing here names a structure or a block: the structures searched by default are the
registry's ranked ones (:func:`~blockid.fitting.registry.searched_structures`), their
block slots are filled with every block family that declares the slot's role
(:attr:`~blockid.blocks.base.Block.search_specs`), and a block's richness is grown
through the option it names (:attr:`~blockid.blocks.base.Block.size_option`). A new
block or structure is searched without editing this module.

**Centring is decided from the data.** A block whose form sits at its input's zero
(:attr:`~blockid.blocks.base.Block.anchored`: a dead zone's band, a saturation's
centre, a two-segment polynomial's break) is fitted on the signal as recorded when that
signal takes both signs (the zero is then where the plant has it: a valve's direction),
and around the operating point when it does not (a 2-10 V signal has no use for a
break at 0 V): the rule ``fit`` applies by default
(:func:`~blockid.fitting.dispatch.default_centring`). Every other candidate with block
slots is fitted around the operating point.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from blockid.blocks.base import BLOCK_TYPES
from blockid.data.dataset import Dataset
from blockid.fitting.registry import STRUCTURES, Structure

__all__ = [
    "ITERATION_SETTINGS",
    "Candidate",
    "delay_candidates",
    "grown",
    "integrating_candidates",
    "n_state_space_parameters",
    "polynomial_state_candidates",
    "state_candidates",
    "order_grid",
    "output_error_orders",
    "structure_candidates",
    "unique",
]

#: Options that set how long a fit iterates, not which model it is.
ITERATION_SETTINGS = ("max_nfev", "tail_fraction", "patience", "rung_nfev")

#: The linear structure of the order search (least squares: fast over a grid).
LINEAR = "arx"
OUTPUT_ERROR = "output-error"

#: Largest polynomial degree, and knots, the richer-nonlinearity stage tries.
MAX_SIZE = {"degree": 9, "knots": 11}
#: Largest monomial degree of a state-space model it tries (grown by one).
MAX_STATE_DEGREE = 5


@dataclass(frozen=True, eq=False)
class Candidate:
    """A structure and its fit options (orders, blocks, centring, iterations)."""

    structure: str
    options: dict[str, Any]

    @property
    def key(self) -> tuple[Any, ...]:
        """Identity of the fit: structure and every option (iterations included)."""
        return self.structure, tuple(sorted(self.options.items()))

    @property
    def model_key(self) -> tuple[Any, ...]:
        """Identity of the model form: without the iteration settings."""
        opts = {k: v for k, v in self.options.items() if k not in ITERATION_SETTINGS}
        return self.structure, tuple(sorted(opts.items()))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Candidate) and self.key == other.key

    def __hash__(self) -> int:
        return hash(self.key)

    @property
    def label(self) -> str:
        shown = ", ".join(
            f"{k}={v}" for k, v in self.options.items() if k not in ITERATION_SETTINGS
        )
        return f"{self.structure}({shown})"

    def orders(self) -> dict[str, Any]:
        return {k: self.options[k] for k in ("na", "nb", "nk") if k in self.options}

    def with_options(self, **changes: Any) -> Candidate:
        return Candidate(self.structure, {**self.options, **changes})


def climb_base(candidate: Candidate) -> tuple[tuple[Any, ...], int] | None:
    """For a polynomial state space fitted degree by degree, the key of the candidate
    whose fit is this one's up to the degree below its top (the same options with that
    degree: without ``start_degree`` and ``rung_nfev`` when it is the start) and that
    degree; None for any other candidate. A fold model of that candidate, fitted on the
    same training data, is where this one's fit continues (identify's climb: the
    finalist's model is the climb's first rung, bit for bit)."""
    o = candidate.options
    if not keeps_fold_models(candidate):
        return None
    if o.get("start_degree") is None or not isinstance(o.get("degree"), int):
        return None
    first, below = max(2, int(o["start_degree"])), o["degree"] - 1
    if below < first:
        return None
    if below == first:
        base = {k: v for k, v in o.items() if k not in ("start_degree", "rung_nfev")}
        return Candidate(candidate.structure, {**base, "degree": below}).key, below
    return candidate.with_options(degree=below).key, below


def keeps_fold_models(candidate: Candidate) -> bool:
    """Whether identify keeps this candidate's fold models as the starts of a climb one
    degree up (:func:`climb_base`): those of a structure fitted degree by degree (the
    registry's ``start_degree`` option: a polynomial state space, whose models are
    small), without integrators."""
    decl = STRUCTURES.get(candidate.structure)
    climbs = decl is not None and "start_degree" in decl.accepted(None)
    return climbs and not candidate.options.get("integrator")


def unique(candidates: Iterable[Candidate]) -> list[Candidate]:
    """The candidates in order, each fit once."""
    out, seen = [], set()
    for c in candidates:
        if c.key not in seen:
            seen.add(c.key)
            out.append(c)
    return out


# ----------------------------------------------------------------------------- linear
def delay_candidates(max_delay: int, probe: int) -> list[Candidate]:
    """ARX models with ``na = nb = probe`` over the delays ``0 .. max_delay``."""
    return [
        Candidate(LINEAR, {"na": probe, "nb": probe, "nk": nk, "center": True})
        for nk in range(max_delay + 1)
    ]


def order_grid(
    recommended: tuple[int, int, int] | None, delays: Sequence[Any], max_order: int
) -> list[Candidate]:
    """ARX ``(na, nb, nk)`` with ``nb <= na + 1`` for the given delays (a number, or a
    per-pair matrix as nested tuples); the order test's neighbourhood first."""
    grid = [
        (na, nb, nk) for nk in delays for na in range(1, max_order + 1) for nb in range(1, na + 2)
    ]
    if recommended is not None:
        na0, nb0, _ = recommended
        near = [g for g in grid if abs(g[0] - na0) <= 2 and abs(g[1] - nb0) <= 2]
        grid = near + [g for g in grid if g not in near]
    return [
        Candidate(LINEAR, {"na": na, "nb": nb, "nk": nk, "center": True}) for na, nb, nk in grid
    ]


def output_error_orders(
    arx: tuple[int, int, int], max_order: int, iterations: dict[str, Any]
) -> list[Candidate]:
    """Output-error candidates around the best ARX orders ``(na, nb, nk)``: ``na - 1`` to
    ``na + 1``, ``nb = na + 1`` (a proper best linear approximation) and the delays from
    ``nk`` down to ``max(nk - 3, 0)`` (equation error overestimates delays under output
    noise)."""
    na0, _, nk0 = arx
    out = []
    for nk in range(nk0, max(nk0 - 3, 0) - 1, -1):
        for na in range(max(na0 - 1, 1), min(na0 + 1, max_order) + 1):
            options = {"na": na, "nb": na + 1, "nk": nk, **iterations}
            out.append(Candidate(OUTPUT_ERROR, options))
    return out


# ----------------------------------------------------------------------------- blocks
def _families(role: str, limit: int | None) -> list[str]:
    """Specs of the block families that take ``role``, most telling first."""
    kinds = sorted(
        (cls.search_priority, kind, cls.search_specs[role])
        for kind, cls in BLOCK_TYPES.items()
        if role in cls.search_specs
    )
    specs = [spec for _, _, spec in kinds]
    return specs if limit is None else specs[:limit]


def _block_class(spec: str) -> type:
    kind = spec.split(":", 1)[0].strip()
    return BLOCK_TYPES[kind]


def _plans(decl: Structure, families: int | None) -> list[dict[str, Any]]:
    """The slot fillings of ``decl``: one slot, every family; two slots, every family
    of each slot with the other slot's default (its first family)."""
    slots = decl.slots
    if not slots:
        return [{}]
    per_slot = [_families(role, families) for role, _ in slots]
    if any(not f for f in per_slot):
        return [{}]
    if len(slots) == 1:
        return [{slots[0][1]: spec} for spec in per_slot[0]]
    defaults = {option: fams[0] for (_, option), fams in zip(slots, per_slot, strict=True)}
    plans: list[dict[str, Any]] = []
    for (_, option), fams in zip(slots, per_slot, strict=True):
        for spec in fams:
            plan = {**defaults, option: spec}
            if plan not in plans:
                plans.append(plan)
    return plans


def _centred(decl: Structure, plan: dict[str, Any], data: Dataset) -> bool:
    """Module notes: the fit's own rule (:func:`~blockid.fitting.dispatch.default_centring`)
    where an anchored block is in the plan, centred otherwise."""
    from blockid.fitting.dispatch import default_centring
    from blockid.fitting.registry import OPTIONS

    blocks = {k: OPTIONS[k].convert(v) for k, v in plan.items() if k.endswith("_block")}
    if not any(b.anchored or not b.centred for b in blocks.values()):
        return True
    return default_centring(decl, blocks, data)


def structure_candidates(
    structures: Sequence[str],
    orders: Sequence[tuple[int, int, int]],
    data: Dataset,
    iterations: dict[str, Any],
    families: int | None = None,
) -> list[Candidate]:
    """Every block-oriented structure's plans on every order set: each structure's
    first plan before any second one, so that the most telling come first."""
    decls = [STRUCTURES[s] for s in structures if STRUCTURES[s].block_oriented]
    plans = {
        d.name: [{**p, **extra} for extra in d.search for p in _plans(d, families)] for d in decls
    }
    rounds = max((len(p) for p in plans.values()), default=0)
    out = []
    for na, nb, nk in orders:
        for r in range(rounds):
            for decl in decls:
                if r < len(plans[decl.name]):
                    out.append(
                        _candidate(decl, plans[decl.name][r], (na, nb, nk), data, iterations)
                    )
    return unique(out)


def _candidate(
    decl: Structure,
    plan: dict[str, Any],
    orders: tuple[int, int, int],
    data: Dataset,
    iterations: dict[str, Any],
    extra: dict[str, Any] | None = None,
) -> Candidate:
    na, nb, nk = orders
    options = {"na": na, "nb": na + 1 if decl.proper else nb, "nk": max(nk, decl.min_delay)}
    options.update(extra or {})
    options.update(plan)
    if "center" not in plan and decl.slots:
        options["center"] = _centred(decl, plan, data)
    options.update(iterations)
    accepted = decl.accepted(None)
    return Candidate(decl.name, {k: v for k, v in options.items() if k in accepted})


def integrating_candidates(
    structures: Sequence[str],
    orders: Sequence[tuple[int, int, int]],
    data: Dataset,
    iterations: dict[str, Any],
    integrations: int,
) -> list[Candidate]:
    """The first plan of every structure that takes an integrator, with ``n = 1 ..
    integrations`` integrators: the linear block before them gets ``na - n`` poles and
    ``nk - 1`` delay (the integrator's sample)."""
    decls = [STRUCTURES[s] for s in structures if "integrator" in STRUCTURES[s].accepted(None)]
    out = []
    for n in range(1, integrations + 1):
        for na, nb, nk in orders:
            for decl in decls:
                na_n = max(na - n, 1)
                plan = {**decl.search[0], **_plans(decl, 1)[0]}
                o = (na_n, nb, max(nk - 1, 0))
                out.append(_candidate(decl, plan, o, data, iterations, {"integrator": n}))
    return unique(out)


# ----------------------------------------------------------------------------- states
def state_candidates(
    structures: Sequence[str], nxs: Sequence[int], iterations: dict[str, Any]
) -> list[Candidate]:
    """The linear state-space structures (``orders = "state"`` and no monomials) at every
    state dimension in ``nxs``."""
    out = []
    for name in structures:
        decl = STRUCTURES[name]
        accepted = decl.accepted(None)
        if decl.orders != "state" or "degree" in accepted or "input_block" in accepted:
            continue
        for nx in nxs:
            options = {"nx": int(nx), **iterations}
            out.append(Candidate(name, {k: v for k, v in options.items() if k in accepted}))
    return unique(out)


def n_state_space_parameters(nx: int, nu: int, ny: int, degree: int, monomials: str) -> int:
    """Parameters of a polynomial state-space model fitted with a constant term
    (:func:`~blockid.models.state_space.monomial_exponents`); ``D`` is not fitted."""
    from blockid.models.state_space import monomial_exponents

    nm = monomial_exponents(nx, nu, degree, monomials, constant=True).shape[0] if degree > 1 else 0
    return nx * nx + nx * nu + ny * nx + (nx + ny) * nm


def polynomial_state_candidates(
    structures: Sequence[str],
    nxs: Sequence[int],
    plans: Sequence[tuple[int, str]],
    signals: tuple[int, int],
    iterations: dict[str, Any],
    max_parameters: int,
) -> list[Candidate]:
    """The state-space structures with monomials (those taking ``degree``) at every
    state dimension in ``nxs`` and every ``(degree, monomials)`` of ``plans``, each with
    at most ``max_parameters`` parameters (``signals`` = inputs, outputs)."""
    out = []
    for name in structures:
        decl = STRUCTURES[name]
        if decl.orders != "state" or "degree" not in decl.accepted(None):
            continue
        accepted = decl.accepted(None)
        for nx in nxs:
            for degree, which in plans:
                if n_state_space_parameters(nx, *signals, degree, which) > max_parameters:
                    continue
                options = {"nx": int(nx), "degree": degree, "monomials": which, **iterations}
                out.append(Candidate(name, {k: v for k, v in options.items() if k in accepted}))
    return unique(out)


def block_state_candidates(
    structures: Sequence[str],
    nxs: Sequence[int],
    plans: Sequence[tuple[str | None, str | None]],
    iterations: dict[str, Any],
    loops: Sequence[str] = (),
) -> list[Candidate]:
    """The state-space structures with blocks (those taking ``input_block``) at every
    state dimension in ``nxs`` and every ``(input block, output block)`` of ``plans``
    (one family on every channel; None: no block on that side), then, for structures
    taking ``loop_block``, a loop per output with each family of ``loops``."""
    out = []
    for name in structures:
        decl = STRUCTURES[name]
        accepted = decl.accepted(None)
        if decl.orders != "state" or "input_block" not in accepted:
            continue
        blocks = [{"input_block": left, "output_block": right} for left, right in plans]
        if "loop_block" in accepted:
            blocks += [{"loop_block": family} for family in loops]
        for nx in nxs:
            for plan in blocks:
                options = {"nx": int(nx), **plan, **iterations}
                kept = {k: v for k, v in options.items() if k in accepted and v is not None}
                out.append(Candidate(name, kept))
    return unique(out)


# ----------------------------------------------------------------------------- growth
def grown(candidate: Candidate) -> list[Candidate]:
    """The candidate with one nonlinearity made richer, one option at a time: a degree
    (``r``, ``r1``, ``r2``) or a block's :attr:`~blockid.blocks.base.Block.size_option`
    raised by 2, up to :data:`MAX_SIZE`; a state-space model's monomial ``degree`` by 1,
    up to :data:`MAX_STATE_DEGREE`, fitted degree by degree from the candidate's own
    (``start_degree``: the higher degree refined from the model of the lower one on the
    same training data, not from the linear start again)."""
    out = []
    for key, value in candidate.options.items():
        if key in ("r", "r1", "r2") and isinstance(value, int) and value + 2 <= MAX_SIZE["degree"]:
            out.append(candidate.with_options(**{key: value + 2}))
        elif key == "degree" and isinstance(value, int) and value + 1 <= MAX_STATE_DEGREE:
            # one degree up, climbed from the model of this degree (a warm start)
            start = candidate.options.get("start_degree", value)
            out.append(candidate.with_options(degree=value + 1, start_degree=start))
        elif isinstance(value, str) and key.endswith("_block"):
            bigger = _grown_spec(value)
            if bigger is not None:
                out.append(candidate.with_options(**{key: bigger}))
    return out


def _grown_spec(spec: str) -> str | None:
    kind, _, rest = spec.partition(":")
    cls = BLOCK_TYPES.get(kind.strip())
    size = None if cls is None else cls.size_option
    if size is None:
        return None
    items = dict(item.split("=", 1) for item in rest.split(";") if "=" in item)
    current = int(items.get(size, 3))
    if current + 2 > MAX_SIZE.get(size, 9):
        return None
    items[size] = str(current + 2)
    return f"{kind}:" + ";".join(f"{k}={v}" for k, v in items.items())
