r"""Binary excitations: PRBS (maximum-length sequences) and random binary signals.

A PRBS of order ``n`` is the output of an ``n``-stage linear-feedback shift register
whose feedback polynomial is primitive over GF(2): the register runs through all
``2^n - 1`` non-zero states before it repeats, so one period holds ``2^(n-1)`` ones and
``2^(n-1) - 1`` zeros. Mapped to the levels -1 and 1 its periodic autocorrelation takes
two values,

.. math::

    R(\tau) = \sum_{t=0}^{L-1} u(t)\, u(t + \tau \bmod L) =
    \begin{cases} L & \tau = 0 \bmod L \\ -1 & \text{otherwise} \end{cases},
    \qquad L = 2^n - 1,

so every line of its DFT but line 0 carries the same power ``L + 1``: a flat spectrum
from ``fs / L`` to the Nyquist frequency in two levels (crest factor 1 for symmetric
levels). Holding each bit ``clock`` samples (as MATLAB's ``idinput`` does for the band
``[0 1/clock]``) shapes the power like ``sinc^2(f clock / fs)``: 3 dB down at about
``0.44 fs / clock``, zero at every multiple of ``fs / clock``; the period becomes
``clock (2^n - 1)`` samples.

A random binary signal draws each bit independently, with equal odds, from the seed;
its spectrum is flat on average only. One period of ``samples`` samples (a whole
number of bits of ``clock`` samples) is repeated ``periods`` times, so that it is
periodic as the PRBS is, and each realisation has its own bits.
"""

from __future__ import annotations

import math

import numpy as np

from blockid.design.checks import (
    DEFAULTS,
    check_count,
    check_levels,
    check_positive,
    check_seed,
    check_size,
    check_whole_bits,
)
from blockid.design.excitation import Excitation, design_rng

__all__ = ["half_power", "msequence", "polynomial", "prbs", "random_binary"]

#: Order n -> the middle terms i of a primitive feedback polynomial
#: ``x^n + sum_i x^i + 1`` over GF(2): trinomials where one exists, else pentanomials,
#: with low middle terms (the usual tables'; tests/design/test_binary.py proves each
#: one primitive). Low terms make :func:`msequence` fill the period in long blocks.
_MIDDLE_TERMS: dict[int, tuple[int, ...]] = {
    2: (1,), 3: (1,), 4: (1,), 5: (2,), 6: (1,), 7: (1,), 8: (4, 3, 2), 9: (4,),
    10: (3,), 11: (2,), 12: (6, 4, 1), 13: (4, 3, 1), 14: (5, 3, 1), 15: (1,),
    16: (5, 3, 2), 17: (3,), 18: (7,), 19: (5, 2, 1), 20: (3,), 21: (2,), 22: (1,),
    23: (5,), 24: (4, 3, 1),
}  # fmt: skip


def half_power(clock: int) -> float | None:
    """The frequency, as a fraction of the sampling frequency, where holding each bit
    ``clock`` samples halves the power of a binary signal:
    ``|sin(pi x clock) / (clock sin(pi x))|^2 = 1/2``; None for ``clock = 1`` (a flat
    spectrum up to the Nyquist frequency). It tends to 0.443 / clock.

    >>> half_power(2), round(half_power(50) * 50, 3)
    (0.25, 0.443)
    """
    clock = check_count("clock", clock)
    if clock == 1:
        return None
    low, high = 0.0, 0.5 / clock  # the gain falls from 1 to at most 1/sqrt(2) on this span
    for _ in range(60):
        mid = (low + high) / 2
        gain = math.sin(math.pi * mid * clock) / (clock * math.sin(math.pi * mid))
        low, high = (mid, high) if gain * gain > 0.5 else (low, mid)
    return round(high, 15)


def polynomial(order: int) -> str:
    """The feedback polynomial of the PRBS of ``order``, as text.

    >>> polynomial(10)
    'x^10 + x^3 + 1'
    """
    order = check_count("order", order)
    terms = [f"x^{i}" if i > 1 else "x" for i in (order, *_MIDDLE_TERMS[order])]
    return " + ".join([*terms, "1"])


