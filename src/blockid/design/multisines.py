r"""Random-phase and odd random-phase multisines, with crest-factor optimisation.

A multisine of ``N`` samples a period excites chosen lines ``k`` of the DFT grid
(frequencies ``k fs / N``) with one amplitude each and random phases:

.. math::

    u(n) = \sum_{k \in K} A \cos(2 \pi k n / N + \varphi_k), \qquad
    A = u_\mathrm{rms} \sqrt{2 / |K|}, \quad \varphi_k \sim U[0, 2\pi),

so every period holds exactly the designed amplitude spectrum and nothing else (no
leakage: an integer number of cycles of every component fits a period), and its RMS
value is ``u_rms`` whatever the phases (Parseval). The odd random-phase multisine of
Schoukens and Pintelon excites odd lines only, and in each group of ``group``
consecutive odd lines leaves one out at random: at the even lines of the output a
measurement sees even nonlinear distortion, at the left-out odd lines odd distortion
(Pintelon & Schoukens, *System Identification: A Frequency Domain Approach*, 2nd ed.,
2012). The left-out lines are drawn once per design and shared by its realisations, so
that averages over realisations see the same grid; the phases differ per realisation.

The crest-factor optimisation is the clipping iteration of van der Ouderaa, Schoukens
and Renneboog (1988): clip the period at the level that the largest fifth of its
samples exceed, take the clipped signal's phases on the designed lines, give them back
the designed amplitudes and zero every other line, repeat. The period kept is the one
of lowest crest factor met (the first is the random-phase start); every candidate is a
restored spectrum, so the amplitude spectrum stays exactly the designed one.
"""

from __future__ import annotations

import numpy as np

from blockid.design.checks import (
    DEFAULTS,
    band_lines,
    check_count,
    check_magnitude,
    check_positive,
    check_seed,
    check_size,
    odd_band_lines,
)
from blockid.design.excitation import Excitation, crest_factor, design_rng

__all__ = ["CLIP_QUANTILE", "multisine", "multisine_lines"]

#: The clipping level of each iteration: this quantile of |u| (the largest fifth of the
#: samples is clipped). 0.7 to 0.8 gave the lowest crest factors after 100 iterations on
#: flat multisines of 4 to 500 lines (1.2 to 1.7, from 2.1 to 4.1 with random phases).
CLIP_QUANTILE = 0.8


def multisine_lines(
    samples: int,
    sampling_time: float = DEFAULTS["sampling_time"],
    f_min: float | None = DEFAULTS["f_min"],
    f_max: float | None = DEFAULTS["f_max"],
    odd: bool = False,
    group: int = DEFAULTS["group"],
    seed: int = DEFAULTS["seed"],
) -> tuple[np.ndarray, np.ndarray | None]:
    """The excited lines of a multisine, and (``odd``) the odd lines left out.

    Every line of the band ``[f_min, f_max]`` (:func:`~blockid.design.checks.band_lines`),
    or with ``odd`` its odd lines less one drawn at random in each complete group of
    ``group`` consecutive ones (a last, incomplete group is kept whole).

    >>> lines, left_out = multisine_lines(64, odd=True, group=3, seed=1)
    >>> len(lines) + len(left_out), bool(np.all(lines % 2 == 1))
    (16, True)
    """
    if not odd:
        return np.asarray(band_lines(samples, sampling_time, f_min, f_max)), None
    group = check_count("group", group)
    candidates = np.asarray(odd_band_lines(samples, sampling_time, f_min, f_max))
    groups = candidates.size // group
    pick = design_rng(seed, 0).integers(0, group, size=groups)
    left_out = candidates[np.arange(groups) * group + pick]
    return np.setdiff1d(candidates, left_out), left_out


