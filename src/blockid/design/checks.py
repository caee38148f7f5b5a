"""The ranges of the design parameters, declared once, and the checks that read them.

Plain Python, no NumPy: the command line runs these checks before it imports anything
numerical (a bad band is answered at once), and the design functions run the same ones.
Every error names the parameter at fault (``ParameterError.parameter``, which the command
line turns into its flag) and says what to change.
"""

from __future__ import annotations

import math
from typing import Any

from blockid.errors import ParameterError

__all__ = [
    "COUNTS",
    "DEFAULTS",
    "KINDS",
    "MAGNITUDE",
    "MAX_SAMPLES",
    "PARAMETERS",
    "band_lines",
    "check_design",
    "check_count",
    "check_levels",
    "check_magnitude",
    "check_positive",
    "check_seed",
    "check_size",
    "check_whole_bits",
    "odd_band_lines",
]

#: The kinds of excitation, with what each is called in a report.
KINDS = {
    "multisine": "random-phase multisine",
    "odd-multisine": "odd random-phase multisine",
    "prbs": "PRBS (maximum-length sequence)",
    "random-binary": "random binary signal",
}

#: The parameters of each kind (besides sampling_time and periods, which all take), the
#: required ones first: a parameter of another kind is refused, not ignored.
#: ``tests/design/test_checks.py`` holds them to the design functions' signatures.
PARAMETERS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "multisine": (("samples",), ("f_min", "f_max", "rms", "crest_iterations", "realisations",
                                 "seed")),
    "odd-multisine": (("samples",), ("f_min", "f_max", "group", "rms", "crest_iterations",
                                     "realisations", "seed")),
    "prbs": (("order",), ("clock", "levels")),
    "random-binary": (("samples",), ("clock", "levels", "realisations", "seed")),
}  # fmt: skip

#: The defaults of the optional parameters, written once: the design functions'
#: signatures and the command line's help read them (``tests/design/test_checks.py``).
#: No crest-factor iterations by default: random phases as drawn are the signal class
#: the best linear approximation's theory assumes (Gaussian-like amplitudes); groups of
#: 3 odd lines are the usual choice for odd random-phase multisines.
DEFAULTS: dict[str, Any] = {
    "sampling_time": 1.0,
    "f_min": None,
    "f_max": None,
    "group": 3,
    "rms": 1.0,
    "crest_iterations": 0,
    "clock": 1,
    "levels": (-1.0, 1.0),
    "periods": 1,
    "realisations": 1,
    "seed": 0,
}

#: Whole-number parameters: name -> (smallest, largest or None), and what they count.
COUNTS: dict[str, tuple[int, int | None, str]] = {
    "samples": (2, None, "samples in one period"),
    "periods": (1, None, "periods of each realisation"),
    "realisations": (1, None, "independent realisations"),
    "group": (2, None, "consecutive odd lines of which one is left out"),
    # the crest factor changes little after a few hundred (CLIP_QUANTILE's note in
    # blockid.design.multisines); the bound keeps the work finite
    "crest_iterations": (0, 10_000, "clipping iterations of the crest-factor optimisation"),
    "clock": (1, None, "samples each bit is held"),
    # 2^24 - 1 = 16.8 million samples a period is already longer than a CSV file holds
    # comfortably; the primitive polynomials of blockid.design.binary cover 2..24
    "order": (2, 24, "stages of the shift register, a period of 2^order - 1 bits"),
}

#: The most samples a design may hold, all periods of all realisations (800 MB as
#: float64, some 2 GB as CSV): more is refused before anything is allocated.
MAX_SAMPLES = 10**8

#: The magnitudes a signal's values (``rms``, ``levels``) may take: their squares, of
#: which the RMS value and the crest factor are made, stay normal float64 numbers.
MAGNITUDE = (1e-150, 1e150)


