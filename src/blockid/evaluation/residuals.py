"""Residual analysis: is what a model leaves white, and independent of the input?

After a fit, the residual ``e = y - ŷ`` on data the model was not fitted on says what the
error figures cannot (Ljung 1999, sec. 16.6; MATLAB's ``resid``):

* **whiteness**: the residual's autocorrelation ``r_e(τ)``, ``τ = 1 .. M``. A model with
  a noise model (ARX, a state space with its Kalman gain) leaves a white one-step
  residual when it has captured the dynamics and the noise; the Ljung-Box statistic
  ``Q = N (N + 2) Σ r_e(τ)² / (N - τ)`` is χ² with ``M`` degrees of freedom if it is.
  An output-error model (every block-oriented model fitted by simulation error, a
  polynomial state space without a predictor) has no noise model: its one-step
  prediction is its free run and its residual is the output noise as the plant
  coloured it, so whiteness is not expected of it and its test says little;
* **independence of the input**: the cross-correlation ``r_ue(τ)`` between the input
  and the residual. At ``τ >= 0`` (the input before the residual) it reveals dynamics
  or a nonlinearity the model missed, whatever its noise model; at ``τ < 0`` it
  indicates feedback from the output to the input in the data (a closed loop), not a
  fault of the model. Its bound uses Ljung's variance ``P / N``, ``P = Σ_k r_e(k)
  r_u(k)``, right also when the residual or the input is coloured. The test statistic
  is formed after **prewhitening** (Box & Jenkins): an AR model of the input (order
  ``min(10, M)``, least squares) filters the input and the residual alike, so that the
  filtered input is white and its cross-correlations with the filtered residual at
  different lags are independent under independence; then ``S = N Σ_{τ=0}^{M}
  r(τ)² / P`` is χ² with ``M + 1`` degrees of freedom. (Without it a slow input makes
  neighbouring lags nearly equal, and summing them as independent rejects far too
  often: a hydraulic record's slow trajectory gave p = 2e-7 with no lag outside its
  bound.) The test assumes open-loop data: with feedback (correlation at negative
  lags) the filter spreads it into the positive lags, and the verdict is not to be
  trusted. **Feedback** is tested with the prewhitened input against the residual as
  it is, over ``τ = -M .. -1`` (the same statistic, ``M`` degrees of freedom): in open
  loop a white input's correlation with an earlier residual is zero even when the
  model is wrong (its error is a causal filter of the input), while the raw
  correlation is not when the input is coloured or periodic: a missed dynamic shows at
  negative lags too, so the raw correlation alone does not indicate a closed loop.
  An input that repeats exactly, period after period (a generated multisine or PRBS),
  carries none of the output's noise, so no feedback is reported for it: an AR filter
  cannot whiten a band-limited periodic input, and its model error would show.

Correlations are pooled over the experiments (lagged products within each experiment
only), with the mean of each signal removed; the first ``skip`` samples of each
experiment (initial conditions) are left out. The bounds are two-sided at
``confidence`` (default 0.99, as ``resid``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from blockid.data.dataset import Dataset
from blockid.errors import DataError, ParameterError

__all__ = ["ResidualAnalysis", "residual_analysis", "residual_check"]

#: Lags tested by default (``resid``'s 25).
MAX_LAG = 25


@dataclass(frozen=True)
class ResidualAnalysis:
    """What :func:`residual_analysis` measured.

    Attributes
    ----------
    mode : {"one-step", "simulation"}
    n_samples : int
        Residual samples used (all experiments, initial samples left out).
    lags : ndarray
        ``0 .. M`` (autocorrelation); ``cross_lags``: ``-M .. M``.
    autocorrelation : dict
        Output name -> ``r_e(τ)`` at ``lags`` (``r_e(0) = 1``).
    auto_bound : float
        The confidence bound of ``r_e(τ)``, ``τ >= 1``, for a white residual.
    cross_correlation : dict
        ``(input, output)`` -> ``r_ue(τ)`` at ``cross_lags``.
    cross_bound : dict
        ``(input, output)`` -> the confidence bound of ``r_ue(τ)`` under independence.
    whiteness : dict
        Output -> ``{"statistic": Q, "p_value": ..., "outside": lags outside the bound,
        "white": p_value >= 1 - confidence}``.
    independence : dict
        ``(input, output)`` -> ``{"statistic": S, "p_value": ..., "outside": causal lags
        (τ >= 0) outside the bound, "outside_negative": τ < 0 outside,
        "independent": p_value >= 1 - confidence, "feedback_statistic" and
        "feedback_p_value": the same test over ``τ < 0``, "feedback": feedback_p_value <
        1 - confidence (a closed loop in the data)}``.
    confidence : float
    noise_model : bool or None
        One-step mode: whether the model was fitted with a noise model, so that its
        one-step residual should be white (least-squares ARX; a state space with its
        predictor gain ``K``); a simulation-error fit was not. None in simulation mode.
    """

    mode: str
    n_samples: int
    lags: np.ndarray
    cross_lags: np.ndarray
    autocorrelation: dict[str, np.ndarray]
    auto_bound: float
    cross_correlation: dict[tuple[str, str], np.ndarray]
    cross_bound: dict[tuple[str, str], float]
    whiteness: dict[str, dict[str, Any]]
    independence: dict[tuple[str, str], dict[str, Any]]
    confidence: float
    noise_model: bool | None = None

    @property
    def passed(self) -> bool:
        """Whether the model passes: its residual independent of every input and, when
        it was fitted with a noise model (one-step mode), white."""
        independent = all(t["independent"] for t in self.independence.values())
        white = all(t["white"] for t in self.whiteness.values())
        return independent and (white or self.noise_model is not True)

    def verdict(self) -> str:
        """One line: pass or fail, the test that decides and what it means."""
        level = f"{self.confidence:.0%}"
        dependent = [(k, t) for k, t in self.independence.items() if not t["independent"]]
        coloured = [(k, t) for k, t in self.whiteness.items() if not t["white"]]
        if dependent:
            (u, y), t = min(dependent, key=lambda kt: kt[1]["p_value"])
            line = (
                f"fails: the residual of {y} correlates with past {u} (p = {t['p_value']:.2g}, "
                f"{t['outside']} lag(s) outside the {level} bound): the model misses input "
                "dynamics or a nonlinearity; try more poles, a longer delay range or a "
                "nonlinear structure"
            )
            if len(dependent) > 1:
                line += f" ({len(dependent)} pairs)"
            if coloured and self.noise_model is True:
                line += "; nor is the residual white"
            return line
        if coloured and self.noise_model is True:
            y, t = min(coloured, key=lambda kt: kt[1]["p_value"])
            return (
                f"fails: the residual of {y} is not white (Ljung-Box Q = {t['statistic']:.3g}, "
                f"p = {t['p_value']:.2g}) though independent of the inputs: the model misses "
                "noise dynamics; try more poles or a noise model"
            )
        if coloured:
            return (
                "passes: independent of the inputs; not white, which a model without a "
                "noise model (fitted by simulation error) is not made to be"
            )
        return f"passes: white and independent of the inputs at {level}"

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON types; pairs as ``"input->output"``; with the one-line
        ``verdict`` and whether the model ``passed``."""

        def pair(k: tuple[str, str]) -> str:
            return f"{k[0]}->{k[1]}"

        return {
            "verdict": self.verdict(),
            "passed": self.passed,
            "mode": self.mode,
            "n_samples": self.n_samples,
            "confidence": self.confidence,
            "noise_model": self.noise_model,
            "lags": self.lags.tolist(),
            "cross_lags": self.cross_lags.tolist(),
            "auto_bound": self.auto_bound,
            "autocorrelation": {k: v.tolist() for k, v in self.autocorrelation.items()},
            "cross_correlation": {pair(k): v.tolist() for k, v in self.cross_correlation.items()},
            "cross_bound": {pair(k): v for k, v in self.cross_bound.items()},
            "whiteness": self.whiteness,
            "independence": {pair(k): v for k, v in self.independence.items()},
        }


