"""What models and fits show in a notebook, and the figures their ``.plot()`` returns.

``Model._repr_html_`` and ``FitResult._repr_html_`` hand off to :func:`model_html` and
:func:`fit_html`: a compact summary in the manner of scikit-learn's estimators and
pandas' frames (the structure and its blocks, the parameters with their standard errors,
the scores on the estimation data, the linear dynamics in a line each, and the static
curves as a small embedded PNG). ``Model.plot`` and ``FitResult.plot`` hand off to
:func:`model_figures`: the report's figures of that model, as
:class:`matplotlib.figure.Figure` objects (no pyplot: nothing is shown twice, nothing
is kept open). matplotlib is imported only when a figure is drawn.
"""

from __future__ import annotations

from collections.abc import Callable
from html import escape
from typing import Any

import numpy as np

from blockid.plotting.blocks import block_name
from blockid.plotting.html import details, encode_png, image, paragraph, table
from blockid.plotting.invariants import basis_dependent, invariants, matrix_rows
from blockid.plotting.linear import describe_dynamics, linear_dynamics
from blockid.plotting.parameters import parameter_table

__all__ = [
    "FIGURES",
    "STYLE",
    "blocks_thumbnail",
    "describe_structure",
    "fit_html",
    "linear_summary",
    "model_figures",
    "model_html",
    "parameter_parts",
]

#: The figures :func:`model_figures` can draw, in the order it draws them.
FIGURES = ("output", "blocks", "linear", "parameters")

#: Parameter tables longer than this are folded (``<details>``) in a summary.
_FOLD = 20

#: The style of a summary's ``<div>`` (inline: a notebook may drop style sheets).
STYLE = (
    "font-family: sans-serif; font-size: 13px; line-height: 1.35; max-width: 52em; "
    "overflow-wrap: anywhere"
)


# ----------------------------------------------------------------------------- text
def describe_structure(model: Any) -> str:
    """The chain of a model in words: ``"two-segment polynomial -> linear (na=3, nb=3,
    nk=8) -> polynomial"``; the orders of an ARX or state-space model otherwise."""
    blocks = getattr(model, "blocks", None)
    if blocks is not None:
        parts = []
        for b in blocks:
            if b.role == "linear":
                parts.append(f"linear (na={b.na}, nb={b.nb}, nk={b.nk})")
            elif b is getattr(model, "feedback", None):
                parts.append(f"fed back: {block_name(b)}")
            else:
                parts.append(block_name(b))
        return " \u2192 ".join(parts)
    if hasattr(model, "nx"):
        extra = getattr(model, "n_monomials", 0)
        return f"{model.nx} states" + (f", {extra} monomials" if extra else "")
    if hasattr(model, "na") and hasattr(model, "nk"):
        na, nb, nk = (np.asarray(getattr(model, k)) for k in ("na", "nb", "nk"))
        if na.size == 1 and nb.size == 1:
            return f"na={int(na.flat[0])}, nb={int(nb.flat[0])}, nk={int(nk.flat[0])}"
        return f"orders na {na.tolist()}, nb {nb.tolist()}, nk {nk.tolist()}"
    return ""


def _signals(model: Any) -> str:
    inputs = ", ".join(getattr(model, "inputs", ()))
    outputs = ", ".join(getattr(model, "outputs", ()))
    ts = getattr(model, "sampling_time", None)
    sampling = f"sampling time {ts:g} s" if ts else "no sampling time (samples)"
    return f"{inputs} \u2192 {outputs}; {sampling}"


def linear_summary(model: Any) -> list[str]:
    """One sentence per linear transfer function
    (:func:`~blockid.plotting.linear.describe_dynamics`): static gain, delay, stability
    and the least damped mode, a negative real pole named a mode at the Nyquist
    frequency."""
    return [describe_dynamics(g) for g in linear_dynamics(model)]


