"""Tests of blockid.plotting.report_figures: the zoom on long records, the static curves
scaled to their nonlinearity with bands only where they mean something, readable names,
and legends and labels that cover or cut nothing (Agg backend, see conftest)."""

import dataclasses

import numpy as np
import pytest

from blockid.blocks import Polynomial
from blockid.data import Dataset
from blockid.evaluation import evaluate
from blockid.models import Hammerstein
from blockid.plotting import report_figures as rf
from blockid.plotting.uncertainty import fit_draws


def _texts(fig):
    out = [t.get_text() for t in fig.texts]
    for legend in fig.legends:
        out += [t.get_text() for t in legend.get_texts()]
    for ax in fig.axes:
        out += [ax.get_title(), ax.get_xlabel(), ax.get_ylabel()]
        out += [t.get_text() for t in ax.get_yticklabels() + ax.get_xticklabels()]
        if ax.get_legend() is not None:
            out += [t.get_text() for t in ax.get_legend().get_texts()]
    return out


def _output(n, seed=0, ts=0.01):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1, 1, n // 10 + 1), 10)[:n]
    model = Hammerstein("u", "y", input_block=Polynomial([0.0, 1.0, 0.0, -0.3]), na=2, nb=2,
                        nk=1, a=[-1.5, 0.7], b=[1.0, 0.5], sampling_time=ts)  # fmt: skip
    y = model.simulate(u)[:, 0] + 0.05 * rng.standard_normal(n)
    data = Dataset.from_arrays(u, y, ["u"], ["y"], sampling_time=ts)
    return evaluate(model, data, "simulation")


def _zooms(fig):
    return [ax for ax in fig.axes if ax.get_title().startswith("zoom on")]


def test_the_zoom_appears_only_on_long_records():
    short = rf.validation_figure(_output(2000), 0)
    assert _zooms(short) == []
    assert len(short.axes) == 2
    output = _output(40_000)
    fig = rf.validation_figure(output, 1000)
    (zoom,) = _zooms(fig)
    start, stop = rf.zoom_window(output.data.experiments[0].y, output.skip, output.outputs[0])
    assert 200 <= stop - start <= 600
    measured = next(line for line in zoom.lines if line.get_label() == "measured")
    np.testing.assert_array_equal(measured.get_ydata(), output.data.experiments[0].y[start:stop, 0])
    model = [line for line in zoom.lines if line is not measured][0]
    np.testing.assert_array_equal(model.get_ydata(), output.outputs[0][start:stop, 0])
    # the time axis is that of the record: the range starts at sample 1000
    assert measured.get_xdata()[0] == pytest.approx((1000 + start) * 0.01)
    assert zoom.get_title() == f"zoom on {rf.zoom_title((start, stop), 1000, 0.01)}"
    assert f"samples {1000 + start} to {1000 + stop - 1} of the record" in zoom.get_title()
    # the window is shaded in the full view, and the legend lies outside every axes
    assert "zoomed window" in _texts(fig)
    assert all(ax.get_legend() is None for ax in fig.axes) and len(fig.legends) == 1


def test_the_zoom_goes_where_the_output_varies_most():
    t = np.arange(40_000)
    y = np.sin(2 * np.pi * t / 50) * (np.abs(t - 25_000) < 300)
    start, stop = rf.zoom_window(y)
    assert stop - start == 200  # four periods of 50 samples
    assert 24_700 <= start and stop <= 25_300


def test_the_zoom_goes_where_the_model_errs_most_not_to_the_end():
    """The output varies most at the end of the record, the model errs most in its
    middle: the zoom shows the error (it once went to the end, a sliver where the model
    did well)."""
    t = np.arange(40_000)
    y = np.sin(2 * np.pi * t / 100) * (1.0 + 4.0 * (t > 39_000))
    y_hat = y.copy()
    y_hat[20_000:20_100] += 0.5  # the model's one bad stretch
    start, stop = rf.zoom_window(y, 0, y_hat)
    assert stop - start == 400  # four periods of 100 samples
    assert start <= 20_000 and 20_100 <= stop
    assert rf.zoom_window(y)[1] > 39_000  # without the model: where the output varies most


def _drawn(ax, label):
    """The artists of ``ax`` drawn with ``label``'s zorder (an envelope's second edge
    and its last samples are unlabelled)."""
    artists = list(ax.lines) + list(ax.collections)
    first = next(a for a in artists if a.get_label() == label)
    return [a for a in artists if a.get_zorder() == first.get_zorder()]


