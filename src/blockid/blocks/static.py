"""Piecewise-linear static nonlinearities: dead zone, saturation, piecewise-linear map.

These are the hard nonlinearities of actuators and valves (paper B's proportional
valve has a dead band and saturates). Each is a :class:`~blockid.blocks.base.StaticBlock`
that evaluates element-wise on arrays of any shape.

The module also holds the small helpers every static block in :mod:`blockid.blocks`
shares: parameter checking that raises :class:`~blockid.errors.ParameterError`, input
conversion, and the :meth:`plot` hand-off to :func:`blockid.plotting.blocks.plot_block`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from blockid.blocks.base import (
    LinearFamily,
    StaticBlock,
    _coinciding,
    _far_outside,
    _vanishing,
    in_every_slot,
)
from blockid.errors import DataError, ParameterError

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["DeadZone", "Saturation", "PiecewiseLinear"]

#: Initial-estimate grids (fractions of the largest input magnitude). The grids hold
#: ``u = 0`` in the dead band and between the knees; the refinement moves them on.
_DEAD_ZONE_GRID = (0.0, 0.05, 0.1, 0.2, 0.3, 0.45, 0.6)
_SATURATION_GRID = (0.2, 0.35, 0.5, 0.65, 0.8, 1.0)


# --------------------------------------------------------------------------- helpers
def _float_scalar(name: str, value: Any, *, positive: bool = False) -> float:
    """Check that ``value`` is one finite real number (``> 0`` if ``positive``)."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a real number, got {value!r}") from None
    if not np.isfinite(x):
        raise ParameterError(f"{name} must be finite, got {x}")
    if positive and x <= 0:
        raise ParameterError(f"{name} must be > 0, got {x}")
    return x


