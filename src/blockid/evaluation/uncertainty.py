"""Standard errors of identified parameters and a confidence band on simulated output.

The covariance of a prediction-error estimate (Ljung, *System Identification*, 2nd ed.,
ch. 9) is, to first order,

.. math::

    \\operatorname{cov}\\hat\\theta \\approx \\hat\\sigma^2 \\bigl(J^T J\\bigr)^{-1},
    \\qquad \\hat\\sigma^2 = \\frac{\\sum_k \\varepsilon(k)^2}{N - n_0 - p}

where ``J`` is the Jacobian of the model's predictions with respect to the ``p`` free
parameters at the estimate, ``ε`` the residuals and ``N - n_0`` the number of samples
after the initial conditions. Which predictions depends on the model:

* **Block-oriented models** (any chain of blocks, and the feedback model): the free-run
  simulation and its analytic sensitivities
  (:meth:`simulate_with_sensitivities` of the model), started from
  the first ``max_lag`` measured outputs of each experiment, which are skipped, as the
  simulation-error fit does. This is the covariance of the output-error estimate, and it
  **assumes the output-error noise model**: white measurement noise added to ``y``. With
  process noise (noise that goes through the dynamics) the free-run residuals are
  coloured and these standard errors are too small. For a model found by another method
  (key-term or backlash RLS) it is the same expression at that method's estimate: the
  uncertainty the estimate would have as an output-error estimate, a lower bound for
  the less efficient recursive estimators.
* **State-space models** (linear and polynomial): the free-run Jacobian in the
  normalised units the fit minimises, over the matrices ``θ`` and every experiment's
  initial state (estimated alongside, as the fit does), with the output-error noise
  model as above. The matrices are unique only up to a change of state basis
  ``x -> T x``: ``J^T J`` is singular in those ``nx²`` directions, so the covariance is
  its pseudo-inverse without them (the directions whose scaled eigenvalue is below
  ``1e-10`` of the largest; their number is in ``basis``). Standard errors are then
  those of the fitted basis, not of a canonical form; the band on simulated output,
  which the basis does not change, is what to read (30 records of a second-order plant
  at 26 dB: the 95 % band held the noise-free output in 95.5 % of the samples). The
  output offsets (normalisation constants from the estimation data) enter the band as
  the centred offsets below.
* **ARX**: the least-squares expression ``σ² (Φ^T Φ)^{-1}`` of every output's regression,
  ``σ²`` from that output's one-step residuals. It assumes white equation error. For
  the recursive ARX methods the final ``P`` of the recursion is not kept by the fit; the
  same expression is used at their final estimate (with forgetting 1 and a large
  ``P(0)``, ``σ² P`` is that expression up to the tiny ``P(0)`` term).

Calibration (``tests/evaluation/test_uncertainty.py``): a Hammerstein-Wiener plant
simulated at 40 dB white output noise and fitted by the default method over 20 noise
seeds; the true parameters lie within two reported standard errors in about 95 % of the
cases, see ``docs/export.md`` for the numbers per parameter group.

Parameters fixed by the normalisation (``b_0 = 1`` after an input block, ``q_1 = 1``)
have standard error 0. A parameter the data cannot determine (a direction of ``J`` with
no excitation) has an infinite standard error, written ``null`` in JSON.

The band on simulated output linearises the simulation around the estimate,
``var ŷ(k) ≈ J_k cov J_k^T``: a confidence band for the noise-free output of the plant,
not a prediction band for measurements (``noise=True`` adds the noise variance).

**Offsets.** A model fitted with ``center`` (the default of Wiener, output-error,
Wiener-Hammerstein and feedback models) takes the means of the estimation data as its
operating point, ``ŷ = y_0 + g(u - u_0; θ)``, and fits ``θ`` with the offsets held. Given
the input, as the covariance above is, ``u_0 = ū`` is not uncertain: the fit adapts ``θ``
to it. The output offset ``y_0 = ȳ`` is, twice over:

* **noise**: ``ȳ`` holds the mean ``v̄`` of the output noise, of variance
  ``σ²/N_eff`` with ``N_eff = N (1 - ρ)/(1 + ρ)`` from the lag-1 autocorrelation ``ρ``
  of the residuals (clipped to ``[0, 0.99]``; ``N`` every estimation sample). To first
  order the simulated output's error at a sample with sensitivity row ``j`` is
  ``v̄ (1 - m) + j (J^T J)^{-1} J^T v`` with ``m = j w`` and ``w = (J^T J)^{-1} J^T 1``,
  the parameter step that best imitates a unit output offset, so its variance is

  .. math:: J_k\\, \\mathrm{cov}\\, J_k^T + \\frac{\\hat\\sigma^2}{N_{\\mathrm{eff}}}
            \\bigl(1 - m_k^2\\bigr)

  (``m ≈ 0`` when no parameter can make a constant, as in a linear block;
  ``m ≈ 1`` when one can, such as a polynomial's constant, which then absorbs the
  offset's error and is already in ``cov``). For ARX, whose noise model is
  ``e/A``, the variance of ``v̄`` is ``(A(1)^{-1} diag(σ²) A(1)^{-T})_{ii} / N``.
* **bias**: ``ȳ`` is not an equilibrium of the plant at ``ū``: the response to the last
  inputs of a record is missing from it, a record that starts away from the operating
  point adds a transient, and for a nonlinear chain the mean of ``f(u)`` is not ``f(ū)``.
  With slow dynamics and a large static gain this error, of order ``1/N``, is larger
  than the noise's. A model without a constant term cannot absorb it, and the mean
  free-run residual on the estimation data shows it: ``b = -mean(y - ŷ)`` estimates the
  constant error of the simulated output.

The band then takes, at each sample, the half-width ``w`` for which an error
``N(b, s²)`` lies in ``±w`` with probability ``level`` (``z s`` when ``b = 0``). An
output-error plant at 30 dB, 400 samples, fitted with ``center`` and checked on a new
input over 12 seeds: the 95 % band held the noise-free output in 27 % of the samples
without the offset terms and 94 % with them (input mean 0.5: 1 % and 96 %). Treating
``ū`` and ``ȳ`` as means of stationary signals (``var(u)/N_eff(u)`` through ``dŷ/du_0``,
``var(y)/N_eff(y)``) would count the excitation as noise: a standard deviation of
0.4-0.5 there, where the simulated output's errors were 0.003-0.07. A centred
Hammerstein-Wiener model whose two-segment input block splits at ``u_0`` while the
plant's splits elsewhere is biased in shape, not in offset: no band from these terms
covers that. Whether the offsets are the estimation means is taken from the fit
(``settings["center"]``) or, for a model alone, from the offsets being equal to the
means of the data.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from statistics import NormalDist
from typing import Any, NamedTuple

import numpy as np

from blockid.data.dataset import Dataset
from blockid.errors import DataError, ParameterError

__all__ = [
    "ParameterCovariance",
    "SimulationBand",
    "band_columns",
    "load_covariance",
    "named_standard_errors",
    "parameter_covariance",
    "simulation_band",
    "standard_errors",
    "with_standard_errors",
]

#: Relative singular value below which a direction of the scaled Jacobian counts as
#: unidentifiable.
_RANK_TOL = 1e-10
#: Eigenvalues of a state-space model's scaled ``J^T J`` below this fraction of the
#: largest are directions of the state basis (``T``), not of the model.
_STATE_BASIS_TOL = 1e-10

#: Methods whose estimate is a least-squares fit of the one-step (ARX) regression.
_RECURSIVE_ARX = ("rls", "aw-rls", "hierarchical-rls")


@dataclass(frozen=True)
class ParameterCovariance:
    """Covariance of a model's free parameters.

    Attributes
    ----------
    names : list of str
        Free parameters (``free_parameter_names()`` of a block-oriented model, the
        ``parameter_names`` of every output of an ARX model, outputs one after another).
    estimate : ndarray, shape (p,)
        Their values.
    matrix : ndarray, shape (p, p)
        The covariance (infinite rows for unidentifiable parameters).
    noise_variance : dict
        ``σ²`` per output.
    degrees_of_freedom : int
        Residual samples minus parameters.
    basis : str
        What the covariance was computed from.
    offsets : dict
        Per output, when the model's offsets are the means of the estimation data
        (``center``; module docstring): ``variance`` of the output offset from the
        noise, ``bias`` (the constant error of the simulated output the residuals show)
        and, for block-oriented models, ``direction`` (``w``: the free-parameter step
        that best imitates a unit output offset). Empty otherwise.
    """

    names: list[str]
    estimate: np.ndarray
    matrix: np.ndarray
    noise_variance: dict[str, float]
    degrees_of_freedom: int
    basis: str
    offsets: dict[str, dict[str, Any]] = field(default_factory=dict)

    @property
    def standard_errors(self) -> np.ndarray:
        """Square roots of the diagonal, one per free parameter."""
        return np.sqrt(np.diag(self.matrix))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (lists of floats; ``None`` for infinite entries)."""
        doc = {
            "names": list(self.names),
            "matrix": [[_finite_or_none(v) for v in row] for row in self.matrix],
            "noise_variance": {k: _finite_or_none(v) for k, v in self.noise_variance.items()},
            "degrees_of_freedom": int(self.degrees_of_freedom),
            "basis": self.basis,
        }
        if self.offsets:
            doc["offsets"] = {
                name: {
                    k: [_finite_or_none(x) for x in v] if k == "direction" else _finite_or_none(v)
                    for k, v in entry.items()
                }
                for name, entry in self.offsets.items()
            }
        return doc

    @classmethod
    def from_dict(cls, data: dict[str, Any], estimate: Any = None) -> ParameterCovariance:
        """Inverse of :meth:`to_dict` (``None`` entries back to infinity)."""
        matrix = np.array(
            [[np.inf if v is None else float(v) for v in row] for row in data["matrix"]]
        ).reshape(len(data["names"]), len(data["names"]))
        noise = {k: np.inf if v is None else float(v) for k, v in data["noise_variance"].items()}
        value = np.full(len(data["names"]), np.nan) if estimate is None else estimate
        offsets = {
            name: {
                k: np.array([np.inf if x is None else float(x) for x in v])
                if k == "direction"
                else (np.inf if v is None else float(v))
                for k, v in entry.items()
            }
            for name, entry in data.get("offsets", {}).items()
        }
        return cls(
            list(data["names"]),
            np.asarray(value, dtype=float),
            matrix,
            noise,
            int(data["degrees_of_freedom"]),
            str(data["basis"]),
            offsets,
        )