def _lagged_sums(a: list[np.ndarray], b: list[np.ndarray], max_lag: int) -> np.ndarray:
    """``Σ_t a(t) b(t + τ)`` for ``τ = -M .. M`` within each experiment, summed."""
    out = np.zeros(2 * max_lag + 1)
    for x, z in zip(a, b, strict=True):
        n = x.size
        for i, tau in enumerate(range(-max_lag, max_lag + 1)):
            if abs(tau) >= n:
                continue
            out[i] += x[: n - tau] @ z[tau:] if tau >= 0 else x[-tau:] @ z[: n + tau]
    return out


def _repeats_exactly(parts: list[np.ndarray]) -> bool:
    """Whether every experiment's signal repeats, to rounding, period after period (a
    generated periodic excitation, at least two periods): such an input cannot carry
    feedback of the output's noise, which differs from period to period."""
    from blockid.evaluation.periods import find_period

    for x in parts:
        period = find_period(x)
        if period is None or x.size < 2 * period:
            return False
        if np.max(np.abs(x[period:] - x[:-period])) > 1e-9 * max(float(np.ptp(x)), 1e-300):
            return False
    return True


#: Order of the AR model that prewhitens the input for the independence test.
PREWHITEN_ORDER = 10


def _prewhitener(parts: list[np.ndarray], order: int) -> Any:
    """The filter ``A(q)`` of a least-squares AR(``order``) model of the (centred)
    signal ``parts``: applied to a signal, its first ``order`` samples are dropped."""
    rows, target = [], []
    for x in parts:
        for t in range(order, x.size):
            rows.append(x[t - order : t][::-1])
            target.append(x[t])
    if len(rows) <= 2 * order:
        return lambda x: x
    a, *_ = np.linalg.lstsq(np.asarray(rows), np.asarray(target), rcond=None)

    def apply(x: np.ndarray) -> np.ndarray:
        if x.size <= order:
            return x[:0]
        out = x[order:].copy()
        for k in range(order):
            out -= a[k] * x[order - 1 - k : x.size - 1 - k]
        return out

    return apply


