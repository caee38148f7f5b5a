r"""The best linear approximation (BLA), measured: how linear is the plant, and where?

A nonlinear plant driven by a random-phase multisine (or Gaussian noise) of a given
power spectrum behaves, on average over the signal's realisations, as a linear system
``G_BLA``; what it does besides is the **stochastic nonlinear distortion** ``Y_s``, which
looks like noise (it changes with the phases) but does not change from period to
period. The robust method of Pintelon & Schoukens (*System Identification: A Frequency
Domain Approach*, 2nd ed., 2012, sec. 3.7 and 4.3) separates it from the noise with
``M`` realisations of ``P`` periods each. With ``U_{m,p}(k)``, ``Y_{m,p}(k)`` the DFT
``X(k) = N^{-1/2} \sum_t x(t) e^{-j 2\pi k t / N}`` of period ``p`` of realisation
``m`` (``N`` samples a period), at the excited lines ``k``:

.. math::

    \bar X_m = \frac{1}{P} \sum_p X_{m,p}, \qquad
    \hat\sigma^2_{\bar X \bar Z, m} = \frac{\sum_p (X_{m,p} - \bar X_m)
        \overline{(Z_{m,p} - \bar Z_m)}}{P (P - 1)}                       \quad (1)

    \hat G_m = \bar Y_m / \bar U_m, \qquad
    \hat\sigma^2_{G,m} = |\hat G_m|^2 \Bigl( \frac{\hat\sigma^2_{\bar Y}}{|\bar Y_m|^2}
        + \frac{\hat\sigma^2_{\bar U}}{|\bar U_m|^2}
        - 2 \operatorname{Re} \frac{\hat\sigma^2_{\bar Y \bar U}}{\bar Y_m \bar U_m^*}
        \Bigr)                                                               \quad (2)

    \hat G_\mathrm{BLA} = \frac{1}{M} \sum_m \hat G_m, \qquad
    \hat\sigma^2_\mathrm{total} = \frac{\sum_m |\hat G_m - \hat G_\mathrm{BLA}|^2}{M (M-1)},
    \qquad
    \hat\sigma^2_\mathrm{noise} = \frac{1}{M^2} \sum_m \hat\sigma^2_{G,m}     \quad (3)

and the variance of ``Ĝ_BLA`` from the nonlinear distortion is ``σ²_total - σ²_noise``
(one realisation's is ``M`` times that). The noise variance needs ``P >= 2``, the total
``M >= 2``. Averaging over periods before dividing keeps input noise from biasing
``G`` (errors in variables). The first periods of each realisation can be dropped as the
plant's transient (``transient_periods``); by default the first is dropped when the
output's first period differs clearly more from the others than they differ among
themselves (:func:`~blockid.evaluation.periods.first_period_differs`; 3 periods or
more).

With an **odd** multisine (odd lines only, some left out: :func:`blockid.design.multisine`
with ``odd=True``) the lines left empty show the distortion directly: even lines carry
the even nonlinear contributions, the odd lines left out the odd ones. Their output
power is referred to the input (over ``M |U(k)|²``, the input's power per line
interpolated over the excited lines) so that it reads on the same axis as
``σ²_total``; with ``P >= 2`` the noise there is known as well.

The confidence ``bound`` is the radius of a circle around ``Ĝ_BLA``: for complex
circular Gaussian errors ``|Ĝ - G|² / σ̂²_total`` is ``F(2, 2(M-1))``, so the radius is
``σ̂_total sqrt(F_{2, 2(M-1)}(confidence))`` (with one realisation, the noise bound
``F(2, 2M(P-1))`` on ``σ̂_noise``, which leaves that realisation's distortion out).

Data that do not repeat get the Welch estimate of :mod:`blockid.evaluation.frf`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from blockid.data.dataset import Dataset
from blockid.errors import DataError, ParameterError
from blockid.evaluation.bla_bands import DEFAULT_BANDS, summarised
from blockid.evaluation.bla_result import BestLinearApproximation, NonExcitedLines
from blockid.evaluation.periods import find_period, first_period_differs, periodic_frames
from blockid.evaluation.spectra import (
    CONFIDENCE,
    check_confidence,
    frequency_unit,
    powered,
    signal_columns,
)

__all__ = ["best_linear_approximation", "robust_bla"]

#: A realisation whose input power at an excited line is below this share of the
#: line's typical power is left out of that line (G would divide by almost nothing).
_WEAK = 1e-4
#: An excitation whose lines found are odd but for a few (at least this share odd) is
#: taken for an odd multisine: the even ones are a disturbance (a mains harmonic in
#: the measured input), left out with a note.
_ODD_SHARE = 0.98


def _excited(u_mean: np.ndarray, lines: Sequence[int] | None, n: int) -> np.ndarray:
    """The excited lines (given, checked; or found from the input's power)."""
    power = np.mean(np.abs(u_mean) ** 2, axis=0)
    last = (n - 1) // 2  # line 0 and the Nyquist line carry no phase: never used
    usable = np.zeros(power.shape, bool)
    usable[1 : last + 1] = True
    found = powered(np.where(usable, power, 0.0))
    if lines is None:
        k = np.flatnonzero(found & usable)
        if k.size == 0:
            raise DataError("the input has no power at any line of the period: it is constant "
                            "or its power lies at 0 Hz only; check the input column")  # fmt: skip
        return k
    k = np.unique(np.asarray(lines, dtype=int))
    outside = k[(k < 1) | (k > last)]
    if outside.size:
        raise ParameterError(f"lines {outside.tolist()[:5]} lie outside 1..{last} (a period of "
                             f"{n} samples)", parameter="lines")  # fmt: skip
    empty = k[~found[k]]
    if empty.size:
        raise DataError(
            f"the input has no power at {empty.size} of the {k.size} lines given "
            f"({empty.tolist()[:8]}{' ...' if empty.size > 8 else ''}): it lies 20 dB or more "
            "below its typical line; give the lines the excitation holds (e.g. "
            "Excitation.lines) or leave lines out to find them",
            parameter="lines",
        )
    return k


def _transient(
    u: np.ndarray, y: np.ndarray, drop: bool, confidence: float, sampling_time: float | None
) -> tuple[np.ndarray, np.ndarray, str | None]:
    """The periods without the first when it holds the plant's transient and ``drop``;
    a note when it does."""
    first = first_period_differs(y)
    if first is None or not first.differs(confidence):
        return u, y, None
    low, high = (k / (u.shape[2] * (sampling_time or 1.0)) for k in first.lines)
    p = "p < 1e-6" if first.p_value < 1e-6 else f"p = {first.p_value:.2g}"
    unit = frequency_unit(sampling_time)
    said = (f"the output's first period differs from the mean of the others {first.excess_db:.1f} "
            f"dB more than they differ among themselves ({low:.4g}-{high:.4g} {unit}, {p}): it "
            "holds the plant's transient")  # fmt: skip
    if drop:
        return u[:, 1:], y[:, 1:], f"{said}, dropped (0 transient periods keeps it)"
    return u, y, f"{said}, kept as asked; it inflates the noise (1 transient period drops it)"


def robust_bla(
    data: Dataset,
    *,
    input: str | None = None,
    output: str | None = None,
    period: int | None = None,
    periods: int | None = None,
    transient_periods: int | None = None,
    lines: Sequence[int] | None = None,
    bands: int | Sequence[tuple[float, float]] = DEFAULT_BANDS,
    confidence: float = CONFIDENCE,
    data_label: str | None = None,
) -> BestLinearApproximation:
    """The BLA of periodic data by the robust method (module docstring).

    Parameters
    ----------
    data : Dataset
        One experiment per realisation, each a whole number of periods.
    input, output : str, optional
        The signals (needed when the data have several).
    period : int, optional
        Samples in one period; default: found from the input
        (:func:`~blockid.evaluation.periods.find_period`).
    periods : int, optional
        Or the number of periods a realisation holds.
    transient_periods : int, optional
        Periods dropped from the start of each realisation; default: the first when
        it differs clearly from the last ones (the plant's transient:
        :func:`~blockid.evaluation.periods.first_period_differs`), with a note; 0
        keeps every period (a note says when the first differs).
    lines : sequence of int, optional
        The excited DFT lines of one period; default: the lines where the input has
        power (:func:`~blockid.evaluation.bla_result.powered`).
    bands : int or sequence of (low, high)
        The summary's bands: a number of bands of equal numbers of excited lines (and
        the lines the input left empty below and above them, a band each), or edges in
        Hz (:func:`~blockid.evaluation.bla_bands.band_edges`).
    confidence : float
        Of the bounds and the tests.
    data_label : str, optional
        Names the data in the summary and the figure.

    Raises
    ------
    DataError
        Non-finite samples, records that are not whole periods, no period found, an
        input without power at the lines, one realisation of one period (no variance).
    ParameterError
        Bad periods, lines, bands or confidence.
    """
    confidence = check_confidence(confidence)
    i, j = signal_columns(data, input, output)
    u, y, held = periodic_frames(data, input_column=i, output_column=j, period=period,
                                 periods=periods,
                                 transient_periods=transient_periods or 0)  # fmt: skip
    notes = []
    if not transient_periods:
        u, y, note = _transient(u, y, transient_periods is None, confidence, data.sampling_time)
        notes += [note] if note else []
    m, p, n = u.shape
    if m < 2 and p < 2:
        raise DataError(
            f"one realisation of one period ({n} samples) gives no variance: measure 2 or "
            "more periods (the noise variance) and 2 or more realisations (the total "
            "variance, hence the nonlinear distortion); 4 to 7 realisations of 2 or more "
            "periods are usual",
            parameter="periods",
        )
    big_u = np.fft.rfft(u, axis=2) / np.sqrt(n)
    big_y = np.fft.rfft(y, axis=2) / np.sqrt(n)
    u_mean, y_mean = big_u.mean(axis=1), big_y.mean(axis=1)  # (1)
    k = _excited(u_mean, lines, n)
    disturbed = k[:0]
    odd_k, even_k = k[k % 2 == 1], k[k % 2 == 0]
    if lines is None and even_k.size and odd_k.size >= _ODD_SHARE * k.size and odd_k.size >= 10:
        shown = ", ".join(
            f"{j} ({j / (n * (data.sampling_time or 1.0)):.4g} "
            f"{frequency_unit(data.sampling_time)})"
            for j in even_k[:5]
        )
        notes.append(f"{even_k.size} even line(s) with input power left out of an odd "
                     f"excitation, taken for a disturbance (mains?): {shown}")  # fmt: skip
        k, disturbed = odd_k, even_k
    power_k = np.mean(np.abs(u_mean[:, k]) ** 2, axis=0)
    weak = np.abs(u_mean[:, k]) ** 2 < _WEAK * power_k
    if weak.any():
        keep = ~weak.any(axis=0)
        notes.append(f"{int((~keep).sum())} line(s) left out: a realisation had almost no "
                     "input power there")  # fmt: skip
        k, power_k = k[keep], power_k[keep]
    g_m = y_mean[:, k] / u_mean[:, k]  # (2)
    g = g_m.mean(axis=0)  # (3)
    var_total = var_noise = output_noise = noise_y = None
    if m >= 2:
        var_total = np.sum(np.abs(g_m - g) ** 2, axis=0) / (m * (m - 1))
    else:
        notes.append("one realisation: the total variance (and the distortion at the "
                     "excited lines) needs 2 or more")  # fmt: skip
    if p >= 2:
        du, dy = big_u - u_mean[:, None], big_y - y_mean[:, None]
        var_u = np.sum(np.abs(du) ** 2, axis=1) / (p * (p - 1))
        noise_y = np.sum(np.abs(dy) ** 2, axis=1) / (p * (p - 1))
        cov_yu = np.sum(dy * np.conj(du), axis=1) / (p * (p - 1))
        yk, uk = y_mean[:, k], u_mean[:, k]
        var_g_m = np.abs(g_m) ** 2 * (
            noise_y[:, k] / np.abs(yk) ** 2
            + var_u[:, k] / np.abs(uk) ** 2
            - 2 * np.real(cov_yu[:, k] / (yk * np.conj(uk)))
        )  # (2)
        var_noise = np.sum(var_g_m, axis=0) / m**2  # (3)
        output_noise = p * noise_y[:, k].mean(axis=0)
    else:
        notes.append("one period a realisation: the noise variance needs 2 or more periods")
    from scipy import stats

    if var_total is not None:
        bound = np.sqrt(var_total * stats.f.ppf(confidence, 2, 2 * (m - 1)))
    else:
        bound = np.sqrt(var_noise * stats.f.ppf(confidence, 2, 2 * m * (p - 1)))
    ts = data.sampling_time or 1.0
    if data.sampling_time is None:
        notes.append("sampling time unknown: frequencies in cycles per sample")
    odd = bool(np.all(k % 2 == 1))
    empty = np.setdiff1d(np.arange(1, (n - 1) // 2 + 1), np.concatenate([k, disturbed]))
    kinds = np.where(empty % 2 == 0, "even", "odd") if odd else np.full(empty.shape, "non-excited")
    refer = m * np.interp(empty, k, power_k)
    nonexcited = NonExcitedLines(
        lines=empty,
        frequencies=empty / (n * ts),
        kind=kinds,
        level=np.mean(np.abs(y_mean[:, empty]) ** 2, axis=0) / refer,
        noise=None if noise_y is None else noise_y[:, empty].mean(axis=0) / refer,
    )  # fmt: skip
    bla = BestLinearApproximation(
        method="robust", frequencies=k / (n * ts), g=g, var_total=var_total,
        var_noise=var_noise, bound=bound, confidence=confidence, sampling_time=ts,
        realisations=m, periods=p, transient_periods=held - p, samples=n, bands=(),
        verdict="", lines=k, output_noise=output_noise, nonexcited=nonexcited,
        odd_design=odd, input_name=data.inputs[i], output_name=data.outputs[j],
        data_label=data_label or data.source or "data", notes=tuple(notes),
        unit=frequency_unit(data.sampling_time),
    )  # fmt: skip
    return summarised(bla, bands)


def best_linear_approximation(
    data: Dataset,
    *,
    input: str | None = None,
    output: str | None = None,
    method: str = "auto",
    period: int | None = None,
    periods: int | None = None,
    transient_periods: int | None = None,
    lines: Sequence[int] | None = None,
    segment: int | None = None,
    bands: int | Sequence[tuple[float, float]] = DEFAULT_BANDS,
    confidence: float = CONFIDENCE,
    data_label: str | None = None,
) -> BestLinearApproximation:
    """Measure the BLA of ``data``: the robust method on periodic data (:func:`robust_bla`),
    else Welch's estimate (:func:`~blockid.evaluation.frf.welch_bla`).

    ``method="auto"`` takes the robust method when a periodic option is given
    (``period``, ``periods``, ``transient_periods`` other than 0, ``lines``) or the input of
    every experiment repeats (:func:`~blockid.evaluation.periods.find_period`), and Welch's
    otherwise, with a note saying so. ``segment`` (samples of a Welch segment) is
    Welch's only. The other parameters are those of :func:`robust_bla`.

    >>> from blockid.data import Experiment
    >>> from blockid.design import multisine
    >>> x = multisine(256, f_max=0.2, periods=3, realisations=4, seed=1)
    >>> u = x.signals
    >>> y = u + 0.1 * u**3 + 0.01 * np.random.default_rng(0).standard_normal(u.shape)
    >>> data = Dataset(("u",), ("y",), 1.0, [Experiment(f"r{m}", u[m], y[m]) for m in range(4)])
    >>> bla = best_linear_approximation(data, transient_periods=1)
    >>> bla.method, bla.realisations, bla.periods, bla.samples
    ('robust', 4, 2, 256)
    """
    if method not in ("auto", "robust", "welch"):
        raise ParameterError(f"method {method!r}: choose auto, robust or welch", parameter="method")
    periodic = {"period": period, "periods": periods, "lines": lines,
                "transient_periods": transient_periods or None}  # fmt: skip
    given = [name for name, value in periodic.items() if value is not None]
    if method == "welch" and given:
        raise ParameterError(
            f"{', '.join(given)} and method welch do not go together: the periodic options "
            "are the robust method's; leave them out, or use method robust",
            parameter=given[0],
        )
    if segment is not None and (method == "robust" or given):
        raise ParameterError(
            f"{', '.join(given) or 'method robust'} and segment do not go together: the "
            "periodic options are the robust method's, segment the Welch estimate's",
            parameter=given[0] if given else "segment",
        )
    note = None
    if method == "auto" and segment is None and not given:
        i, _ = signal_columns(data, input, output)
        found = {find_period(e.u[:, i]) for e in data.experiments}
        if None in found or len(found) > 1:
            method = "welch"
            note = ("the input does not repeat (no period found): the non-periodic Welch "
                    "estimate, which cannot tell noise from distortion")  # fmt: skip
        else:
            period = found.pop()
            for exp in data.experiments:
                if exp.n_samples % period:
                    raise DataError(
                        f"the input repeats every {period} samples (found from it), but "
                        f"experiment '{exp.name}' holds {exp.n_samples}, not a whole number of "
                        "periods: cut each record to whole periods, give the period, or use "
                        "method 'welch' (the non-periodic estimate)",
                        parameter="method",
                    )
    if method == "welch" or segment is not None:
        from blockid.evaluation.frf import welch_bla

        bla = welch_bla(data, input=input, output=output, segment=segment, bands=bands,
                        confidence=confidence, data_label=data_label)  # fmt: skip
        if note:
            import dataclasses

            bla = dataclasses.replace(bla, notes=(note, *bla.notes))
        return bla
    return robust_bla(data, input=input, output=output, period=period, periods=periods,
                      transient_periods=transient_periods, lines=lines, bands=bands,
                      confidence=confidence, data_label=data_label)  # fmt: skip