class SimulationBand(NamedTuple):
    """Confidence band on a simulated output: arrays of shape ``(N, ny)``.

    ``std`` is the standard deviation of the simulated output's error (parameters and,
    for a centred model, the output offset's noise); ``bias`` (shape ``(ny,)``) its
    constant part estimated from the estimation residuals, which widens the band.
    """

    lower: np.ndarray
    upper: np.ndarray
    simulated: np.ndarray
    std: np.ndarray
    level: float
    bias: np.ndarray


def _finite_or_none(value: float) -> float | None:
    value = float(value)
    return value if np.isfinite(value) else None


# ----------------------------------------------------------------------------- covariance
def _least_squares_covariance(J: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, float, int]:
    """``σ² (J^T J)^{-1}`` with ``σ² = |r|^2 / (n - p)``; columns scaled for conditioning,
    directions without excitation given infinite variance."""
    n, p = J.shape
    dof = n - p
    if dof < 1:
        raise DataError(
            f"{n} residual sample(s) for {p} parameter(s): too few to estimate the noise "
            "variance and the parameters' standard errors"
        )
    sigma2 = float(r @ r) / dof
    scale = np.sqrt(np.sum(J**2, axis=0))
    scale[scale == 0] = 1.0
    _, s, vt = np.linalg.svd(J / scale, full_matrices=False)
    keep = s > _RANK_TOL * (s[0] if s.size else 1.0)
    inner = (vt[keep].T / s[keep] ** 2) @ vt[keep]
    cov = sigma2 * inner / np.outer(scale, scale)
    lost = np.any(np.abs(vt[~keep]) > 1e-8, axis=0) if (~keep).any() else np.zeros(p, bool)
    cov[lost, :] = np.inf
    cov[:, lost] = np.inf
    return cov, sigma2, dof


