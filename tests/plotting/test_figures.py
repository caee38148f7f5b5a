"""blockid.plotting.figures: the figures of ``fit``, ``simulate`` and ``predict``."""

from __future__ import annotations

import numpy as np

from blockid.data import Dataset
from blockid.models import ARX


def test_fit_figure_title_says_how_much_it_shows():
    from blockid.evaluation import evaluate
    from blockid.plotting.figures import plot_model_output

    model = ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [-0.5]}}, b={"y": {"u": [1.0]}})
    u = np.random.default_rng(0).standard_normal(5000)
    data = Dataset.from_arrays(u, model.simulate(u), ["u"], ["y"])
    fig = plot_model_output(evaluate(model, data))
    assert "all 5000 samples" in fig.axes[0].get_title()
    assert fig.axes[0].lines[0].get_xdata().size == 5000
    fig = plot_model_output(evaluate(model, data), max_samples=1000)
    assert "every 5th of 5000 samples" in fig.axes[0].get_title()
