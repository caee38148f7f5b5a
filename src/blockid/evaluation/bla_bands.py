"""The bands of a BLA measurement: their levels, the tests, the verdict.

A band's levels are power averages over its lines (:class:`BandSummary`). The test for
nonlinear distortion at the excited lines compares the total variance of ``G`` with
its noise variance: for a linear plant both estimate the same variance, with
``2(M-1)`` and ``2M(P-1)`` real degrees of freedom per line (``M`` realisations, ``P``
periods; complex circular errors), so that over ``L`` lines

.. math::

    F = \\frac{\\overline{\\sigma^2_\\mathrm{total}}}{\\overline{\\sigma^2_\\mathrm{noise}}}
    \\sim F\\bigl(2L(M-1),\\ 2LM(P-1)\\bigr)

(lines taken as independent and of equal variance within the band). At the
non-excited lines the output's power ``|Ȳ|²`` (``2M`` degrees of freedom a line) is
compared with its noise variance in the same way, ``F(2LM, 2LM(P-1))``; with one period
a realisation the odd lines an odd multisine leaves empty are compared with the even
ones instead (``F(2L_oM, 2L_eM)``), which hold noise only when the plant's
nonlinearity is odd. A band shows distortion when the test's p-value is below ``1 -
confidence``; the noise is overstated there when the lower tail of the same test is
(the total, or the output at the empty lines, significantly *below* the noise).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

import numpy as np

from blockid.errors import ParameterError
from blockid.evaluation.bla_result import BandSummary, BestLinearApproximation
from blockid.evaluation.spectra import db

__all__ = ["DEFAULT_BANDS", "band_edges", "parse_bands", "summarised"]

#: Bands of the summary by default: the measured lines in this many bands of equal
#: numbers of lines (and the empty lines below and above them, a band each).
DEFAULT_BANDS = 4


def parse_bands(text: str) -> int | list[tuple[float, float]]:
    """``"4"`` (a number of bands) or ``"1:50,50:200"`` (edges in Hz).

    >>> parse_bands("1:50, 50:200"), parse_bands("3")
    ([(1.0, 50.0), (50.0, 200.0)], 3)
    """
    text = text.strip()
    try:
        if ":" not in text:
            return int(text)
        bands = []
        for part in text.split(","):
            low, high = part.split(":")
            bands.append((float(low), float(high)))
        return bands
    except ValueError:
        raise ParameterError(
            f"bands {text!r}: give a number of bands (e.g. 4) or edges in Hz as "
            "LOW:HIGH,LOW:HIGH (e.g. 1:50,50:200)",
            parameter="bands",
        ) from None


def band_edges(
    frequencies: np.ndarray,
    bands: int | Sequence[tuple[float, float]],
    empty: np.ndarray | None = None,
) -> list[tuple[float, float]]:
    """The bands' edges (Hz): ``bands`` of equal numbers of the measured
    ``frequencies`` (each band from its first line to its last, a gap between
    bands split in the middle), and a band of the ``empty`` (non-excited) lines below
    the first measured line and one of those above the last, when there are such
    lines; or the edges given, checked: each must hold a measured line or an empty one.

    A number of bands thus spans every line of the record, from the first to the last
    below Nyquist: a plant that puts its distortion outside the excited band (the
    harmonics of a band-limited input above it, the low-frequency products of
    hysteresis below it) is not missed by default.

    >>> band_edges(np.array([3.0, 4.0, 5.0, 6.0]), 2, empty=np.array([1.0, 2.0, 7.0]))
    [(1.0, 2.0), (3.0, 4.5), (4.5, 6.0), (7.0, 7.0)]
    """
    f = np.sort(np.asarray(frequencies, dtype=float))
    seen = f if empty is None else np.sort(np.concatenate([f, empty]))
    if isinstance(bands, int | np.integer) and not isinstance(bands, bool):
        if bands < 1:
            raise ParameterError(f"bands must be >= 1, got {bands}", parameter="bands")
        chunks = [c for c in np.array_split(f, min(int(bands), f.size)) if c.size]
        cuts = [(a[-1] + b[0]) / 2 for a, b in zip(chunks, chunks[1:], strict=False)]
        edges = [float(f[0]), *map(float, cuts), float(f[-1])]
        excited = list(zip(edges, edges[1:], strict=False)) if len(edges) > 2 else [
            (edges[0], edges[-1])
        ]  # fmt: skip
        below, above = seen[seen < f[0]], seen[seen > f[-1]]
        return [
            *([(float(below[0]), float(below[-1]))] if below.size else []),
            *excited,
            *([(float(above[0]), float(above[-1]))] if above.size else []),
        ]
    out = []
    for low, high in bands:
        if not (np.isfinite(low) and np.isfinite(high) and 0 <= low < high):
            raise ParameterError(f"band {low:g}:{high:g} Hz: give 0 <= LOW < HIGH",
                                 parameter="bands")  # fmt: skip
        if not np.any((seen >= low) & (seen <= high)):
            raise ParameterError(
                f"band {low:g}:{high:g} Hz holds no line (the lines run from "
                f"{seen[0]:.4g} to {seen[-1]:.4g} Hz, {seen.size} of them); choose bands that "
                "overlap them",
                parameter="bands",
            )
        out.append((float(low), float(high)))
    ordered = sorted(out)
    for (low_a, high_a), (low_b, high_b) in zip(ordered, ordered[1:], strict=False):
        if low_b < high_a:  # a line in both would be counted twice, in the verdict too
            raise ParameterError(
                f"bands {low_a:g}:{high_a:g} and {low_b:g}:{high_b:g} Hz overlap; give bands "
                f"that share at most an edge (e.g. {low_a:g}:{low_b:g},{low_b:g}:{high_b:g})",
                parameter="bands",
            )
    return out


def _in(f: np.ndarray, band: tuple[float, float]) -> np.ndarray:
    return (f >= band[0]) & (f <= band[1])


def _mean(values: np.ndarray | None, mask: np.ndarray) -> float | None:
    if values is None or not mask.any():
        return None
    return float(np.mean(values[mask]))


def _f_test(ratio: float | None, dfn: float, dfd: float) -> float | None:
    """The upper tail ``P(F > ratio)`` of ``F(dfn, dfd)`` (None if undefined)."""
    if ratio is None or not np.isfinite(ratio) or dfn <= 0 or dfd <= 0:
        return None
    from scipy import stats

    return float(stats.f.sf(ratio, dfn, dfd))


def _ratio(a: float | None, b: float | None) -> float | None:
    return None if a is None or b is None or not b > 0 else a / b


def _nonexcited_stats(
    bla: BestLinearApproximation, mask: np.ndarray, alpha: float
) -> dict[str, dict[str, Any]]:
    """The non-excited lines of ``mask`` by kind: levels, noise, test."""
    ne = bla.nonexcited
    m, p = bla.realisations, bla.periods
    out: dict[str, dict[str, Any]] = {}
    for kind in ("even", "odd", "non-excited"):
        sel = mask & (ne.kind == kind)
        n = int(sel.sum())
        if not n:
            continue
        level, noise = _mean(ne.level, sel), _mean(ne.noise, sel)
        pv = _f_test(_ratio(level, noise), 2 * n * m, 2 * n * m * (p - 1))
        low = _f_test(_ratio(noise, level), 2 * n * m * (p - 1), 2 * n * m)
        out[kind] = {
            "lines": n,
            "level_db": db(level),
            "noise_db": None if noise is None else db(noise),
            "distortion_db": None if noise is None else db(level - noise),
            "p_value": pv,
            "detected": None if pv is None else pv < alpha,
            "overstated": None if low is None else low < alpha,
        }
    odd, even = out.get("odd"), out.get("even")
    if p == 1 and odd and even:  # one period: the odd lines against the even ones
        sel_o, sel_e = mask & (ne.kind == "odd"), mask & (ne.kind == "even")
        ratio = _ratio(_mean(ne.level, sel_o), _mean(ne.level, sel_e))
        pv = _f_test(ratio, 2 * odd["lines"] * m, 2 * even["lines"] * m)
        odd.update(p_value=pv, detected=None if pv is None else pv < alpha,
                   against="even", over_even_db=db(ratio))  # fmt: skip
    return out


def _band(bla: BestLinearApproximation, band: tuple[float, float], alpha: float) -> BandSummary:
    mask = _in(bla.frequencies, band)
    n = int(mask.sum())
    m, p = bla.realisations, bla.periods
    total, noise = _mean(bla.var_total, mask), _mean(bla.var_noise, mask)
    pv = low = None
    if bla.method == "robust" and total is not None and noise is not None:
        pv = _f_test(_ratio(total, noise), 2 * n * (m - 1), 2 * n * m * (p - 1))
        low = _f_test(_ratio(noise, total), 2 * n * m * (p - 1), 2 * n * (m - 1))
    distortion = None if total is None or noise is None else db(total - noise)
    nonexcited = {}
    if bla.nonexcited is not None:
        nonexcited = _nonexcited_stats(bla, _in(bla.nonexcited.frequencies, band), alpha)
    return BandSummary(
        low=band[0],
        high=band[1],
        lines=n,
        g_db=db(np.mean(np.abs(bla.g[mask]) ** 2)) if n else None,
        total_db=None if total is None else db(total),
        noise_db=None if noise is None else db(noise),
        distortion_db=distortion,
        p_value=pv,
        detected=None if pv is None else pv < alpha,
        overstated=None if low is None else low < alpha,
        nonexcited=nonexcited,
        coherence=_mean(bla.coherence, mask),
    )


def _where(b: BandSummary, unit: str = "Hz") -> str:
    return f"{b.low:.4g}-{b.high:.4g} {unit}"


#: What the verdict reads: each band with the words that name where it is.
Named = list[tuple[BandSummary, str]]


def _left_out(bla: BestLinearApproximation, edges: Sequence[tuple[float, float]]) -> list:
    """The stretches of neighbouring lines (measured or empty) that no band holds, as
    edges: what given bands leave out, which the verdict reads all the same."""
    ne = bla.nonexcited
    every = bla.frequencies if ne is None else np.concatenate([bla.frequencies, ne.frequencies])
    every = np.sort(every)
    held = np.zeros(every.shape, bool)
    for band in edges:
        held |= _in(every, band)
    out, start = [], None
    for i, inside in enumerate([*held, True]):
        if not inside and start is None:
            start = i
        elif inside and start is not None:
            out.append((float(every[start]), float(every[i - 1])))
            start = None
    return out


def _verdict(bla: BestLinearApproximation, named: Named, count: int, alpha: float) -> str:
    """One line: nonlinear distortion above the noise, and where; or why not known.
    ``named``: the ``count`` bands of the table, then what they left out."""
    level = f"{1 - alpha:.0%} test"
    bands = [b for b, _ in named[:count]]
    if bla.method == "welch":
        worst = min(bands, key=lambda b: b.coherence if b.coherence is not None else 1.0)
        share = 1.0 - (worst.coherence or 0.0)
        return (
            f"non-periodic data: noise and nonlinear distortion are not told apart; the "
            f"coherence is lowest in {_where(worst, bla.unit)} (mean {worst.coherence:.3f}: "
            f"{share:.0%} of the output power there is noise or distortion); measure with several "
            "periods and realisations of a multisine to separate them"
        )
    if bla.periods >= 2:
        return _verdict_with_noise(bla, named, count, alpha, level)
    # several realisations of one period: the even lines of an odd excitation hold the
    # noise (and any even distortion), on the axis of G's variance
    measured = [b for b in bands if b.total_db is not None]
    if not measured:
        return ("one period a realisation and no excited line in the bands: give bands "
                "that hold the excited lines")  # fmt: skip
    head = ("one period a realisation: noise and nonlinear distortion are not told apart by "
            "periods (that needs 2 or more); ")  # fmt: skip
    if not bla.odd_design or not any("even" in b.nonexcited for b, _ in named):
        worst = max(measured, key=lambda b: b.total_db - b.g_db)
        return (f"{head}the total variance of G is {worst.g_db - worst.total_db:.1f} dB below "
                f"|G|² at worst ({_where(worst, bla.unit)})")  # fmt: skip
    found = []  # (dB over the even lines, where)
    m = bla.realisations
    for b, where in named:
        even, odd = b.nonexcited.get("even"), b.nonexcited.get("odd")
        if even and b.total_db is not None:
            over = b.total_db - even["level_db"]
            pv = _f_test(10 ** (over / 10), 2 * b.lines * (m - 1), 2 * even["lines"] * m)
            if pv is not None and pv < alpha:
                found.append((over, f"the total variance of G lies {over:.1f} dB above them "
                                    f"in {where}"))  # fmt: skip
        if odd and odd.get("against") == "even" and odd["detected"]:
            found.append((odd["over_even_db"], f"the odd non-excited lines lie "
                          f"{odd['over_even_db']:.1f} dB above them in {where}"))  # fmt: skip
    if not found:
        return (f"{head}neither the total variance of G nor the odd non-excited lines lie above "
                f"the even lines (the noise and any even distortion; {level}): no sign of odd "
                "nonlinear distortion")  # fmt: skip
    _, where = max(found, key=lambda item: item[0])
    return (f"{head}against the even lines (the noise and any even distortion), {where}: odd "
            "nonlinear distortion, a nonlinear model is worth trying")  # fmt: skip


_KIND = {"even": "the even lines", "odd": "the odd non-excited lines",
         "non-excited": "the non-excited lines"}  # fmt: skip


def _verdict_with_noise(
    bla: BestLinearApproximation, named: Named, count: int, alpha: float, level: str
) -> str:
    """The verdict when the noise is measured (2 periods or more): the largest margin
    of distortion over noise found, at the excited lines (2 realisations or more) or at
    the lines the input left empty, in the bands or in what they left out."""
    found = []  # (margin dB, where)
    showing = 0  # bands of the table with distortion found
    for i, (b, where) in enumerate(named):
        before = len(found)
        if b.detected and b.margin_db is not None:  # detected at a distortion <= 0: noise
            found.append((b.margin_db, where))
        for kind, g in b.nonexcited.items():
            if g["detected"] and g["distortion_db"] is not None:
                margin = g["distortion_db"] - g["noise_db"]
                found.append((margin, f"{where}, at {_KIND[kind]}"))
        showing += i < count and len(found) > before
    head = ""
    if bla.realisations < 2:
        head = ("one realisation: the distortion at the excited lines needs 2 or more, the "
                "lines the input left empty were tested; ")  # fmt: skip
        if bla.nonexcited is None or not bla.nonexcited.lines.size:
            return head[:-2] + ", but the input leaves none: nothing tells distortion from noise"
    shown = []
    if bla.odd_design:
        for kind in ("even", "odd"):
            groups = [b.nonexcited[kind] for b, _ in named if kind in b.nonexcited]
            seen = [g["distortion_db"] - g["noise_db"] for g in groups
                    if g["detected"] and g["distortion_db"] is not None]  # fmt: skip
            shown.append(f"{kind} lines " + (f"up to {max(seen):+.1f} dB over the noise" if seen
                                             else "at the noise"))  # fmt: skip
    tested = f" ({'; '.join([level, ', '.join(shown)] if shown else [level])})"
    over = [where for b, where in named
            if b.overstated or any(g.get("overstated") for g in b.nonexcited.values())]  # fmt: skip
    if not found and over:
        return (
            f"{head}no nonlinear distortion above the noise{tested}; but the noise "
            "variance lies significantly above the total it is part of (of G, or of the "
            f"output at the empty lines) in {', '.join(over)}, where it is "
            "overstated (noise that passes through the plant's dynamics and does not repeat "
            "leaves transients in every period; longer periods make them smaller) and could "
            "hide distortion of its size"
        )
    if not found:
        return (f"{head}no nonlinear distortion above the noise in any band{tested}: "
                "a linear model suffices at this noise level")  # fmt: skip
    margin, where = max(found, key=lambda item: item[0])
    counted = [f"in {showing} of {count} bands"] if count > 1 and showing else []
    more = (
        f" ({'; '.join(counted + [', '.join(shown)] if shown else counted)})"
        if counted or shown
        else ""
    )
    if margin >= 0:
        return (f"{head}nonlinear distortion dominates the noise by {margin:.1f} dB in {where}"
                f"{more}: a nonlinear model is worth trying")  # fmt: skip
    return (f"{head}nonlinear distortion detected, but {-margin:.1f} dB below the noise at most "
            f"({where}){more}: a nonlinear model would gain little over a linear one at this "
            "noise level")  # fmt: skip


def summarised(
    bla: BestLinearApproximation, bands: int | Sequence[tuple[float, float]] = DEFAULT_BANDS
) -> BestLinearApproximation:
    """``bla`` with its band summaries and verdict (tests at ``bla.confidence``)."""
    alpha = 1.0 - bla.confidence
    empty = None if bla.nonexcited is None else bla.nonexcited.frequencies
    edges = band_edges(bla.frequencies, bands, empty)
    summaries = tuple(_band(bla, band, alpha) for band in edges)
    named = [(b, _where(b, bla.unit)) for b in summaries]
    for band in _left_out(bla, edges):  # the verdict reads every line
        named.append((_band(bla, band, alpha), f"{band[0]:.4g}-{band[1]:.4g} {bla.unit} "
                                               "(outside the bands given)"))  # fmt: skip
    verdict = _verdict(bla, named, len(summaries), alpha)
    return dataclasses.replace(bla, bands=summaries, verdict=verdict)