def _fitted_rows(n: int, n0: int, p: int, tail_fraction: float) -> int:
    """Samples of an experiment the simulation-error fit fitted (its held-out tail is
    left out), as :func:`~blockid.fitting.simulation_error.refine` splits them."""
    n_tail = int(round(tail_fraction * n))
    if n - n_tail - n0 < max(p, 1):
        n_tail = 0
    return n - n_tail


def _is_centered(model: Any, data: Dataset) -> bool:
    """Whether the model's offsets are the means of ``data`` (a fit with ``center``)."""
    offsets = np.concatenate(
        [np.atleast_1d(model.input_offset), np.atleast_1d(model.output_offset)]
    ).astype(float)
    means = np.concatenate(
        [
            np.mean(np.vstack([e.u for e in data.experiments]), axis=0),
            np.mean(np.vstack([e.y for e in data.experiments]), axis=0),
        ]
    )
    return bool(np.any(offsets != 0.0) and np.allclose(offsets, means, rtol=1e-9, atol=1e-12))


def _effective_samples(residuals: list[np.ndarray], n: int) -> float:
    """``N (1 - ρ) / (1 + ρ)``: ``ρ`` the lag-1 autocorrelation of the residuals
    (pooled over experiments, clipped to ``[0, 0.99]``), ``N`` the samples averaged."""
    centre = float(np.mean(np.concatenate(residuals)))
    parts = [r - centre for r in residuals]
    power = sum(float(r @ r) for r in parts)
    lagged = sum(float(r[1:] @ r[:-1]) for r in parts)
    rho = min(max(lagged / power, 0.0), 0.99) if power > 0 else 0.0
    return n * (1.0 - rho) / (1.0 + rho)