def multisine(
    samples: int,
    *,
    sampling_time: float = DEFAULTS["sampling_time"],
    f_min: float | None = DEFAULTS["f_min"],
    f_max: float | None = DEFAULTS["f_max"],
    odd: bool = False,
    group: int = DEFAULTS["group"],
    rms: float = DEFAULTS["rms"],
    periods: int = DEFAULTS["periods"],
    realisations: int = DEFAULTS["realisations"],
    crest_iterations: int = DEFAULTS["crest_iterations"],
    seed: int = DEFAULTS["seed"],
) -> Excitation:
    """Random-phase (``odd=False``) or odd random-phase (``odd=True``) multisine.

    Parameters
    ----------
    samples : int
        Samples in one period ``N``; the lines are ``fs / N`` apart.
    sampling_time : float
        Seconds between samples (``1 / fs``).
    f_min, f_max : float, optional
        Band to excite, Hz (default: from the first line up to the Nyquist frequency,
        which itself is never excited).
    odd : bool
        Odd lines only, one in each group of ``group`` consecutive odd lines left out.
    group : int
        Size of those groups (>= 2; 3 is usual).
    rms : float
        RMS value of every realisation.
    periods : int
        Exact repetitions of the period in each realisation.
    realisations : int
        Independent realisations (own phases, from ``seed``; see
        :func:`~blockid.design.excitation.design_rng`).
    crest_iterations : int
        Clipping iterations of the crest-factor optimisation (0: the random phases
        as drawn, the signal class the best linear approximation's theory assumes).
    seed : int
        Seed of the phases and of the left-out lines: the same seed gives the same
        signal bit for bit.

    Returns
    -------
    Excitation

    >>> x = multisine(256, sampling_time=1e-3, f_min=10, f_max=100, rms=0.5)
    >>> x.lines[[0, -1]].tolist(), round(float(x.rms[0]), 12)
    ([3, 25], 0.5)
    """
    samples = check_count("samples", samples)
    sampling_time = check_positive("sampling_time", sampling_time, " s")
    rms = check_magnitude("rms", check_positive("rms", rms))
    periods = check_count("periods", periods)
    realisations = check_count("realisations", realisations)
    check_size({"samples": samples, "periods": periods, "realisations": realisations})
    crest_iterations = check_count("crest_iterations", crest_iterations)
    seed = check_seed(seed)
    lines, left_out = multisine_lines(samples, sampling_time, f_min, f_max, odd, group, seed)
    # A = rms sqrt(2 / F); a line of amplitude A is A N / 2 in numpy's unscaled rfft
    amplitude = rms * np.sqrt(2.0 / lines.size) * samples / 2
    one_period = np.empty((realisations, samples))
    start = np.empty(realisations)
    for r in range(realisations):
        phases = design_rng(seed, r + 1).uniform(0.0, 2.0 * np.pi, size=lines.size)
        period = _period(samples, lines, amplitude, phases)
        start[r] = crest_factor(period)
        one_period[r] = _clip_and_restore(period, lines, amplitude, crest_iterations)
    settings = {
        "f_min": f_min,
        "f_max": f_max,
        "band_hz": [float(k / (samples * sampling_time)) for k in (lines[0], lines[-1])],
        "rms": rms,
        "crest_iterations": crest_iterations,
        "clip_quantile": CLIP_QUANTILE,
        "seed": seed,
    }
    if odd:
        settings["group"] = check_count("group", group)
    return Excitation(
        kind="odd-multisine" if odd else "multisine",
        signals=np.tile(one_period, (1, periods)),
        sampling_time=sampling_time,
        samples=samples,
        periods=periods,
        settings=settings,
        designed_lines=lines,
        left_out=left_out,
        crest_factor_start=start,
    )


def _clip_and_restore(
    period: np.ndarray, lines: np.ndarray, amplitude: float, iterations: int
) -> np.ndarray:
    """The lowest-crest-factor period met in ``iterations`` rounds of clipping and
    restoring the amplitude spectrum (``amplitude`` on ``lines``, zero elsewhere),
    starting from (and possibly being) ``period``."""
    best, best_crest = period, crest_factor(period)
    u = period
    for _ in range(iterations):
        level = np.quantile(np.abs(u), CLIP_QUANTILE)
        phases = np.angle(np.fft.rfft(np.clip(u, -level, level))[lines])
        u = _period(period.size, lines, amplitude, phases)
        crest = crest_factor(u)
        if crest < best_crest:
            best, best_crest = u, crest
    return best


def _period(samples: int, lines: np.ndarray, amplitude: float, phases: np.ndarray) -> np.ndarray:
    """The period of ``samples`` samples whose spectrum is ``amplitude`` (numpy's unscaled
    rfft) with ``phases`` on ``lines`` and zero elsewhere: the design's and every
    restoring round's."""
    spectrum = np.zeros(samples // 2 + 1, dtype=complex)
    spectrum[lines] = amplitude * np.exp(1j * phases)
    return np.fft.irfft(spectrum, n=samples)
