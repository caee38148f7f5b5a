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

:func:`first_period_differs` asks whether the first period still holds the plant's
transient. With ``Y_{m,p}(k)`` the DFT of period ``p`` of realisation ``m`` and
``Ȳ_m`` the mean of periods 2 to ``P``, in a steady state with stationary noise of
variance ``σ²_k`` at line ``k``

.. math::

    d_{m,k} = \\frac{|Y_{m,1} - \\bar Y_m|^2}{1 + 1/(P-1)}, \\qquad
    s_{m,k} = \\frac{1}{P-2} \\sum_{p=2}^{P} |Y_{m,p} - \\bar Y_m|^2

both estimate ``σ²_k``, independently, with 2 and ``2(P-2)`` real degrees of freedom
(complex Gaussian noise): the first period differs from the others as much as they
differ among themselves. Over a group ``G`` of ``L`` neighbouring lines,

.. math::

    F_G = \\frac{\\sum_{m, k \\in G} d_{m,k} / \\ell_k}{\\sum_{m, k \\in G} s_{m,k} / \\ell_k}
    \\sim F\\bigl(2LM,\\ 2LM(P-2)\\bigr),

``ℓ_k`` the noise level of the neighbouring lines (the mean of ``s`` over the ``M``
realisations and the 8 lines either side, the line itself left out), which weighs the
lines alike however the noise is coloured. A transient still dying out in the first
period makes ``F_G`` large where it rings: at few lines (a slow pole: the lowest) or
many (a resonance). The groups are every 16 neighbouring lines, every 32, and so on up
to all of them; the p-value of the group where ``F_G`` is most significant is
multiplied by the number of groups (Bonferroni). In simulation the test fires in about
1 % of records in steady state at ``confidence`` 0.99 (white noise; periods of 256 to
8192 samples), in 3 % for noise of time constant 20 samples in periods of 256. Noise
whose memory is a fair part of the period leaks across the periods' edges into every
line alike and fires it more often; such noise also overstates the noise variance
measured between periods, and dropping a period then costs data but biases nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blockid.data.dataset import Dataset
from blockid.errors import DataError, ParameterError
from blockid.evaluation.spectra import check_finite

__all__ = [
    "CLEAR_DB",
    "MIN_CORRELATION",
    "FirstPeriod",
    "find_period",
    "first_period_differs",
    "periodic_frames",
]

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
                f"whole number of {periods} periods; give the period in samples or cut the "
                "record to whole periods",
                parameter="period",
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
    if n < 3:  # lines 1 .. (n - 1) // 2 lie between 0 Hz and Nyquist: none below 3
        raise ParameterError(
            f"a period of {n} samples holds no frequency line between 0 Hz and the Nyquist "
            "frequency: a BLA needs periods of 3 samples or more (64 or more are usual)",
            parameter="periods" if period is None and periods is not None else "period",
        )
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


#: The smallest group of neighbouring lines of the first-period test (then 32, 64, ...).
_GROUP_LINES = 16
#: Lines either side whose noise level weighs a line (module docstring, ``ℓ_k``).
_NEIGHBOURS = 8
#: The first period must differ from the others by this much more than they differ
#: among themselves (dB) to count as a transient. Kept, it makes the noise variance
#: measured over all ``P`` periods ``1 + (F_G - 1) / (P - 1)`` times too large: at
#: 1 dB, 0.5 dB too large with 3 periods, 0.3 dB with 5.
CLEAR_DB = 1.0


@dataclass(frozen=True)
class FirstPeriod:
    """The first period against the others (:func:`first_period_differs`), at the
    group of lines where it differs most.

    Attributes
    ----------
    excess_db : float
        ``10 log10 F_G`` (module docstring): how much more the first period differs
        from the mean of the others than they differ among themselves, dB.
    p_value : float
        Of ``F_G``, times the number of groups tested (Bonferroni).
    lines : tuple of int
        The group's first and last DFT line.
    """

    excess_db: float
    p_value: float
    lines: tuple[int, int]

    def differs(self, confidence: float) -> bool:
        """Clearly: significant at ``confidence`` and :data:`CLEAR_DB` or more."""
        return self.p_value < 1.0 - confidence and self.excess_db >= CLEAR_DB