def _simulation_covariance(
    model: Any, data: Dataset, method: str | None, tail_fraction: float, centered: bool
) -> ParameterCovariance:
    n0 = model.max_lag
    p = model.free_parameters().size
    rows, residuals, whole = [], [], []
    for e in data.experiments:
        stop = _fitted_rows(e.n_samples, n0, p, tail_fraction)
        # causal: the fitted rows are a prefix of the whole run
        y_hat, dy = model.simulate_with_sensitivities(e.u, e.y[:n0])
        residuals.append(e.y[n0:stop, 0] - y_hat[n0:stop])
        rows.append(dy[n0:stop])
        whole.append(e.y[n0:, 0] - y_hat[n0:])
    J, r = np.vstack(rows), np.concatenate(residuals)
    if not (np.all(np.isfinite(J)) and np.all(np.isfinite(r))):
        raise DataError("the model's simulation on the data is not finite: no standard errors")
    cov, sigma2, dof = _least_squares_covariance(J, r)
    offsets = {}
    if centered:
        n = sum(e.n_samples for e in data.experiments)
        offsets[model.outputs[0]] = {
            "variance": sigma2 / _effective_samples(residuals, n),
            "bias": -float(np.mean(np.concatenate(whole))),
            "direction": np.linalg.lstsq(J, np.ones(len(J)), rcond=None)[0],
        }
    try:
        names = list(model.free_parameter_names())
    except ValueError:  # a block whose parameters are not all in its vector
        names = [f"theta_{k}" for k in range(p)]
    basis = "free-run simulation Jacobian (output-error noise model)"
    if method not in (None, "simulation-error") and not str(method).endswith("refine"):
        basis += f", at the {method} estimate"
    if offsets:
        basis += "; output offset: the estimation mean"
    return ParameterCovariance(
        names,
        model.free_parameters(),
        cov,
        {model.outputs[0]: sigma2},
        dof,
        basis,
        offsets,
    )


def _state_space_covariance(model: Any, data: Dataset, method: str | None) -> ParameterCovariance:
    """``σ² (J^T J)^+`` of a (polynomial) state-space model's ``θ`` with every
    experiment's initial state estimated alongside (module docstring, state space)."""
    H, residuals, sums = model.information([(e.u, e.y) for e in data.experiments])
    r = np.concatenate([x.reshape(-1) for x in residuals])
    p = model.free_parameters().size
    names = list(model.free_parameter_names())
    fixed = np.zeros(H.shape[0], dtype=bool)
    # fitted without feedthrough when D is zero: D held there, as other fixed entries
    fixed[:p] = ~model.parameter_mask(bool(np.any(model.D)))
    free = np.flatnonzero(~fixed)
    if not (np.all(np.isfinite(H)) and np.all(np.isfinite(r))):
        raise DataError("the model's simulation on the data is not finite: no standard errors")
    Hf = H[np.ix_(free, free)]
    scale = np.sqrt(np.diag(Hf))
    scale[scale == 0] = 1.0
    lam, V = np.linalg.eigh(Hf / np.outer(scale, scale))
    keep = lam > _STATE_BASIS_TOL * lam.max()
    rank = int(keep.sum())
    dof = r.size - rank
    if dof < 1:
        raise DataError(
            f"{r.size} residual sample(s) for {rank} identifiable direction(s): too few to "
            "estimate the noise variance and the parameters' standard errors"
        )
    sigma2 = float(r @ r) / dof  # normalised units, pooled over the outputs
    inner = (V[:, keep] / lam[keep]) @ V[:, keep].T / np.outer(scale, scale)
    cov = np.zeros((H.shape[0], H.shape[0]))
    cov[np.ix_(free, free)] = sigma2 * inner
    scales = np.asarray(model.output_scale, dtype=float).reshape(-1)
    offsets = {}  # the output offsets: constants taken from the data, held by the fit
    n = sum(e.n_samples for e in data.experiments)
    for i, name in enumerate(model.outputs):
        own = [x[:, i] for x in residuals]
        step = np.zeros(H.shape[0])  # w = (J^T J)^+ J^T 1_i: θ imitating a unit offset
        step[free] = inner @ sums[i, free]
        offsets[name] = {
            "variance": sigma2 * scales[i] ** 2 / _effective_samples(own, n),
            "bias": -float(np.mean(np.concatenate(own))) * scales[i],
            "direction": step[:p],
        }
    return ParameterCovariance(
        names,
        model.free_parameters(),
        cov[:p, :p],
        {name: sigma2 * float(s) ** 2 for name, s in zip(model.outputs, scales, strict=True)},
        dof,
        "free-run simulation Jacobian with each experiment's initial state (output-error "
        "noise model, normalised units); pseudo-inverse without the state-basis "
        f"directions ({len(free) - rank} left out): standard errors in the fitted basis"
        + ("" if method in (None, "simulation-error") else f", at the {method} estimate")
        + "; output offsets: constants taken from the estimation data",
        offsets,
    )


