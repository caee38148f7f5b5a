"""Every comparison in the blocks, pinned at its boundary.

Values are chosen to be exact in binary (halves, quarters, powers of two), so that the
expected outputs are exact and a ``<`` that became ``<=`` (or a branch that moved by one
rounding) shows up as a wrong number, not as a tolerance question.
"""

from __future__ import annotations

import numpy as np
import pytest

from blockid.blocks import Backlash, DeadZone, PiecewiseLinear, Saturation, TwoSegmentPolynomial


# ---------------------------------------------------------------------- B1 at u = 0
def test_two_segment_polynomial_at_exactly_zero_is_the_positive_segment():
    # f for u >= 0, g = f + p for u < 0 (B1, h(u) = 1 only for u < 0). A jump at 0
    # (f_0 != g_0) makes the side u = 0 belongs to visible.
    block = TwoSegmentPolynomial([0.5, 2.0, 0.25], [-1.5, -1.0, 0.75])  # g = [-1, 1, 1]
    u = np.array([-0.5, -(2.0**-30), -0.0, 0.0, 2.0**-30, 0.5])
    expected = [
        -1.0 + 1.0 * -0.5 + 1.0 * 0.25,  # g(-0.5) = -1.25
        -1.0 - 2.0**-30 + 2.0**-60,  # g just below 0
        0.5,  # f(-0.0): -0.0 is not < 0
        0.5,  # f(0) = f_0
        0.5 + 2.0 * 2.0**-30 + 0.25 * 2.0**-60,
        0.5 + 1.0 + 0.0625,  # f(0.5) = 1.5625
    ]
    assert block(u).tolist() == expected
    assert block(0.0) == 0.5


