"""The BLA measured by the robust method against plants whose truth is known.

Every plant is simulated here (:func:`scipy.signal.lfilter`) on multisines of
:func:`blockid.design.multisine`: a linear plant (the BLA is its frequency response, the
distortion is nil), Wiener plants with a static cubic (odd) or square (even)
nonlinearity, a backlash before a low-pass (hysteresis, whose distortion falls outside
the excited band), a slow plant whose transient fills the first period, and a
Wiener-Hammerstein plant whose true BLA and distortion level are computed from many
noiseless realisations.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import signal

from blockid.blocks.backlash import Backlash
from blockid.data import Dataset, Experiment
from blockid.design import multisine
from blockid.errors import DataError, ParameterError
from blockid.evaluation import best_linear_approximation, robust_bla

#: The linear dynamics of the plants: a Chebyshev low-pass with a 1 dB ripple.
B, A = signal.cheby1(2, 1.0, 0.2)
#: A second filter (the Wiener-Hammerstein plant's output dynamics).
B2, A2 = signal.butter(1, 0.35)


def _record(plant, *, samples=512, periods=3, realisations=6, odd=False, f_min=None,
            f_max=0.3, sigma=0.01, seed=0, rms=1.0) -> tuple[Dataset, object]:  # fmt: skip
    """``realisations`` experiments of ``periods`` periods (the first one the transient)
    of a multisine through ``plant``, white output noise of std ``sigma``."""
    x = multisine(samples, f_min=f_min, f_max=f_max, odd=odd, periods=periods,
                  realisations=realisations, rms=rms, seed=seed)  # fmt: skip
    rng = np.random.default_rng(seed + 100)
    exps = []
    for m, u in enumerate(x.signals):
        y = plant(u) + sigma * rng.standard_normal(u.size)
        exps.append(Experiment(f"r{m + 1}", u, y))
    return Dataset(("u",), ("y",), 1.0, exps, source="simulated"), x


def linear(u):
    return signal.lfilter(B, A, u)


def wiener_cubic(u):
    x = signal.lfilter(B, A, u)
    return x + 0.4 * x**3


def wiener_square(u):
    x = signal.lfilter(B, A, u)
    return x + 0.4 * x**2


def wiener_hammerstein(u):
    x = signal.lfilter(B, A, u)
    return signal.lfilter(B2, A2, np.tanh(1.5 * x))


def _excited(bla):
    """The bands that hold excited lines (by default a band of the empty lines above
    the excitation follows them)."""
    return [b for b in bla.bands if b.lines]


def _true_frf(frequencies, b=B, a=A):
    return signal.freqz(b, a, worN=2 * np.pi * np.asarray(frequencies))[1]


# ----------------------------------------------------------------------------- a linear plant
def test_the_bla_of_a_linear_plant_is_its_frequency_response_within_the_bounds():
    # few realisations: the bound's F(2, 2(M - 1)) is then far from its Gaussian limit
    data, _ = _record(linear, realisations=4, periods=5, sigma=0.05)
    bla = best_linear_approximation(data, transient_periods=1)
    assert (bla.method, bla.realisations, bla.periods, bla.samples) == ("robust", 4, 4, 512)
    error = np.abs(bla.g - _true_frf(bla.frequencies))
    # 99 % bounds hold the truth at (about) 99 % of the lines...
    assert np.mean(error <= bla.bound) >= 0.97
    # ...and are not wide for nothing: |e|² / σ² is exponential, P(|e| < σ/2) = 22 %
    assert np.mean(error <= 0.5 * bla.std) < 0.4
    assert np.mean(error <= 2.0 * bla.std) > 0.9


def test_the_noise_variance_is_that_of_the_noise_added():
    sigma, periods, realisations = 0.05, 6, 5
    data, x = _record(linear, realisations=realisations, periods=periods + 1, sigma=sigma)
    bla = best_linear_approximation(data, transient_periods=1)
    # white noise of variance σ² gives σ² on every line of a period's DFT (scaled 1/√N)
    assert bla.output_noise.mean() == pytest.approx(sigma**2, rel=0.05)
    # and the BLA's noise variance is σ² / (P M |U(k)|²)
    power = np.abs(np.fft.rfft(x.signals[0, :512]) / np.sqrt(512))[bla.lines] ** 2
    expected = sigma**2 / (periods * realisations * power)
    assert np.median(bla.var_noise / expected) == pytest.approx(1.0, rel=0.1)


def test_a_linear_plant_shows_no_distortion_total_is_noise():
    data, _ = _record(linear, realisations=8, periods=5, sigma=0.05)
    bla = best_linear_approximation(data, transient_periods=1)
    for band in _excited(bla):
        assert abs(band.total_db - band.noise_db) < 1.5, band
        assert not band.detected, band
    assert bla.verdict.startswith("no nonlinear distortion above the noise")
    # unbiased: over all lines the two variances agree (M = 3 would show (M-1)/M = -1.8 dB)
    few = best_linear_approximation(_record(linear, realisations=3, periods=7, sigma=0.05)[0],
                                    transient_periods=1)  # fmt: skip
    assert few.var_total.mean() / few.var_noise.mean() == pytest.approx(1.0, abs=0.15)
    # the lines above the band hold the noise only
    ne = bla.nonexcited
    assert 10 * np.log10(ne.level.mean() / ne.noise.mean()) == pytest.approx(0.0, abs=0.5)


def test_noise_on_the_measured_input_is_noise_not_distortion():
    """Errors in variables: the input is measured with noise too. Averaging over periods
    before dividing leaves G unbiased, and eq. (2) counts the input's noise."""
    data, _ = _record(linear, realisations=6, periods=5, sigma=0.005)
    rng = np.random.default_rng(5)
    noisy = [Experiment(e.name, e.u + 0.1 * rng.standard_normal(e.u.shape), e.y)
             for e in data.experiments]  # fmt: skip
    bla = best_linear_approximation(Dataset(("u",), ("y",), 1.0, noisy), transient_periods=1)
    assert bla.var_total.mean() / bla.var_noise.mean() == pytest.approx(1.0, abs=0.2)
    assert not any(b.detected for b in bla.bands)
    assert np.mean(np.abs(bla.g - _true_frf(bla.frequencies)) <= bla.bound) >= 0.97
    # noise of the generator, measured with the input and driving the plant: the noise of
    # U and Y is correlated (the covariance term of eq. (2)), G itself has none of it. A
    # memoryless plant: through dynamics, noise that does not repeat leaves transients in
    # every period, anti-correlated from one period to the next, and the variation
    # between periods overstates their share of the mean (docs/bla.md)
    driven = []
    for e in data.experiments:
        u = e.u[:, 0] + 0.1 * rng.standard_normal(e.n_samples)
        driven.append(Experiment(e.name, u, 0.5 * u + 0.005 * rng.standard_normal(u.size)))
    bla = best_linear_approximation(Dataset(("u",), ("y",), 1.0, driven), transient_periods=1)
    assert bla.var_total.mean() / bla.var_noise.mean() == pytest.approx(1.0, abs=0.2)


