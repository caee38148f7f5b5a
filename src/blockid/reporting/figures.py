"""The report's figures, as base64 PNG text for ``<img src="data:image/png;base64,..">``.

Figures drawn here use :class:`matplotlib.figure.Figure` directly (no pyplot state, no
display needed); those borrowed from :mod:`blockid.plotting.figures` are closed after
encoding. Long records are drawn as a min/max envelope per pixel column, so every
sample counts and a figure stays small.
"""

from __future__ import annotations

import base64
import io
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np

from blockid.reporting.uncertainty import sampled_band

__all__ = [
    "blocks_figure",
    "comparison_figure",
    "encode_png",
    "history_figure",
    "overview_figure",
    "validation_figure",
]

DPI = 100
#: Above this many samples a line is drawn as its min/max envelope.
MAX_POINTS = 3000


def _new_figure(width: float, height: float) -> Any:
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), dpi=DPI, layout="constrained")


def encode_png(fig: Any) -> str:
    """The figure as base64 PNG text (no metadata, so nothing names a web site); a
    pyplot figure is closed afterwards."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=DPI, metadata={"Software": None})
    if getattr(fig, "number", None) is not None:  # made by pyplot: release it
        import matplotlib.pyplot as plt

        plt.close(fig)
    return base64.b64encode(buffer.getvalue()).decode("ascii")


def _line(ax: Any, t: np.ndarray, x: np.ndarray, **style: Any) -> None:
    """``x`` against ``t``; beyond MAX_POINTS samples its min/max envelope per bin."""
    n = x.size
    if n <= MAX_POINTS:
        ax.plot(t, x, lw=0.9, **style)
        return
    width = int(np.ceil(n / (MAX_POINTS // 2)))
    m = n // width * width
    with warnings.catch_warnings():  # a bin of NaN only (skipped samples) stays NaN
        warnings.simplefilter("ignore", RuntimeWarning)
        lo = np.nanmin(x[:m].reshape(-1, width), axis=1)
        hi = np.nanmax(x[:m].reshape(-1, width), axis=1)
    tc = t[:m].reshape(-1, width).mean(axis=1)
    label = style.pop("label", None)
    ax.fill_between(tc, lo, hi, lw=0.6, alpha=0.9, label=label, **style)
    if m < n:
        ax.plot(t[m:], x[m:], lw=0.9, **style)


def _time(ts: float | None, first: int, n: int) -> np.ndarray:
    return (first + np.arange(n)) * (ts or 1.0)


def _time_label(ts: float | None) -> str:
    return "time [s]" if ts else "sample"


def overview_figure(
    data: Any, estimation: tuple[int, int | None] | None, validation: tuple[int, int | None] | None
) -> Any:
    """Every signal of every experiment, the estimation and validation ranges shaded."""
    names = [*data.inputs, *data.outputs]
    exps = data.experiments
    fig = _new_figure(9.0, 0.4 + 1.7 * len(names))
    axes = fig.subplots(len(names), len(exps), squeeze=False, sharex="col")
    ts = data.sampling_time
    for c, exp in enumerate(exps):
        t = _time(ts, 0, exp.n_samples)
        values = np.hstack([exp.u, exp.y])
        for r, name in enumerate(names):
            ax = axes[r, c]
            _line(ax, t, values[:, r], color="C0" if r < len(data.inputs) else "C3")
            for rng, colour, label in (
                (estimation, "C2", "estimation"),
                (validation, "C1", "validation"),
            ):
                if rng is None:
                    continue
                stop = exp.n_samples if rng[1] is None else min(rng[1], exp.n_samples)
                if rng[0] < stop:
                    ax.axvspan(t[rng[0]], t[stop - 1], color=colour, alpha=0.15, lw=0, label=label)
            if c == 0:
                kind = "input" if r < len(data.inputs) else "output"
                ax.set_ylabel(f"{name}\n({kind})", fontsize=8)
            ax.tick_params(labelsize=7)
        axes[0, c].set_title(f"experiment {exp.name!r} ({exp.n_samples} samples)", fontsize=9)
        axes[-1, c].set_xlabel(_time_label(ts), fontsize=8)
    if estimation is not None or validation is not None:
        axes[0, 0].legend(fontsize=7, loc="upper right")
    return fig


def comparison_figure(rows: Sequence[tuple[str, float, float | None]], output: str) -> Any:
    """Fit % of free-run simulation and of one-step prediction per model (one output)."""
    fig = _new_figure(9.0, 0.9 + 0.42 * len(rows))
    ax = fig.subplots()
    y = np.arange(len(rows))
    sim = np.array([r[1] for r in rows], float)
    one = np.array([np.nan if r[2] is None else r[2] for r in rows], float)
    low = min(0.0, float(np.nanmin(np.r_[sim, one, 0.0])))
    show = np.maximum(sim, max(low, -100.0))
    ax.barh(y - 0.2, show, height=0.38, color="C1", label="free-run simulation")
    ax.barh(y + 0.2, np.nan_to_num(one, nan=0.0), height=0.38, color="C0", label="one-step")
    for k, value in enumerate(sim):
        ax.text(max(show[k], 0) + 1, k - 0.2, f"{value:.1f} %", va="center", fontsize=7)
    ax.set_yticks(y, [r[0] for r in rows], fontsize=8)
    ax.invert_yaxis()
    ax.set_xlim(max(low, -100.0), 110)
    ax.axvline(0, color="0.3", lw=0.6)
    ax.set_xlabel(f"fit % of {output} on the validation data (100 % = perfect)", fontsize=8)
    ax.legend(fontsize=7, loc="lower right")
    ax.tick_params(labelsize=7)
    return fig


def validation_figure(
    output: Any,
    first: int,
    bands: Sequence[tuple[np.ndarray, np.ndarray] | None] = (),
    where: str = "validation data",
) -> Any:
    """Measured output and model output (top) and the residual (below) of every output
    and experiment of a :class:`~blockid.evaluation.ModelOutput`.

    ``first`` is the index of the range's first sample in each experiment (the time
    axis is that of the record). ``bands``: per experiment, the lower and upper edge
    (N, ny) of a 95 % band on the model output, shaded when given.
    """
    data = output.data
    mode = "free-run simulation" if output.mode == "simulation" else "one-step prediction"
    rows = 2 * len(data.outputs)
    exps = data.experiments
    fig = _new_figure(9.0, 0.5 + 1.8 * rows)
    axes = fig.subplots(rows, len(exps), squeeze=False, sharex="col")
    ts = data.sampling_time
    for c, (exp, y_hat) in enumerate(zip(exps, output.outputs, strict=True)):
        t = _time(ts, first, exp.n_samples)
        band = bands[c] if c < len(bands) else None
        for j, name in enumerate(data.outputs):
            ax, ax_e = axes[2 * j, c], axes[2 * j + 1, c]
            _line(ax, t, exp.y[:, j], color="0.25", label="measured")
            _line(ax, t, y_hat[:, j], color="C1", label=mode)
            if band is not None:
                ax.fill_between(
                    t, band[0][:, j], band[1][:, j], color="C1", alpha=0.25, lw=0,
                    label="95 % band",
                )  # fmt: skip
            residual = exp.y[:, j] - y_hat[:, j]
            residual[: output.skip] = np.nan  # initial conditions copied from the data
            _line(ax_e, t, residual, color="C3")
            ax_e.axhline(0.0, color="0.5", lw=0.6)
            ax.set_ylabel(name, fontsize=8)
            ax_e.set_ylabel(f"residual\n{name}", fontsize=8)
            score = _score(output.metrics, name)
            if len(exps) == 1:
                ax.set_title(f"{mode} on the {where}: {score}", fontsize=9)
            elif j == 0:  # scores pool every experiment: said once, above the columns
                ax.set_title(f"experiment {exp.name!r}", fontsize=9)
                pooled = "; ".join(f"{o} {_score(output.metrics, o)}" for o in data.outputs)
                fig.suptitle(f"{mode} on the {where}: {pooled}", fontsize=9)
            ax.legend(fontsize=7, loc="upper right")
            for a in (ax, ax_e):
                a.tick_params(labelsize=7)
        axes[-1, c].set_xlabel(_time_label(ts), fontsize=8)
    return fig


def _score(metrics: dict[str, dict[str, float]], name: str) -> str:
    return f"fit {metrics['fit_percent'][name]:.1f} %, RMSE {metrics['rmse'][name]:.4g}"


def blocks_figure(model: Any, u: np.ndarray, models: Sequence[Any] = ()) -> tuple[Any, list[str]]:
    """The identified nonlinear blocks (:func:`blockid.plotting.figures.plot_blocks`)
    over the range their inputs take when ``u`` is simulated, with the 95 % band of the
    drawn ``models`` on each static block. Returns the figure and notes."""
    from blockid.plotting.figures import plot_blocks

    fig = plot_blocks(model, u=u)
    notes: list[str] = []
    panels = [i for i, b in enumerate(model.blocks) if b.role != "linear"]
    for ax, i in zip(fig.axes, panels, strict=False):
        block = model.blocks[i]
        if not models:
            continue
        if block.role != "static" or not ax.lines:
            notes.append(f"no band drawn for the {block.kind} block (it has memory)")
            continue
        grid = np.asarray(ax.lines[0].get_xdata(), float)
        band = sampled_band(models, lambda m, i=i, g=grid: m.blocks[i](g))
        if band is None:
            notes.append(f"no band for the {block.kind} block: too few valid parameter draws")
            continue
        ax.fill_between(grid, band[0], band[1], color="C0", alpha=0.25, lw=0, label="95 % band")
        ax.legend(fontsize=7)
    return fig, notes


def history_figure(history: dict[str, Any], max_points: int = 2000, max_panels: int = 12) -> Any:
    """Parameter estimates of a recursive estimator after each update, one panel per
    group of parameters (``a_1, a_2, ..`` together), at most ``max_points`` updates drawn
    (evenly spaced, the last one included). The y axes fit the estimates after the first
    5 % of the updates, so a start-up transient does not hide where they settle."""
    theta = np.asarray(history["theta"], float)
    names = [str(n) for n in history["names"]]
    k = np.asarray(history.get("update", np.arange(theta.shape[0])))
    rows = np.unique(np.r_[np.arange(0, theta.shape[0], max(1, theta.shape[0] // max_points)),
                           theta.shape[0] - 1])  # fmt: skip
    groups: dict[str, list[int]] = {}
    for i, name in enumerate(names):
        head, _, tail = name.rpartition("_")
        groups.setdefault(head if head and tail.isdigit() else name, []).append(i)
    shown = list(groups.items())[:max_panels]
    cols = 2 if len(shown) > 1 else 1
    n_rows = int(np.ceil(len(shown) / cols))
    fig = _new_figure(9.0, 0.5 + 1.9 * n_rows)
    axes = fig.subplots(n_rows, cols, squeeze=False)
    for ax, (group, members) in zip(axes.flat, shown, strict=False):
        for i in members:
            ax.plot(k[rows], theta[rows, i], lw=0.9, label=names[i])
        settled = theta[rows[len(rows) // 20 :]][:, members]  # after the start-up transient
        if settled.size and np.all(np.isfinite(settled)):
            lo, hi = float(settled.min()), float(settled.max())
            pad = 0.1 * (hi - lo) or 0.1 * max(abs(hi), 1e-12)
            ax.set_ylim(lo - pad, hi + pad)
        ax.set_title(group if len(members) == 1 else f"{group}_*", fontsize=9)
        ax.legend(fontsize=7, loc="upper right", ncol=min(len(members), 4))
        ax.tick_params(labelsize=7)
    for ax in list(axes.flat)[len(shown) :]:
        ax.axis("off")
    for ax in axes[-1]:
        ax.set_xlabel("sample (all passes over the estimation data)", fontsize=8)
    return fig
