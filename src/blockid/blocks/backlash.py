"""Backlash: the hysteretic input block of paper A's choke-finger subsystem (S2).

.. math::

    x(t) = \\begin{cases}
        m_L\\,(u(t) + c_L)  & u(t) < z_L(t) \\\\
        x(t-1)              & z_L(t) \\le u(t) \\le z_R(t) \\\\
        m_R\\,(u(t) - c_R)  & u(t) > z_R(t)
    \\end{cases}
    \\qquad z_L(t) = \\frac{x(t-1)}{m_L} - c_L,\\quad z_R(t) = \\frac{x(t-1)}{m_R} + c_R

(SPEC.md (A3)). With the switching function :math:`h(s) = 1` for :math:`s \\le 0`
and 0 otherwise, :math:`f_1(t) = h(u(t) - z_L(t))` (driving left) and
:math:`f_2(t) = h(z_R(t) - u(t))` (driving right), the three branches are one equation

.. math::

    x(t) = m_L u f_1 + m_L c_L f_1 + m_R u f_2 - m_R c_R f_2 + x(t-1)(1 - f_1)(1 - f_2)

(SPEC.md (A4)), which is what the identification algorithms (A6)–(A8) work with.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from blockid._kernels import writable
from blockid._kernels.backlash import backlash_run
from blockid._kernels.simulation import backlash_sensitivity
from blockid.blocks.base import EDGE_DISTANCE, DynamicBlock, _coinciding, _vanishing
from blockid.errors import DataError, ParameterError

__all__ = ["Backlash"]

#: Dead-band half-widths tried by the initial estimate, as fractions of the input span.
_GRID = (0.0, 0.0025, 0.005, 0.01, 0.02, 0.035, 0.05, 0.075, 0.1, 0.15, 0.2, 0.3)


class Backlash(DynamicBlock):
    """Backlash (play) with slopes ``m_left``, ``m_right`` and dead-band half-widths.

    Parameters
    ----------
    m_left, m_right : float
        Slopes of the left (driving down) and right (driving up) branches, ``> 0``.
    c_left, c_right : float
        Dead-band half-widths, ``>= 0``, in input units: the left branch is the line
        ``x = m_left (u + c_left)``, the right branch ``x = m_right (u - c_right)``.

    Notes
    -----
    The model equations are (A3) and, in switching form, (A4) of SPEC.md (see the
    module docstring). For ``m_left == m_right`` the output does not move after a
    reversal of the input until the input has travelled ``c_left + c_right``.

    Examples
    --------
    >>> import numpy as np
    >>> b = Backlash(m_left=1.0, c_left=0.5, m_right=1.0, c_right=0.5)
    >>> b.simulate(np.array([0.0, 2.0, 1.5, 1.0, 0.5]))
    array([0. , 1.5, 1.5, 1.5, 1. ])
    >>> f1, f2 = b.switching(np.array([0.0, 2.0, 1.5, 1.0, 0.5]))
    >>> f1, f2
    (array([0., 0., 0., 1., 1.]), array([0., 1., 0., 0., 0.]))
    """

    kind: ClassVar[str] = "backlash"
    export_source: ClassVar[str | None] = """
def run(p, u):  # from the middle of the dead band at the first input (rest_state)
    m_left, c_left, m_right, c_right = p["m_left"], p["c_left"], p["m_right"], p["c_right"]
    x = np.empty(len(u))
    if len(u) == 0:
        return x
    u0 = float(u[0])
    prev = 0.5 * (m_left * (u0 + c_left) + m_right * (u0 - c_right))
    for t, ut in enumerate(u.tolist()):
        if ut < prev / m_left - c_left:
            prev = m_left * (ut + c_left)
        elif ut > prev / m_right + c_right:
            prev = m_right * (ut - c_right)
        x[t] = prev
    return x