def test_noise_through_the_dynamics_is_overstated_and_said_so():
    """Generator noise driving a plant with memory: each period holds the transients of
    the noise that came before it, anti-correlated from one period to the next; the
    variation between periods overstates their share of the mean (here by 11.9 dB)."""
    data, _ = _record(linear, realisations=6, periods=5, sigma=0.0)
    rng = np.random.default_rng(5)
    driven = []
    for e in data.experiments:
        u = e.u[:, 0] + 0.1 * rng.standard_normal(e.n_samples)
        driven.append(Experiment(e.name, u, linear(u)))
    bla = best_linear_approximation(Dataset(("u",), ("y",), 1.0, driven), transient_periods=1)
    assert all(b.overstated and not b.detected for b in _excited(bla))
    assert "overstated (noise that passes through the plant's dynamics" in bla.verdict


# ----------------------------------------------------------------------------- nonlinear plants
def test_an_odd_nonlinearity_shows_at_the_odd_lines_left_empty_not_at_the_even_ones():
    data, x = _record(wiener_cubic, odd=True, realisations=6, periods=4, sigma=0.01)
    bla = best_linear_approximation(data, transient_periods=1)
    assert bla.odd_design and set(bla.lines) == set(x.lines)
    for band in _excited(bla):
        assert band.detected and band.margin_db > 20, band
        odd, even = band.nonexcited["odd"], band.nonexcited["even"]
        assert odd["detected"] and odd["distortion_db"] - odd["noise_db"] > 20, band
        assert not even["detected"] and abs(even["level_db"] - even["noise_db"]) < 2, band
        # referred to the input, the lines left empty read on the axis of G's variances:
        # the noise there is the noise of G, the odd distortion that at the excited lines
        assert even["noise_db"] == pytest.approx(band.noise_db, abs=1.0), band
        assert odd["level_db"] == pytest.approx(band.distortion_db, abs=3.0), band
    assert "dominates the noise by" in bla.verdict and "worth trying" in bla.verdict
    assert "even lines at the noise" in bla.verdict


