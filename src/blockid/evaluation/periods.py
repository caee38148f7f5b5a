"""Periodic records: the period of an input, and a record cut into its periods.

A designed excitation (a multisine, a PRBS: :mod:`blockid.design`) repeats exactly;
measured, it repeats up to the input's noise. :func:`find_period` reads the period off
the normalised autocorrelation of the input,

.. math::

    r(L) = \\frac{\\sum_{t=0}^{N-L-1} u(t)\\,u(t+L)}
                {\\sqrt{\\sum_{t=0}^{N-L-1} u(t)^2 \\sum_{t=L}^{N-1} u(t)^2}},

(``u`` centred), which is 1 at a lag that repeats the signal exactly and ``1 / (1 +
σ²/P_u)`` with input noise of variance ``σ²``. The period is the first lag after the
signal has decorrelated (``r < 0.5``) where ``r`` reaches :data:`MIN_CORRELATION`,
refined to the largest ``r`` of that stretch. A slow signal stays correlated with
itself for many samples; requiring the fall first keeps those lags out. At least two
periods must be in the record for the repeat to be seen.

:func:`periodic_frames` checks that every experiment (a realisation) holds a whole
number of periods, the same number in each, drops the transient periods asked for and
returns the samples as arrays ``(realisations, periods, samples)``.
"""

from __future__ import annotations

import numpy as np

from blockid.data.dataset import Dataset
from blockid.errors import DataError, ParameterError
from blockid.evaluation.spectra import check_finite

__all__ = ["MIN_CORRELATION", "find_period", "periodic_frames"]

#: The normalised autocorrelation a lag must reach to be taken for the period: an input
#: repeated with a signal-to-noise ratio of 10 dB or better (``1 / (1 + 0.1) = 0.91``).
MIN_CORRELATION = 0.9
#: The autocorrelation must first fall below this (the signal decorrelates).
_DECORRELATED = 0.5


