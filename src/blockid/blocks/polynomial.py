"""Polynomial static blocks: the plain polynomial and paper B's two-segment polynomial.

:class:`Polynomial` is the output block of the Hammerstein-Wiener model (B3, used
without a constant term) and a general smooth nonlinearity; it can be inverted on a
range where it is monotone (Wiener-type estimators need ``x = N^-1(y)``).
:class:`TwoSegmentPolynomial` is the input block (B1): one polynomial for ``u >= 0``
and another for ``u < 0``, which captures a direction-dependent actuator response.
Both are linear in their parameters: ``regressors(u) @ to_vector() == block(u)``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np
from numpy.polynomial import polynomial as npoly

from blockid.blocks.base import in_every_slot
from blockid.blocks.static import (
    _as_input,
    _check_range,
    _check_theta,
    _float_scalar,
    _float_vector,
    _PlottableStaticBlock,
)
from blockid.errors import EstimationError, ParameterError

__all__ = ["Polynomial", "TwoSegmentPolynomial"]


def _roots(coef: np.ndarray) -> np.ndarray:
    """Roots of a polynomial (lowest power first) whose negligible highest-power
    coefficients (below 1e-15 of the largest) are dropped first: a leading coefficient
    of 1e-308 would put roots beyond the float range (overflow, then NaN in the
    companion matrix); dropped, they are at infinity, which is where they act."""
    coef = np.asarray(coef, dtype=float)
    largest = float(np.max(np.abs(coef), initial=0.0))
    coef = npoly.polytrim(coef, 1e-15 * largest)
    if coef.size < 2:
        return np.zeros(0)
    return npoly.polyroots(coef)


def _monotone_sign(dcoef: np.ndarray, u_min: float, u_max: float) -> int:
    """Sign (+1 / -1) of a derivative polynomial that keeps one sign on the interval.

    Returns 0 when the derivative changes sign inside ``(u_min, u_max)`` or vanishes
    identically, i.e. when the primitive is not strictly monotone there. ``dcoef`` are
    the derivative's coefficients, lowest power first; the ends may be infinite.

    Isolated zeros (e.g. ``3 u^2`` at 0) do not break strict monotonicity. The
    interval is cut at the real parts of all roots (extra cuts are harmless), and the
    derivative is sampled once per piece; samples within rounding error of zero are
    ignored, so a double root that the root finder splits in two does not count as
    a sign change.
    """
    dcoef = npoly.polytrim(dcoef)
    if dcoef.size == 1:
        return int(np.sign(dcoef[0]))
    cuts = np.unique(_roots(dcoef).real)
    edges = np.concatenate(([u_min], cuts[(cuts > u_min) & (cuts < u_max)], [u_max]))
    left, right = edges[:-1], edges[1:]
    with np.errstate(invalid="ignore"):
        mid = left + 0.5 * (right - left)
        # Pieces reaching to -inf / +inf are sampled one step inside their finite end.
        mid = np.where(np.isneginf(left), right - np.maximum(1.0, np.abs(right)), mid)
        mid = np.where(np.isposinf(right), left + np.maximum(1.0, np.abs(left)), mid)
    mid = np.where(np.isneginf(left) & np.isposinf(right), 0.0, mid)
    values = npoly.polyval(mid, dcoef)
    # Horner rounding error bound, scaled generously.
    noise = 64 * np.finfo(float).eps * npoly.polyval(np.abs(mid), np.abs(dcoef))
    signs = np.sign(values[np.abs(values) > noise])
    if signs.size == 0 or np.any(signs != signs[0]):
        return 0
    return int(signs[0])


class Polynomial(_PlottableStaticBlock):
    r"""Polynomial nonlinearity, with or without a constant term.

    .. math::

        w = \sum_{l=l_0}^{r} c_l\, u^l, \qquad
        l_0 = \begin{cases} 0 & \text{constant=True} \\ 1 & \text{constant=False} \end{cases}

    The Hammerstein-Wiener output block (B3), :math:`y = \sum_{m=1}^{r_2} q_m x^m`,
    is ``Polynomial(q, constant=False)``.

    Parameters
    ----------
    coefficients : sequence of float
        :math:`[c_{l_0}, \dots, c_r]`, lowest power first.
    constant : bool, default True
        Whether the first coefficient is the constant term (power 0) or multiplies
        :math:`u` (power 1).

    Examples
    --------
    >>> N = Polynomial([1.0, 0.5], constant=False)      # u + 0.5 u^2
    >>> N([-2.0, 0.0, 2.0]).tolist()
    [0.0, 0.0, 4.0]
    >>> N.regressors([2.0]).tolist()
    [[2.0, 4.0]]
    >>> float(N.inverse([4.0], u_range=(0.0, 3.0))[0])
    2.0
    """

    kind = "polynomial"
    search_specs: ClassVar[dict[str, str]] = in_every_slot("polynomial:degree=3")
    size_option: ClassVar[str | None] = "degree"
    search_priority: ClassVar[int] = 0
    linear_in_parameters = True
    warn_extrapolation = True
    export_source: ClassVar[str | None] = """