def test_an_even_nonlinearity_shows_at_the_even_lines():
    data, _ = _record(wiener_square, odd=True, realisations=6, periods=4, sigma=0.01)
    bla = best_linear_approximation(data, transient_periods=1)
    evens = [b.nonexcited["even"] for b in _excited(bla)]
    odds = [b.nonexcited["odd"] for b in _excited(bla)]
    assert all(g["detected"] and g["distortion_db"] - g["noise_db"] > 20 for g in evens)
    assert not any(g["detected"] for g in odds)
    # an even nonlinearity puts nothing on the odd (excited) lines: G is the linear part's
    assert not any(b.detected for b in bla.bands)
    assert "at the even lines" in bla.verdict and "odd lines at the noise" in bla.verdict


def test_the_bla_of_a_wiener_hammerstein_plant_agrees_with_the_true_one():
    """The true BLA and distortion variance from 200 noiseless realisations; the
    measurement: 8 realisations of 2 periods (after the transient) with noise."""
    truth, _ = _record(wiener_hammerstein, realisations=200, periods=2, sigma=0.0, seed=7)
    data, x = _record(wiener_hammerstein, realisations=8, periods=3, sigma=0.02, seed=1)
    bla = best_linear_approximation(data, transient_periods=1)
    g_m = np.array([np.fft.rfft(e.y[512:, 0])[bla.lines] / np.fft.rfft(e.u[512:, 0])[bla.lines]
                    for e in truth.experiments])  # fmt: skip
    g_true = g_m.mean(axis=0)
    var_true = np.var(g_m, axis=0, ddof=1)  # one realisation's distortion
    error = np.abs(bla.g - g_true)
    assert np.mean(error <= bla.bound) >= 0.95
    assert np.mean(error <= 0.5 * bla.std) < 0.4
    for band in _excited(bla):
        mask = (bla.frequencies >= band.low) & (bla.frequencies <= band.high)
        true_db = 10 * np.log10(var_true[mask].mean() / bla.realisations)
        assert band.distortion_db == pytest.approx(true_db, abs=2.0), band
        assert band.detected


def test_one_realisation_tests_the_lines_left_empty():
    data, _ = _record(wiener_cubic, realisations=1, periods=5, f_max=0.2, sigma=0.01)
    bla = best_linear_approximation(data, transient_periods=1, bands=[(0.0, 0.5)])
    assert bla.var_total is None and bla.var_noise is not None
    assert bla.bands[0].nonexcited["non-excited"]["detected"]
    assert bla.verdict.startswith("one realisation") and "worth trying" in bla.verdict
    lin, _ = _record(linear, realisations=1, periods=5, f_max=0.2, sigma=0.01)
    quiet = best_linear_approximation(lin, transient_periods=1, bands=[(0.0, 0.5)])
    assert "no nonlinear distortion above the noise" in quiet.verdict


