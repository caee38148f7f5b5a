"""Figures of identification results: measured vs model output, identified blocks
against the truth, and parameter trajectories of the recursive methods.

Every title states whether a curve is a free-run simulation or a one-step prediction
and on which data. matplotlib is imported inside the functions.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "block_roles",
    "plot_model_output",
    "plot_blocks",
    "plot_parameter_history",
    "fit_figures",
    "failed_fit_figures",
]


def _figure(n_rows: int, width: float = 9.0, height: float = 2.6) -> tuple[Any, Any]:
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(n_rows, 1, figsize=(width, height * n_rows), squeeze=False)
    return fig, axes[:, 0]


def plot_model_output(
    output: Any,
    *,
    experiment: int | None = None,
    data_label: str = "data",
    max_samples: int | None = None,
) -> Any:
    """Measured output against the model output, one panel per output.

    ``output`` is a :class:`blockid.evaluation.ModelOutput`. By default the whole record
    is drawn (every experiment, one after another); ``experiment`` picks one, and
    ``max_samples`` thins a longer record to every k-th sample. The title says what is
    shown ("all 2200 samples", "every 25th of 5000000 samples"). Returns the Figure.
    """
    from blockid.plotting.runs import MAX_POINTS, MODE_TITLE, _number, shown_samples

    if experiment is not None:
        from dataclasses import replace

        data = output.data
        one = type(data)(
            data.inputs,
            data.outputs,
            data.sampling_time,
            [data.experiments[experiment]],
            data.source,
        )
        output = replace(output, data=one, outputs=[output.outputs[experiment]])
    t, y, y_hat, bounds, _, shown = shown_samples(output, max_samples or MAX_POINTS)
    fig, axes = _figure(len(output.data.outputs))
    mode = MODE_TITLE[output.mode]
    for j, (ax, name) in enumerate(zip(axes, output.data.outputs, strict=True)):
        ax.plot(t, y[:, j], color="0.2", lw=1.0, label="measured")
        ax.plot(t, y_hat[:, j], color="C1", lw=1.0, label=mode)
        for b in bounds:
            ax.axvline(b, color="0.6", ls=":", lw=0.8)
        fit = _number(output.metrics["fit_percent"][name], ".1f")
        rmse = _number(output.metrics["rmse"][name], ".4g")
        ax.set_ylabel(name)
        ax.set_title(
            f"{mode} on {data_label} ({shown}): fit {fit} %, RMSE {rmse}",
            fontsize=9,
        )
        ax.legend(fontsize=8, loc="upper right")
    axes[-1].set_xlabel("time [s]" if output.data.sampling_time else "sample")
    fig.tight_layout()
    return fig


def block_roles(model: Any) -> list[tuple[int, Any, str, str, str]]:
    """``(index, block, which, x label, y label)`` of every nonlinear block of a
    block-oriented model: what the block is in the chain ("input block", "output
    block", "feedback block") and what its input and output are."""
    out = []
    for i, block in enumerate(model.blocks):
        if block.role == "linear":
            continue
        if i == 0:
            labels = ("input block", f"u = {model.inputs[0]} (relative to the input offset)",
                      "w = N1(u)")  # fmt: skip
        elif block is getattr(model, "feedback", None):
            labels = ("feedback block", f"y = {model.outputs[0]} (relative to the output offset)",
                      "N(y), fed back to the input")  # fmt: skip
        elif block is model.output_block:
            labels = ("output block", "x (output of the linear block)",
                      "y = N2(x) (relative to the output offset)")  # fmt: skip
        else:
            labels = (f"block {i}", f"input of block {i}", f"output of block {i}")
        out.append((i, block, *labels))
    return out


def plot_blocks(model: Any, truth: Any = None, u: np.ndarray | None = None) -> Any:
    """Identified nonlinear blocks of a block-oriented model, truth dashed if given.

    ``u`` (the input data) sets each block's input range: the range of the signal that
    enters it when ``u`` is simulated.
    """
    from blockid.plotting.blocks import block_name

    panels = block_roles(model)
    fig, axes = _figure(max(len(panels), 1), width=5.0, height=3.6)
    inputs = None if u is None else model.block_inputs(np.asarray(u, float).reshape(-1, 1))
    ref_blocks = getattr(truth, "blocks", None)
    for ax, (i, block, which, xlabel, ylabel) in zip(axes, panels, strict=False):
        ref = None
        if ref_blocks is not None and len(ref_blocks) == len(model.blocks):
            ref = ref_blocks[i] if type(ref_blocks[i]) is type(block) else None
        s = None if inputs is None else inputs[i]
        if block.role == "dynamic":
            block.plot(ax=ax, u=s, truth=ref)
        else:
            rng = None if s is None else (float(np.min(s)), float(np.max(s)))
            if hasattr(block, "plot"):
                block.plot(ax=ax, u_range=rng, truth=ref)
            else:
                grid = np.linspace(*(rng or (-1.0, 1.0)), 400)
                ax.plot(grid, block(grid), label=block_name(block))
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.set_title(f"{which}: {block_name(block)}", fontsize=9)
    fig.tight_layout()
    return fig


def plot_parameter_history(
    history: dict[str, Any], truth: dict[str, float] | None = None, max_panels: int = 30
) -> Any:
    """Parameter estimates of a recursive method over the samples (as in the papers).

    ``history`` has ``"theta"`` (n_steps, n) and ``"names"`` (n); the true values, if
    given by name, are drawn as dashed lines.
    """
    theta = np.asarray(history["theta"])
    names = list(history["names"])[:max_panels]
    cols = 3
    rows = int(np.ceil(len(names) / cols))
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(rows, cols, figsize=(10, 2.2 * rows), squeeze=False)
    k = np.asarray(history.get("update", np.arange(theta.shape[0])))
    for i, name in enumerate(names):
        ax = axes[i // cols, i % cols]
        ax.plot(k, theta[:, i], lw=1.0)
        if truth and name in truth:
            ax.axhline(truth[name], color="k", ls="--", lw=0.8)
        ax.set_title(name, fontsize=9)
    for j in range(len(names), rows * cols):
        axes[j // cols, j % cols].axis("off")
    fig.supxlabel("sample (all passes)")
    fig.tight_layout()
    return fig


#: The files :func:`fit_figures` may write (which of them depends on the model).
FIT_FIGURES = ("simulation.png", "blocks.png", "parameters.png")


def existing_figures(folder: str | Path | None, names: tuple[str, ...]) -> list[Path]:
    """The files of ``names`` that already exist in ``folder`` (a command refuses to
    replace them without ``--force``, before any work)."""
    if folder is None:
        return []
    return [Path(folder) / n for n in names if (Path(folder) / n).exists()]


def fit_figures(
    result: Any, data: Any, folder: str | Path, truth: Any = None, overwrite: bool = False
) -> list[Path]:
    """Write the figures of a fit to ``folder`` (created if needed); return their paths.

    ``simulation.png``: free-run simulation on the whole estimation record (the title
    says how many samples are drawn); ``blocks.png``:
    identified nonlinear blocks (block-oriented models); ``parameters.png``: parameter
    trajectories (recursive methods that recorded them). An existing file is replaced
    only with ``overwrite`` (:class:`~blockid.errors.DataError` otherwise).
    """
    import matplotlib.pyplot as plt

    from blockid.evaluation.validate import evaluate

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    fig = plot_model_output(
        evaluate(result.model, data, "simulation"), data_label="the estimation data"
    )
    written.append(_save(fig, folder / "simulation.png", overwrite))
    if (
        getattr(result.model, "input_block", None) is not None
        or getattr(result.model, "output_block", None) is not None
    ):
        u = np.concatenate([e.u[:, 0] for e in data.experiments])
        blocks = plot_blocks(result.model, truth, u)
        written.append(_save(blocks, folder / "blocks.png", overwrite))
    if result.history.get("theta") is not None:
        history = plot_parameter_history(result.history)
        written.append(_save(history, folder / "parameters.png", overwrite))
    plt.close("all")
    return written


def failed_fit_figures(
    history: dict[str, Any], folder: str | Path, overwrite: bool = False
) -> list[Path]:
    """:func:`fit_figures` for a recursive fit that raised: ``parameters.png`` from the
    history attached to its :class:`~blockid.errors.EstimationError` (none if empty)."""
    import matplotlib.pyplot as plt

    if history is None or not len(history.get("theta", ())):
        return []
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    fig = plot_parameter_history(history)
    fig.suptitle("parameter estimates up to the failure (no model was returned)", fontsize=9)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    path = _save(fig, folder / "parameters.png", overwrite)
    plt.close(fig)
    return [path]


def _save(fig: Any, path: Path, overwrite: bool = False) -> Path:
    if path.exists() and not overwrite:
        from blockid.errors import DataError

        raise DataError(f"{path} exists; pass --force to replace it", parameter="overwrite")
    fig.savefig(path, dpi=110)
    return path