def _arx_offsets(model: Any, data: Dataset, noise: dict[str, float]) -> dict[str, dict]:
    """The output offsets' noise variance and bias of a centred ARX model: the output
    noise is ``A^{-1} e``, so its mean has covariance ``A(1)^{-1} diag(σ²) A(1)^{-T} / N``."""
    ny = len(model.outputs)
    a1 = np.eye(ny)
    for i, yi in enumerate(model.outputs):
        for j, yj in enumerate(model.outputs):
            a1[i, j] += float(np.sum(model.a[yi][yj]))
    sigma2 = np.diag([noise.get(name, 0.0) for name in model.outputs])
    n = sum(e.n_samples for e in data.experiments)
    try:
        inverse = np.linalg.inv(a1)
        variance = np.diag(inverse @ sigma2 @ inverse.T) / n
    except np.linalg.LinAlgError:  # an integrator: no operating point
        variance = np.full(ny, np.inf)
    n0 = model.max_lag
    residuals = [(e.y - model.simulate(e.u, e.y[:n0]))[n0:] for e in data.experiments]
    bias = -np.mean(np.vstack(residuals), axis=0)
    return {
        name: {"variance": float(variance[i]), "bias": float(bias[i])}
        for i, name in enumerate(model.outputs)
    }


def _arx_covariance(
    model: Any, data: Dataset, method: str | None, centered: bool
) -> ParameterCovariance:
    names: list[str] = []
    values, blocks, noise, dofs = [], [], {}, []
    for i, name in enumerate(model.outputs):
        if model.n_parameters(i) == 0:
            continue
        parts = [model.regressors(e.u, e.y, i) for e in data.experiments]
        Phi = np.vstack([q[0] for q in parts])
        target = np.concatenate([q[1] for q in parts])
        theta = model.parameter_vector(i)
        cov, sigma2, dof = _least_squares_covariance(Phi, target - Phi @ theta)
        names += model.parameter_names(i)
        values.append(theta)
        blocks.append(cov)
        noise[name] = sigma2
        dofs.append(dof)
    p = sum(b.shape[0] for b in blocks)
    matrix = np.zeros((p, p))
    pos = 0
    for b in blocks:  # outputs are fitted separately: block diagonal
        matrix[pos : pos + b.shape[0], pos : pos + b.shape[0]] = b
        pos += b.shape[0]
    basis = "least squares, sigma^2 (Phi^T Phi)^-1"
    if method in _RECURSIVE_ARX:
        basis += f" at the final {method} estimate (the recursion's P is not kept)"
    offsets = _arx_offsets(model, data, noise) if centered else {}
    if offsets:
        basis += "; output offsets: the estimation means"
    return ParameterCovariance(
        names,
        np.concatenate(values) if values else np.zeros(0),
        matrix,
        noise,
        min(dofs, default=0),
        basis,
        offsets,
    )