def test_one_period_compares_g_and_the_odd_lines_with_the_even_ones():
    """With one period a realisation (after the transient) the even lines of an odd
    multisine stand for the noise: G's total variance and the odd lines left out are
    held against them."""
    data, _ = _record(wiener_cubic, odd=True, realisations=6, periods=2, sigma=0.01)
    bla = best_linear_approximation(data, transient_periods=1)
    assert bla.var_noise is None and bla.var_total is not None and bla.periods == 1
    assert bla.verdict.startswith("one period a realisation")
    assert "dB above them in" in bla.verdict and "worth trying" in bla.verdict
    for band in _excited(bla):
        assert band.total_db - band.nonexcited["even"]["level_db"] > 20, band
        assert band.nonexcited["odd"]["detected"] and band.nonexcited["odd"]["over_even_db"] > 20
    lin, _ = _record(linear, odd=True, realisations=6, periods=2, sigma=0.01)
    quiet = best_linear_approximation(lin, transient_periods=1)
    assert "no sign of odd nonlinear distortion" in quiet.verdict


def test_a_stray_even_line_of_an_odd_excitation_is_a_disturbance():
    """A mains harmonic in the measured input of an odd multisine: an even line with
    input power. It is left out of G and of the even lines, with a note."""
    data, x = _record(wiener_cubic, odd=True, realisations=4, periods=3, sigma=0.01)
    hum = 0.2 * np.cos(2 * np.pi * 40 * np.arange(1536) / 512)  # line 40 of a period
    exps = [Experiment(e.name, e.u[:, 0] + hum, e.y[:, 0] + hum) for e in data.experiments]
    bla = best_linear_approximation(Dataset(("u",), ("y",), 1.0, exps), transient_periods=1)
    assert bla.lines.tolist() == x.lines.tolist() and 40 not in bla.nonexcited.lines
    assert (
        "1 even line(s) with input power left out" in bla.notes[0] and "40 (0.07812" in bla.notes[0]
    )


# ----------------------------------------------------------------------------- out of band
def backlash_low_pass(u):
    """Backlash (play of 0.1 either way), then the low-pass: hysteresis, whose products
    fall below the excited band as well as above it."""
    return linear(Backlash(1.0, 0.1, 1.0, 0.1).simulate(u))


def _band_limited(plant, seed=3):
    """One realisation of 4 periods of a random-phase multisine over 0.05-0.2 cycles
    a sample: 51 empty lines below the band, 307 above it up to Nyquist."""
    return _record(plant, samples=1024, periods=4, realisations=1, f_min=0.05, f_max=0.2,
                   sigma=0.01, seed=seed)  # fmt: skip


@pytest.mark.parametrize(("plant", "where"), [(backlash_low_pass, 0), (wiener_cubic, -1)])
def test_by_default_the_distortion_outside_the_excited_band_is_found(plant, where):
    """The default bands span every line from the first to Nyquist: a band below the
    excitation (backlash: 19 dB over the noise there) and one above it (the cubic's
    harmonics), besides the excited band split in four."""
    data, x = _band_limited(plant)
    bla = best_linear_approximation(data)
    assert "nonlinear distortion dominates the noise" in bla.verdict and "worth trying" in (
        bla.verdict
    )
    assert bla.lines[0] == x.lines[0] == 52 and bla.lines[-1] == x.lines[-1] == 204
    below, *excited, above = bla.bands
    assert [b.lines for b in (below, above)] == [0, 0] and len(excited) == 4
    assert (below.low, below.high) == (1 / 1024, 51 / 1024)
    assert (above.low, above.high) == (205 / 1024, 511 / 1024)
    found = bla.bands[where].nonexcited["non-excited"]
    assert found["detected"] and found["distortion_db"] - found["noise_db"] > 10
    assert any(f" in {b.low:.4g}-{b.high:.4g} Hz, at the non-excited lines" in bla.verdict
               for b in (below, above))  # fmt: skip


