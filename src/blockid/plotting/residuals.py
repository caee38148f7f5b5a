"""The figure of a residual analysis (``blockid residuals --plot``): the residual's
autocorrelation per output and its cross-correlation with each input, with the
confidence bounds of :func:`~blockid.evaluation.residuals.residual_analysis`.
matplotlib is imported inside the functions."""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["RESIDUAL_FIGURE", "plot_residuals", "residual_figure"]

#: The file name of the figure.
RESIDUAL_FIGURE = "residuals.png"

_MODE = {"simulation": "free-run simulation", "one-step": "one-step prediction"}


def plot_residuals(analysis: Any, data_label: str = "data") -> Any:
    """A figure: one row per output, its autocorrelation (left) and its
    cross-correlation with each input (right), bounds shaded."""
    import matplotlib.pyplot as plt

    outputs = list(analysis.autocorrelation)
    inputs = sorted({u for u, _ in analysis.cross_correlation}, key=str)
    cols = 1 + len(inputs)
    fig, axes = plt.subplots(len(outputs), cols, figsize=(4.2 * cols, 2.8 * len(outputs)),
                             squeeze=False)  # fmt: skip
    level = f"{analysis.confidence:.0%}"
    for i, y in enumerate(outputs):
        ax = axes[i][0]
        ax.axhspan(-analysis.auto_bound, analysis.auto_bound, color="0.85", label=level)
        ax.stem(analysis.lags, analysis.autocorrelation[y], basefmt=" ")
        white = analysis.whiteness[y]
        ax.set_title(f"autocorrelation of the residual of {y}\n"
                     f"Ljung-Box p = {white['p_value']:.3g}", fontsize=9)  # fmt: skip
        ax.set_xlabel("lag τ")
        ax.legend(loc="upper right", fontsize=8)
        for j, u in enumerate(inputs):
            ax = axes[i][1 + j]
            bound = analysis.cross_bound[(u, y)]
            ax.axhspan(-bound, bound, color="0.85", label=level)
            ax.stem(analysis.cross_lags, analysis.cross_correlation[(u, y)], basefmt=" ")
            test = analysis.independence[(u, y)]
            ax.set_title(f"cross-correlation {u} (t) with residual {y} (t+τ)\n"
                         f"τ >= 0: p = {test['p_value']:.3g}; τ < 0: feedback",
                         fontsize=9)  # fmt: skip
            ax.set_xlabel("lag τ")
    fig.suptitle(f"residual of the {_MODE[analysis.mode]} on {data_label} "
                 f"({analysis.n_samples} samples)", fontsize=10)  # fmt: skip
    fig.tight_layout()
    return fig


def residual_figure(
    analysis: Any, folder: str | Path, *, data_label: str = "data", overwrite: bool = False
) -> Path:
    """Write :func:`plot_residuals` to ``folder/residuals.png`` (the folder created if
    needed); an existing file is replaced only with ``overwrite``."""
    import matplotlib.pyplot as plt

    from blockid.plotting.figures import _save

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    fig = plot_residuals(analysis, data_label=data_label)
    try:
        return _save(fig, folder / RESIDUAL_FIGURE, overwrite)
    finally:
        plt.close(fig)