@pytest.mark.parametrize("n", [2000, 40_000])
def test_the_measured_trace_is_drawn_over_the_model_and_stays_visible(n):
    """Measured output thin and dark above the model's wider, lighter trace (in a long
    record its envelope by its two edges, not a fill that would hide or be hidden)."""
    output = _output(n)
    ax = rf.validation_figure(output, 0).axes[0]
    model = _drawn(ax, "free-run simulation")
    measured = _drawn(ax, "measured")
    assert min(a.get_zorder() for a in measured) > max(a.get_zorder() for a in model)
    assert all(type(a).__name__ == "Line2D" for a in measured)  # lines, never a fill
    if n <= rf.MAX_POINTS:
        assert [type(a).__name__ for a in model] == ["Line2D"]
        assert model[0].get_linewidth() > measured[0].get_linewidth()
        np.testing.assert_array_equal(measured[0].get_ydata(), output.data.experiments[0].y[:, 0])
    else:
        lo, hi = measured[0].get_ydata(), measured[1].get_ydata()  # the envelope's edges
        assert lo.size == hi.size > 1000 and np.all(lo <= hi)
        assert any(type(a).__name__ == "FillBetweenPolyCollection" or "Poly" in type(a).__name__
                   for a in model)  # the model's envelope filled, under the edges  # fmt: skip


def test_the_static_curve_shows_its_deviation_from_the_best_line():
    block = Polynomial([0.1, 2.0, 0.0, 0.5])
    grid = np.linspace(-1, 1, 201)
    c = rf.static_curve(block, grid)
    offset, slope = np.polyfit(grid, block(grid), 1)[::-1]
    np.testing.assert_allclose(c["line"], [offset, slope])
    np.testing.assert_allclose(c["deviation"], block(grid) - (offset + slope * grid), atol=1e-12)
    assert c["band"] is None and c["notes"] == []


def _draws(block, scale, n=60, seed=0):
    """Models whose block's coefficients are the block's plus noise of ``scale``."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        coefficients = block.to_vector() + scale * rng.standard_normal(block.to_vector().size)
        out.append(type("M", (), {"blocks": [block.with_vector(coefficients)]})())
    return out


def test_a_band_that_dwarfs_the_curve_is_not_drawn_and_the_note_says_why():
    block = Polynomial([0.0, 0.01, 0.0, 0.002])  # a nearly flat curve
    grid = np.linspace(-1, 1, 101)
    wide = rf.static_curve(block, grid, _draws(block, 0.5), 0)
    assert wide["band"] is None and wide["deviation_band"] is None
    assert any("times wider than the curve's own range" in n for n in wide["notes"])
    narrow = rf.static_curve(block, grid, _draws(block, 1e-4), 0)
    assert narrow["band"] is not None and narrow["notes"] == []
    lo, hi = narrow["band"]
    assert np.all(lo <= narrow["w"] + 1e-3) and np.all(hi >= narrow["w"] - 1e-3)


def test_the_blocks_figure_fits_its_axes_to_the_curves_and_names_blocks_in_words(
    hammerstein_fit,
):
    fit, est, _ = hammerstein_fit
    u = est.experiments[0].u[:, 0]
    fig, notes = rf.blocks_figure(fit.model, u, fit_draws(fit))
    curve_ax, deviation_ax = fig.axes
    assert curve_ax.get_title() == "input block: two-segment polynomial"
    assert deviation_ax.get_title().startswith("deviation from the best straight line")
    w = curve_ax.lines[0].get_ydata()
    lo, hi = curve_ax.get_ylim()
    span = np.ptp(w)
    assert lo >= w.min() - 1.2 * span and hi <= w.max() + 1.2 * span  # by the curve
    grid = curve_ax.lines[0].get_xdata()
    assert grid.min() == pytest.approx(u.min()) and grid.max() == pytest.approx(u.max())
    texts = " ".join(_texts(fig))
    assert "TwoSegmentPolynomial" not in texts and "Polynomial" not in texts
    assert all(ax.get_legend() is None for ax in fig.axes) and len(fig.legends) == 1
    # a band 20 times wider than the curve: dropped, with a note for the caption
    scale = 20 * np.ptp(w)
    errors = np.full(fit.model.free_parameters().size, scale)
    huge = dataclasses.replace(fit, settings={"standard_errors": errors})
    _, notes = rf.blocks_figure(fit.model, u, fit_draws(huge))
    assert any("no band is drawn" in n for n in notes)


def test_comparison_labels_wrap_between_words_and_the_legend_is_outside():
    long = "identify: hammerstein-wiener(na=2, nb=2, nk=10, input_block=two-segment-polynomial:degree=3, output_block=polynomial:degree=3, center=False)"  # noqa: E501
    fig = rf.comparison_figure([(long, 79.2, None), ("arx (batch)", 11.1, 69.6)], "y")
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_yticklabels()]
    assert labels[0].replace("\n", " ") == long  # nothing cut, only wrapped at spaces
    assert all(len(line) <= 44 or " " not in line for line in labels[0].split("\n"))
    assert ax.get_legend() is None and len(fig.legends) == 1


def test_wrap_never_breaks_a_word():
    text = "input_block=two-segment-polynomial:degree=3, output_block=polynomial:degree=3"
    wrapped = rf.wrap(text, 10)
    assert wrapped.split() == text.split()
