"""What a measurement of the best linear approximation (BLA) holds, and how it reads.

:class:`BestLinearApproximation` is what
:func:`~blockid.evaluation.bla.best_linear_approximation` returns: the frequency
response at the measured lines, its variances (total, noise), the levels at the lines
the input left empty, one :class:`BandSummary` per frequency band and a one-line
verdict. Variances are those of the estimate ``G`` itself (after the averaging over
periods and realisations), in the units of ``|G|²``; levels in dB are ``10 log10`` of
them, so that ``20 log10 |G|`` and the levels share one axis, as in the classic figure
of Pintelon & Schoukens.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from blockid.evaluation.spectra import db

__all__ = ["METHODS", "BandSummary", "BestLinearApproximation", "NonExcitedLines"]

#: The methods: Pintelon & Schoukens' robust method on periodic data, Welch's averaged
#: cross-spectra on any data.
METHODS = {
    "robust": "robust method (periods and realisations of a periodic excitation)",
    "welch": "Welch H1 estimate (averaged, windowed segments)",
}


@dataclass(frozen=True)
class NonExcitedLines:
    """The lines of a periodic record the input left empty (line 0 and the Nyquist line
    left out), where the output holds noise and nonlinear distortion only.

    Attributes
    ----------
    lines : ndarray of int
        DFT lines ``k`` of one period.
    frequencies : ndarray
        Hz.
    kind : ndarray of str
        ``"even"`` or ``"odd"`` when the input excites odd lines only (an odd multisine:
        even lines carry even distortion, the odd lines left out odd distortion), else
        ``"non-excited"``.
    level : ndarray
        The output's power there, referred to the input: the mean over realisations of
        ``|Ȳ(k)|²`` over ``M`` times the input's power per line ``|U(k)|²``
        (interpolated over the excited lines): the variance an excited line would have
        in ``G`` (``var_total``) from that distortion and noise.
    noise : ndarray or None
        The noise part of ``level``, from the variation between periods (None with one
        period).
    """

    lines: np.ndarray
    frequencies: np.ndarray
    kind: np.ndarray
    level: np.ndarray
    noise: np.ndarray | None


@dataclass(frozen=True)
class BandSummary:
    """The levels of one frequency band, power averages over its lines, in dB.

    Attributes
    ----------
    low, high : float
        The band's edges, Hz.
    lines : int
        Lines of the band where ``G`` is measured.
    g_db : float
        ``10 log10`` of the mean ``|G|²``.
    total_db, noise_db : float or None
        Of the mean total and noise variances of ``G`` (None when not measured: one
        realisation, one period).
    distortion_db : float or None
        Of the mean nonlinear distortion variance, ``total - noise``; None when that is
        not positive or either is not measured.
    p_value : float or None
        Of the test "no nonlinear distortion": ``F = total / noise``, ``F(2L(M-1),
        2LM(P-1))``-distributed for a linear plant (``L`` lines, ``M`` realisations,
        ``P`` periods).
    detected : bool or None
        ``p_value < 1 - confidence``.
    overstated : bool or None
        The total variance lies significantly *below* the noise variance (the lower
        tail of the same test under ``1 - confidence``): the noise variance is
        overstated, as it is when noise that passes through the plant's dynamics does
        not repeat (its transients in consecutive periods are anti-correlated), and may
        hide distortion of its size.
    nonexcited : dict
        Kind (``"even"``, ``"odd"``, ``"non-excited"``) -> ``{"lines", "level_db",
        "noise_db", "distortion_db", "p_value", "detected"}`` of the band's non-excited
        lines (``p_value``: ``level / noise`` against ``F(2LM, 2LM(P-1))``; with one
        period the odd lines are tested against the even ones instead).
    coherence : float or None
        Welch: the mean coherence ``γ²`` of the band's lines.
    """

    low: float
    high: float
    lines: int
    g_db: float | None
    total_db: float | None = None
    noise_db: float | None = None
    distortion_db: float | None = None
    p_value: float | None = None
    detected: bool | None = None
    overstated: bool | None = None
    nonexcited: dict[str, dict[str, Any]] = field(default_factory=dict)
    coherence: float | None = None

    @property
    def margin_db(self) -> float | None:
        """Distortion over noise, dB (None unless both are measured and positive)."""
        if self.distortion_db is None or self.noise_db is None:
            return None
        return self.distortion_db - self.noise_db

    def to_dict(self) -> dict[str, Any]:
        return {
            "low_hz": self.low,
            "high_hz": self.high,
            "lines": self.lines,
            "g_db": self.g_db,
            "total_db": self.total_db,
            "noise_db": self.noise_db,
            "distortion_db": self.distortion_db,
            "margin_db": self.margin_db,
            "p_value": self.p_value,
            "detected": self.detected,
            "overstated": self.overstated,
            "nonexcited": self.nonexcited,
            "coherence": self.coherence,
        }


def _fmt(value: float | None, spec: str = ".1f") -> str:
    return "-" if value is None else format(value, spec)


def _p(value: float | None) -> str:
    """A p-value: two digits, very small ones as a bound."""
    return "-" if value is None else "<1e-6" if value < 1e-6 else f"{value:.2g}"


@dataclass(frozen=True)
class BestLinearApproximation:
    """A measured best linear approximation: frequency response, variances, levels.

    Attributes
    ----------
    method : {"robust", "welch"}
    frequencies : ndarray
        Hz, of the lines where ``g`` is given (the excited lines of a periodic input).
    g : ndarray of complex
        The BLA ``G(f)``, output over input.
    var_total : ndarray or None
        Variance of ``g`` from noise and nonlinear distortion together: from the
        variation between realisations (robust, ``M >= 2``), from the coherence (Welch).
    var_noise : ndarray or None
        Variance of ``g`` from noise alone, from the variation between periods (robust,
        ``P >= 2``); None for Welch (non-periodic data cannot tell noise from
        distortion).
    bound : ndarray or None
        Radius of the circle around ``g`` that holds the BLA at ``confidence`` (module
        docstrings of :mod:`~blockid.evaluation.bla` and :mod:`~blockid.evaluation.frf`).
    confidence : float
        Of ``bound`` and of the bands' tests.
    sampling_time : float
    realisations, periods : int
        ``M`` and ``P`` used (Welch: experiments, and 1).
    transient_periods : int
        Dropped from the start of every realisation.
    samples : int
        Samples of a period (robust) or of a segment (Welch).
    lines : ndarray of int or None
        The DFT lines ``k`` of one period (robust).
    output_noise : ndarray or None
        Robust, ``P >= 2``: the noise variance of one period's output DFT (scaled by
        ``1 / sqrt(N)``, so that white noise of variance ``σ²`` gives ``σ²``) at the
        lines of ``g``, mean over the realisations.
    nonexcited : NonExcitedLines or None
        Robust: the lines the input left empty.
    coherence : ndarray or None
        Welch: ``γ²(f)``.
    segments : float or None
        Welch: the number of independent averages the bounds assume.
    bands : tuple of BandSummary
    verdict : str
        One line: is there nonlinear distortion above the noise, and where.
    odd_design : bool
        The input excites odd lines only.
    input_name, output_name, data_label : str
    notes : tuple of str
        What could not be measured, and why.
    """

    method: str
    frequencies: np.ndarray
    g: np.ndarray
    var_total: np.ndarray | None
    var_noise: np.ndarray | None
    bound: np.ndarray | None
    confidence: float
    sampling_time: float
    realisations: int
    periods: int
    transient_periods: int
    samples: int
    bands: tuple[BandSummary, ...]
    verdict: str
    lines: np.ndarray | None = None
    output_noise: np.ndarray | None = None
    nonexcited: NonExcitedLines | None = None
    coherence: np.ndarray | None = None
    segments: float | None = None
    odd_design: bool = False
    input_name: str = "u"
    output_name: str = "y"
    data_label: str = "data"
    notes: tuple[str, ...] = ()
    #: of ``frequencies``: "Hz", or "cycles/sample" when the data gave no sampling time
    unit: str = "Hz"

    # ------------------------------------------------------------------ derived
    @property
    def std(self) -> np.ndarray:
        """Standard deviation of ``g``: total where measured, else that of the noise."""
        var = self.var_total if self.var_total is not None else self.var_noise
        return np.full(self.g.shape, np.nan) if var is None else np.sqrt(var)

    @property
    def var_distortion(self) -> np.ndarray | None:
        """``var_total - var_noise`` per line (may be negative: both are estimates)."""
        if self.var_total is None or self.var_noise is None:
            return None
        return self.var_total - self.var_noise

    def describe(self) -> str:
        """What was measured on what, in one line (the summary's and figure's title)."""
        if self.method == "welch":
            shape = (f"{self.realisations} record(s), segments of {self.samples} samples "
                     f"(~{self.segments:.0f} independent averages)")  # fmt: skip
        else:
            shape = (f"{self.realisations} realisation(s) x {self.periods} period(s) of "
                     f"{self.samples} samples")  # fmt: skip
            if self.transient_periods:
                shape += f", {self.transient_periods} transient period(s) dropped"
        return (f"BLA {self.input_name} -> {self.output_name} on {self.data_label}: "
                f"{METHODS[self.method]}, {shape}")  # fmt: skip

    # ------------------------------------------------------------------ outputs
    def summary_table(self) -> tuple[str, list[str], list[list[str]], list[str]]:
        """A title, the columns and rows of the band table, and lines of text (notes,
        the verdict): what ``blockid bla`` prints."""
        columns = [f"band ({self.unit})", "lines", "|G| dB"]
        if self.method == "welch":
            columns += ["coherence", "std of G dB"]
        else:
            columns += ["total dB", "noise dB", "distortion dB", "distortion - noise dB", "p"]
        kinds = sorted({k for b in self.bands for k in b.nonexcited})
        columns += [f"{k} lines dB (noise)" for k in kinds]
        rows = []
        for b in self.bands:
            row = [f"{b.low:.4g} - {b.high:.4g}", str(b.lines), _fmt(b.g_db)]
            if self.method == "welch":
                row += [_fmt(b.coherence, ".3f"), _fmt(b.total_db)]
            else:
                row += [_fmt(b.total_db), _fmt(b.noise_db), _fmt(b.distortion_db),
                        _fmt(b.margin_db, "+.1f"), _p(b.p_value)]  # fmt: skip
            for k in kinds:
                level = b.nonexcited.get(k)
                row.append("-" if level is None else
                           f"{_fmt(level['level_db'])} ({_fmt(level['noise_db'])})")  # fmt: skip
            rows.append(row)
        return self.describe(), columns, rows, [*self.notes, self.verdict]

    def summary(self) -> str:
        """The summary as plain text: the title, the band table, the notes, the verdict."""
        title, columns, rows, text = self.summary_table()
        widths = [max(len(c), *(len(r[i]) for r in rows)) for i, c in enumerate(columns)]
        lines = [title, "  ".join(c.rjust(w) for c, w in zip(columns, widths, strict=True))]
        lines += ["  ".join(v.rjust(w) for v, w in zip(r, widths, strict=True)) for r in rows]
        return "\n".join([*lines, *text])

    def to_frame(self) -> Any:
        """One row per line: frequency, ``G`` (real, imaginary, dB, degrees), its
        standard deviation, variances and bound."""
        import pandas as pd

        none = np.full(self.g.shape, np.nan)
        return pd.DataFrame(
            {
                "frequency_hz": self.frequencies,
                "g_real": self.g.real,
                "g_imag": self.g.imag,
                "g_db": db(np.abs(self.g) ** 2),
                "g_phase_deg": np.degrees(np.angle(self.g)),
                "std": self.std,
                "var_total": none if self.var_total is None else self.var_total,
                "var_noise": none if self.var_noise is None else self.var_noise,
                "bound": none if self.bound is None else self.bound,
            }
        )

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready document (arrays as lists, complex ``G`` as real and imaginary
        parts; undefined numbers become null through the writer)."""

        def listed(a: np.ndarray | None) -> list | None:
            return None if a is None else np.asarray(a).tolist()

        doc: dict[str, Any] = {
            "method": self.method,
            "description": self.describe(),
            "input": self.input_name,
            "output": self.output_name,
            "data": self.data_label,
            "sampling_time": self.sampling_time,
            "unit": self.unit,
            "realisations": self.realisations,
            "periods": self.periods,
            "transient_periods": self.transient_periods,
            "samples": self.samples,
            "confidence": self.confidence,
            "odd_design": self.odd_design,
            "verdict": self.verdict,
            "notes": list(self.notes),
            "bands": [b.to_dict() for b in self.bands],
            "frequencies_hz": listed(self.frequencies),
            "lines": listed(self.lines),
            "g_real": listed(self.g.real),
            "g_imag": listed(self.g.imag),
            "var_total": listed(self.var_total),
            "var_noise": listed(self.var_noise),
            "bound": listed(self.bound),
            "output_noise": listed(self.output_noise),
            "coherence": listed(self.coherence),
            "segments": self.segments,
        }
        ne = self.nonexcited
        doc["nonexcited"] = None if ne is None else {
            "lines": listed(ne.lines), "frequencies_hz": listed(ne.frequencies),
            "kind": listed(ne.kind), "level": listed(ne.level), "noise": listed(ne.noise),
        }  # fmt: skip
        return doc

    def report_entry(self) -> dict[str, Any]:
        """The little a report needs besides the figure (:meth:`plot`): what was
        measured, the verdict and the band table."""
        title, columns, rows, _ = self.summary_table()
        return {"title": title, "verdict": self.verdict, "notes": list(self.notes),
                "columns": columns, "rows": rows,
                "bands": [b.to_dict() for b in self.bands]}  # fmt: skip

    def plot(self) -> Any:
        """The classic figure (:func:`blockid.plotting.bla.plot_bla`): returns it."""
        from blockid.plotting.bla import plot_bla

        return plot_bla(self)
