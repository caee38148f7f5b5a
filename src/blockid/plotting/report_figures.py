"""The figures of the HTML report, which ``.plot()`` of models and results also return.

Figures drawn here use :class:`matplotlib.figure.Figure` directly (no pyplot state, no
display needed; a notebook shows a returned figure all the same). Long records are drawn
as a min/max envelope per pixel column, so every sample counts and a figure stays small;
a record that long also gets a zoom on a few hundred samples, where the curves can be
told apart. Legends sit outside the axes, so they never cover data, and labels are
wrapped at spaces, never cut.
"""

from __future__ import annotations

import textwrap
import warnings
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from blockid.plotting.uncertainty import sampled_band

__all__ = [
    "BAND_LIMIT",
    "MAX_POINTS",
    "block_signal",
    "blocks_figure",
    "channel_blocks_figure",
    "channel_curve",
    "comparison_figure",
    "history_figure",
    "overview_figure",
    "search_figure",
    "static_curve",
    "validation_figure",
    "wrap",
    "zoom_title",
    "zoom_window",
]

DPI = 100
#: Above this many samples a line is drawn as its min/max envelope, and the output
#: figure adds a zoom.
MAX_POINTS = 3000
#: A band whose median width exceeds this many times the range of the curve it sits on
#: says nothing about the curve's shape: it is not drawn (the caption says so).
BAND_LIMIT = 2.0


def _new_figure(width: float, height: float) -> Any:
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), dpi=DPI, layout="constrained")


def wrap(text: str, width: int = 40) -> str:
    """``text`` on lines of at most ``width`` characters, broken at spaces only (a word
    longer than a line stays whole).

    >>> wrap("hammerstein(na=2, nb=2, input_block=two-segment-polynomial)", 24)
    'hammerstein(na=2, nb=2,\\ninput_block=two-segment-polynomial)'
    """
    return textwrap.fill(text, width, break_long_words=False, break_on_hyphens=False)


def _legend_outside(fig: Any, axes: Sequence[Any], ncol: int = 6) -> None:
    """One legend for ``axes`` above the figure (entries by label, once each)."""
    handles: dict[str, Any] = {}
    for ax in axes:
        for h, label in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(label, h)
    if handles:
        fig.legend(
            handles.values(),
            handles.keys(),
            loc="outside upper center",
            ncol=min(len(handles), ncol),
            fontsize=7,
            frameon=False,
        )