def parameter_covariance(
    model: Any,
    data: Dataset,
    method: str | None = None,
    *,
    tail_fraction: float = 0.0,
    centered: bool | None = None,
) -> ParameterCovariance:
    """Covariance of the free parameters of a fitted model (module docstring).

    Parameters
    ----------
    model : Model
        An ARX model, any chain of blocks (Hammerstein, Wiener, ...) or the feedback model.
    data : Dataset
        The estimation data (the model's signals).
    method : str, optional
        The method that fitted the model (``FitResult.method``), recorded in ``basis``.
    tail_fraction : float, default 0
        For block-oriented models: the fraction at the end of every experiment that the
        fit held out for early stopping (left out here too).
    centered : bool, optional
        Whether the model's offsets are the means of ``data`` (the fit's ``center``);
        then ``offsets`` holds the output offsets' variance and bias. None: they are
        if they equal those means.

    Examples
    --------
    >>> import numpy as np
    >>> from blockid.data import Dataset
    >>> from blockid.models import ARX

    An ARX plant with white equation error of standard deviation 0.1:

    >>> rng = np.random.default_rng(0)
    >>> u, e = rng.standard_normal(2000), 0.1 * rng.standard_normal(2000)
    >>> y = np.zeros(2000)
    >>> for k in range(1, 2000):
    ...     y[k] = 0.5 * y[k - 1] + u[k - 1] + e[k]
    >>> plant = ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [-0.5]}}, b={"y": {"u": [1.0]}})
    >>> cov = parameter_covariance(plant, Dataset.from_arrays(u, y, ["u"], ["y"]))
    >>> cov.names, cov.standard_errors.round(4).tolist()
    (['a[y][y][1]', 'b[y][u][0]'], [0.0019, 0.0022])
    """
    if tuple(data.inputs) != tuple(model.inputs) or tuple(data.outputs) != tuple(model.outputs):
        raise DataError(
            f"the model maps {list(model.inputs)} to {list(model.outputs)} but the data have "
            f"inputs {list(data.inputs)} and outputs {list(data.outputs)}"
        )
    if hasattr(model, "information"):  # a state space: initial states estimated alongside
        return _state_space_covariance(model, data, method)
    if centered is None:
        centered = hasattr(model, "output_offset") and _is_centered(model, data)
    if hasattr(model, "free_parameters"):
        return _simulation_covariance(model, data, method, float(tail_fraction), centered)
    if hasattr(model, "parameter_vector"):
        return _arx_covariance(model, data, method, centered)
    raise ParameterError(
        f"standard errors are computed for ARX and block-oriented models, not for a "
        f"{type(model).__name__}; compute them for each subsystem of a network"
    )


# ----------------------------------------------------------------------------- names
def _free_positions(model: Any) -> list[int]:
    """Positions of the free parameters among the numbers of the model file's
    ``"parameters"`` (flattened in order).

    Found by moving every free parameter (two affine maps with different fixed points,
    which keep signs and orderings, so every block accepts the moved values) and seeing
    which numbers change: the file's names, fixed entries (``b_0``, ``q_1``) and
    numbers that are not parameters (breakpoints) stay where they are.
    """
    flat = np.asarray(_flatten(model.to_dict()["parameters"]))
    if not hasattr(model, "with_free_parameters"):  # ARX: every number is free, in order
        return list(range(flat.size))
    theta = model.free_parameters()
    changed = np.zeros(flat.size, dtype=bool)
    for alpha, beta in ((1 + 2.0**-10, 2.0**-11), (1 + 2.0**-9, 3 * 2.0**-12)):
        moved = model.with_free_parameters(alpha * theta + beta)
        changed |= np.asarray(_flatten(moved.to_dict()["parameters"])) != flat
    return [int(k) for k in np.flatnonzero(changed)]


def _unflatten(template: Any, values: list[float]) -> Any:
    """``template`` (nested dicts, lists, numbers, flags) with its numbers replaced, in
    order, by ``values`` (consumed from the front); flags are kept."""
    if isinstance(template, dict):
        return {k: _unflatten(v, values) for k, v in template.items()}
    if isinstance(template, list | tuple):
        return [_unflatten(v, values) for v in template]
    if isinstance(template, bool) or not isinstance(template, int | float):
        return template
    return values.pop(0)


def _flatten(template: Any) -> list[float]:
    if isinstance(template, dict):
        return [x for v in template.values() for x in _flatten(v)]
    if isinstance(template, list | tuple):
        return [x for v in template for x in _flatten(v)]
    if isinstance(template, bool) or not isinstance(template, int | float):
        return []
    return [float(template)]