def _independence_statistic(
    u: list[np.ndarray], e: list[np.ndarray], max_lag: int
) -> tuple[tuple[float, float], int]:
    """``N Σ_{τ=0}^{M} r_ue(τ)² / P`` of the prewhitened signals (module docstring), the
    same sum over ``τ = -M .. -1`` (feedback), and the first's degrees of freedom."""
    n = int(sum(x.size for x in u))
    uc = [x - np.mean(np.concatenate(u)) for x in u]
    ec = [x - np.mean(np.concatenate(e)) for x in e]
    pu, pe = sum(x @ x for x in uc) / n, sum(x @ x for x in ec) / n
    if not (pu > 0 and pe > 0):
        return (0.0, 0.0), max_lag + 1
    r = _lagged_sums(uc, ec, max_lag) / (n * np.sqrt(pu * pe))
    r_u = _lagged_sums(uc, uc, max_lag) / (n * pu)
    r_e = _lagged_sums(ec, ec, max_lag) / (n * pe)
    big_p = max(float(np.sum(r_u * r_e)), 1e-12)
    causal, loop = r[max_lag:], r[:max_lag]
    return (float(n * np.sum(causal**2) / big_p), float(n * np.sum(loop**2) / big_p)), max_lag + 1


def residual_analysis(
    model: Any,
    data: Dataset,
    mode: str = "one-step",
    *,
    max_lag: int = MAX_LAG,
    confidence: float = 0.99,
    initial_samples: int | None = None,
) -> ResidualAnalysis:
    """Test the residual of ``model`` on ``data`` for whiteness and for independence of
    the inputs (module docstring).

    Parameters
    ----------
    model : Model
    data : Dataset
        Best: data the model was not fitted on.
    mode : {"one-step", "simulation"}
        The residual of the one-step prediction (default, as ``resid``) or of the free
        run (:func:`~blockid.evaluation.evaluate`).
    max_lag : int
        ``M``, the largest lag tested (default 25).
    confidence : float
        Of the bounds and the tests (default 0.99).
    initial_samples : int, optional
        Free run only: as :func:`~blockid.evaluation.evaluate`.

    Raises
    ------
    ParameterError
        For a ``max_lag`` < 1 or a ``confidence`` outside (0, 1).
    DataError
        When the data leave fewer than ``2 M + 10`` residual samples, or a residual or an
        input is constant.
    """
    from scipy import stats

    from blockid.evaluation.validate import evaluate

    if isinstance(max_lag, bool) or not isinstance(max_lag, int | np.integer) or max_lag < 1:
        raise ParameterError(f"max_lag must be a whole number >= 1, got {max_lag!r}",
                             parameter="max_lag")  # fmt: skip
    if not 0.0 < float(confidence) < 1.0:
        raise ParameterError(
            f"confidence must lie between 0 and 1 (e.g. 0.99), got {confidence!r}",
            parameter="confidence",
        )
    result = evaluate(model, data, mode, initial_samples=initial_samples)
    if result.diverged is not None:
        raise DataError(f"the model's output diverges on these data ({result.diverged}): "
                        "its residual cannot be analysed")  # fmt: skip
    skip = result.skip
    pairs = zip(data.experiments, result.outputs, strict=True)
    residuals = [exp.y[skip:] - out[skip:] for exp, out in pairs]
    inputs = [exp.u[skip:] for exp in data.experiments]
    n = int(sum(e.shape[0] for e in residuals))
    if n < 2 * max_lag + 10:
        raise DataError(
            f"{n} residual samples are too few for lags up to {max_lag}: give at least "
            f"{2 * max_lag + 10}, or a smaller max_lag",
            parameter="max_lag",
        )
    z = float(stats.norm.ppf(0.5 + confidence / 2.0))
    lags = np.arange(max_lag + 1)
    cross_lags = np.arange(-max_lag, max_lag + 1)

    def centred(parts: list[np.ndarray], j: int, name: str) -> tuple[list[np.ndarray], float]:
        mean = float(np.mean(np.concatenate([p[:, j] for p in parts])))
        cols = [p[:, j] - mean for p in parts]
        power = float(sum(c @ c for c in cols)) / n
        if not power > 0:
            raise DataError(f"{name} is constant over the residual samples: no correlation "
                            "can be formed; check the data")  # fmt: skip
        return cols, power

    auto, white = {}, {}
    e_cols, r_e_full = {}, {}
    for j, name in enumerate(data.outputs):
        cols, power = centred(residuals, j, f"the residual of {name}")
        e_cols[name] = cols
        full = _lagged_sums(cols, cols, max_lag) / (n * power)
        r_e_full[name] = full
        r = full[max_lag:]
        auto[name] = r
        q = float(n * (n + 2) * np.sum(r[1:] ** 2 / (n - lags[1:])))
        p = float(stats.chi2.sf(q, max_lag))
        white[name] = {
            "statistic": q,
            "p_value": p,
            "outside": int(np.sum(np.abs(r[1:]) > z / np.sqrt(n))),
            "white": p >= 1.0 - confidence,
        }
    cross, bound, indep = {}, {}, {}
    for i, uname in enumerate(data.inputs):
        u_cols, u_power = centred(inputs, i, f"the input {uname}")
        r_u = _lagged_sums(u_cols, u_cols, max_lag) / (n * u_power)
        whiten = _prewhitener(u_cols, min(PREWHITEN_ORDER, max_lag))
        u_white = [whiten(c) for c in u_cols]
        repeats = _repeats_exactly(u_cols)
        for name in data.outputs:
            e_power = float(sum(c @ c for c in e_cols[name])) / n
            r = _lagged_sums(u_cols, e_cols[name], max_lag) / (n * np.sqrt(u_power * e_power))
            big_p = max(float(np.sum(r_e_full[name] * r_u)), 1e-12)
            level = z * np.sqrt(big_p / n)
            causal = r[max_lag:]
            (s, _), dof = _independence_statistic(
                u_white, [whiten(c) for c in e_cols[name]], max_lag
            )
            # feedback: the white input against the residual as it is (module docstring)
            aligned = [c[c.size - w.size :] for c, w in zip(e_cols[name], u_white, strict=True)]
            (_, s_loop), _ = _independence_statistic(u_white, aligned, max_lag)
            p = float(stats.chi2.sf(s, dof))
            if repeats:  # an input that repeats exactly carries none of the output's noise
                s_loop = 0.0
            p_loop = float(stats.chi2.sf(s_loop, max_lag))
            key = (uname, name)
            cross[key], bound[key] = r, float(level)
            indep[key] = {
                "statistic": s,
                "p_value": p,
                "outside": int(np.sum(np.abs(causal) > level)),
                "outside_negative": int(np.sum(np.abs(r[:max_lag]) > level)),
                "independent": p >= 1.0 - confidence,
                "feedback_statistic": s_loop,
                "feedback_p_value": p_loop,
                "feedback": p_loop < 1.0 - confidence,
            }
    # fitted to make its one-step residual white: least squares ARX, a state space with
    # its predictor gain; a simulation-error fit is not (its noise is the plant's, coloured)
    noise_model = None
    if mode == "one-step":
        noise_model = bool(getattr(model, "has_noise_model", False))
    return ResidualAnalysis(
        noise_model=noise_model,
        mode=mode,
        n_samples=n,
        lags=lags,
        cross_lags=cross_lags,
        autocorrelation=auto,
        auto_bound=float(z / np.sqrt(n)),
        cross_correlation=cross,
        cross_bound=bound,
        whiteness=white,
        independence=indep,
        confidence=float(confidence),
    )


def residual_check(model: Any, data: Dataset) -> tuple[ResidualAnalysis | None, str | None]:
    """The residual analysis ``compare`` and the report give every model on the
    validation data: of the one-step prediction (``resid``'s default), of the free run
    for a model that cannot predict one step ahead; None and the reason when neither can
    be analysed (too few samples, a diverging output)."""
    from blockid.errors import BlockidError

    try:
        return residual_analysis(model, data, "one-step"), None
    except BlockidError:
        try:
            return residual_analysis(model, data, "simulation"), None
        except BlockidError as exc:
            return None, str(exc)