def test_two_segment_regressors_at_zero_have_no_negative_part():
    block = TwoSegmentPolynomial([0.5, 2.0, 0.25, -1.0], [-1.5, -1.0, 0.75, 0.5])
    phi = block.regressors(np.array([0.0, -0.0, -2.0, 2.0]))
    # [1, u, u^2, u^3, h, u h, u^2 h, u^3 h] with h(0) = 0 (B4)
    assert phi.tolist() == [
        [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [1.0, -0.0, 0.0, -0.0, 0.0, -0.0, 0.0, -0.0],
        [1.0, -2.0, 4.0, -8.0, 1.0, -2.0, 4.0, -8.0],
        [1.0, 2.0, 4.0, 8.0, 0.0, 0.0, 0.0, 0.0],
    ]
    # and they reproduce the block, including at 0
    u = np.array([-1.5, -0.0, 0.0, 1.5])
    assert np.array_equal(block.regressors(u) @ block.to_vector(), block(u))


# ---------------------------------------------------------------------- dead zone
def test_dead_zone_is_zero_on_both_edges_and_linear_beyond():
    dz = DeadZone(-0.5, 0.75, slope_left=2.0, slope_right=4.0)
    u = np.array([-1.5, -0.5 - 2.0**-20, -0.5, 0.0, 0.75, 0.75 + 2.0**-20, 1.75])
    expected = [-2.0, -(2.0**-19), 0.0, 0.0, 0.0, 2.0**-18, 4.0]
    assert dz(u).tolist() == expected


def test_dead_zone_with_an_empty_band_has_a_kink_at_the_point():
    dz = DeadZone(0.25, 0.25, slope_left=0.5, slope_right=2.0)
    assert dz(np.array([-0.75, 0.25, 1.25])).tolist() == [-0.5, 0.0, 2.0]


# ---------------------------------------------------------------------- saturation
def test_saturation_exactly_at_the_knees():
    sat = Saturation(-1.0, 2.0, slope=2.0)  # knees at u = -0.5 and u = 1
    u = np.array([-3.0, -0.5 - 2.0**-20, -0.5, -0.5 + 2.0**-20, 0.0, 1.0 - 2.0**-20, 1.0, 4.0])
    expected = [-1.0, -1.0, -1.0, -1.0 + 2.0**-19, 0.0, 2.0 - 2.0**-19, 2.0, 2.0]
    assert sat(u).tolist() == expected


# ---------------------------------------------------------------------- piecewise linear
PWL = PiecewiseLinear([-1.0, 0.0, 0.5, 2.0], [1.0, -0.5, 0.25, 3.25])


def test_piecewise_linear_at_every_breakpoint_gives_its_value():
    assert PWL(PWL.breakpoints).tolist() == [1.0, -0.5, 0.25, 3.25]
    # each breakpoint's regressor row is one-hot on that breakpoint
    assert PWL.regressors(PWL.breakpoints).tolist() == np.eye(4).tolist()


def test_piecewise_linear_between_and_beyond_the_ends():
    u = np.array([-3.0, -1.5, -0.5, 0.25, 1.25, 2.5, 4.0])
    expected = [
        1.0 + 1.5 * 2.0,  # first segment (slope -1.5) continued to the left: 4
        1.75,
        0.25,  # midway between 1 and -0.5
        -0.125,  # midway between -0.5 and 0.25
        1.75,  # midway between 0.25 and 3.25
        3.25 + 0.5 * 2.0,  # last segment (slope 2) continued: 4.25
        3.25 + 2.0 * 2.0,
    ]
    assert PWL(u).tolist() == expected
    # beyond the ends only the two end breakpoints carry weight (1 - t, t)
    phi = PWL.regressors(np.array([-3.0, 3.5]))
    assert phi.tolist() == [[3.0, -2.0, 0.0, 0.0], [0.0, 0.0, -1.0, 2.0]]


# ---------------------------------------------------------------------- backlash
def backlash_reference(u, m_left, c_left, m_right, c_right, x0):
    """(A3) and (A4) as SPEC writes them, one sample at a time."""
    x_prev, xs, f1s, f2s = x0, [], [], []
    for ut in u:
        z_left = x_prev / m_left - c_left
        z_right = x_prev / m_right + c_right
        if ut < z_left:
            x = m_left * (ut + c_left)
        elif ut > z_right:
            x = m_right * (ut - c_right)
        else:
            x = x_prev
        xs.append(x)
        f1s.append(1.0 if ut - z_left <= 0 else 0.0)  # h(s) = 1 for s <= 0
        f2s.append(1.0 if z_right - ut <= 0 else 0.0)
        x_prev = x
    return np.array(xs), np.array(f1s), np.array(f2s)


def test_backlash_reversing_exactly_at_the_dead_band_edge_holds_the_output():
    # Slopes 2 and 1/2, half-widths 1/4 and 3/4: every edge below is exact in binary.
    block = Backlash(m_left=2.0, c_left=0.25, m_right=0.5, c_right=0.75)
    # Up to 3 on the right branch: x = 0.5 (3 - 0.75) = 1.125. The dead band is then
    # [zL, zR] = [1.125/2 - 0.25, 1.125/0.5 + 0.75] = [0.3125, 3.0].
    u = np.array(
        [0.0, 1.5, 3.0]  # driving right
        + [0.3125] * 4  # reverse and stop exactly on the left edge
        + [3.0] * 3  # back exactly onto the right edge
        + [0.3125 - 2.0**-10]  # one step past the left edge
        + [0.3125 - 2.0**-10] * 2
    )
    x, (f1, f2) = block.simulate(u, x0=0.0), block.switching(u, x0=0.0)
    x_ref, f1_ref, f2_ref = backlash_reference(u, 2.0, 0.25, 0.5, 0.75, 0.0)
    assert x.tolist() == x_ref.tolist()
    assert f1.tolist() == f1_ref.tolist() and f2.tolist() == f2_ref.tolist()
    # pinned by hand: the output holds at both edges, moves only past one
    assert x.tolist() == [0.0, 0.375, 1.125] + [1.125] * 7 + [2.0 * (0.5625 - 2.0**-10)] * 3
    # at an edge the switching function counts as driving (h(0) = 1) ...
    assert f1[3:7].tolist() == [1.0] * 4 and f2[3:7].tolist() == [0.0] * 4
    assert f2[7:10].tolist() == [1.0] * 3 and f1[7:10].tolist() == [0.0] * 3
    # ... and (A4) then gives the held value, so the two forms agree at the edge
    a4 = (
        2.0 * u * f1
        + 2.0 * 0.25 * f1
        + 0.5 * u * f2
        - 0.5 * 0.75 * f2
        + np.concatenate(([0.0], x[:-1])) * (1 - f1) * (1 - f2)
    )
    assert a4.tolist() == x.tolist()


def test_backlash_without_dead_band_follows_its_branches_exactly():
    # c = 0 and equal slopes: x = m u whichever way the input moves, even at a reversal.
    block = Backlash(0.5, 0.0, 0.5, 0.0)
    u = np.array([0.0, 1.0, 1.0, 0.5, 0.5, -2.0, 1.0])
    assert block.simulate(u, x0=0.0).tolist() == (0.5 * u).tolist()


@pytest.mark.parametrize("x0", [0.0, 1.125, -0.5])
def test_backlash_started_inside_its_band_holds_its_initial_output(x0):
    block = Backlash(2.0, 0.25, 0.5, 0.75)
    # on and inside [zL, zR] of x0 the output never moves (the band is not empty for
    # x0 > -2/3, where the unequal branches cross)
    z_left, z_right = x0 / 2.0 - 0.25, x0 / 0.5 + 0.75
    u = np.linspace(z_left, z_right, 9)
    assert block.simulate(u, x0=x0).tolist() == [x0] * 9


def test_backlash_holds_bit_exactly_on_either_edge_with_paper_a_values(rng):
    # Paper A's S2 values are not exact in binary: m (x/m - c + c) is often one unit in
    # the last place away from x, so recomputing the branch at an edge (instead of
    # holding x(t-1), as (A3) says for zL <= u <= zR) would drift.
    m_left, c_left, m_right, c_right = 0.9, 0.8, 0.95, 0.85
    block = Backlash(m_left, c_left, m_right, c_right)
    x_prev = 0.0
    for level in rng.uniform(-6.0, 6.0, 60):
        x_moved = block.simulate(np.array([level]), x0=x_prev)[0]  # onto a branch
        z_left = x_moved / m_left - c_left
        z_right = x_moved / m_right + c_right
        u = np.array([z_left, z_left, z_right, z_right, z_left])
        held = block.simulate(u, x0=x_moved)
        assert held.tolist() == [x_moved] * 5, (level, x_moved)
        x_prev = x_moved