def parameter_parts(
    model: Any, fit: Any = None, para: Callable[[str], str] = paragraph
) -> list[str]:
    """The HTML of a model's parameters (the report's and the notebook's): a table of
    every estimated parameter with its standard error, and what the table leaves out.

    A state space (:mod:`blockid.plotting.invariants`) gets instead what does not depend
    on its state basis: its poles, static gains, Hankel singular values and Markov
    parameters with their standard errors, then the estimated parameters that do not
    depend on the basis (``D``, blocks, ...); the entries of ``A``, ``B``, ``C`` (and
    ``E``, ...) folded below, values only (their standard errors are those of an
    arbitrary basis). ``para`` makes a paragraph of plain text."""
    t = parameter_table(model, fit)
    if not t.names:
        return []
    notes = [para(n) for n in t.notes()]
    mask = basis_dependent(model)
    found = invariants(model, fit) if mask is not None else None
    if found is None:
        return [table(t.HEADER, t.rows(), digits=6), *notes]
    rows = [r for r, dependent in zip(t.rows(), mask, strict=True) if not dependent]
    parts = [
        para(
            f"A state space is the same model in any state basis (x -> T x), so the "
            f"{int(mask.sum())} entries of {_listed(model, mask)} are unique only up to "
            "that basis: what the data determine is listed instead, in "
            f"{found.units}, with standard errors by the delta method"
            + (
                ""
                if found.standard_errors is not None
                else " (none: the fit carries no covariance)"
            )
            + ". Poles and zeros of every input-output pair, with time constants and "
            "oscillations, are under Linear dynamics."
        ),
        table(("basis-free quantity", *t.HEADER[1:]), found.rows(), digits=6),
        *[para(n) for n in found.notes],
    ]
    if rows:
        parts.append(table(t.HEADER, rows, digits=6))
    parts += notes
    parts.append(
        details(
            f"The matrices in the fitted state basis ({int(mask.sum())} entries; they "
            "depend on the basis)",
            [
                para(
                    "Basis-dependent: another state basis gives other numbers for the "
                    "same model, so neither these values nor their standard errors mean "
                    "anything one by one; no standard errors are shown."
                ),
                table(["matrix row", "values (fitted basis)"], matrix_rows(model)),
            ],
        )
    )
    return parts


def _listed(model: Any, mask: np.ndarray) -> str:
    """``"A, B and C"``: the matrices ``mask`` marks."""
    names = model.free_parameter_names()
    keys = list(dict.fromkeys(n.partition("[")[0] for n, d in zip(names, mask, strict=True) if d))
    return ", ".join(keys[:-1]) + f" and {keys[-1]}" if len(keys) > 1 else keys[0]


def _parameters_html(model: Any, fit: Any) -> str:
    parts = parameter_parts(model, fit, lambda n: f"<p style='margin:.2em 0'>{escape(n)}</p>")
    if not parts:
        return ""
    n = len(parameter_table(model, fit).names)
    summary = f"{n} estimated parameters"
    body = "".join(parts)
    if n > _FOLD and basis_dependent(model) is None:
        return f"<details><summary>{summary}</summary>{body}</details>"
    return f"<p style='margin:.4em 0 .1em'><b>{summary}</b></p>{body}"


def _thumbnail_panels(model: Any, draws: list) -> list[tuple[str, str, np.ndarray, dict]]:
    """``(title, x label, x, curve)`` of each static block over the range recorded in
    estimation (:func:`~blockid.plotting.report_figures.static_curve`)."""
    from blockid.models.block_state_space import BlockStateSpace
    from blockid.plotting.blocks import default_range
    from blockid.plotting.figures import block_roles
    from blockid.plotting.report_figures import block_signal, channel_curve, static_curve

    if isinstance(model, BlockStateSpace):  # a block per channel
        curves = model.static_curves(n_points=200)
        return [(c["title"], c["xlabel"], c["x"], channel_curve(model, c, draws)) for c in curves]
    if getattr(model, "blocks", None) is None:
        return []
    out = []
    for i, block, which, xlabel, _ in block_roles(model):
        if block.role != "static":
            continue
        s = block_signal(model, i, None)
        lo, hi = (float(np.min(s)), float(np.max(s))) if s is not None else default_range(block)
        grid = np.linspace(lo, hi if hi > lo else lo + 1.0, 200)
        out.append(
            (f"{which}: {block_name(block)}", xlabel, grid, static_curve(block, grid, draws, i))
        )
    return out


