"""Piecewise-linear map whose breakpoints are estimated along with its values.

:class:`~blockid.blocks.static.PiecewiseLinear` places its kinks where it is told and is
linear in its values. :class:`FreePiecewiseLinear` is the same map (the same evaluation,
the same hat functions) with the breakpoints free as well, for a kink whose place is not
known (a dead band's edge, the knee of a valve's characteristic). It is no longer linear
in its parameters: the initial estimate fits its values by least squares with the
breakpoints spread over the input's range (:meth:`FreePiecewiseLinear.initial_grid`), and
the simulation-error refinement then moves the breakpoints with the analytic Jacobian.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from blockid.blocks.base import LinearFamily, in_every_slot
from blockid.blocks.static import PiecewiseLinear, _as_input, _check_theta
from blockid.errors import ParameterError

__all__ = ["FreePiecewiseLinear"]

#: How far (in default breakpoint spacings) a breakpoint may leave the range spanned by
#: the starting block's end breakpoints, which :meth:`FreePiecewiseLinear.adapted` puts
#: at the extremes of the estimation input.
_MARGIN = 0.5


class FreePiecewiseLinear(PiecewiseLinear):
    r"""Piecewise-linear map with estimated breakpoints, extrapolated linearly.

    With breakpoints :math:`\beta_0 < \dots < \beta_{n-1}` and values :math:`v_j`, on
    segment :math:`j` (:math:`\beta_j \le u < \beta_{j+1}`, the end segments continued
    beyond the end breakpoints), with :math:`h_j = \beta_{j+1} - \beta_j`,

    .. math::

        w = v_j + \frac{u - \beta_j}{h_j}\,(v_{j+1} - v_j),

    and the derivatives the refinement uses are

    .. math::

        \frac{\partial w}{\partial v_j} = \frac{\beta_{j+1} - u}{h_j}, \quad
        \frac{\partial w}{\partial v_{j+1}} = \frac{u - \beta_j}{h_j}, \quad
        \frac{\partial w}{\partial \beta_j} = \frac{(v_{j+1} - v_j)(u - \beta_{j+1})}{h_j^2},
        \quad
        \frac{\partial w}{\partial \beta_{j+1}} = -\frac{(v_{j+1} - v_j)(u - \beta_j)}{h_j^2}.

    The parameter vector is ``[breakpoints..., values...]``.

    Normalisation (:meth:`free_mask`): the end breakpoints only choose a point on each
    (straight, continued) end segment, so they are fixed; the interior breakpoints and
    all values move. After a linear block, a rescaling of the block's input is the
    linear block's gain, so one interior breakpoint is fixed too: it plays the part of
    the output polynomial's ``q_1 = 1``, and the linear block's gain brings the kinks to
    it.

    Parameters
    ----------
    breakpoints, values : sequence of float
        As for :class:`~blockid.blocks.static.PiecewiseLinear` (here the breakpoints'
        starting places).

    Examples
    --------
    >>> pwl = FreePiecewiseLinear([0.0, 1.0, 3.0], [0.0, 2.0, 3.0])
    >>> pwl([-1.0, 0.5, 2.0, 5.0]).tolist()
    [-2.0, 1.0, 2.5, 4.0]
    >>> pwl.vector_names()
    ['breakpoints_0', 'breakpoints_1', 'breakpoints_2', 'values_0', 'values_1', 'values_2']
    """

    kind = "piecewise-linear-free"
    search_specs: ClassVar[dict[str, str]] = in_every_slot("piecewise-linear-free:knots=5")
    size_option: ClassVar[str | None] = "knots"
    search_priority: ClassVar[int] = 2
    linear_in_parameters = False
    #: The same map, its derivative the same slope (:class:`PiecewiseLinear`'s).
    export_source: ClassVar[str | None] = PiecewiseLinear.export_source

    # ------------------------------------------------------------------ parameters
    def vector_names(self, rename: dict[str, str] | None = None) -> list[str]:
        """``breakpoints_0 .. breakpoints_{n-1}, values_0 .. values_{n-1}``."""
        rename = rename or {}
        n = self.breakpoints.size
        return [
            f"{rename.get(key, key)}_{j}" for key in ("breakpoints", "values") for j in range(n)
        ]

    def to_vector(self) -> np.ndarray:
        """Parameter vector ``[breakpoints..., values...]`` (a copy)."""
        return np.concatenate((self.breakpoints, self.values))

    def with_vector(self, theta: Any) -> FreePiecewiseLinear:
        """New block from ``[breakpoints..., values...]``.

        Raises :class:`~blockid.errors.ParameterError` when the breakpoints are not
        strictly increasing (the refinement then rejects the step).
        """
        n = self.breakpoints.size
        theta = _check_theta(theta, 2 * n, f"{n} breakpoints, then {n} values")
        steps = np.diff(theta[:n])
        if np.any(~(steps > 0)):
            j = int(np.argmax(~(steps > 0)))
            raise ParameterError(
                f"{self.kind}: breakpoints must stay strictly increasing, but breakpoints_"
                f"{j + 1} = {theta[j + 1]:.6g} is not above breakpoints_{j} = {theta[j]:.6g}",
                parameter="theta",
            )
        return type(self)(theta[:n], theta[n:])

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Breakpoints within half a default spacing of the range spanned by the end
        breakpoints (the estimation input's range for a block placed by
        :meth:`adapted`); values free."""
        bp = self.breakpoints
        n = bp.size
        margin = _MARGIN * (bp[-1] - bp[0]) / (n - 1)
        lower = np.concatenate((np.full(n, bp[0] - margin), np.full(n, -np.inf)))
        upper = np.concatenate((np.full(n, bp[-1] + margin), np.full(n, np.inf)))
        return lower, upper

    def free_mask(self, after_linear: bool) -> np.ndarray:
        """End breakpoints fixed; after a linear block, with four breakpoints or more,
        also the interior breakpoint next to the end farther from 0, which fixes the
        block's input gain (class docstring).

        The choice depends on fixed entries only (the end breakpoints), so it is the
        same for every block a fit visits. With two or three breakpoints nothing more is
        fixed (the only interior breakpoint of a symmetric three-point map sits at 0,
        where it fixes no gain): the gain is then shared with the linear block, a flat
        direction the refinement tolerates.
        """
        bp = self.breakpoints
        n = bp.size
        mask = np.ones(2 * n, dtype=bool)
        mask[[0, n - 1]] = False
        if after_linear and n > 3:
            mask[n - 2 if abs(bp[-1]) >= abs(bp[0]) else 1] = False
        return mask

    # ------------------------------------------------------------------ derivatives
    def jacobian(self, u: np.ndarray) -> np.ndarray:
        """``dw/d[breakpoints, values]``, shape ``(N, 2n)`` (class docstring)."""
        u = _as_input(u).ravel()
        bp, v = self.breakpoints, self.values
        n = bp.size
        j, t = self._locate(u)
        h = bp[j + 1] - bp[j]
        dv = v[j + 1] - v[j]
        rows = np.arange(u.size)
        G = np.zeros((u.size, 2 * n))
        G[rows, j] = dv * (t - 1.0) / h  # (v_j+1 - v_j)(u - β_j+1) / h²
        G[rows, j + 1] = -dv * t / h  # -(v_j+1 - v_j)(u - β_j) / h²
        G[rows, n + j] = 1.0 - t  # (β_j+1 - u) / h
        G[rows, n + j + 1] = t  # (u - β_j) / h
        return G

    def derivative(self, u: np.ndarray) -> np.ndarray:
        """``dw/du``: the slope of the segment of each input (the right one at a
        breakpoint)."""
        u = _as_input(u)
        j, _ = self._locate(u)
        bp, v = self.breakpoints, self.values
        return (v[j + 1] - v[j]) / (bp[j + 1] - bp[j])

    # ------------------------------------------------------------------ fitting aids
    @classmethod
    def template(
        cls, knots: int = 5, breakpoints: Sequence[float] | None = None
    ) -> FreePiecewiseLinear:
        """A map to fit: starting ``breakpoints``, or ``knots`` of them spread over the
        estimation input's range when fitting (:meth:`adapted`)."""
        return super().template(knots=knots, breakpoints=breakpoints)  # type: ignore[return-value]

    @classmethod
    def output_template(
        cls, knots: int = 5, breakpoints: Sequence[float] | None = None
    ) -> FreePiecewiseLinear:
        """The output block to fit: the identity (``values = breakpoints``) on
        ``breakpoints`` or on ``knots`` breakpoints over ``[-1, 1]``; the linear block in
        front and the refinement place the signal on it."""
        return cls.template(knots=knots, breakpoints=breakpoints).identity()

    def adapted(self, u: np.ndarray) -> FreePiecewiseLinear:
        """With ``knots``: breakpoints evenly spaced between the input's extremes."""
        if not getattr(self, "_spread", False):
            return self
        placed = super().adapted(u)
        return type(self)(placed.breakpoints, placed.values)

    def initial_grid(self, u: np.ndarray, around: Any = None) -> list[Any]:
        """The breakpoints held where they are (spread over the input by
        :meth:`adapted`): the map is then linear in its values, the hat functions, so
        the initial estimate fits them by the Hammerstein regression; the refinement
        moves the breakpoints."""
        if around is not None:
            return []
        return [LinearFamily(self.regressors, lambda values: type(self)(self.breakpoints, values))]

    def scaled(self, gain: float) -> FreePiecewiseLinear:
        """``gain * N(u)``: the values times ``gain``."""
        return type(self)(self.breakpoints, float(gain) * self.values)

    def identity(self) -> FreePiecewiseLinear:
        """The map ``w = u`` on the same breakpoints."""
        return type(self)(self.breakpoints, self.breakpoints)