def msequence(order: int) -> np.ndarray:
    """One period of the maximum-length sequence of ``order``: ``2^order - 1`` bits (0 or
    1), from the all-ones state.

    With the feedback polynomial ``p(x) = x^n + sum_{i in I} x^i + 1`` the bits obey

    .. math:: s(t) = s(t - n) \\oplus \\bigoplus_{i \\in I} s(t - n + i).

    Over GF(2), ``p(x)^2 = p(x^2)`` (the cross terms cancel in pairs), so the bits obey
    the same recurrence with every lag multiplied by ``2^j`` once ``t >= n 2^j``; its
    shortest lag ``(n - max I) 2^j`` is a block of bits that follows at once from those
    already known. Blocks grow with the sequence, so a period of 2^24 - 1 bits takes a
    few hundred NumPy steps instead of 16 million Python ones.

    >>> msequence(3).tolist()
    [1, 1, 1, 0, 0, 1, 0]
    """
    n = check_count("order", order)
    lower = (0, *_MIDDLE_TERMS[n])  # the terms x^i, i < n, of p (x^0 = 1 included)
    length = 2**n - 1
    bits = np.empty(length, dtype=np.uint8)
    bits[:n] = 1
    filled = n
    while filled < length:
        scale = 1 << ((filled // n).bit_length() - 1)  # the largest 2^j with n 2^j <= filled
        stop = min(length, filled + (n - max(lower)) * scale)
        block = np.zeros(stop - filled, dtype=np.uint8)
        for i in lower:
            lag = (n - i) * scale
            block ^= bits[filled - lag : stop - lag]
        bits[filled:stop] = block
        filled = stop
    return bits


def prbs(
    order: int,
    *,
    clock: int = DEFAULTS["clock"],
    levels: tuple[float, float] = DEFAULTS["levels"],
    periods: int = DEFAULTS["periods"],
    sampling_time: float = DEFAULTS["sampling_time"],
) -> Excitation:
    """Pseudo-random binary sequence: the maximum-length sequence of ``order``, each bit
    held ``clock`` samples, ones at ``levels[1]`` and zeros at ``levels[0]``.

    One period is ``clock * (2^order - 1)`` samples; ``periods`` of them follow each other.
    A PRBS is one sequence, so there is one realisation (another start state would only
    shift it in time).

    >>> x = prbs(5, periods=2)
    >>> x.samples, x.signals.shape, float(x.signals[0, :31].sum())
    (31, (1, 62), 1.0)
    """
    order = check_count("order", order)
    clock = check_count("clock", clock)
    low, high = check_levels(levels)
    periods = check_count("periods", periods)
    sampling_time = check_positive("sampling_time", sampling_time, " s")
    check_size({"order": 2**order - 1, "clock": clock, "periods": periods})
    bits = np.repeat(msequence(order), clock)
    period = np.where(bits == 1, high, low)
    settings = {
        "order": order,
        "polynomial": polynomial(order),
        "clock": clock,
        "levels": [low, high],
        "half_power_hz": _hz(half_power(clock), sampling_time),
    }
    return Excitation(
        kind="prbs",
        signals=np.tile(period, periods)[None, :],
        sampling_time=sampling_time,
        samples=period.size,
        periods=periods,
        settings=settings,
    )


def random_binary(
    samples: int,
    *,
    clock: int = DEFAULTS["clock"],
    levels: tuple[float, float] = DEFAULTS["levels"],
    periods: int = DEFAULTS["periods"],
    realisations: int = DEFAULTS["realisations"],
    seed: int = DEFAULTS["seed"],
    sampling_time: float = DEFAULTS["sampling_time"],
) -> Excitation:
    """Random binary signal: ``samples // clock`` independent bits a period, each held
    ``clock`` samples, drawn per realisation from ``seed`` (realisation r from stream r of
    :func:`~blockid.design.excitation.design_rng`); the period repeated ``periods`` times.

    >>> x = random_binary(12, clock=3, levels=(0, 5), realisations=2, seed=7)
    >>> x.signals.shape, sorted(set(x.signals.ravel().tolist()))
    ((2, 12), [0.0, 5.0])
    """
    samples = check_count("samples", samples)
    clock = check_count("clock", clock)
    check_whole_bits(samples, clock)
    low, high = check_levels(levels)
    periods = check_count("periods", periods)
    realisations = check_count("realisations", realisations)
    check_size({"samples": samples, "periods": periods, "realisations": realisations})
    seed = check_seed(seed)
    sampling_time = check_positive("sampling_time", sampling_time, " s")
    bits = np.stack(
        [design_rng(seed, r + 1).integers(0, 2, size=samples // clock) for r in range(realisations)]
    )
    one_period = np.where(np.repeat(bits, clock, axis=1) == 1, high, low)
    settings = {
        "clock": clock,
        "levels": [low, high],
        "half_power_hz": _hz(half_power(clock), sampling_time),
        "seed": seed,
    }
    return Excitation(
        kind="random-binary",
        signals=np.tile(one_period, (1, periods)),
        sampling_time=sampling_time,
        samples=samples,
        periods=periods,
        settings=settings,
    )


def _hz(fraction: float | None, sampling_time: float) -> float | None:
    return None if fraction is None else fraction / sampling_time