def _line(
    ax: Any,
    t: np.ndarray,
    x: np.ndarray,
    envelope_alpha: float = 0.9,
    edges: bool = False,
    lw: float = 0.9,
    **style: Any,
) -> None:
    """``x`` against ``t``; beyond MAX_POINTS samples its min/max envelope per bin,
    filled (with ``envelope_alpha``, so that an envelope drawn over another leaves it
    visible) or, with ``edges``, drawn as its two edges only (so a filled envelope under
    it shows through)."""
    n = x.size
    if n <= MAX_POINTS:
        ax.plot(t, x, lw=lw, **style)
        return
    width = int(np.ceil(n / (MAX_POINTS // 2)))
    m = n // width * width
    with warnings.catch_warnings():  # a bin of NaN only (skipped samples) stays NaN
        warnings.simplefilter("ignore", RuntimeWarning)
        lo = np.nanmin(x[:m].reshape(-1, width), axis=1)
        hi = np.nanmax(x[:m].reshape(-1, width), axis=1)
    tc = t[:m].reshape(-1, width).mean(axis=1)
    label = style.pop("label", None)
    if edges:
        ax.plot(tc, lo, lw=min(lw, 0.7), label=label, **style)
        ax.plot(tc, hi, lw=min(lw, 0.7), **style)
    else:
        fill = {k: v for k, v in style.items() if k != "alpha"}  # the envelope's own alpha
        ax.fill_between(tc, lo, hi, lw=0.6, alpha=envelope_alpha, label=label, **fill)
    if m < n:
        ax.plot(t[m:], x[m:], lw=lw, **style)


def _time(ts: float | None, first: int, n: int) -> np.ndarray:
    return (first + np.arange(n)) * (ts or 1.0)


def _time_label(ts: float | None) -> str:
    return "time [s]" if ts else "sample"


# ----------------------------------------------------------------------------- data
def overview_figure(
    data: Any, estimation: tuple[int, int | None] | None, validation: tuple[int, int | None] | None
) -> Any:
    """Every signal of every experiment, the estimation and validation ranges shaded."""
    names = [*data.inputs, *data.outputs]
    exps = data.experiments
    fig = _new_figure(9.0, 0.6 + 1.7 * len(names))
    axes = fig.subplots(len(names), len(exps), squeeze=False, sharex="col")
    ts = data.sampling_time
    for c, exp in enumerate(exps):
        t = _time(ts, 0, exp.n_samples)
        values = np.hstack([exp.u, exp.y])
        for r, name in enumerate(names):
            ax = axes[r, c]
            _line(ax, t, values[:, r], color="C0" if r < len(data.inputs) else "C3")
            for rng, colour, label in (
                (estimation, "C2", "estimation range"),
                (validation, "C1", "validation range"),
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
    _legend_outside(fig, list(axes.flat))
    return fig


# ----------------------------------------------------------------------------- scores
def comparison_figure(
    rows: Sequence[tuple[str, float, float | None]], output: str, where: str = "validation data"
) -> Any:
    """Fit % of free-run simulation and of one-step prediction per model (one output).
    Model names are wrapped at spaces; the legend sits above the bars."""
    labels = [wrap(r[0], 44) for r in rows]
    lines = sum(label.count("\n") + 1 for label in labels)
    fig = _new_figure(9.0, 1.2 + 0.2 * lines + 0.3 * len(rows))
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
    ax.set_yticks(y, labels, fontsize=7)
    ax.invert_yaxis()
    ax.set_xlim(max(low, -100.0), 112)
    ax.axvline(0, color="0.3", lw=0.6)
    ax.set_xlabel(f"fit % of {output} on the {where} (100 % = perfect)", fontsize=8)
    ax.tick_params(labelsize=7)
    _legend_outside(fig, [ax])
    return fig


def search_figure(
    points: Sequence[tuple[str, int, float]],
    chosen: int | None = 0,
    baseline: int | None = None,
) -> Any:
    """Every scored candidate of a search: cross-validated free-run RMSE against the
    number of parameters, coloured by structure (``points``: ``(structure,
    parameters, RMSE)``); the chosen one starred, the linear baseline boxed."""
    fig = _new_figure(9.0, 3.6)
    ax = fig.subplots()
    structures = list(dict.fromkeys(p[0] for p in points))
    x = np.array([p[1] for p in points], float)
    y = np.array([p[2] for p in points], float)
    for k, name in enumerate(structures):
        mine = [i for i, p in enumerate(points) if p[0] == name]
        ax.plot(x[mine], y[mine], "o", ms=4, alpha=0.75, color=f"C{k % 10}", label=name)
    for index, marker, label in ((chosen, "*", "chosen"), (baseline, "s", "linear baseline")):
        if index is not None:
            ax.plot(x[index], y[index], marker, ms=13, mfc="none", mec="k", mew=1.3, label=label)
    finite = y[np.isfinite(y) & (y > 0)]
    if finite.size and finite.max() > 10 * finite.min():
        ax.set_yscale("log")
    ax.set_xlabel("parameters", fontsize=8)
    ax.set_ylabel("cross-validated free-run RMSE", fontsize=8)
    ax.tick_params(labelsize=7)
    _legend_outside(fig, [ax], ncol=5)
    return fig


# ----------------------------------------------------------------------------- outputs
def zoom_window(
    y: np.ndarray, skip: int = 0, y_hat: np.ndarray | None = None
) -> tuple[int, int] | None:
    """The samples ``(start, stop)`` of a record's zoom, or None for a record short
    enough to be read whole (at most :data:`MAX_POINTS` samples).

    The window spans four periods of the measured output's dominant frequency (the
    peak of its periodogram), 200 to 600 samples: few enough that measured and model
    output can be told apart at the figure's width. With the model's output ``y_hat``
    it lies where the model errs most (the largest sum of squared errors over the
    window, each output's error divided by that output's standard deviation), wherever
    that is in the record; without it, where the measured output varies most. ``y``
    and ``y_hat`` are (N,) or (N, ny); the first ``skip`` samples (initial conditions)
    are left out.

    >>> t = np.arange(40_000)
    >>> y = np.sin(2 * np.pi * t / 100)
    >>> start, stop = zoom_window(y, 0, y + (np.abs(t - 12_000) < 50))
    >>> stop - start, start <= 11_950 and 12_050 <= stop
    (400, True)
    >>> zoom_window(np.zeros(1000)) is None
    True
    """
    y = np.asarray(y, float).reshape(len(y), -1)
    n = y.shape[0]
    if n <= MAX_POINTS:
        return None
    scale = np.maximum(np.nanstd(y[skip:], axis=0), 1e-300)
    part = np.nan_to_num((y[skip:] - np.nanmean(y[skip:], axis=0)) / scale)
    power = np.sum(np.abs(np.fft.rfft(part, axis=0)) ** 2, axis=1)
    freqs = np.fft.rfftfreq(part.shape[0])
    peak = int(np.argmax(power[1:])) + 1 if power.size > 1 else 0
    length = int(np.clip(4.0 / freqs[peak], 200, 600)) if peak else 400
    length = min(length, part.shape[0])
    if y_hat is not None:
        error = (y - np.asarray(y_hat, float).reshape(y.shape))[skip:] / scale
        part = np.clip(np.nan_to_num(error, nan=0.0, posinf=1e6, neginf=-1e6), -1e6, 1e6)
    energy = np.concatenate([[0.0], np.cumsum(np.sum(part**2, axis=1))])
    windowed = energy[length:] - energy[:-length]
    start = int(np.argmax(windowed))
    return skip + start, skip + start + length


def validation_figure(
    output: Any,
    first: int,
    bands: Sequence[tuple[np.ndarray, np.ndarray] | None] = (),
    where: str = "validation data",
) -> Any:
    """Measured output and model output (top) and the residual (below) of every output
    and experiment of a :class:`~blockid.evaluation.ModelOutput`; on a record longer
    than :data:`MAX_POINTS` samples a third panel zooms on the :func:`zoom_window`
    (shaded in the full view).

    ``first`` is the index of the range's first sample in each experiment (the time
    axis is that of the record). ``bands``: per experiment, the lower and upper edge
    (N, ny) of a 95 % band on the model output, shaded when given.
    """
    data = output.data
    mode = "free-run simulation" if output.mode == "simulation" else "one-step prediction"
    exps = data.experiments
    windows = [
        zoom_window(exp.y, output.skip, y_hat)
        for exp, y_hat in zip(exps, output.outputs, strict=True)
    ]
    per = 3 if any(w is not None for w in windows) else 2
    rows = per * len(data.outputs)
    fig = _new_figure(9.0, 0.7 + 1.8 * rows)
    axes = fig.subplots(rows, len(exps), squeeze=False)
    ts = data.sampling_time
    for c, (exp, y_hat) in enumerate(zip(exps, output.outputs, strict=True)):
        t = _time(ts, first, exp.n_samples)
        band = bands[c] if c < len(bands) else None
        window = windows[c]
        for j, name in enumerate(data.outputs):
            ax, ax_e = axes[per * j, c], axes[per * j + 1, c]
            ax_e.sharex(ax)
            # the model under the measurement, wider and lighter, the measurement on top,
            # thin and dark (its envelope by its edges): neither hides the other
            _line(ax, t, y_hat[:, j], 0.55, lw=1.6, color="C1", alpha=0.85, label=mode,
                  zorder=2)  # fmt: skip
            _line(ax, t, exp.y[:, j], edges=True, lw=0.7, color="0.1", label="measured",
                  zorder=3)  # fmt: skip
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
            if per == 3:
                zoom = axes[per * j + 2, c]
                _zoom(zoom, ax, t, (exp.y[:, j], y_hat[:, j]), band, j, window, (first, ts))
            ax_e.set_xlabel(_time_label(ts), fontsize=8)
            for a in axes[per * j : per * j + per, c]:
                a.tick_params(labelsize=7)
    _legend_outside(fig, list(axes.flat))
    return fig


def zoom_title(window: tuple[int, int], first: int, ts: float | None) -> str:
    """Where a zoom is: ``"samples 38643 to 39042 of the record (t = 386.4 to 390.4 s)"``
    (``window`` within a range that starts at sample ``first`` of the record)."""
    a, b = first + window[0], first + window[1] - 1
    when = f" (t = {a * ts:.6g} to {b * ts:.6g} s)" if ts else ""
    return f"samples {a} to {b} of the record{when}"


def _zoom(
    ax: Any,
    full: Any,
    t: np.ndarray,
    curves: tuple[np.ndarray, np.ndarray],
    band: tuple[np.ndarray, np.ndarray] | None,
    j: int,
    window: tuple[int, int] | None,
    where: tuple[int, float | None],
) -> None:
    """The zoom panel (measured drawn over the model, so neither hides the other)."""
    if window is None:  # this experiment is short: the full view shows every sample
        ax.axis("off")
        return
    a, b = window
    if band is not None:
        ax.fill_between(t[a:b], band[0][a:b, j], band[1][a:b, j], color="C1", alpha=0.25, lw=0)
    ax.plot(t[a:b], curves[1][a:b], color="C1", lw=1.6, alpha=0.9)
    ax.plot(t[a:b], curves[0][a:b], color="0.15", lw=0.8, label="measured")
    full.axvspan(t[a], t[b - 1], color="0.5", alpha=0.3, lw=0, label="zoomed window")
    for edge in (t[a], t[b - 1]):  # a narrow window stays visible in a long record
        full.axvline(edge, color="0.35", lw=0.7, zorder=1)
    ax.set_title(f"zoom on {zoom_title(window, *where)}", fontsize=9)
    ax.set_ylabel(f"{full.get_ylabel()}\n(zoom)", fontsize=8)
    ax.set_xlabel(_time_label(where[1]), fontsize=8)


def _score(metrics: dict[str, dict[str, float]], name: str) -> str:
    return f"fit {metrics['fit_percent'][name]:.1f} %, RMSE {metrics['rmse'][name]:.4g}"


# ----------------------------------------------------------------------------- blocks
def static_curve(
    block: Any,
    grid: np.ndarray,
    models: Sequence[Any] = (),
    index: int | None = None,
    block_of: Callable[[Any], Any] | None = None,
) -> dict[str, Any]:
    """A static block's curve on ``grid``, its deviation from the best straight line,
    and the 95 % bands of both over the drawn ``models`` (block ``index`` of each, or
    what ``block_of(model)`` returns: a callable of the grid), kept only where they are
    meaningful.

    Returns a dict: ``w`` (the curve), ``line`` (``(offset, slope)`` of the least-squares
    line through the curve on the grid), ``deviation`` (``w`` minus that line), ``band``
    and ``deviation_band`` (``(lower, upper)`` or None), and ``notes`` (why a band is not
    drawn). The deviation band is that of each drawn curve's own deviation from its own
    best line: how sure the *shape* is, whatever the gain. A band whose median width is
    more than :data:`BAND_LIMIT` times the range of its curve is dropped with a note.

    >>> from blockid.blocks import Polynomial
    >>> c = static_curve(Polynomial([0.0, 1.0, 0.0, 0.2]), np.linspace(-1, 1, 5))
    >>> np.round(c["line"], 3).tolist(), np.round(c["deviation"], 3).tolist()
    ([0.0, 1.17], [-0.03, 0.06, 0.0, -0.06, 0.03])
    """
    grid = np.asarray(grid, float)
    basis = np.column_stack([np.ones_like(grid), grid])

    def deviation(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        coef = np.linalg.lstsq(basis, w, rcond=None)[0]
        return coef, w - basis @ coef

    with np.errstate(all="ignore"):
        w = np.asarray(block(grid), float)
    line, dev = deviation(w)
    out: dict[str, Any] = {
        "w": w,
        "line": line,
        "deviation": dev,
        "band": None,
        "deviation_band": None,
        "notes": [],
    }
    if not models or (index is None and block_of is None):
        return out
    if block_of is None:
        block_of = lambda m: m.blocks[index]  # noqa: E731
    band = sampled_band(models, lambda m: block_of(m)(grid))
    dev_band = sampled_band(models, lambda m: deviation(np.asarray(block_of(m)(grid)))[1])
    if band is None:
        out["notes"].append("too few valid parameter draws for a band")
        return out
    for key, curve, b, what in (
        ("band", w, band, "curve"),
        ("deviation_band", dev, dev_band, "deviation"),
    ):
        if b is None:
            continue
        width = float(np.median(b[1] - b[0]))
        span = float(np.ptp(curve))
        if width > BAND_LIMIT * span:
            ratio = "infinitely" if span == 0 else f"{width / span:.3g} times"
            out["notes"].append(
                f"the 95 % band of the {what} is {ratio} wider than the {what}'s own range "
                "(median width over the input range): the data do not pin it down, so no "
                "band is drawn on it"
            )
            continue
        out[key] = b
    return out


def block_signal(model: Any, i: int, inputs: list[np.ndarray] | None) -> np.ndarray | None:
    """The signal entering block ``i`` (from ``inputs``, the model's ``block_inputs``),
    or without them the two ends of the range recorded in estimation, or None."""
    if inputs is not None:
        return np.asarray(inputs[i], float)
    key = getattr(model, "_range_key", None)
    recorded = getattr(model, "ranges", {}) or {}
    if key is not None and key(i) in recorded:
        return np.asarray(recorded[key(i)], float)
    return None


def _limits(curve: np.ndarray, band: tuple[np.ndarray, np.ndarray] | None) -> tuple[float, float]:
    """y limits that fit the curve (padded by 10 % of its range) and the band up to one
    more range on either side (a wider band is clipped by the axes)."""
    lo, hi = float(np.min(curve)), float(np.max(curve))
    span = hi - lo or max(abs(hi), 1e-12)
    if band is not None:
        lo = max(min(lo, float(np.min(band[0]))), lo - span)
        hi = min(max(hi, float(np.max(band[1]))), hi + span)
    return lo - 0.1 * span, hi + 0.1 * span


def _static_panels(
    fig: Any, grid_spec: Any, r: int, x: np.ndarray, c: dict[str, Any], labels: tuple[str, ...]
) -> None:
    """Row ``r``: a static block's curve ``c`` (:func:`static_curve`) against ``x``, and
    beside it its deviation from the best straight line, each with its band if any."""
    name, xlabel, ylabel = labels
    ax, ax_d = fig.add_subplot(grid_spec[r, 0]), fig.add_subplot(grid_spec[r, 1])
    ax.plot(x, c["w"], color="C0", lw=1.3, label="identified block")
    ax.plot(x, c["w"] - c["deviation"], color="0.5", ls=":", lw=0.9, label="best straight line")
    ax_d.plot(x, c["deviation"], color="C0", lw=1.3)
    ax_d.axhline(0.0, color="0.5", ls=":", lw=0.9)
    for a, key, curve in ((ax, "band", c["w"]), (ax_d, "deviation_band", c["deviation"])):
        b = c[key]
        if b is not None:
            a.fill_between(x, b[0], b[1], color="C0", alpha=0.2, lw=0, label="95 % band")
        a.set_ylim(*_limits(curve, b))
    ax.set_title(wrap(name, 48), fontsize=9)
    ax.set_xlabel(xlabel, fontsize=8)
    ax.set_ylabel(wrap(ylabel, 30), fontsize=8)
    share = np.ptp(c["deviation"]) / max(np.ptp(c["w"]), 1e-300)
    ax_d.set_title(
        f"deviation from the best straight line ({100 * share:.3g} % of the range)", fontsize=9
    )
    ax_d.set_xlabel(xlabel, fontsize=8)
    ax_d.set_ylabel("curve minus line", fontsize=8)


def channel_curve(model: Any, curve: dict[str, Any], models: Sequence[Any] = ()) -> dict[str, Any]:
    """:func:`static_curve` of one block of a model with a block per channel, ``curve``
    one of its ``static_curves()`` (the block on its grid, each drawn model's the same
    block, :meth:`~blockid.models.block_state_space.BlockStateSpace.block_curve`)."""
    side, k = curve["side"], curve["index"]
    return static_curve(
        lambda g: model.block_curve(side, k, g),
        curve["grid"],
        models,
        block_of=lambda m: lambda g: m.block_curve(side, k, g),
    )


def channel_blocks_figure(
    model: Any, u: np.ndarray | None = None, models: Sequence[Any] = ()
) -> tuple[Any, list[str]] | None:
    """The static blocks of a model with a block per channel (a block state space:
    :meth:`~blockid.models.block_state_space.BlockStateSpace.static_curves`), each over
    the range its argument takes when the inputs ``u`` (N, nu) are simulated (without
    ``u``: the range recorded in estimation), as :func:`blocks_figure` draws a chain's:
    the curve and its deviation from the best straight line, each with the 95 % band of
    the drawn ``models`` where it is meaningful. None when no block has a range."""
    curves = model.static_curves(u)
    if not curves:
        return None
    fig = _new_figure(9.0, 0.5 + 2.9 * len(curves))
    grid_spec = fig.add_gridspec(len(curves), 2)
    notes: list[str] = []
    for r, cv in enumerate(curves):
        c = channel_curve(model, cv, models)
        notes += [f"{cv['title']}: {n}." for n in c["notes"]]
        _static_panels(fig, grid_spec, r, cv["x"], c, (cv["title"], cv["xlabel"], cv["ylabel"]))
    for ax in fig.axes:
        ax.tick_params(labelsize=7)
    _legend_outside(fig, fig.axes)
    return fig, notes


def blocks_figure(
    model: Any, u: np.ndarray | None = None, models: Sequence[Any] = ()
) -> tuple[Any, list[str]]:
    """The identified nonlinear blocks, each over the range its input takes when ``u``
    is simulated (without ``u``: the range recorded in estimation, else the block's
    default).

    A static block gets two panels: its curve, with axes chosen by the curve, and its
    deviation from the best straight line (:func:`static_curve`), which shows the
    nonlinearity at a scale where it is visible; each with the 95 % band of the drawn
    ``models`` where it is meaningful. A block with memory (backlash) is drawn as its
    loop. Returns the figure and sentences for the caption (bands not drawn, and why).
    """
    from blockid.plotting.blocks import block_name, default_range
    from blockid.plotting.figures import block_roles

    panels = block_roles(model)
    inputs = None if u is None else model.block_inputs(np.asarray(u, float).reshape(-1, 1))
    fig = _new_figure(9.0, 0.5 + 2.9 * max(len(panels), 1))
    grid_spec = fig.add_gridspec(max(len(panels), 1), 2)
    notes: list[str] = []
    for r, (i, block, which, xlabel, ylabel) in enumerate(panels):
        name = f"{which}: {block_name(block)}"
        s = block_signal(model, i, inputs)
        if block.role != "static":  # a loop: one wide panel
            ax = fig.add_subplot(grid_spec[r, :])
            block.plot(ax=ax, u=s if s is not None and s.size > 2 else None)
            if ax.get_legend() is not None:
                ax.get_legend().remove()
            ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
            ax.set_title(name, fontsize=9)
            ax.set_xlabel(xlabel, fontsize=8)
            if models:
                notes.append(f"No band for the {name} (it has memory).")
            continue
        lo, hi = (float(np.min(s)), float(np.max(s))) if s is not None else default_range(block)
        if not hi > lo:
            lo, hi = lo - 0.5, hi + 0.5
        grid = np.linspace(lo, hi, 400)
        c = static_curve(block, grid, models, i)
        notes += [f"{name}: {n}." for n in c["notes"]]
        _static_panels(fig, grid_spec, r, grid, c, (name, xlabel, ylabel))
    for ax in fig.axes:
        ax.tick_params(labelsize=7)
    _legend_outside(fig, [a for a in fig.axes if a.get_legend() is None])
    return fig, notes


# ----------------------------------------------------------------------------- recursive
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
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0), frameon=False)
        ax.tick_params(labelsize=7)
    for ax in list(axes.flat)[len(shown) :]:
        ax.axis("off")
    for ax in axes[-1]:
        ax.set_xlabel("sample (all passes over the estimation data)", fontsize=8)
    return fig