def _autocorrelation(x: np.ndarray) -> np.ndarray:
    """``r(L)`` of the module docstring for ``L = 0 .. N // 2``."""
    x = x - x.mean()
    n = x.size
    size = 1 << int(2 * n - 1).bit_length()
    spectrum = np.fft.rfft(x, size)
    c = np.fft.irfft(np.abs(spectrum) ** 2, size)[: n // 2 + 1]
    energy = np.concatenate([[0.0], np.cumsum(x**2)])
    lags = np.arange(n // 2 + 1)
    head = energy[n - lags]  # sum of x(t)^2, t < N - L
    tail = energy[n] - energy[lags]  # sum of x(t)^2, t >= L
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(head * tail > 0, c / np.sqrt(head * tail), 0.0)


def find_period(u: np.ndarray, min_correlation: float = MIN_CORRELATION) -> int | None:
    """The period of the samples ``u`` in samples, or None when none repeats twice.

    >>> t = np.arange(400)
    >>> u = np.sin(2 * np.pi * 3 * t / 100) + np.cos(2 * np.pi * 7 * t / 100 + 1)
    >>> find_period(u)
    100
    >>> find_period(np.random.default_rng(0).standard_normal(400)) is None
    True
    """
    u = np.asarray(u, dtype=float).ravel()
    if u.size < 4 or not np.ptp(u) > 0:
        return None
    r = _autocorrelation(u)
    fallen = np.flatnonzero(r < _DECORRELATED)
    if fallen.size == 0:
        return None
    above = np.flatnonzero((r >= min_correlation) & (np.arange(r.size) > fallen[0]))
    if above.size == 0:
        return None
    start = above[0]
    stop = start
    while stop + 1 < r.size and r[stop + 1] >= min_correlation:
        stop += 1
    return int(start + np.argmax(r[start : stop + 1]))


def _period_of(data: Dataset, column: int, period: int | None, periods: int | None) -> int:
    """The samples of one period: given, from the number of periods, or found."""
    lengths = [exp.n_samples for exp in data.experiments]
    if period is not None:
        if isinstance(period, bool) or not isinstance(period, int | np.integer) or period < 2:
            raise ParameterError(f"period must be a whole number of samples >= 2, got {period!r}",
                                 parameter="period")  # fmt: skip
        if periods is not None and periods * period != lengths[0]:
            raise ParameterError(
                f"period = {period} and periods = {periods} make {period * periods} samples, "
                f"but the record holds {lengths[0]}; give one of them",
                parameter="periods",
            )
        return int(period)
    if periods is not None:
        if isinstance(periods, bool) or not isinstance(periods, int | np.integer) or periods < 1:
            raise ParameterError(f"periods must be a whole number >= 1, got {periods!r}",
                                 parameter="periods")  # fmt: skip
        if lengths[0] % periods:
            raise DataError(
                f"experiment '{data.experiments[0].name}' holds {lengths[0]} samples, not a "
                f"whole number of {periods} periods; give the period in samples (period) or "
                "cut the record to whole periods",
            )
        return lengths[0] // int(periods)
    found = []
    for exp in data.experiments:
        p = find_period(exp.u[:, column])
        if p is None:
            raise DataError(
                f"no period found in the input of experiment '{exp.name}' ({exp.n_samples} "
                "samples): it does not repeat at least twice with a correlation of "
                f"{MIN_CORRELATION} or more; give the period in samples or the number of "
                "periods a record holds, each realisation as its own experiment, or use the "
                "non-periodic estimate (method 'welch')",
                parameter="period",
            )
        found.append(p)
    if len(set(found)) > 1:
        shown = ", ".join(f"'{e.name}': {p}" for e, p in zip(data.experiments, found, strict=True))
        raise DataError(
            f"the experiments repeat with different periods ({shown} samples); a BLA needs one "
            "frequency grid: give the period",
            parameter="period",
        )
    return found[0]


def periodic_frames(
    data: Dataset,
    *,
    input_column: int = 0,
    output_column: int = 0,
    period: int | None = None,
    periods: int | None = None,
    transient_periods: int = 0,
) -> tuple[np.ndarray, np.ndarray, int]:
    """The input and output of every experiment cut into periods.

    Each experiment of ``data`` is one realisation. The period (samples) is ``period``,
    or the record's length over ``periods``, or found by :func:`find_period` on the
    input. Returns ``u`` and ``y`` of shape ``(realisations, periods, samples)`` without
    the first ``transient_periods`` of each realisation, and the number of periods
    each realisation held before.

    Raises
    ------
    DataError
        A record that is not a whole number of periods, realisations of different
        lengths, no period found, non-finite samples.
    ParameterError
        A period or a number of periods that is not a whole number, a period that
        disagrees with ``periods``, every period dropped as transient.
    """
    check_finite(data, input_column, output_column)
    n = _period_of(data, input_column, period, periods)
    held = []
    for exp in data.experiments:
        if exp.n_samples % n:
            whole = exp.n_samples // n
            raise DataError(
                f"experiment '{exp.name}' holds {exp.n_samples} samples, not a whole number "
                f"of periods of {n} ({whole} periods and {exp.n_samples - whole * n} samples "
                f"more); cut each record to whole periods (drop its first "
                f"{exp.n_samples - whole * n} samples, the start of the transient)",
                parameter="period",
            )
        held.append(exp.n_samples // n)
    if len(set(held)) > 1:
        shown = ", ".join(f"'{e.name}': {p}" for e, p in zip(data.experiments, held, strict=True))
        raise DataError(f"the realisations hold different numbers of periods ({shown}); give "
                        "each the same number (cut the longer ones)")  # fmt: skip
    total = held[0]
    if isinstance(transient_periods, bool) or not isinstance(transient_periods, int | np.integer) \
            or transient_periods < 0:  # fmt: skip
        raise ParameterError(f"transient_periods must be a whole number >= 0, got "
                             f"{transient_periods!r}", parameter="transient_periods")  # fmt: skip
    if transient_periods >= total:
        raise ParameterError(
            f"transient_periods = {transient_periods} would drop every period: each "
            f"realisation holds {total} period(s) of {n} samples; drop fewer",
            parameter="transient_periods",
        )
    m = data.n_experiments
    u = np.stack([exp.u[:, input_column] for exp in data.experiments]).reshape(m, total, n)
    y = np.stack([exp.y[:, output_column] for exp in data.experiments]).reshape(m, total, n)
    return u[:, transient_periods:], y[:, transient_periods:], total
