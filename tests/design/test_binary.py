"""PRBS and random binary signals: the maximum-length sequence against a plain shift
register, every feedback polynomial primitive, the period 2^n - 1 and the two-valued
autocorrelation, bits held by the clock, and the seed deciding every bit."""

import numpy as np
import pytest

from blockid.design import msequence, prbs, random_binary
from blockid.design.binary import _MIDDLE_TERMS, half_power
from blockid.design.checks import COUNTS

ORDERS = range(COUNTS["order"][0], COUNTS["order"][1] + 1)


def _shift_register(order):
    """The slow twin: the bits of a Fibonacci shift register with the feedback polynomial
    x^n + sum x^i + 1, one bit at a time, from the all-ones state."""
    taps = (0, *_MIDDLE_TERMS[order])
    bits = [1] * order
    while len(bits) < 2**order - 1:
        t = len(bits)
        bit = 0
        for i in taps:
            bit ^= bits[t - order + i]
        bits.append(bit)
    return np.array(bits, dtype=np.uint8)


def _primitive(order, terms):
    """Whether x^n + sum x^terms + 1 is primitive over GF(2): x has order 2^n - 1 modulo
    it (x^(2^n - 1) = 1, and x^((2^n - 1) / q) != 1 for every prime q dividing 2^n - 1)."""
    modulus = (1 << order) | 1
    for i in terms:
        modulus |= 1 << i

    def times(a, b):
        product = 0
        while b:
            if b & 1:
                product ^= a
            b >>= 1
            a <<= 1
            if a >> order & 1:
                a ^= modulus
        return product

    def power(e):
        result, base = 1, 2
        while e:
            if e & 1:
                result = times(result, base)
            base = times(base, base)
            e >>= 1
        return result

    m = 2**order - 1
    primes, rest, d = set(), m, 2
    while d * d <= rest:
        while rest % d == 0:
            primes.add(d)
            rest //= d
        d += 1
    if rest > 1:
        primes.add(rest)
    return power(m) == 1 and all(power(m // q) != 1 for q in primes)


def test_every_order_has_a_primitive_feedback_polynomial():
    assert set(_MIDDLE_TERMS) == set(ORDERS)
    assert all(_primitive(n, _MIDDLE_TERMS[n]) for n in ORDERS)


@pytest.mark.parametrize("order", range(2, 13))
def test_the_sequence_is_the_shift_register_s(order):
    assert np.array_equal(msequence(order), _shift_register(order))


@pytest.mark.parametrize("order", [2, 3, 5, 8, 11, 16, 18])
def test_the_sequence_has_period_2n_minus_1(order):
    bits = msequence(order)
    length = 2**order - 1
    assert bits.size == length and int(bits.sum()) == 2 ** (order - 1)
    # every non-zero n-bit state once: no shorter period is possible
    circular = np.concatenate([bits, bits[: order - 1]]).astype(np.int64)
    states = sum(circular[k : k + length] << k for k in range(order))
    assert np.unique(states).size == length and 0 not in states


@pytest.mark.parametrize("order", [4, 7, 10])
def test_the_prbs_autocorrelation_is_two_valued(order):
    x = prbs(order, periods=3)
    length = 2**order - 1
    period = x.signals[0, :length]
    assert x.samples == length and np.array_equal(x.signals[0], np.tile(period, 3))
    r = np.array([period @ np.roll(period, lag) for lag in range(length)])
    assert r[0] == length and np.all(r[1:] == -1)
    power = np.abs(np.fft.rfft(period)) ** 2
    np.testing.assert_allclose(power[1:], length + 1, rtol=1e-9)
    assert np.array_equal(x.lines, np.arange(1, length // 2 + 1))
    assert x.rms[0] == 1.0 and x.crest_factor[0] == 1.0


def test_the_clock_holds_each_bit_and_the_levels_are_kept():
    x = prbs(5, clock=3, levels=(0.5, 2.0), periods=2)
    assert x.samples == 93 and x.signals.shape == (1, 186)
    bits = x.signals[0, :93].reshape(31, 3)
    assert np.all(bits == bits[:, :1])
    assert np.array_equal(bits[:, 0], np.where(msequence(5) == 1, 2.0, 0.5))
    # no power at multiples of fs / clock (line 31 of the 93-sample period)
    assert 31 not in x.lines and 30 in x.lines and 32 in x.lines
    assert x.settings["half_power_hz"] == pytest.approx(half_power(3))


def test_half_power_against_the_hold_s_gain():
    for clock in (2, 3, 10):
        f = half_power(clock)
        gain = np.sin(np.pi * f * clock) / (clock * np.sin(np.pi * f))
        assert gain**2 == pytest.approx(0.5, abs=1e-12)
    assert half_power(1) is None


def test_the_random_binary_signal_is_periodic_held_and_seeded():
    x = random_binary(60, clock=4, levels=(-3, 1), periods=3, realisations=2, seed=8)
    periods = x.signals.reshape(2, 3, 60)
    assert np.array_equal(periods[:, 1], periods[:, 0]) and np.array_equal(
        periods[:, 2], periods[:, 0]
    )
    held = periods[:, 0].reshape(2, 15, 4)
    assert np.all(held == held[:, :, :1]) and set(np.unique(x.signals)) == {-3.0, 1.0}
    assert not np.array_equal(periods[0, 0], periods[1, 0])
    again = random_binary(60, clock=4, levels=(-3, 1), periods=3, realisations=2, seed=8)
    assert again.signals.tobytes() == x.signals.tobytes()
    one = random_binary(60, clock=4, levels=(-3, 1), periods=3, realisations=1, seed=8)
    assert one.signals.tobytes() == x.signals[:1].tobytes()
    other = random_binary(60, clock=4, levels=(-3, 1), seed=9)
    assert not np.array_equal(other.signals[0], periods[0, 0])