"""

    def __init__(self, m_left: float, c_left: float, m_right: float, c_right: float) -> None:
        self.m_left = _check_parameter("m_left", m_left, positive=True)
        self.c_left = _check_parameter("c_left", c_left, positive=False)
        self.m_right = _check_parameter("m_right", m_right, positive=True)
        self.c_right = _check_parameter("c_right", c_right, positive=False)

    @property
    def parameters(self) -> dict[str, Any]:
        """``{"m_left", "c_left", "m_right", "c_right"}`` as floats (SPEC Conventions)."""
        return {
            "m_left": self.m_left,
            "c_left": self.c_left,
            "m_right": self.m_right,
            "c_right": self.c_right,
        }

    def to_vector(self) -> np.ndarray:
        """``[m_left, c_left, m_right, c_right]`` as a float array."""
        return np.array([self.m_left, self.c_left, self.m_right, self.c_right])

    def with_vector(self, theta: Any) -> Backlash:
        """Backlash with ``[m_left, c_left, m_right, c_right] = theta``."""
        theta = np.asarray(theta, dtype=float).reshape(-1)
        if theta.size != 4:
            raise ParameterError(f"a backlash takes 4 parameter values, got {theta.size}")
        return Backlash(*theta)

    @classmethod
    def template(cls) -> Backlash:
        """A backlash to fit: the initial estimate searches its dead band on a grid."""
        return cls(1.0, 0.0, 1.0, 0.0)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Slopes positive (at least 1e-6 of their current value), dead bands >= 0."""
        lower = np.array([1e-6 * self.m_left, 0.0, 1e-6 * self.m_right, 0.0])
        return lower, np.full(4, np.inf)

    def scaled(self, gain: float) -> Backlash:
        if not gain > 0:
            raise ParameterError(
                f"cannot absorb the gain {gain:.4g} into a backlash, whose slopes must be "
                "positive: scale it by the gain's magnitude and keep the sign in the linear "
                "block after it (b_0 = -1), as the fits do"
            )
        return Backlash(gain * self.m_left, self.c_left, gain * self.m_right, self.c_right)

    def initial_grid(self, u: np.ndarray, around: Any = None) -> list[Any]:
        """Unit-slope backlashes with ``c_L = c_R = c`` **(choice)**, ``c`` on a grid of
        fractions of the input's span; with ``around`` (the best of them) a finer grid
        of 9 between its two neighbours."""
        span = float(np.ptp(u)) or 1.0
        grid = [span * g for g in _GRID]
        if around is None:
            return [Backlash(1.0, c, 1.0, c) for c in grid]
        k = int(np.argmin([abs(c - around.c_left) for c in grid]))
        fine = np.linspace(grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)], 9)
        return [Backlash(1.0, c, 1.0, c) for c in fine]

    def degeneracy(self, low: float, high: float) -> list[str]:
        """No play left (a static map with two slopes), a play wider than the input's
        range (an output that hardly moves), a branch whose slope vanishes beside the
        other: see :meth:`Block.degeneracy`."""
        play = self.c_left + self.c_right
        what = (
            f"the two sides of its play (c_left = {self.c_left:.3g}, c_right = {self.c_right:.3g})"
        )
        notes = _coinciding(
            what, play, low, high,
            "it has no play and is a static map with two slopes; fit a Hammerstein model "
            "with a piecewise-linear input block, or use data whose input reverses over a "
            "wider span",
        )  # fmt: skip
        width = high - low
        if np.isfinite(width) and width > 0 and play > EDGE_DISTANCE * width:
            notes.append(
                f"has a play c_left + c_right = {play:.3g}, {play / width:.3g} times the width "
                f"of the range its input covered in estimation [{low:.4g}, {high:.4g}]: its "
                "output hardly moves after the input's first reversal, so its slopes are not "
                "identified; fit a block of another form, or use data whose input travels "
                "further"
            )
        return notes + _vanishing(
            [("m_left", self.m_left), ("m_right", self.m_right)],
            "so the block holds its output on that branch; check that the plant does, or "
            "fit a block of another form",
        )

    def rest_state(self, u0: float) -> float:
        """The middle of the dead band at the first input, so that no start-up jump is
        simulated."""
        return 0.5 * (self.m_left * (u0 + self.c_left) + self.m_right * (u0 - self.c_right))

    def sensitivity(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Output from :meth:`rest_state` and its exact derivative with respect to
        ``[m_left, c_left, m_right, c_right]`` (branch derivatives, held in the band)."""
        u = np.ascontiguousarray(np.asarray(u, dtype=float))
        mL, cL, mR, cR = self.to_vector()
        u0 = u[0]
        x0 = self.rest_state(float(u0))
        dx0 = np.array([0.5 * (u0 + cL), 0.5 * mL, 0.5 * (u0 - cR), -0.5 * mR])
        return backlash_sensitivity(u, self.to_vector(), x0, dx0)

    def to_theta(self) -> np.ndarray:
        """Backlash part of the key-term-separated parameter vector of (A6).

        Returns ``[m_left, m_left*c_left, m_right, m_right*c_right]``.
        """
        return np.array(
            [self.m_left, self.m_left * self.c_left, self.m_right, self.m_right * self.c_right]
        )

    @classmethod
    def from_theta(cls, theta: np.ndarray) -> Backlash:
        """Read the backlash back from ``θ[:4]`` of (A6).

        ``m_left = θ1, c_left = θ2/θ1, m_right = θ3, c_right = θ4/θ3``.

        Examples
        --------
        >>> Backlash.from_theta([0.5, 0.4, 0.5, 0.425])
        Backlash(m_left=0.5, c_left=0.8, m_right=0.5, c_right=0.85)
        """
        theta = np.asarray(theta, dtype=float).ravel()
        if theta.size != 4:
            raise ParameterError(
                f"theta must hold 4 values [m_left, m_left*c_left, m_right, m_right*c_right], "
                f"got {theta.size}"
            )
        m_left = _check_parameter("theta[0] (m_left)", theta[0], positive=True)
        m_right = _check_parameter("theta[2] (m_right)", theta[2], positive=True)
        return cls(
            m_left=m_left,
            c_left=float(theta[1]) / m_left,
            m_right=m_right,
            c_right=float(theta[3]) / m_right,
        )

    def check_branches(self, u_min: float, u_max: float) -> None:
        """Check that the two branch lines do not cross for inputs in ``[u_min, u_max]``.

        The left line ``m_left (u + c_left)`` must not fall below the right line
        ``m_right (u - c_right)`` anywhere in the range; otherwise the dead band of
        (A3) is empty and the block is not a backlash there. With equal slopes the
        lines are parallel and the check always passes.

        Raises
        ------
        ParameterError
            If the range is invalid or the lines cross inside it.
        """
        lo = _check_parameter("u_min", u_min, positive=None)
        hi = _check_parameter("u_max", u_max, positive=None)
        if lo > hi:
            raise ParameterError(f"u_min ({lo}) must not exceed u_max ({hi}); swap them")
        # gap(u) = mL (u + cL) - mR (u - cR) is linear in u: check both ends.
        for u in (lo, hi):
            gap = self.m_left * (u + self.c_left) - self.m_right * (u - self.c_right)
            if gap < 0.0:
                cross = -(self.m_left * self.c_left + self.m_right * self.c_right) / (
                    self.m_left - self.m_right
                )
                raise ParameterError(
                    f"the backlash branches cross at u = {cross:.6g}, inside the input range "
                    f"[{lo:.6g}, {hi:.6g}]: the left line m_left*(u + c_left) falls below the "
                    f"right line m_right*(u - c_right) there; restrict the input range or use "
                    f"slopes m_left, m_right that are closer together"
                )

    def simulate(self, u: np.ndarray, x0: float = 0.0) -> np.ndarray:
        """Output ``x`` of (A3) for the input sequence ``u``, starting from ``x(-1) = x0``."""
        return self._run(u, x0)[0]

    def switching(self, u: np.ndarray, x0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Switching sequences ``f1`` (driving left) and ``f2`` (driving right) of (A4).

        Returned as float arrays of 0.0/1.0, for the trajectory that :meth:`simulate`
        produces from the same ``u`` and ``x0``.
        """
        _, f1, f2 = self._run(u, x0)
        return f1, f2

    def plot(self, ax: Any = None, u: np.ndarray | None = None, truth: Backlash | None = None):
        """Draw the hysteresis loop; see :func:`blockid.plotting.backlash.plot_backlash`."""
        from blockid.plotting.backlash import plot_backlash

        return plot_backlash(self, ax=ax, u=u, truth=truth)

    def _run(self, u: np.ndarray, x0: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        arr = np.asarray(u, dtype=float)
        if arr.ndim != 1:
            raise DataError(f"u must be a one-dimensional sequence, got shape {arr.shape}")
        if not np.all(np.isfinite(arr)):
            bad = int(np.flatnonzero(~np.isfinite(arr))[0])
            raise DataError(f"u contains a non-finite value at index {bad}; remove or fill it")
        x_start = _check_parameter("x0", x0, positive=None)
        return backlash_run(writable(arr), self.to_vector(), x_start)


def _check_parameter(name: str, value: Any, positive: bool | None) -> float:
    """Return ``value`` as a finite float; ``positive`` True: > 0, False: >= 0, None: any."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(number):
        raise ParameterError(f"{name} must be finite, got {number}")
    if positive is True and number <= 0.0:
        raise ParameterError(f"{name} must be > 0 (a backlash slope), got {number}")
    if positive is False and number < 0.0:
        raise ParameterError(f"{name} must be >= 0 (a dead-band half-width), got {number}")
    return number