#: A group counts as clearly above, for where the transient rings, at this p-value or
#: below (Bonferroni already applied; well below any confidence asked).
_WHERE = 1e-3


def _groups(count: int) -> list[np.ndarray]:
    """Groups of 16, 32, ... neighbouring lines of ``count``, up to one of them all."""
    out, size = [], _GROUP_LINES
    while True:
        parts = max(1, count // size)
        out += np.array_split(np.arange(count), parts)
        if parts == 1:
            return out
        size *= 2


def first_period_differs(y: np.ndarray) -> FirstPeriod | None:
    """Does the first period of ``y`` (cut into periods: ``(realisations, periods,
    samples)``) still hold the plant's transient? The test of the module docstring over
    lines 1 to the last below Nyquist: of the groups significant at 0.999 and
    :data:`CLEAR_DB` or more above, the one of the largest excess (where the transient
    rings); else the most significant group of those :data:`CLEAR_DB` or more above, or
    of all; None with fewer than 3 periods.

    >>> rng = np.random.default_rng(0)
    >>> y = np.tile(np.sin(np.arange(512)), (1, 4, 1)) + 0.01 * rng.standard_normal((1, 4, 512))
    >>> first_period_differs(y).differs(0.99)
    False
    >>> y[0, 0, :20] += np.exp(-np.arange(20.0) / 4)  # a transient dying out in period 1
    >>> first_period_differs(y).differs(0.99)
    True
    """
    m, p, n = y.shape
    if p < 3 or n < 3:  # no line between 0 Hz and Nyquist below 3 samples a period
        return None
    spectra = np.fft.rfft(y, axis=2)[:, :, 1 : (n - 1) // 2 + 1]
    rest = spectra[:, 1:].mean(axis=1)
    d = np.abs(spectra[:, 0] - rest) ** 2 / (1.0 + 1.0 / (p - 1))
    s = np.sum(np.abs(spectra[:, 1:] - rest[:, None]) ** 2, axis=1) / (p - 2)
    level = s.mean(axis=0)
    window = np.ones(2 * _NEIGHBOURS + 1)
    # "full" cut to the lines: "same" returns the window's length for fewer lines
    inside = slice(_NEIGHBOURS, _NEIGHBOURS + level.size)
    around = np.convolve(level, window)[inside] - level  # the line itself left out
    count = np.convolve(np.ones(level.size), window)[inside] - 1
    weight = np.divide(count, around, out=np.zeros(level.size), where=around > 0)  # 1 / ℓ_k
    a, b = d * weight, s * weight
    from scipy import stats

    groups = _groups(level.size)
    found = []
    for group in groups:
        lines = int(np.count_nonzero(weight[group]))
        top, bottom = a[:, group].sum(), b[:, group].sum()
        if not (lines and top > 0 and bottom > 0):
            continue
        ratio = top / bottom
        pv = stats.f.sf(ratio, 2 * lines * m, 2 * lines * m * (p - 2))
        found.append(FirstPeriod(excess_db=float(10 * np.log10(ratio)),
                                 p_value=float(min(1.0, len(groups) * pv)),
                                 lines=(int(group[0]) + 1, int(group[-1]) + 1)))  # fmt: skip
    if not found:
        return None
    above = [f for f in found if f.excess_db >= CLEAR_DB]
    clear = [f for f in above if f.p_value < _WHERE]
    if clear:  # where it rings: the largest excess among the groups clearly above
        return max(clear, key=lambda f: f.excess_db)
    return min(above or found, key=lambda f: f.p_value)