def check_design(kind: str, given: dict[str, Any]) -> None:
    """Refuse an unknown ``kind``, a missing required parameter, a parameter ``kind`` does
    not take, or a value out of range, before any signal is made.

    >>> check_design("prbs", {"order": 7, "clock": 2})
    >>> check_design("prbs", {"order": 7, "rms": 2.0})
    Traceback (most recent call last):
    ...
    blockid.errors.ParameterError: prbs takes no rms (a parameter of multisine, odd-multisine)
    """
    if kind not in PARAMETERS:
        raise ParameterError(
            f"unknown excitation {kind!r}; choose one of {', '.join(PARAMETERS)}",
            parameter="kind",
        )
    required, optional = PARAMETERS[kind]
    for name in given:
        if name not in (*required, *optional, "sampling_time", "periods"):
            takers = [k for k, (req, opt) in PARAMETERS.items() if name in (*req, *opt)]
            raise ParameterError(
                f"{kind} takes no {name} (a parameter of {', '.join(takers)})", parameter=name
            )
    for name in required:
        if given.get(name) is None:
            what = COUNTS[name][2]
            raise ParameterError(f"{kind} needs {name} ({what})", parameter=name)
    for name, value in given.items():
        if name in COUNTS:
            check_count(name, value)
    if "seed" in given:
        check_seed(given["seed"])
    if "levels" in given:
        check_levels(given["levels"])
    if "rms" in given:
        check_magnitude("rms", check_positive("rms", given["rms"]))
    periods = given.get("periods", DEFAULTS["periods"])
    if kind == "prbs":
        check_size({"order": 2 ** given["order"] - 1, "clock": given.get("clock", 1),
                    "periods": periods})  # fmt: skip
    else:
        realisations = given.get("realisations", DEFAULTS["realisations"])
        check_size({"samples": given["samples"], "periods": periods,
                    "realisations": realisations})  # fmt: skip
    sampling_time = given.get("sampling_time", DEFAULTS["sampling_time"])
    check_positive("sampling_time", sampling_time, " s")
    band = (given.get("samples"), sampling_time, given.get("f_min"), given.get("f_max"))
    if kind == "multisine":
        band_lines(*band)
    if kind == "odd-multisine":
        odd_band_lines(*band)
    if kind == "random-binary":
        check_whole_bits(given["samples"], given.get("clock", DEFAULTS["clock"]))


def check_size(factors: dict[str, int]) -> None:
    """Refuse a design of more than :data:`MAX_SAMPLES` samples, the product of
    ``factors`` (parameter -> the samples it multiplies by), naming the largest.

    >>> check_size({"samples": 10**6, "periods": 1000, "realisations": 1})
    Traceback (most recent call last):
    ...
    blockid.errors.ParameterError: the design would hold 1e+09 samples (samples 1000000 x ...
    """
    total = math.prod(int(v) for v in factors.values())
    if total > MAX_SAMPLES:
        worst = max(factors, key=lambda name: factors[name])
        shown = " x ".join(f"{name} {value}" for name, value in factors.items())
        raise ParameterError(
            f"the design would hold {total:.3g} samples ({shown}), more than the "
            f"{MAX_SAMPLES:.0e} a design may hold (800 MB in memory); lower {worst}",
            parameter=worst,
        )


def check_magnitude(name: str, value: float) -> float:
    """``value`` (> 0) within :data:`MAGNITUDE`, or a ParameterError naming ``name``."""
    low, high = MAGNITUDE
    if not low <= value <= high:
        raise ParameterError(
            f"{name} = {value:g} lies outside {low:g}..{high:g}: the squares of the samples "
            "would overflow or vanish; rescale the signal",
            parameter=name,
        )
    return value


def check_whole_bits(samples: int, clock: int) -> None:
    """Refuse a period of ``samples`` samples that is not a whole number of bits of
    ``clock`` samples."""
    if samples % clock:
        raise ParameterError(
            f"samples ({samples}) must be a whole number of bits of clock = {clock} samples; "
            f"take a multiple of {clock} or another clock",
            parameter="samples",
        )


def check_count(name: str, value: Any) -> int:
    """``value`` as an int within :data:`COUNTS` ``[name]``, or a ParameterError naming
    ``name`` and its range."""
    low, high, what = COUNTS[name]
    span = f">= {low}" if high is None else f"{low}..{high}"
    if isinstance(value, bool) or not _integral(value):
        raise ParameterError(
            f"{name} must be a whole number {span} ({what}), got {value!r}", parameter=name
        )
    number = int(value)
    if number < low or (high is not None and number > high):
        raise ParameterError(f"{name} must be {span} ({what}), got {number}", parameter=name)
    return number


def _integral(value: Any) -> bool:
    """A whole number of another type (NumPy's integers)."""
    try:
        return int(value) == value
    except (TypeError, ValueError, OverflowError):
        return False


def check_seed(seed: Any) -> int:
    """``seed`` as an int >= 0 (the seed of a design's random streams)."""
    if isinstance(seed, bool) or not _integral(seed) or int(seed) < 0:
        raise ParameterError(f"seed must be a whole number >= 0, got {seed!r}", parameter="seed")
    return int(seed)