def named_standard_errors(model: Any, cov: ParameterCovariance | np.ndarray) -> dict[str, Any]:
    """Standard errors with the shape of the model file's ``"parameters"``.

    Fixed entries (``b_0 = 1`` after an input block, ``q_1 = 1``) get 0; an infinite
    standard error is ``None`` (JSON ``null``).

    Raises :class:`~blockid.errors.ParameterError` if ``cov`` does not fit the model.
    """
    matrix = cov.matrix if isinstance(cov, ParameterCovariance) else np.asarray(cov, float)
    se = np.sqrt(np.abs(np.diag(matrix)))
    if hasattr(model, "shaped"):  # a state space shapes its own numbers like its matrices
        if se.size != model.free_parameters().size:
            raise ParameterError(
                f"a covariance of {se.size} free parameters does not fit the "
                f"{model.structure} model's {model.free_parameters().size} free parameters"
            )
        shaped = model.shaped(se)
        return _unflatten(shaped, [_finite_or_none(v) for v in _flatten(shaped)])
    template = model.to_dict()["parameters"]
    positions = _free_positions(model)
    if len(positions) != se.size:
        raise ParameterError(
            f"a covariance of {se.size} free parameters does not fit the "
            f"{model.structure} model's {len(positions)} free parameters"
        )
    values = [0.0] * len(_flatten(template))
    for k, v in zip(positions, se, strict=True):
        values[k] = _finite_or_none(v)
    return _unflatten(template, values)


def standard_errors(model: Any, data: Dataset, method: str | None = None) -> dict[str, Any]:
    """Standard errors of a fitted model's parameters on its estimation data, shaped
    like the model file's ``"parameters"`` (see :func:`parameter_covariance`)."""
    return named_standard_errors(model, parameter_covariance(model, data, method))


def with_standard_errors(result: Any, data: Dataset) -> Any:
    """A copy of a :class:`~blockid.fitting.result.FitResult` whose ``settings`` carry
    ``"standard_errors"`` (shaped like the parameters) and ``"covariance"`` (of the free
    parameters: names, matrix, noise variance, degrees of freedom, basis).

    ``data`` is the estimation data the result was fitted on. The simulation-error fit's
    held-out tail (``settings["tail_fraction"]``) is left out, as the fit left it out.
    A fit with ``center`` (``settings["center"]``) adds the output offsets' variance and
    bias to the covariance (module docstring).
    """
    tail = float(result.settings.get("tail_fraction") or 0.0)
    centered = result.settings.get("center")
    cov = parameter_covariance(
        result.model,
        data,
        result.method,
        tail_fraction=tail,
        centered=None if centered is None else bool(centered),
    )
    settings = {
        **result.settings,
        "standard_errors": named_standard_errors(result.model, cov),
        "covariance": cov.to_dict(),
    }
    return replace(result, settings=settings)


# ----------------------------------------------------------------------------- band
def _output_sensitivities(model: Any, u: Any, y_initial: Any) -> tuple[np.ndarray, np.ndarray]:
    """Simulated output (N, ny) and its derivative (N, ny, p) to the free parameters, as
    the model provides them (``output_sensitivities``)."""
    provide = getattr(model, "output_sensitivities", None)
    if provide is None:
        raise ParameterError(
            f"a {type(model).__name__} gives no output sensitivities: simulation bands "
            "are drawn for ARX, block-oriented, feedback and state-space models"
        )
    return provide(u, y_initial)


