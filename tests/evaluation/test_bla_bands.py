"""The bands of a BLA summary: their edges, their tests, the verdict's cases."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from blockid.errors import ParameterError
from blockid.evaluation.bla_bands import band_edges, parse_bands, summarised
from blockid.evaluation.bla_result import BestLinearApproximation, NonExcitedLines


def test_bands_parse_from_a_count_or_edges():
    assert parse_bands(" 3 ") == 3
    assert parse_bands("0:1.5,1.5:4") == [(0.0, 1.5), (1.5, 4.0)]
    for text in ("a", "1:2:3", "1-2", ""):
        with pytest.raises(ParameterError, match="give a number of bands"):
            parse_bands(text)


def test_default_bands_hold_equal_numbers_of_lines_and_split_gaps_in_the_middle():
    f = np.array([1.0, 2.0, 3.0, 4.0, 10.0, 11.0, 12.0, 13.0])
    assert band_edges(f, 2) == [(1.0, 7.0), (7.0, 13.0)]
    assert band_edges(f, 1) == [(1.0, 13.0)]
    assert len(band_edges(f[:3], 10)) == 3  # no more bands than lines
    with pytest.raises(ParameterError, match="bands must be >= 1"):
        band_edges(f, 0)


def test_a_number_of_bands_adds_the_empty_lines_below_and_above_the_excited_ones():
    f = np.array([3.0, 4.0, 5.0, 6.0])
    assert band_edges(f, 2, empty=np.array([1.0, 2.0, 4.5, 7.0, 8.0])) == [
        (1.0, 2.0), (3.0, 4.5), (4.5, 6.0), (7.0, 8.0),
    ]  # fmt: skip
    assert band_edges(f, 1, empty=np.array([7.0])) == [(3.0, 6.0), (7.0, 7.0)]
    assert band_edges(f, 1, empty=np.array([])) == [(3.0, 6.0)]


def test_given_bands_must_hold_a_line():
    f = np.array([1.0, 2.0, 3.0])
    assert band_edges(f, [(0.0, 1.5), (1.5, 9.0)]) == [(0.0, 1.5), (1.5, 9.0)]
    with pytest.raises(ParameterError, match="band 4:5 Hz holds no line"):
        band_edges(f, [(4.0, 5.0)])
    assert band_edges(f, [(4.0, 5.0)], empty=np.array([4.5])) == [(4.0, 5.0)]
    with pytest.raises(ParameterError, match="give 0 <= LOW < HIGH"):
        band_edges(f, [(2.0, 1.0)])


def _bla(total: float, noise: float, m: int = 5, p: int = 4, lines: int = 50, above=None):
    """A robust result whose every line has these variances (the bands' tests and the
    verdict read nothing else); ``above``: the (level, noise) of 50 empty lines above."""
    f = np.arange(1, lines + 1, dtype=float)
    empty = None
    if above is not None:
        k = np.arange(lines + 1, lines + 51)
        empty = NonExcitedLines(lines=k, frequencies=k.astype(float),
                                kind=np.full(50, "non-excited"), level=np.full(50, above[0]),
                                noise=np.full(50, above[1]))  # fmt: skip
    return BestLinearApproximation(
        method="robust", frequencies=f, g=np.ones(lines, complex),
        var_total=np.full(lines, total), var_noise=np.full(lines, noise), bound=None,
        confidence=0.99, sampling_time=1.0, realisations=m, periods=p, transient_periods=0,
        samples=2 * lines + 2, bands=(), verdict="", nonexcited=empty,
    )  # fmt: skip


def test_the_test_at_the_excited_lines_is_an_f_test():
    """With 50 lines, 5 realisations and 4 periods: F(400, 1500) under no distortion;
    a ratio of 1.25 (1 dB) is its 99.8th percentile."""
    from scipy import stats

    same = summarised(_bla(1.0, 1.0), bands=1).bands[0]
    assert same.p_value == pytest.approx(0.5, abs=0.02) and not same.detected
    assert same.distortion_db is None and same.margin_db is None
    above = summarised(_bla(1.25, 1.0), bands=1).bands[0]
    assert above.p_value == pytest.approx(stats.f.sf(1.25, 400, 1500))
    assert above.detected and above.margin_db == pytest.approx(10 * np.log10(0.25))
    assert not above.overstated
    below = summarised(_bla(0.75, 1.0), bands=1).bands[0]
    assert below.overstated and not below.detected


@pytest.mark.parametrize(
    ("total", "noise", "start"),
    [
        (101.0, 1.0, "nonlinear distortion dominates the noise by 20.0 dB in 1-25.5 Hz (in 2 of"),
        (
            1.3,
            1.0,
            "nonlinear distortion detected, but 5.2 dB below the noise at most (1-25.5 Hz) (in 2",
        ),
        (1.0, 1.0, "no nonlinear distortion above the noise in any band (99% test): a linear"),
        (0.5, 1.0, "no nonlinear distortion above the noise (99% test); but the noise variance"),
    ],
)
def test_the_verdict_says_what_the_bands_found(total, noise, start):
    bla = summarised(_bla(total, noise), bands=2)
    assert bla.verdict.startswith(start), bla.verdict
    assert ("worth trying" in bla.verdict) == (total > 2 * noise)


def test_the_verdict_of_one_period_cannot_tell_noise_from_distortion():
    bla = dataclasses.replace(_bla(0.01, 1.0, p=1), var_noise=None)
    bla = summarised(bla, bands=1)
    assert bla.bands[0].noise_db is None and bla.bands[0].p_value is None
    assert bla.verdict == (
        "one period a realisation: noise and nonlinear distortion are not told apart by periods "
        "(that needs 2 or more); the total variance of G is 20.0 dB below |G|² at worst "
        "(1-50 Hz)"
    )


def test_the_verdict_reads_the_empty_lines_the_bands_given_leave_out():
    """Distortion (20 dB over the noise) only above the excited lines: the default bands
    hold those lines; bands given that leave them out do not hide it, and say so."""
    bla = _bla(1.0, 1.0, above=(101.0, 1.0))
    default = summarised(bla, bands=2)
    assert [(b.low, b.high) for b in default.bands] == [(1, 25.5), (25.5, 50), (51, 100)]
    assert default.verdict.startswith("nonlinear distortion dominates the noise by 20.0 dB in "
                                      "51-100 Hz, at the non-excited lines (in 1 of 3 bands)")  # fmt: skip
    given = summarised(bla, bands=[(0.0, 50.0)])
    assert len(given.bands) == 1
    assert given.verdict.startswith("nonlinear distortion dominates the noise by 20.0 dB in "
                                    "51-100 Hz (outside the bands given), at the non-excited")  # fmt: skip
    quiet = summarised(_bla(1.0, 1.0, above=(1.0, 1.0)), bands=[(0.0, 50.0)])
    assert quiet.verdict.endswith("a linear model suffices at this noise level")


def test_empty_lines_below_their_noise_say_it_is_overstated():
    """The output at the empty lines 10 dB below its own noise: the noise is overstated
    (noise through the dynamics), as where the total lies below the noise."""
    bla = summarised(_bla(1.0, 1.0, above=(0.1, 1.0)), bands=2)
    assert bla.bands[-1].nonexcited["non-excited"]["overstated"]
    assert "lies significantly above the total it is part of (of G, or of the output at the " \
        "empty lines) in 51-100 Hz, where it is overstated" in bla.verdict  # fmt: skip
