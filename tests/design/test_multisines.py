"""Random-phase and odd random-phase multisines: the DFT of a period holds the designed
lines and nothing else, periods repeat exactly, the RMS value is the one asked for, the
crest-factor optimisation lowers the crest factor and keeps the amplitude spectrum, and
the seed decides every bit."""

import numpy as np
import pytest

from blockid.design import multisine, multisine_lines

FS = 1000.0
N = 1000  # lines 1 Hz apart


def _periods(x):
    """(realisations, periods, samples) view of the signals."""
    return x.signals.reshape(x.realisations, x.periods, x.samples)


def _line_magnitudes(x):
    return np.abs(np.fft.rfft(_periods(x)[:, 0, :], axis=1))


@pytest.mark.parametrize("iterations", [0, 30])
def test_a_period_holds_the_designed_lines_and_nothing_else(iterations):
    x = multisine(
        N, sampling_time=1 / FS, f_min=10, f_max=200, rms=0.3, realisations=2,
        crest_iterations=iterations, seed=4,
    )  # fmt: skip
    lines = np.arange(10, 201)  # 10..200 Hz on a 1 Hz grid, both edges on it
    assert np.array_equal(x.designed_lines, lines) and np.array_equal(x.lines, lines)
    magnitude = _line_magnitudes(x)
    designed = 0.3 * np.sqrt(2 / lines.size) * N / 2  # A N / 2, A = rms sqrt(2 / F)
    np.testing.assert_allclose(magnitude[:, lines], designed, rtol=1e-9)
    others = np.delete(magnitude, lines, axis=1)
    assert others.max() < 1e-9 * designed
    energy_off = (others**2).sum() / (magnitude**2).sum()
    assert energy_off < 1e-18


def test_the_odd_random_phase_multisine_excites_odd_lines_less_one_in_each_group():
    x = multisine(N, sampling_time=1 / FS, f_min=10, f_max=200, odd=True, group=3, seed=2)
    odd = np.arange(11, 200, 2)  # the odd lines of the band
    excited, left_out = x.designed_lines, x.left_out
    assert np.all(excited % 2 == 1) and np.array_equal(np.union1d(excited, left_out), odd)
    assert np.intersect1d(excited, left_out).size == 0
    groups = odd[: odd.size // 3 * 3].reshape(-1, 3)
    assert [np.isin(g, left_out).sum() for g in groups] == [1] * len(groups)
    assert np.isin(odd[odd.size // 3 * 3 :], excited).all()  # the incomplete last group
    magnitude = _line_magnitudes(x)[0]
    assert np.array_equal(x.lines, excited)
    empty = np.concatenate([left_out, np.arange(0, N // 2 + 1, 2)])  # left out and even
    assert magnitude[empty].max() < 1e-9 * magnitude[excited].min()


def test_the_left_out_lines_are_shared_by_the_realisations_and_the_phases_are_not():
    x = multisine(256, odd=True, realisations=3, periods=1, seed=9)
    alone = multisine_lines(256, odd=True, seed=9)
    assert np.array_equal(x.designed_lines, alone[0]) and np.array_equal(x.left_out, alone[1])
    spectra = np.fft.rfft(x.signals, axis=1)[:, x.designed_lines]
    phases = np.angle(spectra)
    assert not np.allclose(phases[0], phases[1]) and not np.allclose(phases[1], phases[2])
    magnitude = np.abs(spectra)
    assert np.allclose(magnitude, magnitude[0], rtol=1e-9, atol=0)


def test_periods_are_exact_repetitions():
    x = multisine(128, periods=4, realisations=2, crest_iterations=5, seed=1)
    p = _periods(x)
    assert x.signals.shape == (2, 4 * 128)
    assert all(np.array_equal(p[:, k], p[:, 0]) for k in range(4))


@pytest.mark.parametrize(("odd", "iterations"), [(False, 0), (True, 0), (False, 40), (True, 40)])
def test_the_rms_value_is_the_one_asked_for(odd, iterations):
    x = multisine(
        512, sampling_time=0.01, f_min=1, f_max=30, odd=odd, rms=2.5, periods=2,
        realisations=2, crest_iterations=iterations, seed=3,
    )  # fmt: skip
    np.testing.assert_allclose(x.rms, 2.5, rtol=1e-12)


def test_crest_factor_optimisation_lowers_the_crest_factor_and_keeps_the_spectrum():
    common = dict(sampling_time=1 / FS, f_min=1, f_max=200, rms=1.0, realisations=3, seed=5)
    start = multisine(N, **common)
    optimised = multisine(N, crest_iterations=100, **common)
    np.testing.assert_array_equal(optimised.crest_factor_start, start.crest_factor)
    assert np.all(start.crest_factor > 3.3)  # random phases: 3.34 to 3.74 here
    assert np.all(optimised.crest_factor <= 1.6)  # the figure docs/design.md states (1.53)
    np.testing.assert_allclose(
        _line_magnitudes(optimised), _line_magnitudes(start), rtol=1e-9, atol=1e-9
    )
    np.testing.assert_allclose(optimised.rms, 1.0, rtol=1e-12)


def test_the_same_seed_gives_the_same_signal_bit_for_bit():
    kwargs = dict(odd=True, f_min=0.01, f_max=0.3, realisations=2, crest_iterations=10)
    a, b = multisine(300, seed=11, **kwargs), multisine(300, seed=11, **kwargs)
    assert a.signals.tobytes() == b.signals.tobytes()
    assert not np.array_equal(a.signals, multisine(300, seed=12, **kwargs).signals)


def test_a_realisation_does_not_depend_on_how_many_were_asked_for():
    two = multisine(200, realisations=2, seed=7)
    five = multisine(200, realisations=5, seed=7)
    assert two.signals.tobytes() == five.signals[:2].tobytes()