def test_by_default_a_linear_plant_with_the_same_design_shows_none():
    data, _ = _band_limited(linear)
    bla = best_linear_approximation(data)
    assert bla.verdict.endswith("no nonlinear distortion above the noise in any band (99% "
                                "test): a linear model suffices at this noise level")  # fmt: skip
    assert len(bla.bands) == 6 and not any(
        g["detected"] for b in bla.bands for g in b.nonexcited.values()
    )


def test_bands_given_that_leave_the_distortion_out_do_not_hide_it():
    data, _ = _band_limited(backlash_low_pass)
    bla = best_linear_approximation(data, bands=[(0.05, 0.2)])
    assert len(bla.bands) == 1 and not bla.bands[0].nonexcited
    assert "in 0.0009766-0.0498 Hz (outside the bands given), at the non-excited lines" in (
        bla.verdict
    )
    assert "worth trying" in bla.verdict


# ----------------------------------------------------------------------------- the transient
def slow(u):
    """A first-order low-pass of time constant 50 samples: its transient from rest lasts
    a good part of a 512-sample period."""
    return signal.lfilter([0.02], [1.0, -0.98], u)


def test_the_first_period_holding_the_transient_is_dropped_by_default():
    sigma = 0.02
    data, _ = _record(slow, realisations=2, periods=4, sigma=sigma, seed=1)
    bla = best_linear_approximation(data)
    assert (bla.periods, bla.transient_periods) == (3, 1)
    assert bla.notes[0].startswith("the output's first period differs from the mean of the "
                                   "others")  # fmt: skip
    assert bla.notes[0].endswith("it holds the plant's transient, dropped (0 transient periods "
                                 "keeps it)")  # fmt: skip
    assert bla.output_noise.mean() == pytest.approx(sigma**2, rel=0.1)
    # kept, the transient counts as noise: here 21 % too much of it
    kept = best_linear_approximation(data, transient_periods=0)
    assert (kept.periods, kept.transient_periods) == (4, 0) and "kept as asked" in kept.notes[0]
    assert kept.output_noise.mean() > 1.15 * sigma**2
    # a record in steady state from its first sample: nothing is dropped
    steady = Dataset(("u",), ("y",), 1.0, [Experiment(e.name, e.u[512:], e.y[512:])
                                           for e in data.experiments])  # fmt: skip
    assert best_linear_approximation(steady).periods == 3
    assert not any("first period" in note for note in best_linear_approximation(steady).notes)


# ----------------------------------------------------------------------------- the periods
def test_the_period_is_found_given_or_counted_alike():
    data, _ = _record(linear, realisations=3, periods=4)
    found = best_linear_approximation(data)
    given = robust_bla(data, period=512)
    counted = robust_bla(data, periods=4)
    assert found.samples == given.samples == counted.samples == 512
    np.testing.assert_allclose(found.g, counted.g)
    assert robust_bla(data, periods=4, transient_periods=1).periods == 3


def test_lines_given_are_used_and_checked():
    data, x = _record(linear, realisations=3, periods=3, f_max=0.2)
    bla = robust_bla(data, lines=x.lines[::2])
    assert bla.lines.tolist() == x.lines[::2].tolist()
    with pytest.raises(DataError, match="no power at 2 of the 3 lines"):
        robust_bla(data, lines=[x.lines[0], 200, 201])
    with pytest.raises(ParameterError, match="outside 1..255"):
        robust_bla(data, lines=[0, 3])


# ----------------------------------------------------------------------------- bad input
def _bad(data, error, match, **kwargs):
    with pytest.raises(error, match=match):
        best_linear_approximation(data, **kwargs)


