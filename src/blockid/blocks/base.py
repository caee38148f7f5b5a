"""Common interface of the blocks a block-oriented model is built from.

A *static* block maps each input sample to an output sample, ``w = N(u)``. A
*dynamic* (hysteretic) block such as backlash has memory: its output depends on its
own previous output as well. The linear dynamic block is
:class:`blockid.blocks.linear.LinearBlock`.

Every block owns its mathematics, so that models, estimators and the command line
work with any block without knowing its kind:

* evaluation (``__call__`` / :meth:`DynamicBlock.simulate`);
* parameters: named (:attr:`Block.parameters`, as model files name them), as one vector
  (:meth:`Block.to_vector` / :meth:`Block.with_vector`), their bounds
  (:meth:`Block.bounds`) and which of them are fixed by the normalisation of a cascade
  (:meth:`Block.free_mask`);
* derivatives: with respect to the parameters (:meth:`StaticBlock.jacobian`,
  :meth:`DynamicBlock.sensitivity`) and to the input (:meth:`StaticBlock.derivative`),
  for the simulation-error fit;
* scaling by a gain (:meth:`Block.scaled`), initial shapes for the initial estimate
  (:meth:`Block.initial_grid`), a placeholder to fit (:meth:`Block.template`), the rest
  state (:meth:`DynamicBlock.rest_state`), inversion (:meth:`StaticBlock.invert`);
* serialisation (:meth:`Block.to_dict` / :meth:`Block.from_dict`).

The defaults here are numerical (central differences, bisection) so that a new block
needs only ``kind``, ``__init__``, :attr:`~Block.parameters` and ``__call__``; blocks that
know their derivatives analytically override them. ``docs/extending.md`` shows a
user-defined block used in every structure.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from blockid.errors import BlockidError, EstimationError, ModelFileError, ParameterError

__all__ = [
    "BLOCK_TYPES",
    "EDGE_DISTANCE",
    "EDGE_GAP",
    "SLOPE_RATIO",
    "Block",
    "DynamicBlock",
    "LinearFamily",
    "StaticBlock",
    "block_from_dict",
    "block_template",
    "channel_specs",
    "in_every_slot",
]

#: Registry ``kind -> class`` filled by :meth:`Block.__init_subclass__`; used to load
#: blocks back from model files and to choose blocks by name.
BLOCK_TYPES: dict[str, type[Block]] = {}

#: Relative step of the numerical derivatives.
_STEP = 1e-6

#: Two edges of a block (a dead zone's, a saturation's knees, neighbouring breakpoints,
#: the two sides of a backlash's play) closer than this fraction of the range its
#: argument covered in estimation coincide: the data cannot tell them apart, and the
#: block has collapsed into another form (:meth:`Block.degeneracy`).
EDGE_GAP = 1e-3
#: An edge more than this many widths of its argument's range beyond that range is far
#: outside it: no data reach it, so neither it nor the part of the block beyond it is
#: identified (a dead zone's lower edge at -292 313 with slope 6e-7 on an argument
#: within +-3).
EDGE_DISTANCE = 1.0
#: A slope on the data below this fraction of the block's steepest one vanishes. The
#: slopes are compared with each other, not with a gain of their own: a block's gain is
#: shared with the linear part next to it, so only their ratios say what it does.
SLOPE_RATIO = 1e-3


# ---------------------------------------------------------------- degenerate blocks
def _width(low: float, high: float) -> float | None:
    """The width of an argument range, None when there is none to compare with."""
    width = float(high) - float(low)
    return width if np.isfinite(width) and width > 0 else None


def _range_text(low: float, high: float) -> str:
    return f"the range its argument covered in estimation [{low:.4g}, {high:.4g}]"


def _coinciding(what: str, gap: float, low: float, high: float, becomes: str) -> list[str]:
    """A note when two edges ``what`` lie ``gap`` apart, below :data:`EDGE_GAP` of the
    argument's range: the block has collapsed into what ``becomes`` says (with what to
    do)."""
    width = _width(low, high)
    if width is None or not gap < EDGE_GAP * width:
        return []
    return [
        f"has {what} only {gap:.3g} apart, {gap / width:.2g} of {_range_text(low, high)}: {becomes}"
    ]


def _far_outside(edges: list[tuple[str, float]], low: float, high: float) -> list[str]:
    """A note for the edge (``name = value`` text, value) furthest beyond the argument's
    range, when it is more than :data:`EDGE_DISTANCE` widths beyond."""
    width = _width(low, high)
    if width is None:
        return []
    distance = [(max(low - v, v - high) / width, name) for name, v in edges]
    worst, name = max(distance, default=(0.0, ""))
    if not worst > EDGE_DISTANCE:
        return []
    return [
        f"has {name}, {worst:.3g} widths outside {_range_text(low, high)}: no data reach "
        "it, so neither it nor the block beyond it is identified and the model "
        "extrapolates there with values the data never chose; fit a block of another "
        "form (without that side), or use data that reach it"
    ]


def _vanishing(slopes: list[tuple[str, float]], becomes: str) -> list[str]:
    """A note for the flattest of ``slopes`` (name, value: the slopes the data reach)
    when it is below :data:`SLOPE_RATIO` of the steepest one."""
    steepest = max((abs(v) for _, v in slopes), default=0.0)
    if not steepest > 0 or not np.isfinite(steepest):
        return []
    name, value = min(slopes, key=lambda nv: abs(nv[1]))
    if not abs(value) < SLOPE_RATIO * steepest:
        return []
    return [
        f"has {name} = {value:.3g}, {abs(value) / steepest:.2g} of its steepest slope on the "
        f"data ({steepest:.3g}): that side is flat, {becomes}"
    ]


class Block(ABC):
    """Base class of all blocks.

    Subclasses set the class attribute ``kind`` (the name used in model files and on
    the command line, e.g. ``"polynomial"``) and implement :attr:`parameters`; the
    constructor must accept the entries of :attr:`parameters` as keywords.
    """

    kind: ClassVar[str] = ""
    #: ``"static"`` (memoryless), ``"dynamic"`` (nonlinear with memory, acting on the
    #: measured input) or ``"linear"`` (the linear dynamic block): the role in a chain.
    role: ClassVar[str] = ""
    #: True when the block output is ``regressors(u) @ to_vector()``.
    linear_in_parameters: ClassVar[bool] = False
    #: True when the block says nothing reliable outside the input range it was fitted
    #: on (polynomials); models then warn when data leave that range.
    warn_extrapolation: ClassVar[bool] = False
    #: False for a block whose form sits at given values of its signal (a piecewise-linear
    #: map with given breakpoints): fits with it are then never centred by default, since
    #: centring would move the signal off those values.
    centred: ClassVar[bool] = True
    #: How ``identify`` searches the block: ``{role: spec}`` for each role it takes in a
    #: structure's slots (``"input"``, ``"output"``, ``"feedback"``), the spec as
    #: :func:`block_template` reads it. Empty: not searched. A user's block that declares
    #: it is searched like the built-in ones.
    search_specs: ClassVar[dict[str, str]] = {}
    #: The spec option that sets the block's richness (``"degree"``, ``"knots"``), grown by
    #: ``identify`` while the held-out error falls; None: fixed form.
    size_option: ClassVar[str | None] = None
    #: Order among the families of a slot in the search (smaller first; the smallest is
    #: the slot's default when another slot is varied).
    search_priority: ClassVar[int] = 100
    #: True for a block whose form sits at its input's zero (a dead zone's band, a
    #: saturation's centre, a two-segment polynomial's break): a fit with it is on the
    #: signal as recorded when that takes both signs (the zero is then where the plant
    #: has it), around the operating point when not (a 2-10 V signal has no use for a
    #: break at 0 V) (:func:`blockid.fitting.dispatch.default_centring`).
    anchored: ClassVar[bool] = False
    #: The block's own rule in the NumPy-only module ``blockid export --to python``
    #: writes (:func:`blockid.models.export.to_python_module`): Python source that uses
    #: ``np`` (and the module's ``_polyval(x, c)``, ``_derivative(c)``) and nothing else,
    #: with ``p`` the block's :meth:`to_dict` as JSON gives it back (lists, floats) and
    #: ``s``, ``u`` float arrays. A static block's defines ``evaluate(p, s)`` (its
    #: output) and, if the block has its own :meth:`StaticBlock.derivative` and the
    #: module needs a slope (a tangent beyond the estimation range, a block state
    #: space), ``slope(p, s)`` (without it the module takes the default's central
    #: differences), and may define ``scalar(p)``: a plain-Python function of one float
    #: equal to ``evaluate`` bit for bit, which a feedback loop calls sample by sample
    #: (without it the loop calls ``evaluate`` on one-element arrays, several times
    #: slower); a dynamic block's defines ``run(p, u)`` (its output from
    #: :meth:`DynamicBlock.rest_state`). Each must give the block's numbers operation by
    #: operation. None: the block is not exported (the export says so).
    export_source: ClassVar[str | None] = None

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if cls.__dict__.get("kind"):
            BLOCK_TYPES[cls.kind] = cls

    # ------------------------------------------------------------------ parameters
    @property
    @abstractmethod
    def parameters(self) -> dict[str, Any]:
        """Named parameters, JSON-serialisable (floats, lists of floats, flags)."""

    def to_vector(self) -> np.ndarray:
        """All numeric parameters as one vector, in the order of :attr:`parameters`."""
        values = [v for v in self.parameters.values() if not isinstance(v, bool)]
        if not values:
            return np.zeros(0)
        return np.concatenate([np.atleast_1d(np.asarray(v, dtype=float)) for v in values])

    def with_vector(self, theta: Any) -> Block:
        """A block of the same kind and form with :meth:`to_vector` replaced by ``theta``."""
        theta = np.asarray(theta, dtype=float).reshape(-1)
        if theta.size != self.to_vector().size:
            raise ParameterError(
                f"{self.kind} takes {self.to_vector().size} parameter value(s), got {theta.size}"
            )
        params, pos = {}, 0
        for key, value in self.parameters.items():
            if isinstance(value, bool):
                params[key] = value
                continue
            size = np.atleast_1d(np.asarray(value)).size
            chunk = theta[pos : pos + size]
            params[key] = chunk.tolist() if isinstance(value, list | tuple) else float(chunk[0])
            pos += size
        try:
            return type(self)(**params)
        except BlockidError:
            raise
        except (TypeError, ValueError) as exc:  # a user block's own check
            raise ParameterError(f"{self.kind}: {exc}") from None

    @classmethod
    def display_names(cls, position: str) -> dict[str, str]:
        """How a model names this block's parameters at ``position`` (``"input"``,
        ``"output"`` or ``"middle"``): the SPEC names (the input polynomial's ``f``, the
        output polynomial's ``q``). Default: the parameters' own names."""
        return {}

    def check_output_block(self) -> None:  # noqa: B027 - optional hook
        """Raise :class:`ParameterError` when the block cannot end a cascade as its output
        block (the output offset carries any constant)."""

    def vector_names(self, rename: dict[str, str] | None = None) -> list[str]:
        """A name for every entry of :meth:`to_vector`: ``name`` for a number, ``name_j``
        for the entries of a list (``rename`` maps parameter names to display names)."""
        rename = rename or {}
        names: list[str] = []
        for key, value in self.parameters.items():
            if isinstance(value, bool):
                continue
            base = rename.get(key, key)
            if isinstance(value, list | tuple):
                names += [f"{base}_{j}" for j in range(len(value))]
            else:
                names.append(base)
        return names

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of :meth:`to_vector` for the simulation-error fit."""
        n = self.to_vector().size
        return np.full(n, -np.inf), np.full(n, np.inf)

    def free_mask(self, after_linear: bool) -> np.ndarray:
        """Which entries of :meth:`to_vector` an estimator may move.

        A gain between two blocks of a cascade is not identifiable. A linear block that
        follows a nonlinear one fixes ``b_0 = 1``; a static block that follows a linear
        block (``after_linear``) must fix its own input gain: by construction (unit
        slope at the origin, like ``limit * tanh(x / limit)``) or by returning False
        here for the entry that carries it (the output polynomial fixes ``q_1 = 1``).
        """
        return np.ones(self.to_vector().size, dtype=bool)

    def check_normalised(self, after_linear: bool) -> None:  # noqa: B027 - optional hook
        """Raise :class:`ParameterError` if the fixed entries do not hold their values."""

    def degeneracy(self, low: float, high: float) -> list[str]:
        """How the block has degenerated for an argument over ``[low, high]`` (the range
        it covered in estimation): each a clause that completes "the input block
        (dead-zone) ...", saying what the block has become and what to do. Blocks with
        edges and slopes (dead zone, saturation, backlash, piecewise-linear maps) look
        for edges that coincide (:data:`EDGE_GAP`), edges far outside the range
        (:data:`EDGE_DISTANCE`) and slopes that vanish (:data:`SLOPE_RATIO`); the
        default finds nothing."""
        return []

    # ------------------------------------------------------------------ fitting aids
    def check_data(self, u: np.ndarray) -> None:  # noqa: B027 - optional hook
        """Raise :class:`~blockid.errors.EstimationError` when input data ``u`` cannot
        identify this block (default: any data can)."""

    @classmethod
    def template(cls, **options: Any) -> Block:
        """A block of this kind with placeholder parameters, to be fitted.

        ``options`` fix its form (e.g. ``degree`` of a polynomial, ``knots`` of a
        piecewise-linear map); see :func:`block_template`.
        """
        raise ParameterError(
            f"the {cls.kind} block has no default form; construct one with its parameters "
            "and pass it as the starting block"
        )

    def adapted(self, u: np.ndarray) -> Block:
        """The template adapted to the data's input range (default: unchanged)."""
        return self

    def scaled(self, gain: float) -> Block:
        """The block followed by a gain: ``gain * N(u)`` as a block of the same kind.

        Used to move a gain from the linear block into this block (``b_0 = 1``).
        """
        if self.linear_in_parameters:
            return self.with_vector(gain * self.to_vector())
        raise ParameterError(
            f"the {self.kind} block cannot absorb a gain; implement {type(self).__name__}."
            "scaled(gain) to use it before a linear block"
        )

    def initial_grid(self, u: np.ndarray, around: Any = None) -> list[Any]:
        """Shapes tried by the initial estimate, for input data ``u``.

        Each entry is either a block with unit gain (the linear block that follows is
        fitted by least squares and its ``b_0`` moved into the block with
        :meth:`scaled`) or a :class:`LinearFamily` (a sub-family linear in some
        parameters, fitted by the Hammerstein regression). With ``around`` (the best
        candidate of the first grid) a block may return a finer second grid. Blocks
        linear in their parameters need no grid; the default for the others is the block
        itself, its parameters taken as the starting shape.
        """
        if self.linear_in_parameters or around is not None:
            return []
        return [self]

    # ------------------------------------------------------------------ files
    def to_dict(self) -> dict[str, Any]:
        """Plain-dict form ``{"kind": ..., **parameters}`` for model files."""
        return {"kind": self.kind, **self.parameters}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Block:
        """Inverse of :meth:`to_dict`."""
        params = {k: v for k, v in data.items() if k != "kind"}
        return cls(**params)

    def __repr__(self) -> str:
        inner = ", ".join(f"{k}={v!r}" for k, v in self.parameters.items())
        return f"{type(self).__name__}({inner})"


class StaticBlock(Block):
    """A memoryless nonlinearity ``w(k) = N(u(k))``."""

    role: ClassVar[str] = "static"

    def run(self, u: np.ndarray) -> np.ndarray:
        """The block's output for the input sequence ``u``."""
        return np.asarray(self(u), dtype=float)

    @abstractmethod
    def __call__(self, u: np.ndarray) -> np.ndarray:
        """Evaluate the block on an array of inputs (any shape)."""

    def jacobian(self, u: np.ndarray) -> np.ndarray:
        """``dN(u_k)/dθ``, shape ``(N, n)`` for ``N = u.size`` and ``θ = to_vector()``.

        Blocks linear in their parameters return their regressors; the default is
        central differences.
        """
        u = np.asarray(u, dtype=float).ravel()
        if self.linear_in_parameters:
            return np.asarray(self.regressors(u), dtype=float)  # type: ignore[attr-defined]
        theta = self.to_vector()
        G = np.zeros((u.size, theta.size))
        for k in range(theta.size):
            h = _STEP * max(1.0, abs(theta[k]))
            values = []
            for step in (h, -h):
                t = theta.copy()
                t[k] += step
                try:
                    values.append((step, np.asarray(self.with_vector(t)(u), dtype=float)))
                except BlockidError:  # a parameter at its bound: one-sided difference
                    values.append((0.0, np.asarray(self(u), dtype=float)))
            (s1, w1), (s2, w2) = values
            if s1 != s2:
                G[:, k] = (w1 - w2) / (s1 - s2)
        return G

    def derivative(self, u: np.ndarray) -> np.ndarray:
        """``dN/du`` element-wise (default: central differences)."""
        u = np.asarray(u, dtype=float)
        h = _STEP * np.maximum(1.0, np.abs(u))
        return (np.asarray(self(u + h), dtype=float) - np.asarray(self(u - h), dtype=float)) / (
            2.0 * h
        )

    def piecewise_linear(self) -> tuple[np.ndarray, np.ndarray, float, float] | None:
        """The block as breakpoints, values and the two end slopes, when it *is* a
        piecewise-linear map continued by straight lines (dead zone, saturation,
        piecewise-linear maps): the compiled feedback loop
        (:class:`~blockid.models.feedback.LinearFeedback`) then evaluates it. None (the
        default) for any other block, which the loop evaluates in Python."""
        return None

    def compiled_form(self) -> tuple[str, np.ndarray] | None:
        """The block as the compiled loop of a block state-space model evaluates it
        (:mod:`blockid._kernels.loop`): ``("table", [n, breakpoints, values,
        slope_left, slope_right])`` for a block that :meth:`piecewise_linear` describes
        (the default), ``("polynomial", [m, c_0 .. c_m-1])`` or
        ``("two-segment-polynomial", [m, f, p])``; None for any other block, which the
        loop evaluates in Python."""
        table = self.piecewise_linear()
        if table is None:
            return None
        xs, ys, left, right = table
        return "table", np.r_[len(xs), xs, ys, left, right].astype(float)

    def feedback_mask(self) -> np.ndarray:
        """Which entries of :meth:`to_vector` an estimator may move when the block feeds
        the output back around a linear block
        (:class:`~blockid.models.feedback.LinearFeedback`). Default
        ``free_mask(after_linear=False)``: the loop has no gain to share with the linear
        block (``u`` enters it with unit gain)."""
        return self.free_mask(after_linear=False)

    def forward(
        self, u: np.ndarray, S_in: np.ndarray, own: np.ndarray, init: Any = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Output and its sensitivities to every parameter of a model (chain rule).

        ``S_in`` (N, n) holds ``du/dθ`` for the model's free parameters, ``own`` the model
        column of each entry of :meth:`to_vector` (-1 where fixed). Returns ``w = N(u)``
        and ``dw/dθ = N'(u) du/dθ``, plus ``dN/dθ_own`` in the block's own columns (added,
        so that sensitivities carried in from an initial state are kept).
        """
        w = np.asarray(self(u), dtype=float)
        S = self.derivative(u)[:, None] * S_in
        free = own >= 0
        if free.any():
            S[:, own[free]] += self.jacobian(u)[:, free]
        return w, S

    def inverse_on(self, w: np.ndarray, u_range: tuple[float, float]) -> np.ndarray:
        """``u = N^{-1}(w)`` on the finite interval ``u_range``, where the block must be
        strictly monotone; outputs beyond the interval's image map to its ends.

        The default bisects (to machine precision); raises
        :class:`~blockid.errors.EstimationError` where the block is not monotone.
        """
        lo, hi = float(u_range[0]), float(u_range[1])
        grid = np.linspace(lo, hi, 513)
        values = np.asarray(self(grid), dtype=float)
        steps = np.diff(values)
        if not (np.all(steps > 0) or np.all(steps < 0)):
            raise EstimationError(
                f"the {self.kind} block is not strictly monotone over [{lo:.4g}, {hi:.4g}], "
                "so its input cannot be recovered from its output"
            )
        sign = 1.0 if steps[0] > 0 else -1.0
        w = np.asarray(w, dtype=float)
        a = np.full(w.shape, lo)
        b = np.full(w.shape, hi)
        target = sign * np.clip(w, values.min(), values.max())
        for _ in range(80):
            mid = 0.5 * (a + b)
            below = sign * np.asarray(self(mid), dtype=float) < target
            a = np.where(below, mid, a)
            b = np.where(below, b, mid)
        return 0.5 * (a + b)

    def invert(self, w: np.ndarray, seen: tuple[float, float] | None = None) -> np.ndarray:
        """``u = N^{-1}(w)`` for one-step prediction and for starting a simulation from
        measured outputs.

        ``seen`` is the input range the block was fitted on; the default inverts on it,
        widened by half its width (:meth:`inverse_on`). Raises
        :class:`~blockid.errors.EstimationError` where the block is not invertible.
        """
        if seen is None:
            raise EstimationError(
                f"the {self.kind} block cannot be inverted without the input range it was fitted on"
            )
        lo, hi = float(seen[0]), float(seen[1])
        pad = 0.5 * (hi - lo) + 1e-12
        return self.inverse_on(w, (lo - pad, hi + pad))

    def identity(self) -> StaticBlock | None:
        """The block of this form that passes its input through, if there is one (the
        output polynomial ``q = [1, 0, ..]``); a second start for fits with it."""
        return None

    def normalised_input(self) -> tuple[StaticBlock, float] | None:
        """``(N', g)`` with ``N(x) = N'(g x)`` and ``N'`` of unit input gain, or None.

        The initial estimate fits an output block freely by least squares (blocks linear
        in their parameters), then moves its input gain ``g`` into the linear block in
        front. Blocks that cannot say return None (their template is used as the start).
        """
        return None


class DynamicBlock(Block):
    """A nonlinearity with memory (e.g. backlash): ``x(k) = N(u(k), x(k-1))``.

    A dynamic block acts on the measured input: in a model it comes first.
    """

    role: ClassVar[str] = "dynamic"

    def run(self, u: np.ndarray) -> np.ndarray:
        """The block's output for ``u``, started at :meth:`rest_state`."""
        return self.simulate(u, x0=self.rest_state(float(u[0])) if u.size else 0.0)

    @abstractmethod
    def simulate(self, u: np.ndarray, x0: float = 0.0) -> np.ndarray:
        """Run the block over the input sequence ``u`` from the initial output ``x0``."""

    def rest_state(self, u0: float) -> float:
        """The output before the first sample when the block starts at rest at ``u0``."""
        return 0.0

    def sensitivity(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Output from :meth:`rest_state` and its derivative with respect to
        :meth:`to_vector`, shape ``(N, n)`` (default: central differences)."""
        u = np.asarray(u, dtype=float)
        x = self.simulate(u, self.rest_state(float(u[0])))
        theta = self.to_vector()
        G = np.zeros((u.size, theta.size))
        for k in range(theta.size):
            h = _STEP * max(1.0, abs(theta[k]))
            t = theta.copy()
            t[k] += h
            try:
                moved = self.with_vector(t)
            except BlockidError:
                continue
            G[:, k] = (moved.simulate(u, moved.rest_state(float(u[0]))) - x) / h
        return x, G

    def forward(
        self, u: np.ndarray, S_in: np.ndarray, own: np.ndarray, init: Any = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Output from rest and its sensitivities (see :meth:`StaticBlock.forward`); the
        input is the measured one, so only the block's own columns are non-zero."""
        x, G = self.sensitivity(u)
        S = np.zeros_like(S_in)
        free = own >= 0
        S[:, own[free]] = G[:, free]
        return x, S


@dataclass(frozen=True)
class LinearFamily:
    """A family of blocks linear in some parameters, for the initial estimate.

    ``regressors(u)`` gives the basis (N, n) and ``build(vector)`` the block whose
    output is ``regressors(u) @ vector``; e.g. a dead zone with fixed edges is linear in
    its two slopes.
    """

    regressors: Callable[[np.ndarray], np.ndarray]
    build: Callable[[np.ndarray], Block]


def block_from_dict(data: dict[str, Any]) -> Block:
    """Rebuild a block from :meth:`Block.to_dict` output."""
    kind = data.get("kind") if isinstance(data, dict) else None
    if kind not in BLOCK_TYPES:
        known = ", ".join(sorted(BLOCK_TYPES)) or "none loaded"
        raise ModelFileError(f"unknown block kind {kind!r}; known kinds: {known}")
    try:
        return BLOCK_TYPES[kind].from_dict(data)
    except (TypeError, ValueError, BlockidError) as exc:
        raise ModelFileError(f"the {kind} block is damaged ({exc})") from None


def _option_value(text: str) -> Any:
    parts = [p for p in text.split(",") if p.strip()]
    try:
        numbers = [float(p) for p in parts]
    except ValueError:
        low = text.strip().lower()
        if low in ("true", "false"):
            return low == "true"
        return text.strip()
    numbers = [
        int(v) if v.is_integer() and "." not in p else v
        for v, p in zip(numbers, parts, strict=True)
    ]
    return numbers[0] if len(numbers) == 1 else numbers


def in_every_slot(spec: str) -> dict[str, str]:
    """:attr:`Block.search_specs` of a block searched with the same ``spec`` in every
    slot it takes: input, output and feedback.

    >>> in_every_slot("dead-zone")
    {'input': 'dead-zone', 'output': 'dead-zone', 'feedback': 'dead-zone'}
    """
    return {"input": spec, "output": spec, "feedback": spec}


def channel_specs(value: Any) -> dict[str, Any] | None:
    """Blocks named by channel, ``{channel: spec}``, from a mapping, a text
    ``"CHANNEL=KIND[:options]"`` or a list of such texts; None when ``value`` names no
    channel (one block for every channel).

    >>> channel_specs(["u1=dead-zone", "u2=polynomial:degree=3"])
    {'u1': 'dead-zone', 'u2': 'polynomial:degree=3'}
    >>> channel_specs("polynomial:degree=3") is None
    True
    """
    if isinstance(value, dict):
        return {str(k): v for k, v in value.items()}
    items = [value] if isinstance(value, str) else value
    if not isinstance(items, list | tuple) or not all(isinstance(v, str) for v in items):
        return None
    pairs: dict[str, Any] = {}
    for item in items:
        head, eq, spec = item.partition("=")
        if not eq or ":" in head:
            if len(items) > 1:
                raise ParameterError(
                    f"{item!r}: with several blocks, name each one's channel, e.g. "
                    "'u1=dead-zone' 'u2=polynomial:degree=3'"
                )
            return None
        if head.strip() in pairs:
            raise ParameterError(f"channel {head.strip()!r} is given two blocks")
        pairs[head.strip()] = spec.strip()
    return pairs


def block_template(spec: str, *, output: bool = False) -> Block:
    """A block to fit, from its name and form: ``"KIND[:key=value[;key=value..]]"``.

    ``KIND`` is a block's ``kind`` (``dead-zone``, ``saturation``, ``polynomial``,
    ``piecewise-linear``, ``two-segment-polynomial``, ``backlash`` or a user block's);
    the options go to its :meth:`Block.template` (with ``output=True``, to its
    ``output_template`` where it has one: the output polynomial has no constant term and
    starts as the identity). Lists are comma separated.

    >>> block_template("polynomial:degree=2")
    Polynomial(coefficients=[0.0, 0.0, 0.0], constant=True)
    >>> block_template("dead-zone")
    DeadZone(lower=0.0, upper=0.0, slope_left=1.0, slope_right=1.0)
    """
    kind, _, rest = spec.strip().partition(":")
    kind = kind.strip().lower().replace("_", "-")
    aliases = {"deadzone": "dead-zone", "pwl": "piecewise-linear", "two-segment": None}
    kind = aliases.get(kind, kind) or "two-segment-polynomial"
    if kind not in BLOCK_TYPES or kind == "linear":
        known = ", ".join(sorted(k for k in BLOCK_TYPES if k != "linear"))
        raise ParameterError(f"unknown block {spec.strip()!r}; choose one of {known}")
    options: dict[str, Any] = {}
    for item in rest.split(";") if rest.strip() else []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ParameterError(
                f"block option {item.strip()!r} of {kind!r} must be key=value, e.g. "
                "'polynomial:degree=3' or 'piecewise-linear:knots=7'"
            )
        options[key.strip().replace("-", "_")] = _option_value(value)
    cls = BLOCK_TYPES[kind]
    make = getattr(cls, "output_template", cls.template) if output else cls.template
    try:
        return make(**options)
    except TypeError as exc:
        raise ParameterError(f"block {kind!r}: {exc}") from None
