"""A designed excitation: its samples, what was asked for and the properties it has.

:class:`Excitation` is what :func:`~blockid.design.multisine`,
:func:`~blockid.design.prbs` and :func:`~blockid.design.random_binary` return. Its
properties are measured on the samples themselves, not copied from the request: the
excited lines are read off the DFT of one period, the RMS value and the crest factor
off the samples, so that the report says what the file holds.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from blockid.design.checks import KINDS

__all__ = ["Excitation", "crest_factor", "design_rng"]

#: A line is excited when its DFT magnitude exceeds this share of the largest one (the
#: lines a multisine leaves empty hold rounding errors ~1e-16 of it).
_LINE_FLOOR = 1e-9


def crest_factor(u: Any) -> np.ndarray:
    """Peak over RMS value, ``max |u| / sqrt(mean(u^2))``, of each row of ``u`` (of the
    samples: the continuous signal between them may peak higher).

    >>> float(crest_factor([1.0, -1.0, 1.0, -1.0]))
    1.0
    """
    u = np.asarray(u, dtype=float)
    return np.abs(u).max(axis=-1) / np.sqrt(np.mean(u**2, axis=-1))


def design_rng(seed: int, stream: int) -> np.random.Generator:
    """The random generator of one stream of a design with ``seed``: stream 0 draws what
    all realisations share (the odd multisine's left-out lines), stream r >= 1 the phases
    or bits of realisation r. A realisation's stream does not depend on how many others
    were asked for: realisation 2 of a 5-realisation design is realisation 2 of a
    2-realisation design with the same seed."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(stream,)))


@dataclass(frozen=True)
class Excitation:
    """Realisations of a periodic excitation signal and what they were designed as.

    Attributes
    ----------
    kind : str
        One of :data:`~blockid.design.checks.KINDS`.
    signals : ndarray, shape (realisations, periods * samples)
        One row per realisation: ``periods`` exact repetitions of one period.
    sampling_time : float
        Seconds between samples.
    samples : int
        Samples in one period (the frequency resolution is ``1 / (samples *
        sampling_time)``).
    periods : int
        Repetitions of the period in each realisation.
    settings : dict
        The design's parameters as given (band, RMS value, order, levels, seed...).
    designed_lines : ndarray of int or None
        Multisines: the DFT lines given energy, the same for every realisation.
    left_out : ndarray of int or None
        Odd random-phase multisines: the odd lines in the band left empty, one in each
        group of consecutive odd lines, where odd nonlinear distortion shows.
    crest_factor_start : ndarray or None
        Multisines: each realisation's crest factor with its random phases, before the
        crest-factor optimisation.
    """

    kind: str
    signals: np.ndarray
    sampling_time: float
    samples: int
    periods: int
    settings: dict[str, Any] = field(default_factory=dict)
    designed_lines: np.ndarray | None = None
    left_out: np.ndarray | None = None
    crest_factor_start: np.ndarray | None = None

    # ---------------------------------------------------------------------- measured
    @property
    def realisations(self) -> int:
        """Number of realisations (rows of :attr:`signals`)."""
        return self.signals.shape[0]

    @property
    def resolution(self) -> float:
        """Distance between DFT lines of one period, Hz."""
        return 1.0 / (self.samples * self.sampling_time)

    @property
    def period_seconds(self) -> float:
        """Length of one period, s."""
        return self.samples * self.sampling_time

    @property
    def rms(self) -> np.ndarray:
        """RMS value of each realisation."""
        return np.sqrt(np.mean(self.signals**2, axis=1))

    @property
    def peak(self) -> np.ndarray:
        """Largest absolute sample of each realisation."""
        return np.abs(self.signals).max(axis=1)

    @property
    def crest_factor(self) -> np.ndarray:
        """Crest factor of each realisation (:func:`crest_factor`)."""
        return crest_factor(self.signals)

    def spectrum(self) -> np.ndarray:
        """DFT of the first period of each realisation, lines ``0 .. samples // 2``
        (shape ``(realisations, samples // 2 + 1)``; unscaled, as ``numpy.fft.rfft``)."""
        return np.fft.rfft(self.signals[:, : self.samples], axis=1)

    @property
    def lines(self) -> np.ndarray:
        """The excited DFT lines ``k >= 1`` (frequency ``k * resolution``): those holding
        energy in some realisation, read off :meth:`spectrum`."""
        magnitude = np.abs(self.spectrum())[:, 1:]
        floor = _LINE_FLOOR * magnitude.max(axis=1, keepdims=True)
        return np.flatnonzero((magnitude > floor).any(axis=0)) + 1

    # ---------------------------------------------------------------------- outputs
    def to_frame(self, name: str = "u") -> Any:
        """The samples as a long table: columns ``t`` (seconds from the start of the
        realisation), ``realisation`` (1, 2, ...), ``period`` (1, 2, ... within the
        realisation) and ``name``. Read back with ``time_column="t"`` and
        ``experiment_column="realisation"``: each realisation is one experiment."""
        import pandas as pd

        n = self.signals.shape[1]
        index = np.arange(n)
        return pd.DataFrame(
            {
                "t": np.tile(index * self.sampling_time, self.realisations),
                "realisation": np.repeat(np.arange(1, self.realisations + 1), n),
                "period": np.tile(index // self.samples + 1, self.realisations),
                name: self.signals.reshape(-1),
            }
        )

    def summary(self) -> tuple[str, list[str], list[list[str]], list[str]]:
        """What ``blockid design`` prints: a title, the columns and rows of a table (a
        row per realisation: RMS, mean, peak, crest factor and, optimised, the random
        phases' crest factor) and lines of text (the excited lines, the left-out ones,
        a binary signal's levels and spectrum)."""
        fs = 1.0 / self.sampling_time
        title = (
            f"{KINDS[self.kind]}: {_count(self.realisations, 'realisation')} x "
            f"{_count(self.periods, 'period')} x {self.samples} samples at {fs:g} Hz (period "
            f"{self.period_seconds:g} s, lines {self.resolution:.4g} Hz apart)"
        )
        columns = ["realisation", "RMS", "mean", "peak", "crest factor"]
        start = self.crest_factor_start
        if start is not None:
            columns.append("crest factor, random phases")
        rows = []
        for r in range(self.realisations):
            mean = self.signals[r].mean()
            mean = 0.0 if abs(mean) <= 1e-12 * self.rms[r] else mean  # a multisine's rounding
            row = [str(r + 1), f"{self.rms[r]:.4g}", f"{mean:.3g}", f"{self.peak[r]:.4g}",
                   f"{self.crest_factor[r]:.3f}"]  # fmt: skip
            if start is not None:
                row.append(f"{start[r]:.3f}")
            rows.append(row)
        text = [f"excited lines {_lines(self.lines, self.resolution)}"]
        if self.left_out is not None:
            text.append(
                f"odd lines left out {_lines(self.left_out, self.resolution)}: odd nonlinear "
                "distortion shows there, even distortion at the even lines"
            )
        settings = self.settings
        if "clock" in settings:
            low, high = settings["levels"]
            held = settings["clock"]
            line = f"levels {low:g} and {high:g}; "
            if "polynomial" in settings:
                line = f"feedback polynomial {settings['polynomial']}; " + line
            if held == 1:
                line += "one sample a bit: the power spread evenly up to the Nyquist frequency"
            else:
                line += (
                    f"each bit held {held} samples: power 3 dB down at "
                    f"{settings['half_power_hz']:.4g} Hz, none at multiples of {fs / held:g} Hz"
                )
            text.append(line)
        return title, columns, rows, text

    def to_dict(self) -> dict[str, Any]:
        """The design and its measured properties as a JSON-ready document."""
        lines = self.lines
        doc: dict[str, Any] = {
            "kind": self.kind,
            "description": KINDS[self.kind],
            "sampling_time": self.sampling_time,
            "sampling_frequency": 1.0 / self.sampling_time,
            "samples_per_period": self.samples,
            "periods": self.periods,
            "realisations": self.realisations,
            "samples_per_realisation": int(self.signals.shape[1]),
            "period_seconds": self.period_seconds,
            "resolution_hz": self.resolution,
            "lines": lines.tolist(),
            "frequencies_hz": (lines * self.resolution).tolist(),
            "settings": dict(self.settings),
        }
        if self.left_out is not None:
            doc["left_out_lines"] = self.left_out.tolist()
            doc["left_out_frequencies_hz"] = (self.left_out * self.resolution).tolist()
        measured = {
            "rms": self.rms,
            "peak": self.peak,
            "mean": self.signals.mean(axis=1),
            "crest_factor": self.crest_factor,
        }
        if self.crest_factor_start is not None:
            measured["crest_factor_start"] = self.crest_factor_start
        doc["signals"] = [
            {"realisation": r + 1, **{k: float(v[r]) for k, v in measured.items()}}
            for r in range(self.realisations)
        ]
        return doc


#: Lines listed one by one at most; a longer list is shown by its ends.
_SHOWN = 12


def _lines(lines: Any, resolution: float) -> str:
    """``(count): k1, k2, ... (f1 .. f2 Hz)``; a long list by its ends."""
    if len(lines) == 0:
        return "none"
    ks = [int(k) for k in lines]
    if len(ks) <= _SHOWN:
        shown = ", ".join(map(str, ks))
    else:
        half = _SHOWN // 2
        shown = f"{', '.join(map(str, ks[:half]))}, ..., {', '.join(map(str, ks[-half:]))}"
    step = {b - a for a, b in zip(ks, ks[1:], strict=False)}
    kind = ", every line" if step == {1} else ", every odd line" if step == {2} else ""
    band = f"{ks[0] * resolution:.4g} .. {ks[-1] * resolution:.4g} Hz"
    return f"({len(ks)}{kind}): {shown} ({band})"


def _count(n: int, what: str) -> str:
    return f"{n} {what}" + ("" if n == 1 else "s")
