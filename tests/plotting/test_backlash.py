"""The hysteresis-loop figure of a backlash (plotting/backlash.py): the loop on its
input, the branch lines, the truth, the default sweep."""

from __future__ import annotations

import numpy as np
import pytest

from blockid.blocks.backlash import Backlash
from blockid.plotting.backlash import triangular_sweep


def test_plot_draws_loop_branches_and_truth():
    import matplotlib.pyplot as plt

    block = Backlash(0.9, 0.8, 0.9, 0.85)
    ax = block.plot(truth=Backlash(1.0, 0.7, 1.0, 0.9))
    lines = ax.get_lines()
    assert [ln.get_label() for ln in lines] == [
        "backlash loop",
        "left branch",
        "right branch",
        "truth",
    ]
    u, x = lines[0].get_data()
    np.testing.assert_array_equal(x, block.simulate(u))
    assert u.max() == pytest.approx(4 * 1.65)
    assert lines[1].get_linestyle() == "--"
    plt.close(ax.figure)


def test_backlash_plot_draws_the_loop_over_the_given_input():
    import matplotlib.pyplot as plt

    block = Backlash(1.0, 0.2, 1.5, 0.1)
    u = np.array([0.0, 1.0, 2.0, 1.0, -1.0, -2.0])
    ax = block.plot(u=u)
    try:
        loop, left, right = ax.get_lines()[:3]
        np.testing.assert_array_equal(loop.get_xdata(), u)
        # from x = 0: dead band at u = 0, right branch 1.5 (u - 0.1) up to u = 2, then
        # left branch u + 0.2 on the way down
        np.testing.assert_allclose(loop.get_ydata(), [0.0, 1.35, 2.85, 1.2, -0.8, -1.8])
        np.testing.assert_array_equal(left.get_xdata(), [-2.0, 2.0])  # the input's span
        np.testing.assert_allclose(right.get_ydata(), [-3.15, 2.85])
    finally:
        plt.close(ax.figure)


def test_the_sweep_runs_up_down_and_back_in_equal_steps():
    np.testing.assert_allclose(
        triangular_sweep(1.0, n_per_leg=2),
        [0.0, 0.5, 1.0, 0.5, 0.0, -0.5, -1.0, -0.5, 0.0, 0.5, 1.0],
    )


def test_a_backlash_without_play_is_drawn_over_a_unit_sweep_and_titled_by_its_parameters():
    import matplotlib.pyplot as plt

    ax = Backlash(2.0, 0.0, 0.5, 0.0).plot()
    try:
        u, x = ax.get_lines()[0].get_data()
        assert (u.min(), u.max()) == (-1.0, 1.0)
        np.testing.assert_allclose(x[u == 1.0], 0.5)  # right slope on the way up
        assert ax.get_title() == "backlash m_L=2, c_L=0, m_R=0.5, c_R=0"
    finally:
        plt.close(ax.figure)
