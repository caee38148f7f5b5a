r"""The frequency response of non-periodic data: Welch's H1 estimate, its coherence
and confidence bounds.

Data that do not repeat (noise, a PRBS record cut anywhere, operating data) give no
periods to average; the classical estimate averages windowed segments instead (Welch
1967; Bendat & Piersol, *Random Data*, 4th ed., 2010, ch. 9): with ``S_uu``, ``S_yy``
and ``S_uy`` the averaged auto and cross spectra (:func:`scipy.signal.welch` and
:func:`scipy.signal.csd`: Hann windows of ``segment`` samples, half overlapping,
pooled over the experiments in proportion to their segments),

.. math::

    \hat G(f) = \frac{S_{uy}}{S_{uu}}, \qquad
    \hat\gamma^2(f) = \frac{|S_{uy}|^2}{S_{uu} S_{yy}}, \qquad
    \hat\sigma^2_G(f) = \frac{1 - \hat\gamma^2}{\hat\gamma^2}
        \frac{|\hat G|^2}{n_d - 1},

where the coherence ``γ²`` is the share of the output's power a linear response to the
input explains; the rest is noise **and** nonlinear distortion, which these data cannot
tell apart. ``σ²_G`` is the variance of ``Ĝ`` when the segments' output errors are
independent complex Gaussian given the input (the least-squares fit of one complex
gain over ``n_d`` segments: ``E|Ĝ - G|² = σ²_N / (n_d S_uu)``, and ``(1 - γ̂²) |Ĝ|² /
γ̂² = n_d σ̂²_N / ((n_d - 1) S_uu)`` estimates it with ``2(n_d - 1)`` degrees of
freedom), so that ``|Ĝ - G|² / σ̂²_G`` is ``F(2, 2(n_d - 1))`` and the bound at
``confidence`` is the radius ``σ̂_G sqrt(F_{2, 2(n_d - 1)}(confidence))``. Overlapping
segments are not independent: ``n_d`` is the number ``K`` of segments over Welch's
variance factor ``1 + 2 ρ (K - 1) / K``, ``ρ = (Σ w(t) w(t + D))² / (Σ w²)²`` of the
window ``w`` shifted by the step ``D`` (1/36 for Hann windows half overlapping). The
bound leaves out the bias of a window wider than a resonance (take longer segments
where ``G`` changes fast).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from blockid.data.dataset import Dataset
from blockid.errors import DataError, ParameterError
from blockid.evaluation.bla_bands import DEFAULT_BANDS, summarised
from blockid.evaluation.bla_result import BestLinearApproximation
from blockid.evaluation.spectra import (
    CONFIDENCE,
    check_confidence,
    check_finite,
    frequency_unit,
    powered,
    signal_columns,
)

__all__ = ["MIN_SEGMENTS", "welch_bla"]

#: Segments (of the default length) the data should hold at least: the default segment
#: is the longest power of two that gives this many, half overlapping.
MIN_SEGMENTS = 16
#: The shortest segment taken by default.
_SHORTEST = 16


def _segment(lengths: list[int], segment: int | None) -> int:
    """The segment length: given and checked, or the default."""
    shortest, total = min(lengths), sum(lengths)
    if segment is None:
        wanted = total * 2 // (MIN_SEGMENTS + 1)
        segment = max(_SHORTEST, 1 << max(0, int(wanted).bit_length() - 1))
        segment = min(segment, shortest)
    elif isinstance(segment, bool) or not isinstance(segment, int | np.integer) or segment < 8:
        raise ParameterError(f"segment must be a whole number of samples >= 8, got {segment!r}",
                             parameter="segment")  # fmt: skip
    if segment > shortest:
        raise ParameterError(
            f"segment = {segment} samples is longer than the shortest experiment "
            f"({shortest} samples); give a segment of at most {shortest}",
            parameter="segment",
        )
    return int(segment)


def welch_bla(
    data: Dataset,
    *,
    input: str | None = None,
    output: str | None = None,
    segment: int | None = None,
    bands: int | Sequence[tuple[float, float]] = DEFAULT_BANDS,
    confidence: float = CONFIDENCE,
    data_label: str | None = None,
) -> BestLinearApproximation:
    """The frequency response of ``data`` by Welch's H1 estimate (module docstring).

    Parameters
    ----------
    data : Dataset
        Any records of the input and output (several experiments are pooled).
    input, output : str, optional
        The signals (needed when the data have several).
    segment : int, optional
        Samples of a segment: the resolution is ``1 / (segment * sampling_time)``;
        default: the longest power of two that leaves :data:`MIN_SEGMENTS` segments.
    bands, confidence, data_label
        As :func:`~blockid.evaluation.bla.robust_bla`.

    Raises
    ------
    DataError
        Non-finite samples, fewer than 3 independent averages, an input without power.
    ParameterError
        A bad segment, bands or confidence.
    """
    from scipy import signal

    confidence = check_confidence(confidence)
    i, j = signal_columns(data, input, output)
    check_finite(data, i, j)
    n = _segment([e.n_samples for e in data.experiments], segment)
    step = n - n // 2
    ts = data.sampling_time or 1.0
    options = {"fs": 1.0 / ts, "window": "hann", "nperseg": n, "noverlap": n // 2}
    s_uu = s_yy = s_uy = 0.0
    count = 0
    for exp in data.experiments:
        u, y = exp.u[:, i], exp.y[:, j]
        k = (u.size - n) // step + 1
        f, puu = signal.welch(u, **options)
        _, pyy = signal.welch(y, **options)
        _, puy = signal.csd(u, y, **options)  # conj(U) Y: S_uy
        s_uu, s_yy, s_uy = s_uu + k * puu, s_yy + k * pyy, s_uy + k * puy
        count += k
    w = signal.get_window("hann", n)
    rho = (w[: n - step] @ w[step:]) ** 2 / (w @ w) ** 2
    n_d = count / (1.0 + 2.0 * rho * (count - 1) / count)
    if n_d < 3:
        raise DataError(
            f"{count} segment(s) of {n} samples make {n_d:.1f} independent averages: the "
            "variance of G needs 3 or more; give a shorter segment or more data",
            parameter="segment",
        )
    lines = np.flatnonzero(powered(np.where((f > 0) & (f < f[-1]), s_uu, 0.0)))
    if lines.size == 0:
        raise DataError("the input has no power at any frequency: it is constant; check the "
                        "input column")  # fmt: skip
    g = s_uy[lines] / s_uu[lines]
    with np.errstate(divide="ignore", invalid="ignore"):
        coherence = np.clip(np.abs(s_uy[lines]) ** 2 / (s_uu[lines] * s_yy[lines]), 0.0, 1.0)
        var = np.where(coherence > 0, (1 - coherence) / coherence, np.inf) * np.abs(g) ** 2
    var = var / (n_d - 1)
    from scipy import stats

    bla = BestLinearApproximation(
        method="welch", frequencies=f[lines], g=g, var_total=var, var_noise=None,
        bound=np.sqrt(var * stats.f.ppf(confidence, 2, 2 * (n_d - 1))),
        confidence=confidence, sampling_time=ts, realisations=data.n_experiments, periods=1,
        transient_periods=0, samples=n, bands=(), verdict="", coherence=coherence,
        segments=float(n_d), input_name=data.inputs[i], output_name=data.outputs[j],
        data_label=data_label or data.source or "data",
        notes=() if data.sampling_time else ("sampling time unknown: frequencies in cycles "
                                             "per sample",),
        unit=frequency_unit(data.sampling_time),
    )  # fmt: skip
    return summarised(bla, bands)
