"""Tests of blockid.plotting.blocks and the blocks' plot() hand-off (Agg backend, see conftest)."""

import subprocess
import sys

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.axes import Axes

from blockid.blocks.base import DynamicBlock
from blockid.blocks.polynomial import Polynomial, TwoSegmentPolynomial
from blockid.blocks.static import DeadZone, PiecewiseLinear, Saturation
from blockid.errors import ParameterError
from blockid.plotting import plot_block

BLOCKS = [
    Polynomial([0.1, 1.0, -0.3]),
    Polynomial([1.0, 0.2], constant=False),
    TwoSegmentPolynomial.from_segments([0.0, 1.0, 0.2], [0.0, 0.4]),
    DeadZone(-0.5, 0.5),
    Saturation(-1.0, 1.0, slope=2.0),
    PiecewiseLinear([-1.0, 0.0, 2.0], [1.0, 0.0, 1.0]),
]


@pytest.mark.parametrize("block", BLOCKS, ids=repr)
def test_plot_draws_one_curve_and_saves_png(block, tmp_path):
    ax = block.plot()
    assert isinstance(ax, Axes)
    assert len(ax.get_lines()) == 1
    u, w = ax.get_lines()[0].get_data()
    np.testing.assert_allclose((u[0], u[-1]), block.default_u_range())
    np.testing.assert_allclose(w, block(u))
    assert ax.get_xlabel() == "input u"
    assert ax.get_ylabel() == "output w = N(u)"
    path = tmp_path / f"{block.kind}.png"
    ax.figure.savefig(path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_plot_with_truth_adds_dashed_line_and_legend():
    truth = DeadZone(-0.5, 0.5)
    estimate = DeadZone(-0.4, 0.6, slope_left=0.9)
    ax = estimate.plot(truth=truth, color="red")
    lines = ax.get_lines()
    assert len(lines) == 2
    assert lines[0].get_color() == "red"
    assert lines[1].get_linestyle() == "--"
    u, w_true = lines[1].get_data()
    np.testing.assert_allclose(w_true, truth(u))
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["estimate", "true"]
    # default range covers both blocks' ranges
    assert (u[0], u[-1]) == pytest.approx((-1.5, 1.6))


def test_plot_on_given_axes_and_range():
    _, ax = plt.subplots()
    out = plot_block(Polynomial([0.0, 0.0, 1.0]), ax=ax, u_range=(-3.0, 2.0), n_points=11)
    assert out is ax
    u, w = ax.get_lines()[0].get_data()
    np.testing.assert_allclose(u, np.linspace(-3.0, 2.0, 11))
    np.testing.assert_allclose(w, u**2)


def test_plot_errors():
    class Relay(DynamicBlock):
        @property
        def parameters(self):
            return {}

        def simulate(self, u, x0=0.0):
            return np.sign(u)

    with pytest.raises(ParameterError, match="block must be a static block.*got Relay"):
        plot_block(Relay())
    with pytest.raises(ParameterError, match="truth must be a static block"):
        DeadZone(0.0, 1.0).plot(truth=Relay())
    with pytest.raises(ParameterError, match="u_range must have low < high"):
        DeadZone(0.0, 1.0).plot(u_range=(1.0, 1.0))
    with pytest.raises(ParameterError, match="n_points must be at least 2"):
        plot_block(DeadZone(0.0, 1.0), n_points=1)


def test_importing_blocks_and_plotting_does_not_import_matplotlib():
    code = (
        "import sys, blockid.plotting, blockid.blocks.polynomial, blockid.blocks.static; "
        "assert 'matplotlib' not in sys.modules, 'matplotlib imported eagerly'"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_the_blocks_figure_of_a_feedback_model_draws_the_fed_back_block():
    """Over the range the output takes in a free run; the report draws this figure."""
    from blockid.blocks.linear import LinearBlock
    from blockid.models.feedback import LinearFeedback
    from blockid.plotting.figures import plot_blocks

    model = LinearFeedback(
        "u", "y", linear=LinearBlock(2, 1, 1, a=[-1.5, 0.7], b=[0.5]),
        feedback=DeadZone(-0.3, 0.4, 0.8, 0.6),
    )  # fmt: skip
    u = np.random.default_rng(0).normal(0.0, 1.0, 500)
    v, y = model.block_inputs(u)
    np.testing.assert_allclose(y, model.simulate(u)[:, 0])
    np.testing.assert_allclose(v, u - model.feedback(y))
    fig = plot_blocks(model, u=u)
    (ax,) = fig.axes
    assert ax.get_title() == "feedback block: dead zone"  # the kind in words
    grid = ax.lines[0].get_xdata()
    assert grid.min() == pytest.approx(y.min()) and grid.max() == pytest.approx(y.max())
    plt.close(fig)


def test_static_block_plot_draws_the_block_over_the_given_range():
    ax = DeadZone(-0.5, 0.5, slope_left=2.0).plot(u_range=(-1.0, 1.0), n_points=5)
    try:
        (line,) = ax.get_lines()
        np.testing.assert_array_equal(line.get_xdata(), [-1.0, -0.5, 0.0, 0.5, 1.0])
        np.testing.assert_array_equal(line.get_ydata(), [-1.0, 0.0, 0.0, 0.0, 0.5])
        assert line.get_label() == "dead zone"  # readable, not the class name
    finally:
        plt.close(ax.figure)