def _powers(p):
    c = [float(v) for v in p["coefficients"]]
    return np.array(c if p.get("constant", True) else [0.0] + c)

def evaluate(p, s):
    return _polyval(s, _powers(p))

def slope(p, s):
    return _polyval(s, _derivative(_powers(p)))

def scalar(p):
    c = [float(v) for v in _powers(p)]

    def one(x):
        value = c[-1] + x * 0
        for i in range(2, len(c) + 1):
            value = c[-i] + value * x
        return value

    return one
"""

    def __init__(self, coefficients: Sequence[float], constant: bool = True) -> None:
        self.coefficients = _float_vector("coefficients", coefficients)
        if not isinstance(constant, bool | np.bool_):
            raise ParameterError(f"constant must be True or False, got {constant!r}")
        self.constant = bool(constant)

    @property
    def parameters(self) -> dict[str, Any]:
        return {"coefficients": self.coefficients.tolist(), "constant": self.constant}

    @classmethod
    def template(cls, degree: int = 3, constant: bool = True) -> Polynomial:
        """A polynomial of the given degree to fit (the identity when without constant:
        ``q = [1, 0, ..]``, as the output block of a cascade starts)."""
        if isinstance(degree, bool) or not isinstance(degree, int | np.integer) or degree < 1:
            raise ParameterError(f"degree must be a whole number >= 1, got {degree!r}")
        if constant:
            return cls(np.zeros(int(degree) + 1), constant=True)
        return cls([1.0] + [0.0] * (int(degree) - 1), constant=False)

    @classmethod
    def display_names(cls, position: str) -> dict[str, str]:
        """``f`` as the input block (B1's name), ``q`` as the output block (B3)."""
        return {"input": {"coefficients": "f"}, "output": {"coefficients": "q"}}.get(position, {})

    def check_output_block(self) -> None:
        if self.constant:
            raise ParameterError(
                "the output block must be a Polynomial without constant term (B3): use "
                "Polynomial(q, constant=False) (the output offset carries the constant)"
            )

    @classmethod
    def output_template(cls, degree: int = 3, constant: bool = False) -> Polynomial:
        """The output block of B3 to fit: ``q = [1, 0, .., 0]`` of the given degree (a
        constant term is refused after a linear block, B3)."""
        return cls.template(degree, constant=constant)

    @property
    def _linear_index(self) -> int:
        """Position of the coefficient of ``u`` in :attr:`coefficients`."""
        return 1 if self.constant else 0

    def free_mask(self, after_linear: bool) -> np.ndarray:
        """After a linear block the coefficient of ``u`` is fixed to 1 (``q_1 = 1``, B3)."""
        mask = np.ones(self.coefficients.size, dtype=bool)
        if after_linear and self.coefficients.size > self._linear_index:
            mask[self._linear_index] = False
        return mask

    def feedback_mask(self) -> np.ndarray:
        """In feedback the coefficient of ``y`` is fixed (to 0): a linear feedback only
        moves the poles, which ``A`` does (:mod:`blockid.models.feedback`)."""
        return self.free_mask(after_linear=True)

    def check_normalised(self, after_linear: bool) -> None:
        if not after_linear:
            return
        k = self._linear_index
        if self.coefficients.size <= k or self.coefficients[k] != 1.0:
            got = self.coefficients[k] if self.coefficients.size > k else "none"
            raise ParameterError(
                f"q_1 is fixed to 1 (normalisation B3): the coefficient of the linear term "
                f"must be 1 after a linear block; got {got}"
            )

    def identity(self) -> Polynomial | None:
        """Without constant: ``q = [1, 0, .., 0]`` of the same degree."""
        return None if self.constant else Polynomial.template(self.degree, constant=False)

    def normalised_input(self) -> tuple[Polynomial, float] | None:
        """Without constant: ``g = q_1`` and ``q'_m = q_m / g^m``, so ``N(x) = N'(g x)``."""
        if self.constant:
            return None
        g = float(self.coefficients[0])
        if g == 0:
            return None
        n = self.coefficients.size
        return Polynomial(self.coefficients / g ** np.arange(1, n + 1), constant=False), g

    def inverse_on(self, w: np.ndarray, u_range: tuple[float, float]) -> np.ndarray:
        """:meth:`inverse` on ``u_range``, clipping outputs beyond its image."""
        try:
            return self.inverse(w, u_range=u_range, clip=True)
        except ParameterError as exc:
            raise EstimationError(str(exc)) from None

    def monotone_branch(self) -> tuple[float, float]:
        """The interval around ``u = 0`` on which the polynomial is monotone.

        It runs to the nearest stationary points on either side (infinite where there
        is none).
        """
        crit = _roots(npoly.polyder(self._powers))
        real = crit[np.abs(crit.imag) < 1e-12].real if crit.size else np.zeros(0)
        lo = max((r for r in real if r < 0), default=-np.inf)
        hi = min((r for r in real if r > 0), default=np.inf)
        return float(lo), float(hi)

    def invert(self, w: np.ndarray, seen: tuple[float, float] | None = None) -> np.ndarray:
        """``u = N^{-1}(w)`` on the monotone branch around 0.

        The branch must contain the input range ``seen`` the block was fitted on (when
        known); outputs beyond the branch's reach map to its ends.
        """
        lo, hi = self.monotone_branch()
        if seen is not None and (seen[0] < lo or seen[1] > hi):
            raise EstimationError(
                f"the output block {self.coefficients.tolist()} is not monotone over the range "
                f"of x it was fitted on [{seen[0]:.4g}, {seen[1]:.4g}] (it turns at "
                f"{lo if seen[0] < lo else hi:.4g}), so past x cannot be recovered from the "
                "measured y; one-step prediction is not defined. Use free-run simulation"
            )
        w = np.asarray(w, dtype=float)
        scale = 1.0 + float(np.max(np.abs(w), initial=0.0))
        big = 1e6 * scale
        rng = (max(lo, -big), min(hi, big))
        try:
            return self.inverse(w, u_range=rng, clip=True)
        except (ParameterError, EstimationError) as exc:
            raise EstimationError(
                f"the output block {self.coefficients.tolist()} cannot be inverted on its "
                f"monotone branch {rng} ({exc}); one-step prediction is not defined"
            ) from None

    @property
    def degree(self) -> int:
        """Highest power ``r`` (counting zero leading coefficients)."""
        return self.coefficients.size - (1 if self.constant else 0)

    @property
    def _powers(self) -> np.ndarray:
        """Coefficients of all powers from 0, i.e. with a 0 constant prepended if needed."""
        if self.constant:
            return self.coefficients
        return np.concatenate(([0.0], self.coefficients))

    def __call__(self, u: np.ndarray) -> np.ndarray:
        return npoly.polyval(_as_input(u), self._powers)

    def compiled_form(self) -> tuple[str, np.ndarray]:
        return "polynomial", np.r_[self._powers.size, self._powers].astype(float)

    def derivative(self, u: np.ndarray) -> np.ndarray:
        r""":math:`dw/du = \sum_l l\, c_l\, u^{l-1}`, element-wise (same shape as ``u``)."""
        return npoly.polyval(_as_input(u), npoly.polyder(self._powers))

    def jacobian(self, u: np.ndarray) -> np.ndarray:
        """``dN/dc_l = u^l``, shape ``(N, n)`` (the powers, each computed directly)."""
        u = _as_input(u).ravel()
        first = 0 if self.constant else 1
        return np.column_stack([u**k for k in range(first, self.degree + 1)])

    def regressors(self, u: np.ndarray) -> np.ndarray:
        """Powers ``[u^l0 .. u^r]``, shape ``(N, n)`` for ``N = u.size`` (``u`` flattened)."""
        u = _as_input(u).ravel()
        powers = np.vander(u, self.degree + 1, increasing=True)
        return powers if self.constant else powers[:, 1:]

    def vector_names(self, rename: dict[str, str] | None = None) -> list[str]:
        """``c_l`` by power ``l`` (``q_1, q_2, ..`` without constant)."""
        base = (rename or {}).get("coefficients", "coefficients")
        first = 0 if self.constant else 1
        return [f"{base}_{j + first}" for j in range(self.coefficients.size)]

    def to_vector(self) -> np.ndarray:
        """Parameter vector: the coefficients (a copy)."""
        return self.coefficients.copy()

    def with_vector(self, theta: np.ndarray) -> Polynomial:
        """New polynomial of the same form with coefficients ``theta``."""
        return Polynomial(
            _check_theta(theta, self.coefficients.size, "one per coefficient"), self.constant
        )

    def is_monotone(self, u_min: float = -np.inf, u_max: float = np.inf) -> bool:
        """Whether the polynomial is strictly monotone on ``[u_min, u_max]``.

        The ends may be infinite (the default checks the whole real line). The
        derivative may touch zero at isolated points (``u^3`` is monotone).

        Examples
        --------
        >>> square = Polynomial([0.0, 0.0, 1.0])
        >>> square.is_monotone(-1.0, 1.0), square.is_monotone(0.0, 1.0)
        (False, True)
        """
        lo, hi = _check_range("(u_min, u_max)", (u_min, u_max), allow_infinite=True)
        return _monotone_sign(npoly.polyder(self._powers), lo, hi) != 0

    def inverse(
        self,
        w: np.ndarray,
        u_range: tuple[float, float] | None = None,
        u0: np.ndarray | float | None = None,
        *,
        clip: bool = False,
        tol: float = 1e-12,
        max_iter: int = 100,
    ) -> np.ndarray:
        """Solve ``N(u) = w`` for ``u``, element-wise, where ``N`` is monotone.

        Vectorised Newton iteration with a bisection safeguard: every sample keeps a
        bracket ``[lo, hi]`` around its root, and a Newton step that leaves the
        bracket or does not halve the previous step is replaced by bisection, so the
        iteration always converges.

        Parameters
        ----------
        w : array_like
            Output values (any shape). NaN gives NaN.
        u_range : (float, float), optional
            Finite input interval on which to invert; the polynomial must be strictly
            monotone there. None inverts on the whole real line, which needs a
            polynomial monotone everywhere (odd degree).
        u0 : float or array_like, optional
            Starting guess (broadcast to ``w``); default the middle of the bracket.
        clip : bool, default False
            With ``u_range``, values of ``w`` outside ``N(u_range)`` raise an error
            unless ``clip`` is True, in which case they map to the nearer end.
        tol : float, default 1e-12
            Stop when a step is below ``tol * (1 + |u|)``.
        max_iter : int, default 100
            Iteration limit (bisection alone gains one bit per iteration).

        Returns
        -------
        numpy.ndarray
            ``u`` with the shape of ``w``.

        Raises
        ------
        ParameterError
            If the polynomial is not monotone on the range, or ``w`` falls outside
            the range's image and ``clip`` is False.
        """
        w = _as_input(w, "w")
        tol = _float_scalar("tol", tol, positive=True)
        if int(max_iter) < 1:
            raise ParameterError(f"max_iter must be >= 1, got {max_iter}")
        whole_line = u_range is None
        a, b = (-np.inf, np.inf) if whole_line else _check_range("u_range", u_range)
        powers = npoly.polytrim(self._powers)
        dpowers = npoly.polyder(powers)
        sign = _monotone_sign(dpowers, a, b)
        if sign == 0:
            where = "on the whole real line" if whole_line else f"on u_range=({a}, {b})"
            raise ParameterError(
                f"cannot invert {self!r}: it is not strictly monotone {where}; "
                "pass a u_range on which it is monotone (see is_monotone)"
            )

        shape = w.shape
        w = w.ravel().copy()
        if whole_line:
            # Cauchy bound: every root of N(u) - w lies in |u| <= 1 + max_k |a_k / a_r|.
            rest = np.abs(powers[1:-1]).max(initial=0.0)
            bound = 1.0 + np.maximum(np.abs(powers[0] - w), rest) / abs(powers[-1])
            lo, hi = -bound, bound.copy()
        else:
            w_lo, w_hi = sorted((float(npoly.polyval(a, powers)), float(npoly.polyval(b, powers))))
            outside = (w < w_lo) | (w > w_hi)
            if np.any(outside) and not clip:
                bad = w[outside][0]
                raise ParameterError(
                    f"w = {bad} is outside [{w_lo}, {w_hi}], the image of u_range=({a}, {b}); "
                    "widen u_range or pass clip=True"
                )
            w = np.clip(w, w_lo, w_hi)
            lo, hi = np.full(w.shape, a), np.full(w.shape, b)

        active = np.isfinite(w)  # samples still iterating; NaN in, NaN out
        with np.errstate(invalid="ignore"):
            u = 0.5 * (lo + hi)
            step = hi - lo  # last step length, per sample
        if u0 is not None:
            try:
                u0 = np.broadcast_to(_as_input(u0, "u0"), shape).ravel()
            except ValueError:
                raise ParameterError(
                    f"u0 must be a number or broadcast to w's shape {shape}"
                ) from None
            u = np.clip(u0, lo, hi)
        u[~active] = np.nan
        for _ in range(int(max_iter)):
            k = np.flatnonzero(active)
            if k.size == 0:
                break
            uk = u[k]
            g = sign * (npoly.polyval(uk, powers) - w[k])  # increasing in u
            dg = sign * npoly.polyval(uk, dpowers)
            below = g < 0
            lo[k[below]] = uk[below]
            hi[k[~below]] = uk[~below]
            with np.errstate(divide="ignore", invalid="ignore"):
                newton = uk - g / dg
            bisect = (
                ~np.isfinite(newton)
                | (newton <= lo[k])
                | (newton >= hi[k])
                | (2.0 * np.abs(newton - uk) > step[k])
            )
            unew = np.where(bisect, 0.5 * (lo[k] + hi[k]), newton)
            unew = np.where(g == 0, uk, unew)
            step[k] = np.abs(unew - uk)
            u[k] = unew
            small = tol * (1.0 + np.abs(unew))
            done = (step[k] <= small) | (hi[k] - lo[k] <= small)
            active[k[done]] = False
        if np.any(active):
            raise EstimationError(
                f"polynomial inverse did not converge in {max_iter} iterations for "
                f"{np.count_nonzero(active)} sample(s); raise max_iter or tol"
            )
        return u.reshape(shape)


class TwoSegmentPolynomial(_PlottableStaticBlock):
    r"""Two-segment polynomial input block of the Hammerstein-Wiener model (B1).

    .. math::

        w = \sum_{l=0}^{r_1} f_l\, u^l + \sum_{l=0}^{r_1} p_l\, u^l\, h(u), \qquad
        h(u) = \begin{cases} 1 & u < 0 \\ 0 & u \ge 0 \end{cases}

    so :math:`w = \sum f_l u^l` for :math:`u \ge 0` and :math:`w = \sum g_l u^l` with
    :math:`g_l = f_l + p_l` for :math:`u < 0`. The parameter vector is
    :math:`[f_0..f_{r_1}, p_0..p_{r_1}]` and the regressors are
    :math:`[1, u, .., u^{r_1}, h, u h, .., u^{r_1} h]`, as in (B4).

    Parameters
    ----------
    f : sequence of float
        :math:`[f_0, \dots, f_{r_1}]`, the polynomial for ``u >= 0``.
    p : sequence of float
        :math:`[p_0, \dots, p_{r_1}]`, the change of the polynomial for ``u < 0``
        (same length as ``f``).

    Examples
    --------
    >>> N = TwoSegmentPolynomial.from_segments(positive=[0.0, 2.0], negative=[0.0, 0.5])
    >>> N.parameters
    {'f': [0.0, 2.0], 'p': [0.0, -1.5]}
    >>> N([-2.0, 1.0]).tolist()
    [-1.0, 2.0]
    """

    kind = "two-segment-polynomial"
    anchored: ClassVar[bool] = True
    search_specs: ClassVar[dict[str, str]] = {"input": "two-segment-polynomial:degree=3"}
    size_option: ClassVar[str | None] = "degree"
    search_priority: ClassVar[int] = 1
    linear_in_parameters = True
    warn_extrapolation = True
    export_source: ClassVar[str | None] = """
def evaluate(p, s):
    return _polyval(s, np.array(p["f"])) + (s < 0) * _polyval(s, np.array(p["p"]))

def slope(p, s):
    return _polyval(s, _derivative(p["f"])) + (s < 0) * _polyval(s, _derivative(p["p"]))
"""

    def __init__(self, f: Sequence[float], p: Sequence[float]) -> None:
        self.f = _float_vector("f", f)
        self.p = _float_vector("p", p)
        if self.p.size != self.f.size:
            raise ParameterError(
                f"f and p must have the same length r1 + 1, got {self.f.size} and {self.p.size}; "
                "pad the shorter one with zeros"
            )

    @classmethod
    def template(cls, degree: int = 3) -> TwoSegmentPolynomial:
        """A two-segment polynomial of order ``degree`` (r1) to fit."""
        if isinstance(degree, bool) or not isinstance(degree, int | np.integer) or degree < 1:
            raise ParameterError(f"degree (r1) must be a whole number >= 1, got {degree!r}")
        return cls(np.zeros(int(degree) + 1), np.zeros(int(degree) + 1))

    def check_data(self, u: np.ndarray) -> None:
        """Both segments need inputs: ``u`` must take both signs."""
        if not (np.any(u < 0) and np.any(u >= 0)):
            raise EstimationError(
                "the input never changes sign, so the two polynomials of the two-segment "
                "input block (B1) cannot both be identified; use data that span both signs "
                "of u, or a Polynomial input block"
            )

    def derivative(self, u: np.ndarray) -> np.ndarray:
        u = _as_input(u)
        return npoly.polyval(u, npoly.polyder(self.f)) + (u < 0) * npoly.polyval(
            u, npoly.polyder(self.p)
        )

    @classmethod
    def from_segments(
        cls, positive: Sequence[float], negative: Sequence[float]
    ) -> TwoSegmentPolynomial:
        """Build from the two polynomials ``f`` (``u >= 0``) and ``g`` (``u < 0``).

        Both are lowest power first; the shorter one is padded with zeros.
        """
        f = _float_vector("positive", positive)
        g = _float_vector("negative", negative)
        n = max(f.size, g.size)
        f = np.pad(f, (0, n - f.size))
        g = np.pad(g, (0, n - g.size))
        return cls(f, g - f)  # p_l = g_l - f_l (B1)

    @property
    def parameters(self) -> dict[str, Any]:
        return {"f": self.f.tolist(), "p": self.p.tolist()}

    @property
    def order(self) -> int:
        """Polynomial order :math:`r_1`."""
        return self.f.size - 1

    @property
    def g(self) -> np.ndarray:
        """Coefficients :math:`g_l = f_l + p_l` of the polynomial for ``u < 0``."""
        return self.f + self.p

    def compiled_form(self) -> tuple[str, np.ndarray]:
        return "two-segment-polynomial", np.r_[self.f.size, self.f, self.p].astype(float)

    def __call__(self, u: np.ndarray) -> np.ndarray:
        u = _as_input(u)
        h = u < 0  # (B1)
        return npoly.polyval(u, self.f) + h * npoly.polyval(u, self.p)

    def regressors(self, u: np.ndarray) -> np.ndarray:
        """``[1, u, .., u^r1, h, u h, .., u^r1 h]``, shape ``(N, 2 (r1 + 1))`` (B4)."""
        u = _as_input(u).ravel()
        powers = np.vander(u, self.f.size, increasing=True)
        return np.hstack((powers, powers * (u < 0)[:, None]))

    def to_vector(self) -> np.ndarray:
        """Parameter vector :math:`[f_0..f_{r_1}, p_0..p_{r_1}]` (B4)."""
        return np.concatenate((self.f, self.p))

    def with_vector(self, theta: np.ndarray) -> TwoSegmentPolynomial:
        """New block with ``theta = [f_0..f_r1, p_0..p_r1]``."""
        n = self.f.size
        theta = _check_theta(theta, 2 * n, "f then p")
        return TwoSegmentPolynomial(theta[:n], theta[n:])
