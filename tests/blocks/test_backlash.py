"""Backlash block (SPEC.md (A3), (A4)) against a plain-Python reference."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest

from blockid.blocks.backlash import Backlash
from blockid.blocks.base import block_from_dict
from blockid.errors import DataError, ParameterError
from blockid.plotting.backlash import triangular_sweep

matplotlib.use("Agg")

PARAMETER_SETS = [
    (0.9, 0.8, 0.9, 0.85),  # paper A, Table 1
    (1.0, 0.5, 1.0, 0.5),
    (1.3, 0.2, 0.7, 1.1),  # unequal slopes: lines cross at u = -(0.26 + 0.77)/0.6 = -1.72
    (2.0, 0.0, 2.0, 0.0),  # no play: a pure gain
]


def reference_backlash(u, m_left, c_left, m_right, c_right, x0):
    """(A3) written out sample by sample in plain Python."""
    x, x_prev = [], x0
    for u_t in u:
        z_left = x_prev / m_left - c_left
        z_right = x_prev / m_right + c_right
        if u_t < z_left:
            x_t = m_left * (u_t + c_left)
        elif u_t > z_right:
            x_t = m_right * (u_t - c_right)
        else:
            x_t = x_prev
        x.append(x_t)
        x_prev = x_t
    return np.array(x)


def reference_switching(u, x, m_left, c_left, m_right, c_right, x0):
    """f1 = h(u - zL), f2 = h(zR - u) of (A4), h(s) = 1 for s <= 0, on a given trajectory."""
    x_prev = np.concatenate([[x0], x[:-1]])
    z_left = x_prev / m_left - c_left
    z_right = x_prev / m_right + c_right
    return (u - z_left <= 0).astype(float), (z_right - u <= 0).astype(float)


def random_inputs(rng, n=600):
    """White noise, a random walk and a triangular sweep with dither: all three regimes."""
    white = rng.uniform(-1.5, 1.5, n)
    walk = np.cumsum(rng.normal(0.0, 0.3, n))
    tri = triangular_sweep(3.0, n_per_leg=n // 6)
    tri = tri + rng.normal(0.0, 0.05, tri.size)
    return [white, walk, tri]


@pytest.mark.parametrize("params", PARAMETER_SETS)
def test_kernel_matches_reference(params):
    rng = np.random.default_rng(1)
    block = Backlash(*params)
    for u in random_inputs(rng):
        x0 = float(rng.normal())
        expected = reference_backlash(u, *params, x0)
        np.testing.assert_array_equal(block.simulate(u, x0=x0), expected)
        f1, f2 = block.switching(u, x0=x0)
        ref_f1, ref_f2 = reference_switching(u, expected, *params, x0)
        np.testing.assert_array_equal(f1, ref_f1)
        np.testing.assert_array_equal(f2, ref_f2)


def test_triangular_sweep_traces_the_loop_exactly():
    # Paper's block, sweep 0 -> 5 -> -5 -> 5 in steps of 0.05: after the first reversal
    # x follows the right line on the way up, the left line on the way down.
    block = Backlash(0.9, 0.8, 0.9, 0.85)
    u = triangular_sweep(5.0, n_per_leg=100)
    x = block.simulate(u)
    np.testing.assert_array_equal(x, reference_backlash(u, 0.9, 0.8, 0.9, 0.85, 0.0))
    going_down = np.flatnonzero(np.diff(u, prepend=u[0]) < 0)
    on_left = going_down[u[going_down] < 5.0 - 1.65 - 1e-9]
    np.testing.assert_allclose(x[on_left], 0.9 * (u[on_left] + 0.8), rtol=0, atol=1e-12)
    going_up = np.flatnonzero(np.diff(u, prepend=u[0]) > 0)
    on_right = going_up[(u[going_up] > 0.85 + 1e-9) & (np.arange(u.size)[going_up] < 100)]
    np.testing.assert_allclose(x[on_right], 0.9 * (u[on_right] - 0.85), rtol=0, atol=1e-12)
    assert x.max() == pytest.approx(0.9 * (5.0 - 0.85))
    assert x.min() == pytest.approx(0.9 * (-5.0 + 0.8))


@pytest.mark.parametrize("params", PARAMETER_SETS)
def test_switching_form_a4_reproduces_a3(params):
    m_left, c_left, m_right, c_right = params
    rng = np.random.default_rng(2)
    block = Backlash(*params)
    for u in random_inputs(rng):
        if m_left != m_right:
            u = u - min(0.0, u.min() + 1.5)  # stay where the branches do not cross
        block.check_branches(u.min(), u.max())
        x = block.simulate(u, x0=0.3)
        f1, f2 = block.switching(u, x0=0.3)
        x_prev = np.concatenate([[0.3], x[:-1]])
        x_a4 = (
            m_left * u * f1
            + m_left * c_left * f1
            + m_right * u * f2
            - m_right * c_right * f2
            + x_prev * (1 - f1) * (1 - f2)
        )
        if c_left + c_right == 0.0:
            # No play: (A4) double-counts when u lands exactly on zL = zR (f1 = f2 = 1).
            both = (f1 == 1) & (f2 == 1)
            x_a4[both] = x[both]
        np.testing.assert_allclose(x_a4, x, rtol=0, atol=1e-12)
        # While driving left/right the output is on that branch; otherwise it holds.
        hold = (f1 == 0) & (f2 == 0)
        np.testing.assert_array_equal(x[hold], x_prev[hold])


def test_dead_band_width_equal_slopes():
    m, c_left, c_right = 0.9, 0.8, 0.85
    block = Backlash(m, c_left, m, c_right)
    peak = 10.0
    u_up = np.linspace(0.0, peak, 101)
    u_back = peak - np.arange(1, 401) * 0.01  # reverse in steps of 0.01
    u = np.concatenate([u_up, u_back])
    x = block.simulate(u)
    x_peak = m * (peak - c_right)
    assert x[100] == pytest.approx(x_peak)
    travelled = peak - u_back
    moved = x[101:] != x_peak
    first_move = int(np.argmax(moved))
    # Constant while the input travelled less than cL + cR = 1.65, moving right after.
    assert np.all(~moved[:first_move])
    assert travelled[first_move - 1] <= c_left + c_right + 1e-9
    assert travelled[first_move] > c_left + c_right - 1e-9
    assert travelled[first_move] == pytest.approx(1.66)
    np.testing.assert_allclose(x[101 + first_move :], m * (u_back[first_move:] + c_left))


def test_dead_band_unequal_slopes():
    # After driving right to u = 4 (x = 0.7 (4 - 1.1) = 2.03), the output holds until
    # u < zL = 2.03/1.3 - 0.2.
    block = Backlash(1.3, 0.2, 0.7, 1.1)
    x = block.simulate(np.array([4.0, 2.03 / 1.3 - 0.2 + 1e-6, 2.03 / 1.3 - 0.2 - 0.1]))
    assert x[0] == pytest.approx(2.03)
    assert x[1] == x[0]
    assert x[2] == pytest.approx(1.3 * (2.03 / 1.3 - 0.1))


def test_dict_round_trip():
    block = Backlash(m_left=0.9, c_left=0.8, m_right=0.95, c_right=0.85)
    data = block.to_dict()
    assert data == {
        "kind": "backlash",
        "m_left": 0.9,
        "c_left": 0.8,
        "m_right": 0.95,
        "c_right": 0.85,
    }
    for again in (Backlash.from_dict(data), block_from_dict(data)):
        assert isinstance(again, Backlash)
        assert again.parameters == block.parameters


def test_theta_round_trip():
    block = Backlash(0.9, 0.8, 0.9, 0.85)
    np.testing.assert_allclose(block.to_theta(), [0.9, 0.72, 0.9, 0.765])
    again = Backlash.from_theta(block.to_theta())
    np.testing.assert_allclose(again.to_vector(), block.to_vector(), rtol=1e-15)


@pytest.mark.parametrize(
    ("kwargs", "word"),
    [
        ({"m_left": 0.0}, "m_left must be > 0"),
        ({"m_right": -1.0}, "m_right must be > 0"),
        ({"c_left": -0.1}, "c_left must be >= 0"),
        ({"c_right": float("nan")}, "c_right must be finite"),
        ({"m_left": "steep"}, "m_left must be a number"),
    ],
)
def test_invalid_parameters(kwargs, word):
    params = {"m_left": 1.0, "c_left": 0.5, "m_right": 1.0, "c_right": 0.5, **kwargs}
    with pytest.raises(ParameterError, match=word):
        Backlash(**params)


def test_from_theta_rejects_bad_vectors():
    with pytest.raises(ParameterError, match="4 values"):
        Backlash.from_theta([1.0, 2.0, 3.0])
    with pytest.raises(ParameterError, match=r"theta\[0\] \(m_left\) must be > 0"):
        Backlash.from_theta([-0.9, 0.7, 0.9, 0.7])


def test_check_branches():
    Backlash(0.9, 0.8, 0.9, 0.85).check_branches(-1e6, 1e6)  # parallel: always fine
    block = Backlash(1.3, 0.2, 0.7, 1.1)  # gap(u) = 0.6 u + 1.03, zero at u = -1.7167
    block.check_branches(-1.7, 50.0)
    with pytest.raises(ParameterError, match=r"cross at u = -1.71667"):
        block.check_branches(-2.0, 50.0)
    steeper_right = Backlash(0.7, 1.1, 1.3, 0.2)  # gap(u) = -0.6 u + 1.03, zero at 1.7167
    steeper_right.check_branches(-50.0, 1.7)
    with pytest.raises(ParameterError, match="cross at u = 1.71667"):
        steeper_right.check_branches(0.0, 2.0)
    with pytest.raises(ParameterError, match="u_min"):
        block.check_branches(1.0, 0.0)


def test_bad_inputs():
    block = Backlash(1.0, 0.5, 1.0, 0.5)
    with pytest.raises(DataError, match="one-dimensional"):
        block.simulate(np.zeros((3, 2)))
    with pytest.raises(DataError, match="index 2"):
        block.simulate(np.array([0.0, 1.0, np.nan]))
    with pytest.raises(ParameterError, match="x0 must be finite"):
        block.simulate(np.zeros(3), x0=np.inf)


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
def test_backlash_template_is_the_unit_backlash():
    assert Backlash.template().parameters == {
        "m_left": 1.0,
        "c_left": 0.0,
        "m_right": 1.0,
        "c_right": 0.0,
    }


def test_backlash_slope_lower_bounds_scale_with_each_slope():
    lower, upper = Backlash(2.0, 0.1, 3.0, 0.2).bounds()
    np.testing.assert_allclose(lower, [2e-6, 0.0, 3e-6, 0.0])
    assert np.all(np.isinf(upper))


def test_backlash_with_vector_takes_a_column():
    b = Backlash(2.0, 0.1, 3.0, 0.2).with_vector(np.array([[1.5], [0.0], [2.5], [0.1]]))
    assert b.parameters == {"m_left": 1.5, "c_left": 0.0, "m_right": 2.5, "c_right": 0.1}


@pytest.mark.parametrize(
    ("lo", "hi", "named"), [(float("nan"), 1.0, "u_min"), (0.0, float("inf"), "u_max")]
)
def test_backlash_check_branches_names_the_bad_end(lo, hi, named):
    with pytest.raises(ParameterError, match=f"^{named} must be finite"):
        Backlash(1.0, 0.1, 1.0, 0.1).check_branches(lo, hi)


def test_backlash_with_vector_reports_a_missing_value_as_not_finite():
    # the vector is read as floats first: None becomes NaN, refused as not finite
    with pytest.raises(ParameterError, match=r"^m_left must be finite, got nan$"):
        Backlash.template().with_vector([None, 0.0, 1.0, 0.0])


def test_backlash_degeneracy_no_play_too_much_play_and_a_flat_branch():
    (none,) = Backlash(1.0, 0.0, 1.2, 1e-5).degeneracy(-2.0, 3.0)
    assert "c_right = 1e-05) only 1e-05 apart" in none and "no play" in none
    (wide,) = Backlash(1.0, 3.0, 1.0, 3.0).degeneracy(-2.0, 3.0)
    assert "c_left + c_right = 6, 1.2 times the width" in wide and "hardly moves" in wide
    (flat,) = Backlash(1e-5, 0.1, 1.0, 0.1).degeneracy(-2.0, 3.0)
    assert "m_left = 1e-05" in flat and "holds its output" in flat
    assert Backlash(0.9, 0.8, 0.9, 0.85).degeneracy(-4.0, 4.0) == []  # paper A's