def simulation_band(
    model: Any,
    cov: ParameterCovariance | np.ndarray,
    u: Any,
    y_initial: Any = None,
    level: float = 0.95,
    *,
    noise: bool = False,
) -> SimulationBand:
    """Confidence band on the free-run simulation, by linearisation.

    .. math:: \\hat y(k) \\pm z_{(1+\\ell)/2} \\sqrt{J_k\\, \\mathrm{cov}\\, J_k^T}

    For a centred model (``cov.offsets``) the output offset's noise variance is added
    and its bias ``b`` widens the band to the half-width that holds an error
    ``N(b, std²)`` with probability ``level`` (module docstring).

    Parameters
    ----------
    model : Model
        The fitted model.
    cov : ParameterCovariance or ndarray
        Covariance of its free parameters (:func:`parameter_covariance`).
    u, y_initial
        As for ``model.simulate``.
    level : float, default 0.95
        Probability the band holds the noise-free output at each sample.
    noise : bool, default False
        Add the noise variance (a band for measurements instead of for the plant's
        output); needs a :class:`ParameterCovariance`.

    Returns
    -------
    SimulationBand
        ``lower``, ``upper``, ``simulated``, ``std`` (arrays ``(N, ny)``), ``level`` and
        ``bias`` (``(ny,)``).
    """
    if not 0.0 < float(level) < 1.0:
        raise ParameterError(f"level must be between 0 and 1, got {level!r}", parameter="level")
    matrix = cov.matrix if isinstance(cov, ParameterCovariance) else np.asarray(cov, float)
    y, dy = _output_sensitivities(model, u, y_initial)
    if dy.shape[2] != matrix.shape[0]:
        raise ParameterError(
            f"the covariance is of {matrix.shape[0]} parameters but the model has {dy.shape[2]}"
        )
    with np.errstate(invalid="ignore"):
        var = np.einsum("nop,pq,noq->no", dy, matrix, dy)
        bias = np.zeros(var.shape[1])
        offsets = cov.offsets if isinstance(cov, ParameterCovariance) else {}
        for j, name in enumerate(model.outputs):
            if name not in offsets:
                continue
            entry = offsets[name]
            share = 0.0  # m_k: how much of an offset the parameters imitate
            if "direction" in entry:
                share = dy[:, j, :] @ np.asarray(entry["direction"], float)
            added = var[:, j] + entry["variance"] * (1.0 - share**2)
            var[:, j] = np.maximum(added, entry["variance"])
            bias[j] = entry["bias"]
    var = np.where(np.isnan(var), np.inf, np.maximum(var, 0.0))
    if noise:
        if not isinstance(cov, ParameterCovariance):
            raise ParameterError("noise=True needs a ParameterCovariance (its noise variance)")
        var = var + np.array([cov.noise_variance.get(n, 0.0) for n in model.outputs])[None, :]
    std = np.sqrt(var)
    half = _half_width(bias, std, float(level))
    return SimulationBand(y - half, y + half, y, std, float(level), bias)


def _half_width(bias: np.ndarray, std: np.ndarray, level: float) -> np.ndarray:
    """The ``w`` with ``P(|b + s Z| <= w) = level`` for ``Z ~ N(0, 1)``, per entry of
    ``std`` (``s``, shape ``(N, ny)``) and ``bias`` (``b``, shape ``(ny,)``).

    ``z s`` without a bias. Otherwise found by bisection between ``z s`` (too narrow
    once ``b != 0``) and ``|b| + z s`` (wide enough).
    """
    z = NormalDist().inv_cdf(0.5 + 0.5 * level)
    b = np.broadcast_to(np.abs(bias)[None, :], std.shape)
    if np.all(b == 0):
        return z * std
    from scipy.special import ndtr

    ok = np.isfinite(std) & (std > 0) & np.isfinite(b)
    s, m = np.where(ok, std, 1.0), np.where(ok, b, 0.0)
    lo, hi = z * s, m + z * s
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        short = ndtr((mid - m) / s) - ndtr((-mid - m) / s) < level
        lo, hi = np.where(short, mid, lo), np.where(short, hi, mid)
    return np.where(ok, hi, np.where(np.isfinite(std) & np.isfinite(b), b, np.inf))


def load_covariance(path: Any) -> ParameterCovariance:
    """The covariance stored in a model file by :func:`with_standard_errors`.

    Raises :class:`~blockid.errors.ModelFileError` when the file has none.
    """
    import json
    from pathlib import Path

    from blockid.errors import ModelFileError

    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
        record = doc["estimation"]["settings"]["covariance"]
    except (OSError, ValueError, KeyError, TypeError):
        raise ModelFileError(
            f"{path} holds no parameter covariance: fit the model with standard errors "
            "to get a confidence band"
        ) from None
    return ParameterCovariance.from_dict(record)


def band_columns(
    model: Any, cov: ParameterCovariance | np.ndarray, data: Dataset, level: float = 0.95
) -> dict[str, np.ndarray]:
    """``<output>_lower`` and ``<output>_upper`` over every experiment of ``data`` (each
    simulated from its first ``max_lag`` measured outputs, as ``blockid simulate``
    does), in the row order of ``Dataset.to_frame``."""
    parts = [
        simulation_band(model, cov, e.u, e.y[: model.max_lag], level) for e in data.experiments
    ]
    out: dict[str, np.ndarray] = {}
    for j, name in enumerate(model.outputs):
        out[f"{name}_lower"] = np.concatenate([b.lower[:, j] for b in parts])
        out[f"{name}_upper"] = np.concatenate([b.upper[:, j] for b in parts])
    return out