def _float_vector(name: str, values: Any, *, min_length: int = 1) -> np.ndarray:
    """Check ``values`` is a 1-D sequence of finite reals; return a read-only copy."""
    try:
        arr = np.array(values, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a list of real numbers, got {values!r}") from None
    if arr.ndim != 1:
        raise ParameterError(f"{name} must be a flat list of numbers, got shape {arr.shape}")
    if arr.size < min_length:
        raise ParameterError(f"{name} needs at least {min_length} value(s), got {arr.size}")
    if not np.all(np.isfinite(arr)):
        raise ParameterError(f"{name} must contain finite numbers only, got {arr.tolist()}")
    arr.setflags(write=False)
    return arr


def _as_input(u: Any, name: str = "u") -> np.ndarray:
    """Convert the block input to a float array (any shape)."""
    try:
        return np.asarray(u, dtype=float)
    except (TypeError, ValueError):
        raise DataError(f"block input {name} must be numeric, got {type(u).__name__}") from None


def _check_range(name: str, u_range: Any, *, allow_infinite: bool = False) -> tuple[float, float]:
    """Check an input range ``(low, high)`` with ``low < high``; return it as floats."""
    try:
        low, high = (float(x) for x in u_range)
    except (TypeError, ValueError):
        raise ParameterError(
            f"{name} must be a pair of numbers (low, high), got {u_range!r}"
        ) from None
    if np.isnan(low) or np.isnan(high) or not (allow_infinite or np.isfinite([low, high]).all()):
        raise ParameterError(f"{name} must hold finite numbers, got ({low}, {high})")
    if low >= high:
        raise ParameterError(f"{name} must have low < high, got ({low}, {high})")
    return low, high


def _check_theta(theta: Any, size: int, what: str) -> np.ndarray:
    """Check a parameter vector handed to ``with_vector``."""
    arr = _float_vector("theta", theta)
    if arr.size != size:
        raise ParameterError(f"theta must have {size} entries ({what}), got {arr.size}")
    return arr


class _PlottableStaticBlock(StaticBlock):
    """A static block with a default plotting range and a :meth:`plot` hand-off."""

    def default_u_range(self) -> tuple[float, float]:
        """Input range that shows the shape of the curve (used when plotting)."""
        return (-1.0, 1.0)

    def plot(
        self,
        ax: Axes | None = None,
        u_range: tuple[float, float] | None = None,
        truth: StaticBlock | None = None,
        **kwargs: Any,
    ) -> Axes:
        """Draw the input-output curve ``w = N(u)``.

        See :func:`blockid.plotting.blocks.plot_block` for the arguments.
        """
        from blockid.plotting.blocks import plot_block

        return plot_block(self, ax=ax, u_range=u_range, truth=truth, **kwargs)


# --------------------------------------------------------------------------- blocks
class DeadZone(_PlottableStaticBlock):
    r"""Dead zone: no output on ``[lower, upper]``, linear outside.

    .. math::

        w = \begin{cases}
            m_L\,(u - u_L) & u < u_L \\
            0              & u_L \le u \le u_R \\
            m_R\,(u - u_R) & u > u_R
        \end{cases}

    Parameters
    ----------
    lower, upper : float
        Edges :math:`u_L \le u_R` of the dead band.
    slope_left, slope_right : float, default 1.0
        Slopes :math:`m_L, m_R > 0` outside the band.

    Examples
    --------
    >>> DeadZone(-0.5, 1.0, slope_right=2.0)([-1.0, 0.0, 2.0]).tolist()
    [-0.5, 0.0, 2.0]
    """

    kind = "dead-zone"
    anchored: ClassVar[bool] = True
    search_specs: ClassVar[dict[str, str]] = in_every_slot("dead-zone")
    search_priority: ClassVar[int] = 4
    export_source: ClassVar[str | None] = """
def evaluate(p, s):
    return p["slope_left"] * np.minimum(s - p["lower"], 0.0) + p["slope_right"] * np.maximum(
        s - p["upper"], 0.0
    )

def slope(p, s):
    return p["slope_left"] * (s < p["lower"]) + p["slope_right"] * (s > p["upper"])
"""

    def __init__(
        self, lower: float, upper: float, slope_left: float = 1.0, slope_right: float = 1.0
    ) -> None:
        self.lower = _float_scalar("lower", lower)
        self.upper = _float_scalar("upper", upper)
        if self.lower > self.upper:
            raise ParameterError(
                f"dead zone needs lower <= upper, got lower={self.lower}, upper={self.upper}; "
                "swap them"
            )
        self.slope_left = _float_scalar("slope_left", slope_left, positive=True)
        self.slope_right = _float_scalar("slope_right", slope_right, positive=True)

    @property
    def parameters(self) -> dict[str, Any]:
        return {
            "lower": self.lower,
            "upper": self.upper,
            "slope_left": self.slope_left,
            "slope_right": self.slope_right,
        }

    def __call__(self, u: np.ndarray) -> np.ndarray:
        u = _as_input(u)
        # lower <= upper, so at most one of the two terms is non-zero.
        return self.slope_left * np.minimum(u - self.lower, 0.0) + self.slope_right * np.maximum(
            u - self.upper, 0.0
        )

    @classmethod
    def template(cls) -> DeadZone:
        """A dead zone to fit: the initial estimate searches its edges on a grid."""
        return cls(0.0, 0.0)

    def jacobian(self, u: np.ndarray) -> np.ndarray:
        """``dw/d[lower, upper, slope_left, slope_right]``, shape ``(N, 4)``."""
        u = _as_input(u).ravel()
        left, right = np.minimum(u - self.lower, 0.0), np.maximum(u - self.upper, 0.0)
        return np.column_stack(
            (-self.slope_left * (u < self.lower), -self.slope_right * (u > self.upper), left, right)
        )

    def derivative(self, u: np.ndarray) -> np.ndarray:
        u = _as_input(u)
        return self.slope_left * (u < self.lower) + self.slope_right * (u > self.upper)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Slopes stay positive (at least 1e-6 of their current value)."""
        lower = np.full(4, -np.inf)
        lower[[2, 3]] = 1e-6 * np.array([self.slope_left, self.slope_right])
        return lower, np.full(4, np.inf)

    def piecewise_linear(self) -> tuple[np.ndarray, np.ndarray, float, float]:
        """Zero between the edges, the two slopes beyond them."""
        edges = np.array([self.lower, self.upper])
        return edges, np.zeros(2), self.slope_left, self.slope_right

    def scaled(self, gain: float) -> DeadZone:
        return DeadZone(self.lower, self.upper, gain * self.slope_left, gain * self.slope_right)

    def initial_grid(self, u: np.ndarray, around: Any = None) -> list[Any]:
        """Edges ``[-f_1 U, f_2 U]`` (``U = max |u|``) on a 7 x 7 grid; for fixed edges
        the dead zone is linear in its two slopes (:class:`LinearFamily`)."""
        if around is not None:
            return []
        peak = float(np.max(np.abs(u))) or 1.0
        return [
            _dead_zone_family(-peak * f1, peak * f2)
            for f1 in _DEAD_ZONE_GRID
            for f2 in _DEAD_ZONE_GRID
        ]

    def default_u_range(self) -> tuple[float, float]:
        width = self.upper - self.lower
        margin = width if width > 0 else max(abs(self.lower), abs(self.upper), 1.0)
        return (self.lower - margin, self.upper + margin)

    def degeneracy(self, low: float, high: float) -> list[str]:
        """Edges that coincide (no dead band left: a kink), an edge far outside the
        argument's range (that side and its slope never seen), a slope that vanishes
        beside the other on a side the data reach (a one-sided dead zone): see
        :meth:`Block.degeneracy`."""
        lower, upper = self.lower + 0.0, self.upper + 0.0  # shown without "-0"
        edges = f"its edges (lower = {lower:.6g}, upper = {upper:.6g})"
        notes = _coinciding(
            edges, self.upper - self.lower, low, high,
            "the dead band has vanished and the block is a kink with two slopes; fit a "
            "linear model or a piecewise-linear block, or use data that show a dead band",
        )  # fmt: skip
        notes += _far_outside(
            [(f"lower = {lower:.6g} (slope_left = {self.slope_left:.3g} below it)", lower),
             (f"upper = {upper:.6g} (slope_right = {self.slope_right:.3g} above it)", upper)],
            low, high,
        )  # fmt: skip
        reached = [("slope_left", self.slope_left)] if low < self.lower else []
        reached += [("slope_right", self.slope_right)] if high > self.upper else []
        if len(reached) == 2:
            notes += _vanishing(
                reached,
                "so the block is a one-sided dead zone (a rectifier); check that the plant "
                "is one, or fit a block of another form",
            )
        return notes


class Saturation(_PlottableStaticBlock):
    r"""Saturation: a linear gain clipped to ``[lower, upper]``.

    .. math::

        w = \min\bigl(\max(m\,u,\ w_{\min}),\ w_{\max}\bigr)

    Parameters
    ----------
    lower, upper : float
        Output limits :math:`w_{\min} < w_{\max}`.
    slope : float, default 1.0
        Gain :math:`m > 0` of the linear part.

    Examples
    --------
    >>> Saturation(-1.0, 2.0, slope=2.0)([-3.0, 0.25, 3.0]).tolist()
    [-1.0, 0.5, 2.0]
    """

    kind = "saturation"
    anchored: ClassVar[bool] = True
    search_specs: ClassVar[dict[str, str]] = in_every_slot("saturation")
    search_priority: ClassVar[int] = 3
    export_source: ClassVar[str | None] = """
def evaluate(p, s):
    return np.clip(p["slope"] * s, p["lower"], p["upper"])

def slope(p, s):
    v = p["slope"] * s
    return p["slope"] * ((v >= p["lower"]) & (v <= p["upper"]))
"""

    def __init__(self, lower: float, upper: float, slope: float = 1.0) -> None:
        self.lower = _float_scalar("lower", lower)
        self.upper = _float_scalar("upper", upper)
        if self.lower >= self.upper:
            raise ParameterError(
                f"saturation needs lower < upper, got lower={self.lower}, upper={self.upper}"
            )
        self.slope = _float_scalar("slope", slope, positive=True)

    @property
    def parameters(self) -> dict[str, Any]:
        return {"lower": self.lower, "upper": self.upper, "slope": self.slope}

    def __call__(self, u: np.ndarray) -> np.ndarray:
        return np.clip(self.slope * _as_input(u), self.lower, self.upper)

    @classmethod
    def template(cls) -> Saturation:
        """A saturation to fit: the initial estimate searches its knees on a grid."""
        return cls(-1.0, 1.0)

    def jacobian(self, u: np.ndarray) -> np.ndarray:
        """``dw/d[lower, upper, slope]``, shape ``(N, 3)``."""
        u = _as_input(u).ravel()
        v = self.slope * u
        inside = (v >= self.lower) & (v <= self.upper)
        return np.column_stack((v < self.lower, v > self.upper, u * inside)).astype(float)

    def derivative(self, u: np.ndarray) -> np.ndarray:
        v = self.slope * _as_input(u)
        return self.slope * ((v >= self.lower) & (v <= self.upper))

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The slope stays positive (at least 1e-6 of its current value)."""
        lower = np.full(3, -np.inf)
        lower[2] = 1e-6 * self.slope
        return lower, np.full(3, np.inf)

    def piecewise_linear(self) -> tuple[np.ndarray, np.ndarray, float, float]:
        """The limits reached at the knees ``lower / slope`` and ``upper / slope``, flat
        beyond them."""
        knees = np.array([self.lower, self.upper]) / self.slope
        return knees, np.array([self.lower, self.upper]), 0.0, 0.0

    def scaled(self, gain: float) -> Saturation:
        return Saturation(gain * self.lower, gain * self.upper, gain * self.slope)

    def initial_grid(self, u: np.ndarray, around: Any = None) -> list[Any]:
        """Unit-slope saturations with knees at ``-f_1 U`` and ``f_2 U`` (6 x 6 grid)."""
        if around is not None:
            return []
        peak = float(np.max(np.abs(u))) or 1.0
        return [
            Saturation(-peak * f1, peak * f2) for f1 in _SATURATION_GRID for f2 in _SATURATION_GRID
        ]

    def default_u_range(self) -> tuple[float, float]:
        knee_lo, knee_hi = self.lower / self.slope, self.upper / self.slope
        margin = 0.5 * (knee_hi - knee_lo)
        return (knee_lo - margin, knee_hi + margin)

    def degeneracy(self, low: float, high: float) -> list[str]:
        """Knees that coincide (no linear part left: a relay), a knee far outside the
        argument's range (a limit never reached): see :meth:`Block.degeneracy`."""
        knee_lo, knee_hi = self.lower / self.slope, self.upper / self.slope
        notes = _coinciding(
            f"its knees (lower / slope = {knee_lo:.6g}, upper / slope = {knee_hi:.6g})",
            knee_hi - knee_lo, low, high,
            "the linear part between the limits has vanished and the block is a relay (a "
            "step between its limits); fit a block of another form, or use data that show "
            "the linear part",
        )  # fmt: skip
        return notes + _far_outside(
            [(f"its lower knee lower / slope = {knee_lo:.6g}", knee_lo),
             (f"its upper knee upper / slope = {knee_hi:.6g}", knee_hi)],
            low, high,
        )  # fmt: skip


class PiecewiseLinear(_PlottableStaticBlock):
    r"""Piecewise-linear map through given points, extrapolated linearly beyond them.

    With breakpoints :math:`\beta_0 < \dots < \beta_{n-1}` and values :math:`v_j`,

    .. math::

        w = \sum_{j=0}^{n-1} v_j\,\Lambda_j(u)

    where :math:`\Lambda_j` are the hat functions (1 at :math:`\beta_j`, 0 at the
    other breakpoints, linear in between); the first and last segments continue
    beyond the end breakpoints. The output is linear in the values, so
    ``regressors(u) @ to_vector() == self(u)``.

    Parameters
    ----------
    breakpoints : sequence of float
        At least two strictly increasing input values.
    values : sequence of float
        Output at each breakpoint (same length).

    Examples
    --------
    >>> pwl = PiecewiseLinear([0.0, 1.0, 3.0], [0.0, 2.0, 3.0])
    >>> pwl([-1.0, 0.5, 2.0, 5.0]).tolist()
    [-2.0, 1.0, 2.5, 4.0]
    """

    kind = "piecewise-linear"
    search_specs: ClassVar[dict[str, str]] = {"input": "piecewise-linear:knots=7"}
    size_option: ClassVar[str | None] = "knots"
    search_priority: ClassVar[int] = 5
    linear_in_parameters = True
    export_source: ClassVar[str | None] = """
def _segments(p, s):
    bp, v = np.array(p["breakpoints"]), np.array(p["values"])
    j = np.clip(np.searchsorted(bp, s, side="right") - 1, 0, bp.size - 2)
    return bp, v, j

def evaluate(p, s):
    bp, v, j = _segments(p, s)
    t = (s - bp[j]) / (bp[j + 1] - bp[j])
    return v[j] + t * (v[j + 1] - v[j])

def slope(p, s):
    bp, v, j = _segments(p, s)
    return (v[j + 1] - v[j]) / (bp[j + 1] - bp[j])
"""

    def __init__(self, breakpoints: Sequence[float], values: Sequence[float]) -> None:
        self.breakpoints = _float_vector("breakpoints", breakpoints, min_length=2)
        if np.any(np.diff(self.breakpoints) <= 0):
            raise ParameterError(
                "breakpoints must be strictly increasing, got "
                f"{self.breakpoints.tolist()}; sort them and drop duplicates"
            )
        self.values = _float_vector("values", values, min_length=2)
        if self.values.size != self.breakpoints.size:
            raise ParameterError(
                f"values must have one entry per breakpoint ({self.breakpoints.size}), "
                f"got {self.values.size}"
            )

    @property
    def parameters(self) -> dict[str, Any]:
        return {"breakpoints": self.breakpoints.tolist(), "values": self.values.tolist()}

    @property
    def centred(self) -> bool:  # type: ignore[override]
        """Breakpoints spread over the data (``knots``) move with the centring; given
        breakpoints sit on the signal's own values, so a fit with them is not centred by
        default (:attr:`Block.centred`)."""
        return bool(getattr(self, "_spread", False))

    def _locate(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Segment index ``j`` (0..n-2) and position ``t`` of ``u`` in ``[β_j, β_j+1]``.

        ``t`` is outside ``[0, 1]`` on the extrapolated end segments.
        """
        bp = self.breakpoints
        j = np.clip(np.searchsorted(bp, u, side="right") - 1, 0, bp.size - 2)
        t = (u - bp[j]) / (bp[j + 1] - bp[j])
        return j, t

    def __call__(self, u: np.ndarray) -> np.ndarray:
        u = _as_input(u)
        j, t = self._locate(u)
        v = self.values
        return v[j] + t * (v[j + 1] - v[j])

    def piecewise_linear(self) -> tuple[np.ndarray, np.ndarray, float, float]:
        """Its breakpoints and values, the end segments' slopes beyond them."""
        bp, v = self.breakpoints, self.values
        left = (v[1] - v[0]) / (bp[1] - bp[0])
        right = (v[-1] - v[-2]) / (bp[-1] - bp[-2])
        return bp.copy(), v.copy(), float(left), float(right)

    def regressors(self, u: np.ndarray) -> np.ndarray:
        r"""Hat-function basis, shape ``(N, n)`` for ``N = u.size`` (``u`` is flattened).

        Row ``k`` holds :math:`\Lambda_j(u_k)`: ``1 - t`` and ``t`` in the columns of
        the two breakpoints around ``u_k``, zero elsewhere.
        """
        u = _as_input(u).ravel()
        j, t = self._locate(u)
        phi = np.zeros((u.size, self.breakpoints.size))
        rows = np.arange(u.size)
        phi[rows, j] = 1.0 - t
        phi[rows, j + 1] = t
        return phi

    def vector_names(self, rename: dict[str, str] | None = None) -> list[str]:
        """``values_0 .. values_{n-1}`` (the breakpoints are not estimated)."""
        base = (rename or {}).get("values", "values")
        return [f"{base}_{j}" for j in range(self.values.size)]

    def to_vector(self) -> np.ndarray:
        """Parameter vector: the values at the breakpoints (a copy)."""
        return self.values.copy()

    def with_vector(self, theta: np.ndarray) -> PiecewiseLinear:
        """New block with the same breakpoints and values ``theta``."""
        values = _check_theta(theta, self.breakpoints.size, "one value per breakpoint")
        return PiecewiseLinear(self.breakpoints, values)

    @classmethod
    def template(
        cls, knots: int = 7, breakpoints: Sequence[float] | None = None
    ) -> PiecewiseLinear:
        """A map to fit: given ``breakpoints``, or ``knots`` of them spread over the
        estimation input's range when fitting (:meth:`adapted`)."""
        if breakpoints is not None:
            bp = _float_vector("breakpoints", breakpoints, min_length=2)
            return cls(bp, np.zeros(bp.size))
        if isinstance(knots, bool) or not isinstance(knots, int | np.integer) or knots < 2:
            raise ParameterError(f"knots must be a whole number >= 2, got {knots!r}")
        block = cls(np.linspace(-1.0, 1.0, int(knots)), np.zeros(int(knots)))
        block._spread = True
        return block

    def adapted(self, u: np.ndarray) -> PiecewiseLinear:
        """With ``knots``: breakpoints evenly spaced between the input's extremes."""
        if not getattr(self, "_spread", False):
            return self
        lo, hi = float(np.min(u)), float(np.max(u))
        if not hi > lo:
            raise ParameterError(
                "the input is constant, so a piecewise-linear block cannot be placed on it"
            )
        n = self.breakpoints.size
        return PiecewiseLinear(np.linspace(lo, hi, n), np.zeros(n))

    def default_u_range(self) -> tuple[float, float]:
        lo, hi = float(self.breakpoints[0]), float(self.breakpoints[-1])
        margin = 0.1 * (hi - lo)
        return (lo - margin, hi + margin)

    def degeneracy(self, low: float, high: float) -> list[str]:
        """The closest neighbouring breakpoints when they coincide (a jump the data
        cannot resolve), a breakpoint far outside the argument's range (its value never
        seen): see :meth:`Block.degeneracy`. Flat segments are a shape (a saturation),
        not a degeneracy, so the slopes are not checked."""
        bp = self.breakpoints
        j = int(np.argmin(np.diff(bp)))
        notes = _coinciding(
            f"breakpoints_{j} = {bp[j]:.6g} and breakpoints_{j + 1} = {bp[j + 1]:.6g}",
            float(bp[j + 1] - bp[j]), low, high,
            "the segment between them is a jump the data cannot resolve; fit fewer knots",
        )  # fmt: skip
        return notes + _far_outside(
            [(f"breakpoints_{k} = {b:.6g}", float(b)) for k, b in enumerate(bp)], low, high
        )


def _dead_zone_family(lower: float, upper: float) -> LinearFamily:
    """Dead zones with fixed edges: linear in ``[slope_left, slope_right]``."""

    def basis(v: np.ndarray) -> np.ndarray:
        return np.column_stack((np.minimum(v - lower, 0.0), np.maximum(v - upper, 0.0)))

    return LinearFamily(basis, lambda slopes: DeadZone(lower, upper, *slopes))
