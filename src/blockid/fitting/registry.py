"""The one registry of model structures, their estimators and their options.

Every structure is declared here once: the blocks it has, the methods that identify it
(the first is the default), and for each method the options it takes. Everything else
is generated from this declaration: :func:`~blockid.fitting.fit_model` resolves and
checks options with it, the command line builds its ``--help`` and its flags from it,
the model-level estimators (:mod:`blockid.fitting.estimator`) take their keywords from
it, and the tests check that every option reaches its fitter.

An option is declared once in :data:`OPTIONS` with its type, its allowed range and its
help text. :meth:`Option.convert` turns a Python value *or* the text a user typed (on
the command line or in a ``key=value`` network spec) into the typed value, and names the
Python parameter when the value is wrong (the command line maps that name to its flag).

=====================  ==========================================  ==================
structure              methods                                     default
=====================  ==========================================  ==================
arx                    batch, rls, aw-rls, hierarchical-rls        batch
hammerstein            simulation-error, key-term-rls              simulation-error
wiener                 simulation-error, key-term-rls              simulation-error
hammerstein-wiener     simulation-error, key-term-rls              simulation-error
backlash               simulation-error, aw-rls                    simulation-error
output-error           simulation-error                            simulation-error
wiener-hammerstein     simulation-error                            simulation-error
feedback               simulation-error                            simulation-error
=====================  ==========================================  ==================

``integrator`` (output-error, hammerstein, backlash, wiener-hammerstein with method
simulation-error) puts an :class:`~blockid.blocks.integrator.Integrator` after the last
linear block, for plants that integrate; :func:`blockid.fitting.dispatch.run_method`
wires it for any such method (:mod:`blockid.fitting.integrator`).

``identify``'s search space is declared here too: a structure's ``search_rank`` puts it
in the default search, its ``slots`` name the block options every block family fills
(:attr:`blockid.blocks.base.Block.search_specs`), and ``search`` adds fixed option sets.
A new structure or block is searched without editing the search.

Estimators are named as text and model classes by loaders (:mod:`blockid.fitting._targets`),
imported only when a fit runs, so that importing the registry (and the CLI) stays cheap.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from blockid.defaults import RECURSIVE
from blockid.errors import ParameterError
from blockid.fitting import _targets

__all__ = [
    "COMPARED_BY_DEFAULT",
    "COMPARED_MULTIVARIABLE",
    "compared_by_default",
    "OPTIONS",
    "STRUCTURES",
    "Method",
    "Option",
    "Structure",
    "check_compared",
    "checked",
    "get_structure",
    "option_flag",
    "parse_orders",
    "resolve_options",
    "searched_structures",
]


# ----------------------------------------------------------------------------- values
def _text(value: Any) -> str | None:
    return value.strip() if isinstance(value, str) else None


def parse_orders(value: Any, name: str) -> Any:
    """An order: a whole number ``>= 0``, or for ARX a matrix (rows: outputs).

    Text ``"2"`` gives 2 and ``"2,1;1,2"`` gives ``[[2, 1], [1, 2]]``.

    >>> parse_orders("2,1;1,2", "na"), parse_orders(3, "nb")
    ([[2, 1], [1, 2]], 3)
    """
    text = _text(value)
    if text is None:
        if isinstance(value, bool):
            raise ParameterError(f"{name} must be a whole number >= 0, got {value!r}")
        return value  # numbers and matrices are checked by the model
    try:
        rows = [[int(v) for v in row.replace(" ", ",").split(",") if v] for row in text.split(";")]
    except ValueError:
        rows = []
    if not rows or not all(rows):
        raise ParameterError(
            f"{name}={text!r}: give a whole number, or a matrix with rows separated by ';' "
            "and entries by ',' (rows: outputs), e.g. 2 or '2,1;1,2'"
        )
    if any(v < 0 for row in rows for v in row):
        raise ParameterError(f"{name} must hold whole numbers >= 0; got {text!r}")
    if len({len(row) for row in rows}) > 1:
        raise ParameterError(
            f"{name}={text!r}: every row of the matrix needs as many entries (one per "
            f"output for na, one per input for nb and nk); got rows of "
            f"{', '.join(str(len(row)) for row in rows)}"
        )
    if len(rows) == 1 and len(rows[0]) == 1:
        return rows[0][0]
    return rows


def _count(value: Any, name: str, low: float, high: float | None = None) -> int:
    allowed = f">= {low:g}" if high is None else f"from {low:g} to {high:g}"
    text = _text(value)
    if text is not None:
        try:
            value = int(text)
        except ValueError:
            raise ParameterError(f"{name} must be a whole number {allowed}, got {text!r}") from None
    if isinstance(value, bool) or not isinstance(value, int) and not _is_integer(value):
        raise ParameterError(f"{name} must be a whole number {allowed}, got {value!r}")
    if value < low or (high is not None and value > high):
        raise ParameterError(f"{name} must be a whole number {allowed}, got {value!r}")
    return int(value)


def _is_integer(value: Any) -> bool:
    try:
        import numpy as np
    except ImportError:  # pragma: no cover - numpy is a dependency
        return False
    return isinstance(value, np.integer)


def _real(value: Any, name: str, low: float | None, high: float | None, open_low: bool) -> float:
    text = _text(value)
    try:
        number = float(text if text is not None else value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a number, got {value!r}") from None
    if isinstance(value, bool) or math.isnan(number):
        raise ParameterError(f"{name} must be a number, got {value!r}")
    if low is not None and (number < low or (open_low and number == low)):
        rel = ">" if open_low else ">="
        raise ParameterError(f"{name} must be {rel} {low:g}, got {number:g}")
    if high is not None and number > high:
        raise ParameterError(f"{name} must be <= {high:g}, got {number:g}")
    return number


def _boolean(value: Any, name: str) -> bool:
    text = _text(value)
    if text is not None:
        low = text.lower()
        if low in ("true", "yes", "1", "on"):
            return True
        if low in ("false", "no", "0", "off"):
            return False
        raise ParameterError(f"{name} must be true or false, got {text!r}")
    import numpy as np

    if isinstance(value, bool | np.bool_):  # NumPy 2 names its type "bool", not "bool_"
        return bool(value)
    raise ParameterError(f"{name} must be True or False, got {value!r}")


def _forgetting(value: Any, name: str) -> Any:
    from blockid.estimators.forgetting import ForgettingSchedule

    try:
        return ForgettingSchedule.parse(value)
    except ParameterError as exc:
        raise ParameterError(f"{name}: {exc}") from None


def _block(value: Any, name: str) -> Any:
    """A block, or (blocks per channel, for a model of several inputs or outputs) a dict
    ``{channel: block}`` from a mapping, ``"u1=dead-zone"`` or a list of such texts."""
    from blockid.blocks.base import Block, block_template, channel_specs

    if isinstance(value, Block):
        return value
    specs = channel_specs(value)
    if specs is not None:
        return {
            channel: spec if isinstance(spec, Block) or spec is None else _block(spec, name)
            for channel, spec in specs.items()
        }
    text = _text(value)
    if text is None:
        raise ParameterError(
            f"{name} must be a block (e.g. DeadZone(0, 0)) or its name, such as 'dead-zone' "
            f"or 'piecewise-linear:knots=7', got {value!r}"
        )
    try:
        return block_template(text, output=name == "output_block")
    except ParameterError as exc:
        raise ParameterError(f"{name}: {exc}{_block_hint(text)}") from None


def _block_hint(spec: str) -> str:
    """`` (did you mean 'polynomial'?)`` for a misspelt block kind, else nothing."""
    import difflib

    from blockid.blocks.base import BLOCK_TYPES

    kind = spec.partition(":")[0].strip().lower()
    if kind in BLOCK_TYPES:
        return ""
    near = difflib.get_close_matches(kind, [k for k in BLOCK_TYPES if k != "linear"], n=1)
    return f" (did you mean {near[0]!r}?)" if near else ""


def _numbers(value: Any, name: str) -> Any:
    """A number or a list of numbers (text: comma separated)."""
    text = _text(value)
    if text is not None:
        try:
            parts = [float(p) for p in text.split(",") if p.strip()]
        except ValueError:
            raise ParameterError(
                f"{name} must be a number or comma-separated numbers, got {text!r}"
            ) from None
        if not parts:
            raise ParameterError(f"{name} must be a number or comma-separated numbers, got ''")
        return parts[0] if len(parts) == 1 else parts
    return value


# ----------------------------------------------------------------------------- options
#: Text that stands for "no value: the method's default" (e.g. ``forgetting=none``).
_NONE = ("none", "null", "default")


@dataclass(frozen=True)
class Option:
    """One estimator option: its Python name, type, allowed range and help text.

    ``kind`` is one of ``"orders"`` (whole number or ARX matrix), ``"count"`` (whole
    number ``>= low``, ``<= high`` when given), ``"real"`` (number in ``[low, high]``,
    ``(low, high]`` with ``open_low``), ``"bool"``, ``"forgetting"`` (factor or
    schedule, parsed once into a :class:`~blockid.estimators.ForgettingSchedule`),
    ``"block"`` (a block or its name, see :func:`blockid.blocks.base.block_template`),
    ``"numbers"`` and ``"choice"`` (one of ``choices``).
    """

    name: str
    kind: str
    help: str
    low: float | None = None
    high: float | None = None
    open_low: bool = False
    #: Shown as the value's placeholder in help, e.g. ``SCHEDULE``.
    metavar: str = ""
    #: The allowed values of a ``"choice"``.
    choices: tuple[str, ...] = ()

    def convert(self, value: Any) -> Any:
        """The typed, checked value of ``value`` (a Python value or text); None (or the
        text ``none``) stays None: the method's default applies.

        Raises :class:`~blockid.errors.ParameterError` naming the parameter.
        """
        if value is None or (isinstance(value, str) and value.strip().lower() in _NONE):
            return None
        try:
            return self._convert(value)
        except ParameterError as exc:
            raise ParameterError(str(exc), parameter=self.name) from None

    def _convert(self, value: Any) -> Any:
        if self.kind == "orders":
            return parse_orders(value, self.name)
        if self.kind == "count":
            return _count(value, self.name, 0 if self.low is None else self.low, self.high)
        if self.kind == "real":
            return _real(value, self.name, self.low, self.high, self.open_low)
        if self.kind == "bool":
            return _boolean(value, self.name)
        if self.kind == "forgetting":
            return _forgetting(value, self.name)
        if self.kind == "block":
            return _block(value, self.name)
        if self.kind == "numbers":
            return _numbers(value, self.name)
        if self.kind == "choice":
            text = _text(value)
            if text is None or text.lower() not in self.choices:
                raise ParameterError(
                    f"{self.name} must be one of {', '.join(self.choices)}, got {value!r}"
                )
            return text.lower()
        raise AssertionError(f"unknown option kind {self.kind!r}")  # pragma: no cover


def _options(*items: Option) -> dict[str, Option]:
    return {o.name: o for o in items}


#: Every option any estimator takes, declared once.
OPTIONS: dict[str, Option] = _options(
    Option("na", "orders", "Output lags na (ARX: a matrix 'N,N;N,N' per output).", metavar="N"),
    Option("nb", "orders", "Input coefficients nb (b_0..b_nb-1), N or ARX matrix.", metavar="N"),
    Option("nk", "orders", "Input delay nk in samples, N or ARX matrix.", metavar="N"),
    Option("r1", "count", "Degree of the two-segment input polynomial (B1).", low=1),
    Option(
        "r2", "count", "Degree of the output polynomial (B3; the middle block of L1-N-L2).", low=1
    ),
    Option(
        "input_block",
        "block",
        "Input block: two-segment-polynomial, polynomial[:degree=N], dead-zone, "
        "saturation, piecewise-linear[:knots=N], piecewise-linear-free[:knots=N] (breakpoints "
        "estimated too) or a user block's kind. For several inputs or outputs "
        "(block-state-space) one kind for every channel, or CHANNEL=KIND, repeated.",
        metavar="KIND",
    ),
    Option(
        "output_block",
        "block",
        "Output block: polynomial[:degree=N], piecewise-linear-free[:knots=N], dead-zone, "
        "saturation or a user block's kind. For several inputs or outputs "
        "(block-state-space) one kind for every channel, or CHANNEL=KIND, repeated.",
        metavar="KIND",
    ),
    Option(
        "loop_block",
        "block",
        "Loop block (block-state-space): a static block inside the core's loop, fed by a "
        "combination of its states and inputs and acting back on them (Lur'e feedback, the "
        "middle block of a Wiener-Hammerstein path): one kind for a loop per output, or "
        "OUTPUT=KIND, repeated (a loop started from that output).",
        metavar="KIND",
    ),
    Option(
        "integrator",
        "count",
        "Integrators after the last linear block, for a plant that integrates (position "
        "from force): 0, 1 or 2; na, nb, nk are the linear block's before it.",
        low=0,
        high=2,
        metavar="N",
    ),
    Option(
        "center",
        "bool",
        "Fit around the mean operating point (offsets kept in the model).",
    ),
    Option("refine", "bool", "Refine the estimate on free-run simulation error afterwards."),
    Option(
        "standard_errors",
        "bool",
        "Standard errors and covariance of the parameters in the result and model file.",
    ),
    Option(
        "allow_unstable",
        "bool",
        "Keep an ARX model with poles on or outside the unit circle.",
    ),
    Option(
        "convergence_check",
        "bool",
        "Fail when a recursive ARX estimate's one-step MSE exceeds max_mse_ratio times "
        "the least-squares optimum.",
    ),
    Option(
        "max_mse_ratio",
        "real",
        "Convergence check of recursive ARX methods: allowed one-step MSE ratio.",
        low=1.0,
    ),
    Option(
        "forgetting",
        "forgetting",
        "Forgetting factor in (0, 1], or a schedule such as 0.98:200,1.",
        metavar="SCHEDULE",
    ),
    Option(
        "initial_covariance",
        "real",
        "P(0) scale of the recursive methods (default "
        + ", ".join(
            f"{v['initial_covariance']:.0e} for {k}".replace("e+0", "e")
            for k, v in RECURSIVE.items()
            if "initial_covariance" in v
        )
        + ").",
        low=0.0,
        open_low=True,
    ),
    Option(
        "initial_parameters",
        "numbers",
        "theta(0) of a paper's recursive algorithm: one number, or one per parameter.",
        metavar="X[,X..]",
    ),
    Option("passes", "count", "Passes of a recursive method over the data.", low=1),
    Option(
        "tol",
        "real",
        "Convergence tolerance on the relative parameter change over one pass.",
        low=0.0,
        open_low=True,
    ),
    Option(
        "normalize",
        "bool",
        "Run a paper's recursion on signals divided by their spread (mapped back exactly).",
    ),
    Option(
        "eps1",
        "real",
        "AW-RLS weight lambda = eps1 s + eps2 (A8): eps1 >= 0 (default "
        f"{RECURSIVE['aw-rls']['eps1']:g} for arx aw-rls, "
        f"{RECURSIVE['backlash-aw-rls']['eps1']:g} for backlash).",
        low=0.0,
    ),
    Option(
        "eps2",
        "real",
        "AW-RLS weight (A8): eps2 > 0, the weight's floor as P shrinks (default "
        f"{RECURSIVE['aw-rls']['eps2']:g}).",
        low=0.0,
        open_low=True,
    ),
    Option(
        "record_history",
        "bool",
        "Keep the parameter trajectory of a recursive method.",
    ),
    Option(
        "r", "count", "Degree r of the feedback polynomial N(y) = c_2 y^2 + .. + c_r y^r.", low=1
    ),
    Option(
        "feedback_block",
        "block",
        "Feedback block instead of the polynomial: dead-zone, saturation, "
        "piecewise-linear[:knots=N], piecewise-linear-free[:knots=N] or a user block's kind.",
        metavar="KIND",
    ),
    Option(
        "nx",
        "count",
        "State dimension (default: state space, where the subspace method's canonical "
        "correlations drop most; polynomial state space, the smallest order whose linear "
        "model simulates held-back halves of the data within 2 % of the best).",
        low=1,
    ),
    Option(
        "max_order",
        "count",
        "Largest state dimension the default order is chosen among.",
        low=1,
    ),
    Option("horizon", "count", "Past and future horizon of the subspace method.", low=2),
    Option(
        "weighting",
        "choice",
        "Subspace weighting: moesp or cva (canonical correlations).",
        metavar="moesp|cva",
        choices=("moesp", "cva"),
    ),
    Option("feedthrough", "bool", "Estimate a direct term D from input to output."),
    Option(
        "degree",
        "count",
        "Largest total degree of the state-space monomials (2-5; 1: linear).",
        low=1,
        high=5,
    ),
    Option(
        "start_degree",
        "count",
        "Fit the monomials degree by degree from this one up to --degree, each degree "
        "started from the fit below it (default: --degree at once).",
        low=1,
        high=5,
    ),
    Option(
        "rung_nfev",
        "count",
        "With --start-degree: limit on simulations of each degree above the first "
        "(default: --max-nfev).",
        low=1,
    ),
    Option(
        "monomials",
        "choice",
        "Monomials of the states and inputs (full), of the states only, or of the inputs only.",
        metavar="full|states|inputs",
        choices=("full", "states", "inputs"),
    ),
    Option(
        "margin",
        "real",
        "Widening of the monomials' clipping range beyond the linear start's, per side.",
        low=0.0,
    ),
    Option("max_nfev", "count", "Simulation-error fit: limit on simulations.", low=1),
    Option(
        "tail_fraction",
        "real",
        "Simulation-error fit: fraction held out for early stopping (0 switches it off).",
        low=0.0,
        high=0.9,
    ),
    Option(
        "patience",
        "count",
        "Simulation-error fit: iterations without a better tail error before stopping.",
        low=1,
    ),
    Option("ftol", "real", "Simulation-error fit: cost tolerance.", low=0.0, open_low=True),
    Option("xtol", "real", "Simulation-error fit: step tolerance.", low=0.0, open_low=True),
    Option("gtol", "real", "Simulation-error fit: gradient tolerance.", low=0.0, open_low=True),
)


def checked(name: str, value: Any) -> Any:
    """``value`` of option ``name`` converted and checked against its one declaration in
    :data:`OPTIONS` (type, range, open or closed ends), for a fitter called directly from
    Python: the same check and message as through :func:`resolve_options`, never a second
    range written in the fitter. None stays None.

    >>> checked("margin", 0.5)
    0.5
    >>> checked("eps1", 0.0)
    0.0
    """
    return OPTIONS[name].convert(value)


def option_flag(name: str) -> str:
    """The command-line flag of an option: ``initial_covariance`` -> ``--initial-covariance``."""
    return "--" + name.replace("_", "-")


# ----------------------------------------------------------------------------- methods
@dataclass(frozen=True)
class Method:
    """An estimator of a structure: the function that runs it and the options it takes.

    ``target`` is ``"module:function"``; :func:`blockid.fitting.dispatch.run_method`
    calls it as ``function(data, structure=..., method=..., **options)``, the keywords
    ``structure``/``method`` only where ``passes`` names them. The registry only
    declares: nothing here runs a fit.
    """

    name: str
    target: str
    options: tuple[str, ...]
    help: str
    recursive: bool = False
    #: Which of "structure" and "method" the function takes as keywords.
    passes: tuple[str, ...] = ()

    def function(self) -> Callable[..., Any]:
        module, name = self.target.split(":")
        return getattr(importlib.import_module(module), name)


@dataclass(frozen=True)
class Structure:
    """A model structure: name, model class (its loader), blocks, methods (default first)."""

    name: str
    model_loader: Callable[[], type]
    help: str
    methods: tuple[Method, ...]
    #: Options every method of the structure takes (handled by fit_model itself).
    common: tuple[str, ...] = ()
    #: Fit around the operating point unless told otherwise.
    center_default: bool = False
    block_oriented: bool = True
    #: A linear model (no static block, no state monomials): ``identify`` chooses a
    #: model beyond linear only when it beats the best linear one consistently.
    linear: bool = False
    #: Place in ``identify``'s default search (smaller first); None: searched only when
    #: asked for by name. The search list is this field, never a list of names.
    search_rank: int | None = None
    #: The block slots ``identify`` fills with every block family that declares the
    #: role (:attr:`blockid.blocks.base.Block.search_specs`): ``(role, option)`` pairs,
    #: e.g. ``("input", "input_block")``.
    slots: tuple[tuple[str, str], ...] = ()
    #: Option sets ``identify`` adds to the linear orders (and to the slots' blocks),
    #: most telling first.
    search: tuple[dict[str, Any], ...] = ({},)
    #: Smallest input delay the structure's fit takes (a loop needs one sample).
    min_delay: int = 0
    #: The search gives the structure ``nb = na + 1`` (a proper BLA of a chain).
    proper: bool = False
    #: How the search gives the structure its orders: ``"polynomial"`` (``na, nb, nk``
    #: of the order stages) or ``"state"`` (a state dimension ``nx``).
    orders: str = "polynomial"
    #: With ``integrator``: the structure and options fitted to the differenced output
    #: for the start, where the structure's own blocks cannot carry the operating point
    #: (None: the structure itself).
    integrator_start: tuple[str, dict[str, Any]] | None = None
    method_names: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "method_names", tuple(m.name for m in self.methods))

    @property
    def default_method(self) -> Method:
        return self.methods[0]

    def method(self, name: str | None) -> Method:
        """The method called ``name`` (None: the default)."""
        if name is None:
            return self.default_method
        for m in self.methods:
            if m.name == name:
                return m
        raise ParameterError(
            f"method={name!r} does not apply to {self.name}; choose one of "
            f"{', '.join(self.method_names)}"
        )

    def accepted(self, method: str | None) -> tuple[str, ...]:
        """Options of this structure fitted by ``method``, in declaration order."""
        return self.common + self.method(method).options

    def model_class(self) -> type:
        return self.model_loader()


_ORDERS = ("na", "nb", "nk")
_RECURSIVE = ("initial_covariance", "passes")
_ARX = _ORDERS + ("center", "allow_unstable", "standard_errors")
_SIMULATION_ERROR = ("max_nfev", "tail_fraction", "patience", "ftol", "xtol", "gtol")
_PAPER = ("passes", "tol", "initial_covariance", "initial_parameters", "normalize")


def _arx_method(name: str, options: tuple[str, ...], help: str) -> Method:
    return Method(
        name,
        "blockid.fitting.arx:fit_arx",
        _ARX + options,
        help,
        recursive=name != "batch",
        passes=("method",),
    )


def _block_methods(blocks: tuple[str, ...], paper: Method) -> tuple[Method, ...]:
    return (
        Method(
            "simulation-error",
            "blockid.fitting.simulation_error:fit_simulation_error",
            blocks + _SIMULATION_ERROR,
            "minimise the free-run simulation error (converges; the default)",
            passes=("structure",),
        ),
        paper,
    )


def _key_term(blocks: tuple[str, ...]) -> Method:
    return Method(
        "key-term-rls",
        "blockid.fitting.key_term:fit_key_term_rls",
        blocks + ("forgetting",) + _PAPER + ("record_history",),
        "paper B's key-term RLS with internal-variable estimation (B4, B5)",
        recursive=True,
        passes=("structure",),
    )


_CHECK = ("convergence_check", "max_mse_ratio")
_STATE_SPACE = ("nx", "max_order", "horizon", "weighting", "feedthrough", "standard_errors")
_REFINEMENT = ("max_nfev", "tail_fraction", "patience", "ftol", "xtol", "gtol")

#: The structures, in the order the command line lists them.
STRUCTURES: dict[str, Structure] = {
    s.name: s
    for s in (
        Structure(
            "arx",
            _targets.ARX,
            "linear ARX, multi-input multi-output (MATLAB na/nb/nk)",
            (
                _arx_method("batch", (), "batch least squares (QR)"),
                _arx_method(
                    "rls",
                    ("forgetting",) + _RECURSIVE + _CHECK,
                    "recursive least squares with forgetting factor or schedule",
                ),
                _arx_method(
                    "aw-rls",
                    ("eps1", "eps2") + _RECURSIVE + _CHECK,
                    "adaptive-weighted RLS (A8)",
                ),
                _arx_method(
                    "hierarchical-rls",
                    ("forgetting",) + _RECURSIVE + _CHECK,
                    "hierarchical RLS, one sub-estimator per output lag group (A10)",
                ),
            ),
            block_oriented=False,
            linear=True,
            search_rank=0,
        ),
        Structure(
            "hammerstein",
            _targets.Hammerstein,
            "static input block, then a linear block (N1-L)",
            _block_methods(("r1", "input_block", "integrator"), _key_term(("r1",))),
            common=_ORDERS + ("center", "refine", "standard_errors"),
            search_rank=3,
            slots=(("input", "input_block"),),
        ),
        Structure(
            "wiener",
            _targets.Wiener,
            "linear block, then a static output block (L-N2)",
            _block_methods(("r2", "output_block"), _key_term(("r2",))),
            common=_ORDERS + ("center", "refine", "standard_errors"),
            center_default=True,
            search_rank=4,
            slots=(("output", "output_block"),),
        ),
        Structure(
            "hammerstein-wiener",
            _targets.HammersteinWiener,
            "input block, linear block, output block (N1-L-N2, paper B)",
            _block_methods(("r1", "r2", "input_block", "output_block"), _key_term(("r1", "r2"))),
            common=_ORDERS + ("center", "refine", "standard_errors"),
            search_rank=5,
            slots=(("input", "input_block"), ("output", "output_block")),
        ),
        Structure(
            "backlash",
            _targets.BacklashModel,
            "backlash, then a linear block (paper A's pseudo-Hammerstein)",
            _block_methods(
                ("integrator",),
                Method(
                    "aw-rls",
                    "blockid.fitting.backlash:fit_backlash_aw_rls",
                    ("eps1", "eps2") + _PAPER + ("record_history",),
                    "paper A's adaptive-weighted RLS with internal-variable estimation (A8)",
                    recursive=True,
                ),
            ),
            common=_ORDERS + ("center", "refine", "standard_errors"),
            min_delay=1,
            search_rank=7,
        ),
        Structure(
            "output-error",
            _targets.OutputError,
            "linear output-error model B/A, fitted on free-run simulation error",
            (
                Method(
                    "simulation-error",
                    "blockid.fitting.simulation_error:fit_simulation_error",
                    ("integrator",) + _SIMULATION_ERROR,
                    "minimise the free-run simulation error from a least-squares ARX start",
                    passes=("structure",),
                ),
            ),
            common=_ORDERS + ("center", "standard_errors"),
            center_default=True,
            # an input offset: the velocity of an integrating plant need not vanish at
            # the mean input, so the start carries an affine input block
            integrator_start=("hammerstein", {"input_block": "polynomial:degree=1"}),
            linear=True,
            search_rank=1,
        ),
        Structure(
            "wiener-hammerstein",
            _targets.WienerHammerstein,
            "linear, static polynomial, linear (L1-N-L2), from the split of the BLA",
            (
                Method(
                    "simulation-error",
                    "blockid.fitting.wiener_hammerstein:fit_wiener_hammerstein",
                    ("r2", "integrator") + _SIMULATION_ERROR,
                    "split the best linear approximation's poles and zeros, score every "
                    "split, refine the best on free-run simulation error",
                ),
            ),
            common=_ORDERS + ("center", "standard_errors"),
            center_default=True,
            search=({"r2": 5},),
            proper=True,
            search_rank=6,
        ),
        Structure(
            "state-space",
            _targets.StateSpace,
            "linear state space x(k+1) = A x + B u, y = C x + D u, multi-input multi-output: "
            "subspace (MOESP or CVA), refined on the free-run error",
            (
                Method(
                    "simulation-error",
                    "blockid.fitting.state_space:fit_state_space",
                    _STATE_SPACE + _REFINEMENT,
                    "subspace estimate, then every parameter refined on the free-run error",
                ),
                Method(
                    "subspace",
                    "blockid.fitting.state_space:fit_subspace",
                    _STATE_SPACE,
                    "subspace estimate only (MOESP or CVA weighting)",
                ),
            ),
            block_oriented=False,
            linear=True,
            orders="state",
            search_rank=8,
        ),
        Structure(
            "polynomial-state-space",
            _targets.PolynomialStateSpace,
            "polynomial nonlinear state space (PNLSS): A x + B u + E z(x, u), C x + D u + "
            "F z(x, u), monomials z of degree 2..r, started from the linear state space",
            (
                Method(
                    "simulation-error",
                    "blockid.fitting.state_space:fit_polynomial_state_space",
                    _STATE_SPACE
                    + ("degree", "monomials", "margin", "start_degree", "rung_nfev")
                    + _REFINEMENT,
                    "linear state-space start, then every parameter refined on the free-run "
                    "error with the monomials",
                ),
            ),
            block_oriented=False,
            orders="state",
            search_rank=9,
        ),
        Structure(
            "block-state-space",
            _targets.BlockStateSpace,
            "a static block per input and/or output channel around a linear state space "
            "(Hammerstein, Wiener, Hammerstein-Wiener of several inputs and outputs)",
            (
                Method(
                    "simulation-error",
                    "blockid.fitting.block_state_space:fit_block_state_space",
                    ("input_block", "output_block", "loop_block") + _STATE_SPACE + _REFINEMENT,
                    "linear state-space start with every input and output block near the "
                    "identity and every loop open, then every parameter refined on the "
                    "free-run error (exact Jacobian)",
                ),
                Method(
                    "batch",
                    "blockid.fitting.block_arx:fit_block_arx",
                    ("input_block", "output_block", "na", "nb", "nk"),
                    "Hammerstein on a matrix-ARX core: least squares on the input powers, "
                    "each channel's block split off by a rank-1 approximation",
                    passes=("method",),
                ),
                Method(
                    "rls",
                    "blockid.fitting.block_arx:fit_block_arx",
                    (
                        "input_block",
                        "output_block",
                        "na",
                        "nb",
                        "nk",
                        "forgetting",
                        "initial_covariance",
                        "passes",
                    ),
                    "Hammerstein on a matrix-ARX core: RLS on the input powers (online: "
                    "stream, partial_fit), each channel's block split off by a rank-1 "
                    "approximation",
                    recursive=True,
                    passes=("method",),
                ),
                Method(
                    "key-term-rls",
                    "blockid.fitting.key_term_channels:fit_key_term_block",
                    ("input_block", "output_block", "na", "nb", "nk", "forgetting", "center")
                    + _PAPER
                    + ("record_history",),
                    "paper B's key-term RLS for one output of several inputs (online: "
                    "stream, partial_fit; default: two-segment polynomial per input, cubic "
                    "output block)",
                    recursive=True,
                ),
            ),
            block_oriented=False,
            orders="state",
            search_rank=10,
        ),
        Structure(
            "feedback",
            _targets.LinearFeedback,
            "linear block with a static nonlinearity of the output (polynomial, dead zone, "
            "saturation, piecewise-linear) fed back to its input (Lur'e form: Duffing "
            "oscillator, Silverbox)",
            (
                Method(
                    "simulation-error",
                    "blockid.fitting.feedback:fit_feedback",
                    ("r", "feedback_block") + _SIMULATION_ERROR,
                    "equation-error start, then minimise the free-run simulation error",
                ),
            ),
            common=_ORDERS + ("center", "standard_errors"),
            center_default=True,
            min_delay=1,
            search_rank=2,
            slots=(("feedback", "feedback_block"),),
        ),
    )
}


def searched_structures() -> tuple[str, ...]:
    """The structures ``identify`` searches by default: those with a ``search_rank``,
    in its order."""
    ranked = [s for s in STRUCTURES.values() if s.search_rank is not None]
    return tuple(s.name for s in sorted(ranked, key=lambda s: s.search_rank))


#: The structures ``compare`` identifies unless told otherwise (paper B's four).
COMPARED_BY_DEFAULT = ("arx", "hammerstein", "wiener", "hammerstein-wiener")
#: ... on data of several inputs or outputs, which the chain structures cannot take.
COMPARED_MULTIVARIABLE = ("arx", "state-space", "polynomial-state-space")


def compared_by_default(n_inputs: int, n_outputs: int) -> tuple[str, ...]:
    """The structures ``compare`` and ``report`` identify unless told otherwise, by the
    data's shape: paper B's four on one input and one output, else ARX and the linear
    and polynomial state space."""
    return COMPARED_BY_DEFAULT if n_inputs == n_outputs == 1 else COMPARED_MULTIVARIABLE


def get_structure(name: Any) -> Structure:
    """The declaration of structure ``name``, or a clear error listing the known ones."""
    if name not in STRUCTURES:
        raise ParameterError(
            f"structure={name!r} is unknown; choose one of {', '.join(STRUCTURES)}"
        )
    return STRUCTURES[name]


def check_compared(structures: Sequence[str], method: str | None) -> None:
    """Refuse what a comparison of ``structures`` would drop or fail on late: no or an
    unknown structure, a shared ``method`` none of them offers (each structure takes the
    method where it offers it, else its default)."""
    if not structures:
        raise ParameterError(
            "no structure to compare; name at least one, e.g. arx,hammerstein",
            parameter="structures",
        )
    unknown = [s for s in structures if s not in STRUCTURES]
    if unknown:
        raise ParameterError(
            f"structures {unknown} are unknown; choose among {', '.join(STRUCTURES)}",
            parameter="structures",
        )
    if method is not None and not any(method in STRUCTURES[s].method_names for s in structures):
        raise ParameterError(
            f"method={method!r} is offered by none of {', '.join(structures)}", parameter="method"
        )


#: Option kinds whose conversion imports the numerical stack (blocks, schedules);
#: :func:`resolve_options` with ``light=True`` leaves their values to the fit.
_HEAVY_KINDS = ("block", "forgetting")


def resolve_options(
    structure: str, method: str | None, options: dict[str, Any], *, light: bool = False
) -> tuple[Structure, str, dict[str, Any]]:
    """Check ``options`` against the registry and convert their values.

    Returns the structure, the method name and the typed options (``None`` values
    dropped: the method's default applies). An option the method does not use is an
    error that lists the ones it does. ``light=True`` (the command line, before it
    imports NumPy) checks everything but the block and forgetting values, which are
    returned as given.
    """
    decl = get_structure(structure)
    chosen = decl.method(method)
    given = {k: v for k, v in options.items() if v is not None}
    accepted = decl.accepted(chosen.name)
    unused = [k for k in given if k not in accepted]
    if unused:
        raise ParameterError(
            f"{', '.join(unused)} not used by {structure} with method {chosen.name}; it takes "
            f"{', '.join(accepted)}",
            parameter=unused[0],
        )
    converted = {
        k: v if light and OPTIONS[k].kind in _HEAVY_KINDS else OPTIONS[k].convert(v)
        for k, v in given.items()
    }
    return decl, chosen.name, {k: v for k, v in converted.items() if v is not None}