def test_one_realisation_of_one_period_has_no_variance():
    data, _ = _record(linear, realisations=1, periods=2)
    _bad(data, DataError, "one realisation of one period .* gives no variance: measure 2 or "
         "more periods", transient_periods=1)  # fmt: skip


def test_a_record_not_a_whole_number_of_periods_is_refused():
    data, _ = _record(linear, realisations=2, periods=3)
    _bad(data, DataError, "1536 samples, not a whole number of periods of 500 .3 periods and "
         "36 samples more.", period=500)  # fmt: skip
    _bad(data, DataError, "not a whole number of 5 periods", periods=5)
    _bad(data, ParameterError, "period = 512 and periods = 2 make 1024", period=512, periods=2)
    _bad(data, ParameterError, "would drop every period", transient_periods=3)


def test_non_finite_samples_are_refused():
    data, _ = _record(linear, realisations=2, periods=3)
    y = data.experiments[1].y.copy()
    y[700] = np.nan
    exps = [data.experiments[0], Experiment("r2", data.experiments[1].u, y)]
    _bad(Dataset(("u",), ("y",), 1.0, exps), DataError, "'r2': the output is nan at sample 700")


def test_an_input_without_power_is_refused():
    exps = [Experiment(f"r{m}", np.ones(1024), np.zeros(1024)) for m in range(2)]
    _bad(Dataset(("u",), ("y",), 1.0, exps), DataError, "no power at any line", period=256)


def test_realisations_of_other_lengths_or_periods_are_refused():
    data, _ = _record(linear, realisations=2, periods=3)
    e = data.experiments
    short = [e[0], Experiment("r2", e[1].u[:1024], e[1].y[:1024])]
    _bad(Dataset(("u",), ("y",), 1.0, short), DataError, "different numbers of periods",
         period=512)  # fmt: skip
    noise = np.random.default_rng(0).standard_normal(1536)
    mixed = [e[0], Experiment("r2", noise, noise)]
    _bad(Dataset(("u",), ("y",), 1.0, mixed), DataError, "no period found in the input of "
         "experiment 'r2'", method="robust")  # fmt: skip


def test_options_that_do_not_go_together_are_refused():
    data, _ = _record(linear, realisations=2, periods=3)
    _bad(data, ParameterError, "method 'fast'", method="fast")
    _bad(data, ParameterError, "period and segment do not go together", period=512, segment=64)
    _bad(data, ParameterError, "transient_periods and segment", transient_periods=1,
         segment=64)  # fmt: skip
    _bad(data, ParameterError, "confidence must lie between 0 and 1", confidence=95)
    _bad(data, ParameterError, "band 0.6:0.7 Hz holds no line", bands=[(0.6, 0.7)])
    two = Dataset(("u", "v"), ("y",), 1.0,
                  [Experiment(e.name, np.hstack([e.u, e.u]), e.y) for e in data.experiments])  # fmt: skip
    _bad(two, ParameterError, "the data have 2 inputs .u, v.; name the input")
    assert best_linear_approximation(two, input="v").input_name == "v"


# ----------------------------------------------------------------------------- real data
DATA = Path(os.environ.get("BLOCKID_BENCHMARK_DATA",
                           Path(__file__).resolve().parents[2].parent / "shared" / "data"))  # fmt: skip


def _benchmark(folder: str, file: str) -> Path:
    path = DATA / folder / file
    if not path.exists():
        pytest.skip(f"{path} absent (the shared benchmark data, $BLOCKID_BENCHMARK_DATA)")
    return path


#: The last sample (exclusive) of each of the 10 odd multisine realisations of
#: SNLS80mV: each is ~410 samples of transient, then one period of 8192 samples, then
#: a gap of ~90 samples with no input (docs/bla.md).
SILVERBOX_ENDS = (49183, 57877, 66573, 75263, 83958, 92648, 101339, 110031, 118725, 127418)


