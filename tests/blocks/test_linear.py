"""Tests of blockid.blocks.linear: LinearBlock's defaults, stored coefficients, static
gain and initial outputs."""

import numpy as np
import pytest

from blockid.blocks.linear import LinearBlock
from blockid.errors import OrderError


def test_linear_block_static_gain():
    # G(1) = (1 + 0.5) / (1 - 0.5) = 3
    assert LinearBlock(1, 2, 1, [-0.5], [1.0, 0.5]).static_gain() == 3.0
    assert LinearBlock(1, 1, 1, [-1.0], [1.0]).static_gain() == float("inf")  # integrator


def test_linear_block_defaults_and_stored_coefficients():
    g = LinearBlock(1, 2, 1)
    assert g.a.tolist() == [0.0] and g.b.tolist() == [0.0, 0.0]  # b_0 = 0 unless unit_b0
    assert LinearBlock(1, 2, 1, unit_b0=True).b.tolist() == [1.0, 0.0]
    h = LinearBlock(1, 2, 1, a=[0], b=[1, 2])  # whole numbers are stored as floats
    assert h.a.dtype == np.float64 and h.b.dtype == np.float64
    assert all(type(v) is float for v in h.to_dict()["b"])
    with pytest.raises(ValueError, match="read-only"):
        h.a[0] = 0.5
    with pytest.raises(ValueError, match="read-only"):
        h.b[0] = 0.5


def test_linear_block_names_a_bad_na():
    with pytest.raises(OrderError, match=r"^na=-1: a block-oriented \(single-input"):
        LinearBlock(-1)


def test_linear_block_simulate_takes_a_column_of_initial_outputs():
    g = LinearBlock(2, 1, 1, a=[-0.5, 0.0], b=[1.0])
    # the first max_lag = 2 outputs given (x(0) = 2, x(1) = 4), the third row unused; then
    # x(k) = 0.5 x(k-1) + w(k-1): 3, 2.5
    x = g.simulate(np.ones(4), x_init=np.array([[2.0], [4.0], [7.0]]))
    np.testing.assert_array_equal(x, [2.0, 4.0, 3.0, 2.5])
