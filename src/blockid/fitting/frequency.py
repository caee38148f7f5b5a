"""A discrete transfer function fitted to a measured frequency response (the BLA).

Given the frequency response ``G(k)`` measured at lines ``f_k`` with the variance
``σ²_k`` of each (:func:`~blockid.evaluation.best_linear_approximation`: its total
variance, noise and nonlinear distortion together, where measured), find

.. math::

    \\hat G(z) = z^{-n_k} \\frac{b_0 + b_1 z^{-1} + \\dots + b_{n_b-1} z^{-(n_b-1)}}
                              {1 + a_1 z^{-1} + \\dots + a_{n_a} z^{-n_a}},
    \\qquad z_k = e^{j 2 \\pi f_k T_s},

minimising the weighted least-squares cost (Pintelon & Schoukens 2012, ch. 9)

.. math:: V(\\theta) = \\sum_k |G(k) - \\hat G(z_k, \\theta)|^2 / \\sigma_k^2 .

``V`` is not linear in ``a``; two steps, as is usual:

1. **Sanathanan-Koerner iterations**: multiply the error by ``A(z_k)``, which makes it
   linear in ``θ``, and divide by the previous iteration's ``A(z_k)`` so that the
   weighting tends to the right one: ``min Σ |A(z_k) G(k) - B(z_k)|² / (|A_prev(z_k)|²
   σ²_k)``, a real linear least-squares problem (real and imaginary parts stacked),
   from ``A_prev = 1`` (Levy's estimate), until ``θ`` settles;
2. **Levenberg-Marquardt** on ``V`` itself from there (SK's fixed point is not ``V``'s
   minimum when the data are noisy), with the analytic Jacobian
   ``∂Ĝ/∂b_j = z^{-n_k-j}/A``, ``∂Ĝ/∂a_i = -z^{-i} B/A²``.

**Uncertainty.** With circular complex errors of variance ``σ²_k`` each real and
imaginary part of ``(G - Ĝ)/σ_k`` has variance 1/2, so ``cov θ = (JᵀJ)⁻¹ / 2``, ``J`` the
Jacobian of the stacked weighted residual. ``V`` at the minimum is about ``F - n_θ / 2``
(``F`` lines) when the model is right and the variances are known; weighted by
variances *estimated* with ``d`` degrees of freedom each (a BLA of ``M`` realisations:
``d = 2(M - 1)``) it is ``d / (d - 2)`` times that, since ``E[1/σ̂²] = d / (d - 2) /
σ²`` (1.25 for 6 realisations). The ratio of ``V`` to its expected value is reported:
about 1 for a right model, well above 1 when the orders miss dynamics the data show.

The result is an :class:`~blockid.models.OutputError` model, ``B/A`` from the input
(no noise model), which ``blockid simulate`` runs like any other.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from blockid.errors import DataError, OrderError

__all__ = ["FrequencyFit", "fit_bla", "fit_frequency_response"]

#: Sanathanan-Koerner iterations at most, and the relative change that stops them.
SK_ITERATIONS, SK_TOLERANCE = 50, 1e-10


@dataclass(frozen=True)
class FrequencyFit:
    """A transfer function ``z^-nk B/A`` fitted to a frequency response.

    Attributes
    ----------
    a : ndarray
        ``[a_1 .. a_na]``.
    b : ndarray
        ``[b_0 .. b_{nb-1}]`` (of ``z^-nk .. z^-(nk+nb-1)``).
    nk : int
    covariance : ndarray
        Of ``[a, b]`` (module docstring).
    cost : float
        ``V`` at the minimum.
    lines : int
        ``F``, the lines fitted.
    sampling_time : float
    input_name, output_name : str
    variance_dof : float, optional
        Degrees of freedom of each line's estimated variance (None: known variances).
    """

    a: np.ndarray
    b: np.ndarray
    nk: int
    covariance: np.ndarray
    cost: float
    lines: int
    sampling_time: float
    input_name: str = "u"
    output_name: str = "y"
    variance_dof: float | None = None

    @property
    def standard_errors(self) -> np.ndarray:
        """Of ``[a, b]``."""
        return np.sqrt(np.diag(self.covariance))

    @property
    def cost_ratio(self) -> float:
        """``V`` over its expected value for a right model (module docstring): about 1."""
        expected = max(self.lines - (self.a.size + self.b.size) / 2.0, 1.0)
        d = self.variance_dof
        if d is not None and d > 2:
            expected *= d / (d - 2.0)
        return float(self.cost / expected)

    @property
    def poles(self) -> np.ndarray:
        return np.roots(np.r_[1.0, self.a]) if self.a.size else np.zeros(0, complex)

    def response(self, frequencies: Any) -> np.ndarray:
        """``Ĝ`` at ``frequencies`` (Hz)."""
        z1 = np.exp(-2j * np.pi * np.asarray(frequencies, float) * self.sampling_time)
        return _ratio(self.a, self.b, self.nk, z1)

    def model(self) -> Any:
        """The fit as an :class:`~blockid.models.OutputError` model."""
        from blockid.models import OutputError

        return OutputError(
            self.input_name, self.output_name, na=self.a.size, nb=self.b.size, nk=self.nk,
            a=self.a, b=self.b, sampling_time=self.sampling_time,
        )  # fmt: skip

    def names(self) -> list[str]:
        return [f"a_{i + 1}" for i in range(self.a.size)] + [f"b_{j}" for j in range(self.b.size)]

    def to_dict(self) -> dict[str, Any]:
        return {
            "na": int(self.a.size), "nb": int(self.b.size), "nk": self.nk,
            "a": self.a.tolist(), "b": self.b.tolist(),
            "standard_errors": dict(zip(self.names(), self.standard_errors.tolist(), strict=True)),
            "cost": self.cost, "lines": self.lines, "cost_ratio": self.cost_ratio,
            "stable": bool(np.all(np.abs(self.poles) < 1.0)),
            "poles": [[float(p.real), float(p.imag)] for p in self.poles],
        }  # fmt: skip


def _powers(z1: np.ndarray, first: int, count: int) -> np.ndarray:
    """``z^-(first + j)``, ``j = 0 .. count-1``, one column each."""
    return z1[:, None] ** (first + np.arange(count))[None, :]


def _ratio(a: np.ndarray, b: np.ndarray, nk: int, z1: np.ndarray) -> np.ndarray:
    big_a = 1.0 + _powers(z1, 1, a.size) @ a
    return (_powers(z1, nk, b.size) @ b) / big_a


def fit_frequency_response(
    frequencies: Any,
    g: Any,
    variance: Any,
    na: int,
    nb: int,
    nk: int = 0,
    *,
    sampling_time: float = 1.0,
    input_name: str = "u",
    output_name: str = "y",
    variance_dof: float | None = None,
) -> FrequencyFit:
    """Fit ``z^-nk B/A`` (``na`` poles, ``nb`` numerator coefficients) to ``g`` measured
    at ``frequencies`` (Hz) with variances ``variance`` (module docstring; estimated
    with ``variance_dof`` degrees of freedom each, None: known).

    Raises
    ------
    OrderError
        For orders that are not whole numbers (``na, nk >= 0``, ``nb >= 1``).
    DataError
        When fewer lines with a finite, positive variance remain than ``(na + nb) / 2 +
        1`` (each line gives two real equations).

    Examples
    --------
    >>> f = np.linspace(0.01, 0.49, 50)
    >>> z1 = np.exp(-2j * np.pi * f)
    >>> g = 0.5 * z1 / (1 - 0.8 * z1)
    >>> fit = fit_frequency_response(f, g, np.full(50, 1e-6), na=1, nb=1, nk=1)
    >>> np.round(fit.a, 6).tolist(), np.round(fit.b, 6).tolist()
    ([-0.8], [0.5])
    """
    from scipy.optimize import least_squares

    for name, value, low in (("na", na, 0), ("nb", nb, 1), ("nk", nk, 0)):
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < low:
            raise OrderError(f"{name} must be a whole number >= {low}, got {value!r}")
    f = np.asarray(frequencies, float).ravel()
    g = np.asarray(g, complex).ravel()
    var = np.asarray(variance, float).ravel()
    keep = np.isfinite(g) & np.isfinite(var) & (var > 0) & np.isfinite(f)
    f, g, sigma = f[keep], g[keep], np.sqrt(var[keep])
    if 2 * f.size < na + nb + 2:
        raise DataError(
            f"{f.size} lines with a measured variance are too few for {na} + {nb} "
            "coefficients: give lower orders or a measurement of more lines"
        )
    z1 = np.exp(-2j * np.pi * f * sampling_time)
    za, zb = _powers(z1, 1, na), _powers(z1, nk, nb)

    def stacked(x: np.ndarray) -> np.ndarray:
        return np.concatenate([x.real, x.imag])

    theta = np.zeros(na + nb)
    prev = np.ones_like(z1)
    for _ in range(SK_ITERATIONS):  # Sanathanan-Koerner: min |A G - B|² / |A_prev σ|²
        w = 1.0 / (prev * sigma)
        rows = np.hstack([za * (g * w)[:, None], -zb * w[:, None]])
        new, *_ = np.linalg.lstsq(stacked(rows), stacked(-g * w), rcond=None)
        change = np.linalg.norm(new - theta) / max(np.linalg.norm(new), 1e-300)
        theta = new
        prev = 1.0 + za @ theta[:na]
        if change < SK_TOLERANCE:
            break

    def residual(th: np.ndarray) -> np.ndarray:  # (G - B/A) / σ, real and imaginary parts
        return stacked((g - (zb @ th[na:]) / (1.0 + za @ th[:na])) / sigma)

    def jacobian(th: np.ndarray) -> np.ndarray:
        big_a = 1.0 + za @ th[:na]
        big_b = zb @ th[na:]
        d = np.hstack([-za * (big_b / big_a**2)[:, None], zb / big_a[:, None]])
        return -stacked(d / sigma[:, None])

    solved = least_squares(residual, theta, jac=jacobian, method="lm", xtol=1e-14,
                           ftol=1e-14, gtol=1e-14)  # fmt: skip
    theta = solved.x
    jac = jacobian(theta)
    covariance = 0.5 * np.linalg.pinv(jac.T @ jac)
    return FrequencyFit(
        a=theta[:na].copy(), b=theta[na:].copy(), nk=int(nk), covariance=covariance,
        cost=float(np.sum(residual(theta) ** 2)), lines=int(f.size),
        sampling_time=float(sampling_time), input_name=input_name, output_name=output_name,
        variance_dof=variance_dof,
    )  # fmt: skip


def fit_bla(bla: Any, na: int, nb: int, nk: int = 0) -> FrequencyFit:
    """:func:`fit_frequency_response` on a measured BLA
    (:class:`~blockid.evaluation.BestLinearApproximation`), weighted by its total
    variance where measured (noise and nonlinear distortion: what the BLA is uncertain
    by), else its noise variance, or Welch's variance.

    Raises
    ------
    DataError
        For a BLA without a variance (one realisation of one period).
    """
    std = bla.std
    if not np.any(np.isfinite(std)):
        raise DataError(
            "the BLA has no variance to weigh its lines by (one realisation of one "
            "period): measure 2 or more periods or realisations"
        )
    if bla.method == "welch":
        dof = 2.0 * (bla.segments - 1.0) if bla.segments else None
    elif bla.var_total is not None:  # between realisations
        dof = 2.0 * (bla.realisations - 1)
    else:  # between the periods of each realisation
        dof = 2.0 * bla.realisations * (bla.periods - 1)
    return fit_frequency_response(
        bla.frequencies, bla.g, std**2, na, nb, nk, sampling_time=bla.sampling_time,
        input_name=bla.input_name, output_name=bla.output_name, variance_dof=dof,
    )  # fmt: skip
