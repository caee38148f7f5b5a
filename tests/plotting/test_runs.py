"""Figures of a model run on data (plotting/runs.py): what is drawn of a record (time
across experiments, thinning with its ordinal), the panels and titles, and the file."""

import numpy as np
import pytest

from blockid.data import Dataset
from blockid.data.dataset import Experiment
from blockid.errors import DataError
from blockid.evaluation import evaluate
from blockid.models import ARX
from blockid.plotting.runs import plot_run, run_figure, shown_samples

MODEL = ARX(["u"], ["y"], na=1, nb=1, nk=1, a={"y": {"y": [-0.5]}}, b={"y": {"u": [1.0]}})


def _output(lengths=(30, 20), ts=0.5, mode="simulation"):
    rng = np.random.default_rng(0)
    experiments = []
    for k, n in enumerate(lengths):
        u = rng.standard_normal(n)
        experiments.append(Experiment(f"e{k}", u, MODEL.simulate(u)[:, 0] + 0.1))
    data = Dataset(("u",), ("y",), ts, experiments)
    return evaluate(MODEL, data, mode)


def test_every_sample_is_shown_in_time_across_the_experiments():
    out = _output()
    x, y, y_hat, bounds, step, text = shown_samples(out)
    assert step == 1 and text == "all 50 samples in 2 experiments"
    np.testing.assert_array_equal(x, 0.5 * np.arange(50))
    assert bounds == [15.0]  # the second experiment starts at sample 30
    np.testing.assert_array_equal(y[30:, 0], out.data.experiments[1].y[:, 0])
    np.testing.assert_array_equal(y_hat[:30], out.outputs[0])


@pytest.mark.parametrize(
    ("points", "step", "ordinal"),
    [(25, 2, "2nd"), (4, 13, "13th"), (2, 25, "25th"), (3, 17, "17th")],
)
def test_a_long_record_is_thinned_and_the_title_says_to_what(points, step, ordinal):
    x, *_, shown_step, text = shown_samples(_output(), max_points=points)
    assert shown_step == step and text == f"every {ordinal} of 50 samples in 2 experiments"
    np.testing.assert_array_equal(x, 0.5 * np.arange(0, 50, step))


def test_two_panels_per_output_titled_with_mode_data_and_scores():
    import matplotlib.pyplot as plt

    out = _output(lengths=(40,), ts=None, mode="one-step")
    fig = plot_run(out, data_label="d.csv [0:40]")
    try:
        top, bottom = fig.axes
        fit = out.metrics["fit_percent"]["y"]
        assert top.get_title() == (
            f"one-step prediction on d.csv [0:40] (all 40 samples): fit {fit:.1f} %, "
            f"RMSE {out.metrics['rmse']['y']:.4g}"
        )
        np.testing.assert_allclose(
            bottom.get_lines()[0].get_ydata(),
            out.data.experiments[0].y[:, 0] - out.outputs[0][:, 0],
        )
        assert (
            bottom.get_xlabel() == "sample"
            and bottom.get_title() == "measured - one-step prediction"
        )
    finally:
        plt.close(fig)


def test_the_figure_file_is_named_by_mode_and_kept_without_overwrite(tmp_path):
    out = _output()
    path = run_figure(out, tmp_path / "figs")
    assert path == tmp_path / "figs" / "simulation.png" and path.read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(DataError, match=r"simulation\.png exists; pass --force to replace it$"):
        run_figure(out, tmp_path / "figs")
    assert run_figure(_output(mode="one-step"), tmp_path / "figs").name == "prediction.png"