def silverbox_realisations(path: Path) -> Dataset:
    """The 10 realisations of the Silverbox multisine, one period each (docs/bla.md)."""
    frame = pd.read_csv(path)
    u, y = frame["V1"].to_numpy(), frame["V2"].to_numpy()
    exps = [Experiment(f"realisation {m + 1}", u[end - 8202 : end - 10], y[end - 8202 : end - 10])
            for m, end in enumerate(SILVERBOX_ENDS)]  # fmt: skip
    return Dataset(("V1",), ("V2",), 1 / 610.35, exps, source="SNLS80mV.csv")


def test_silverbox_shows_odd_distortion_above_the_even_lines():
    data = silverbox_realisations(_benchmark("silverbox", "SNLS80mV.csv"))
    bands = [(0, 50), (50, 100), (100, 150), (150, 200), (200, 305)]
    bla = best_linear_approximation(data, periods=1, bands=bands)
    assert bla.odd_design and bla.lines.size == 1342 and bla.frequencies[-1] < 200
    assert "2014 (150.1 Hz)" in bla.notes[0]  # the mains' third harmonic on the input
    out = bla.bands[-1].nonexcited
    assert out["odd"]["detected"] and out["odd"]["over_even_db"] > 15
    assert "odd nonlinear distortion" in bla.verdict


def test_bouc_wen_shows_distortion_far_above_the_noise_at_the_empty_lines():
    path = _benchmark("bouc_wen", "bouc_wen_train_multisine_generated.csv")
    frame = pd.read_csv(path)
    data = Dataset.from_arrays(frame["u"], frame["y"], ["u"], ["y"], sampling_time=1 / 750)
    bla = best_linear_approximation(data, transient_periods=1, bands=[(0, 5), (5, 150)])
    assert (bla.realisations, bla.periods, bla.samples) == (1, 4, 8192)
    low = bla.bands[0].nonexcited["non-excited"]
    assert low["detected"] and low["distortion_db"] - low["noise_db"] > 30
    assert "worth trying" in bla.verdict


def test_bouc_wen_by_default_shows_the_distortion_below_the_band():
    """The command as a new user types it (no sampling time, no options): the bands
    below and above the excitation are there, the first period is dropped as the
    transient, and the hysteresis is found below the band."""
    frame = pd.read_csv(_benchmark("bouc_wen", "bouc_wen_train_multisine_generated.csv"))
    data = Dataset.from_arrays(frame["u"], frame["y"], ["u"], ["y"])
    bla = best_linear_approximation(data)
    assert (bla.periods, bla.transient_periods) == (4, 1)
    assert "it holds the plant's transient, dropped" in bla.notes[0]
    below = bla.bands[0]
    assert below.lines == 0 and below.high < bla.frequencies[0]
    low = below.nonexcited["non-excited"]
    assert low["detected"] and low["distortion_db"] - low["noise_db"] > 30
    assert bla.bands[-1].high == pytest.approx(4095 / 8192)
    assert (
        "nonlinear distortion dominates the noise by 40.3 dB in 0.0001221-0.00647 cycles/sample"
        in (bla.verdict)
    )
    assert "worth trying" in bla.verdict


def test_wiener_hammerstein_process_noise_buries_the_distortion():
    path = _benchmark("wiener_hammerstein_process_noise", "WH_EstimationExample.csv")
    frame = pd.read_csv(path, header=None, skiprows=1)
    exps = [Experiment(f"r{k + 1}", frame[10 + k].to_numpy(), frame[20 + k].to_numpy())
            for k in range(10)]  # fmt: skip
    bla = best_linear_approximation(Dataset(("u",), ("y",), 1 / 78125, exps))
    assert (bla.realisations, bla.periods, bla.samples) == (10, 2, 4096)
    assert not any(b.detected for b in bla.bands)
    assert abs(bla.bands[0].total_db - bla.bands[0].noise_db) < 1.0
