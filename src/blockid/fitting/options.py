"""The options of every fitter, each declared once: its kind, range, help and parser.

An option is declared once in :data:`OPTIONS` with its type, its allowed range and its
help text. :meth:`Option.convert` turns a Python value *or* the text a user typed (on
the command line or in a ``key=value`` network spec) into the typed value, and names the
Python parameter when the value is wrong (the command line maps that name to its flag).
A fitter called directly from Python checks its arguments with :func:`checked`, the
same check and message.

This module sits below :mod:`blockid.fitting.registry` and every fitter: the registry
names the fitters (and so imports them when a fit runs), and the fitters check their
options here, so the two never import each other. It imports nothing heavy at module
level (the command line reads it before NumPy is loaded).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from blockid.defaults import RECURSIVE
from blockid.errors import ParameterError

__all__ = ["OPTIONS", "Option", "checked", "option_flag", "parse_orders"]


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
