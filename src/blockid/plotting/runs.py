"""Figures of a model run on data: measured against model output, and the error.

:func:`plot_run` draws a :class:`~blockid.evaluation.ModelOutput` (``blockid simulate``
and ``predict`` with ``--plot``): for every output, measured and model output over the
whole record (every experiment, one after another) and the error below it. Titles say
free-run simulation or one-step prediction, the data and range, and how many samples
are drawn: a record longer than ``max_points`` is thinned to every k-th sample, and the
title says so. matplotlib is imported inside the functions.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["MODE_TITLE", "plot_run", "run_figure", "shown_samples"]

#: How each mode of evaluation is named in titles.
MODE_TITLE = {
    "simulation": "free-run simulation",
    "one-step": "one-step prediction",
    "k-step": "k-step-ahead prediction",
}

#: Points drawn per curve at most; longer records are thinned (and the title says so).
MAX_POINTS = 200_000


def shown_samples(output: Any, max_points: int | None = MAX_POINTS) -> tuple[Any, ...]:
    """The record of a model run as drawn: ``(x, y, y_hat, bounds, step, text)``.

    ``x`` is time (or sample number without a sampling time) running on across the
    experiments; ``bounds`` the x positions where a new experiment starts; ``step``
    the thinning (1: every sample); ``text`` says what is shown, e.g. ``"all 2200
    samples"`` or ``"every 25th of 5000000 samples"``.
    """
    data = output.data
    y = np.vstack([e.y for e in data.experiments])
    y_hat = np.vstack(output.outputs)
    n = y.shape[0]
    step = 1 if max_points is None or n <= max_points else int(np.ceil(n / max_points))
    ts = data.sampling_time or 1.0
    x = np.arange(n) * ts
    starts = np.cumsum([0] + [e.n_samples for e in data.experiments[:-1]])
    bounds = [float(k * ts) for k in starts[1:]]
    many = f" in {data.n_experiments} experiments" if data.n_experiments > 1 else ""
    if step == 1:
        text = f"all {n} samples{many}"
    else:
        text = f"every {_ordinal(step)} of {n} samples{many}"
    return x[::step], y[::step], y_hat[::step], bounds, step, text


def _ordinal(k: int) -> str:
    suffix = "th" if 10 <= k % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(k % 10, "th")
    return f"{k}{suffix}"


def _number(value: float, spec: str) -> str:
    """A metric for a title; an undefined one (NaN) as ``n/a``."""
    return "n/a" if value is None or not np.isfinite(value) else format(value, spec)


def plot_run(output: Any, *, data_label: str = "data", max_points: int | None = MAX_POINTS) -> Any:
    """Measured against model output and the error, whole record, two panels per output.

    Parameters
    ----------
    output : ModelOutput
        What :func:`blockid.evaluation.evaluate` returns.
    data_label : str
        Names the data (and range) in the titles.
    max_points : int or None
        Thin longer records to every k-th sample (None: draw every sample).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    x, y, y_hat, bounds, _, shown = shown_samples(output, max_points)
    names = output.data.outputs
    fig, axes = plt.subplots(
        2 * len(names), 1, figsize=(10, 2.4 * 2 * len(names)), squeeze=False, sharex=True
    )
    mode = MODE_TITLE[output.mode]
    for j, name in enumerate(names):
        top, bottom = axes[2 * j, 0], axes[2 * j + 1, 0]
        top.plot(x, y[:, j], color="0.2", lw=0.8, label="measured")
        top.plot(x, y_hat[:, j], color="C1", lw=0.8, label=mode)
        bottom.plot(x, y[:, j] - y_hat[:, j], color="C3", lw=0.8)
        for ax in (top, bottom):
            for b in bounds:
                ax.axvline(b, color="0.6", ls=":", lw=0.8)
        fit = _number(output.metrics["fit_percent"][name], ".1f")
        rmse = _number(output.metrics["rmse"][name], ".4g")
        top.set_title(f"{mode} on {data_label} ({shown}): fit {fit} %, RMSE {rmse}", fontsize=9)
        top.set_ylabel(name)
        top.legend(fontsize=8, loc="upper right")
        bottom.set_ylabel(f"error {name}")
        bottom.set_title(f"measured - {mode}", fontsize=9)
    axes[-1, 0].set_xlabel("time [s]" if output.data.sampling_time else "sample")
    fig.tight_layout()
    return fig


#: The file :func:`run_figure` writes, by mode.
RUN_FIGURES = {
    "simulation": "simulation.png",
    "one-step": "prediction.png",
    "k-step": "prediction.png",
}


def run_figure(
    output: Any, folder: str | Path, *, data_label: str = "data", overwrite: bool = False
) -> Path:
    """Write :func:`plot_run` to ``folder/simulation.png`` (free run) or
    ``folder/prediction.png`` (one step); the folder is created if needed. An existing
    file is replaced only with ``overwrite``."""
    import matplotlib.pyplot as plt

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / RUN_FIGURES[output.mode]
    if path.exists() and not overwrite:
        from blockid.errors import DataError

        raise DataError(f"{path} exists; pass --force to replace it", parameter="overwrite")
    fig = plot_run(output, data_label=data_label)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