def check_positive(name: str, value: Any, unit: str = "") -> float:
    """``value`` as a finite float > 0, or a ParameterError naming ``name``."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if not (math.isfinite(number) and number > 0):
        raise ParameterError(
            f"{name} must be a finite number > 0{unit}, got {value!r}", parameter=name
        )
    return number


def check_levels(levels: Any) -> tuple[float, float]:
    """The (low, high) levels of a binary signal: two finite numbers, low < high (a pair
    or the text ``"LOW,HIGH"``)."""
    if isinstance(levels, str):
        levels = levels.split(",")
    try:
        low, high = (float(v) for v in levels)
    except (TypeError, ValueError):
        raise ParameterError(
            f"levels must be two numbers LOW,HIGH (e.g. -1,1), got {levels!r}",
            parameter="levels",
        ) from None
    if not (math.isfinite(low) and math.isfinite(high)) or low >= high:
        raise ParameterError(
            f"levels must be two finite numbers LOW,HIGH with LOW < HIGH, got {low:g},{high:g}",
            parameter="levels",
        )
    largest = max(abs(low), abs(high))
    if largest > MAGNITUDE[1] or largest < MAGNITUDE[0]:
        check_magnitude("levels", largest)
    return low, high


def band_lines(
    samples: int, sampling_time: float, f_min: float | None, f_max: float | None
) -> range:
    """The DFT lines ``k`` of a period of ``samples`` samples whose frequencies
    ``k / (samples * sampling_time)`` lie in the band ``[f_min, f_max]`` (Hz).

    Line 0 (the mean) and the Nyquist line ``samples / 2`` are never excited: a sine at
    the Nyquist frequency is sampled at the same phase every time, so its amplitude
    would depend on its phase. ``f_min`` defaults to the first line, ``f_max`` to the
    Nyquist frequency. A band edge within a millionth of a line of the grid counts as on
    it (``f_max = 200`` with lines 0.1 Hz apart includes line 2000).

    >>> band_lines(1000, 0.001, 10.0, 200.0)
    range(10, 201)
    >>> band_lines(8, 1.0, None, None)  # 0 and the Nyquist line 4 left out
    range(1, 4)
    """
    samples = check_count("samples", samples)
    sampling_time = check_positive("sampling_time", sampling_time, " s")
    fs = 1.0 / sampling_time
    nyquist = fs / 2
    resolution = fs / samples
    low = 0.0 if f_min is None else _frequency("f_min", f_min)
    high = nyquist if f_max is None else _frequency("f_max", f_max)
    if high > nyquist * (1 + 1e-12):
        raise ParameterError(
            f"f_max = {high:g} Hz is above the Nyquist frequency {nyquist:g} Hz (half the "
            f"sampling frequency {fs:g} Hz); lower f_max or sample faster",
            parameter="f_max",
        )
    if low > high:
        raise ParameterError(
            f"f_min = {low:g} Hz is above f_max = {high:g} Hz; give f_min <= f_max",
            parameter="f_min",
        )
    first = max(1, math.ceil(low / resolution - 1e-6))
    last = min(math.floor(high / resolution + 1e-6), math.ceil(samples / 2) - 1)
    if first > last:
        raise ParameterError(
            f"no line of the frequency grid lies in the band {low:g}..{high:g} Hz: the lines "
            f"are {resolution:g} Hz apart (sampling frequency {fs:g} Hz / {samples} samples), "
            "line 0 and the Nyquist line are never excited; widen the band (f_min, f_max) or "
            "take more samples a period (a finer grid)",
            parameter="f_max" if f_max is not None else "f_min",
        )
    return range(first, last + 1)


def odd_band_lines(
    samples: int, sampling_time: float, f_min: float | None, f_max: float | None
) -> range:
    """The odd lines of :func:`band_lines`.

    >>> odd_band_lines(1000, 0.001, 10.0, 200.0)
    range(11, 201, 2)
    """
    lines = band_lines(samples, sampling_time, f_min, f_max)
    odd = lines[lines[0] % 2 == 0 :: 2]
    if not odd:
        raise ParameterError(
            f"no odd line in the band: its only line, {lines[0]}, is even; widen the band "
            "(f_min, f_max) or take more samples a period",
            parameter="f_max" if f_max is not None else "f_min",
        )
    return odd


def _frequency(name: str, value: Any) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if not (math.isfinite(number) and number >= 0):
        raise ParameterError(
            f"{name} must be a frequency >= 0 in Hz, got {value!r}", parameter=name
        )
    return number