def blocks_thumbnail(model: Any, fit: Any = None, dpi: int = 80) -> Any | None:
    """The static blocks' curves side by side, small (the 95 % band where the fit
    carries standard errors and the band is meaningful), each over the range its
    argument covered in estimation, or None without such blocks. A block state space's
    blocks too (one per channel)."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    from blockid.plotting.report_figures import wrap
    from blockid.plotting.uncertainty import fit_draws

    if getattr(model, "blocks", None) is None and not hasattr(model, "static_curves"):
        return None
    panels = _thumbnail_panels(model, fit_draws(fit, n=100))
    if not panels:
        return None
    fig = Figure(figsize=(3.0 * len(panels), 2.3), dpi=dpi, layout="constrained")
    for ax, (title, xlabel, x, c) in zip(
        fig.subplots(1, len(panels), squeeze=False)[0], panels, strict=True
    ):
        if c["band"] is not None:
            ax.fill_between(x, c["band"][0], c["band"][1], color="C0", alpha=0.2, lw=0)
        ax.plot(x, c["w"], color="C0", lw=1.4)
        ax.set_title(wrap(title, 36), fontsize=8)
        ax.set_xlabel(xlabel.split(" (")[0], fontsize=7)
        ax.tick_params(labelsize=7)
        ax.xaxis.set_major_locator(MaxNLocator(4))
        ax.yaxis.set_major_locator(MaxNLocator(5))
    return fig


def model_html(model: Any, fit: Any = None) -> str:
    """A compact HTML summary of a model (and of the fit that made it)."""
    parts = [
        f"<p style='margin:.2em 0'><b>{escape(getattr(model, 'structure', '') or 'model')} "
        f"model</b>: {escape(_signals(model))}</p>"
    ]
    chain = describe_structure(model)
    if chain:
        parts.append(f"<p style='margin:.2em 0'>{escape(chain)}</p>")
    if fit is not None:
        parts.append(f"<p style='margin:.2em 0'>{escape(_fit_line(fit))}</p>")
    parts.append(_parameters_html(model, fit))
    lines = linear_summary(model)
    if lines:
        items = "".join(f"<li>{escape(x)}</li>" for x in lines)
        parts.append(f"<ul style='margin:.3em 0; padding-left:1.2em'>{items}</ul>")
    thumb = blocks_thumbnail(model, fit)
    if thumb is not None:
        parts.append(
            image(encode_png(thumb, dpi=80), "the static blocks' curves", "max-width:100%")
        )
    return f'<div class="blockid-summary" style="{STYLE}">' + "\n".join(parts) + "</div>"


def _fit_line(fit: Any) -> str:
    mode = "free-run simulation" if fit.metrics_mode == "simulation" else "one-step prediction"
    scores = []
    metrics = fit.estimation_metrics or {}
    for output in metrics.get("fit_percent", {}):
        fit_pct = metrics["fit_percent"][output]
        rmse = metrics.get("rmse", {}).get(output, float("nan"))
        scores.append(f"{output}: fit {fit_pct:.1f} %, RMSE {rmse:.4g}")
    shown = "; ".join(scores) if scores else "no scores recorded"
    return (
        f"Fitted by {fit.method} on {fit.n_samples} samples; {mode} on the estimation "
        f"data: {shown}."
    )


def fit_html(fit: Any) -> str:
    """A compact HTML summary of a :class:`~blockid.fitting.result.FitResult`."""
    return model_html(fit.model, fit)


# ----------------------------------------------------------------------------- figures
def model_figures(
    model: Any, data: Any = None, *, fit: Any = None, which: str | None = None
) -> Any:
    """The report's figures of ``model``: a dict ``name -> Figure`` of those that apply,
    or the one named by ``which``.

    ``"output"`` (with ``data``): measured against free-run simulated output on
    ``data`` and the residual, a zoom on long records, the 95 % band when ``fit``
    carries standard errors; ``"blocks"``: the nonlinear blocks over the range their
    input takes on ``data`` (without it: the range recorded in estimation), with their
    deviation from a straight line; ``"linear"``: poles and zeros, step response and
    Bode plot of every linear transfer function; ``"parameters"``: the trajectories a
    recursive estimator recorded in ``fit.history``.
    """
    from blockid.errors import ParameterError
    from blockid.plotting import report_figures as rf
    from blockid.plotting.linear import linear_figure
    from blockid.plotting.uncertainty import fit_draws, output_bands

    if which is not None and which not in FIGURES:
        raise ParameterError(
            f"which={which!r}: choose one of {', '.join(FIGURES)}", parameter="which"
        )
    wanted = FIGURES if which is None else (which,)
    draws = fit_draws(fit) if {"output", "blocks"} & set(wanted) else []
    out: dict[str, Any] = {}
    if "output" in wanted and data is not None:
        from blockid.evaluation.validate import evaluate

        simulated = evaluate(model, data, "simulation")
        bands, _ = output_bands(fit, simulated, draws) if fit is not None else ([], "")
        out["output"] = rf.validation_figure(simulated, 0, bands, "given data")
    from blockid.models.block_state_space import BlockStateSpace

    blocks = getattr(model, "blocks", None)
    if "blocks" in wanted and isinstance(model, BlockStateSpace):
        u = None if data is None else np.vstack([x.u for x in data.experiments])
        drawn = rf.channel_blocks_figure(model, u, draws)
        if drawn is not None:
            out["blocks"] = drawn[0]
    elif "blocks" in wanted and blocks and any(b.role != "linear" for b in blocks):
        u = None
        if data is not None and len(getattr(model, "inputs", ())) == 1:
            u = np.concatenate([x.u[:, 0] for x in data.experiments])
        out["blocks"] = rf.blocks_figure(model, u, draws)[0]
    systems = linear_dynamics(model) if "linear" in wanted else []
    if systems:
        out["linear"] = linear_figure(systems)
    history = getattr(fit, "history", None) or {}
    if "parameters" in wanted and len(history.get("theta", ())) and "names" in history:
        out["parameters"] = rf.history_figure(history)
    if which is None:
        return out
    if which not in out:
        reason = "no data were given" if which == "output" else "the model has none"
        raise ParameterError(f"no {which!r} figure: {reason}", parameter="which")
    return out[which]
