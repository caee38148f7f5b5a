"""The report's sections about each model itself: its parameters with their standard
errors, its linear dynamics, its nonlinear blocks and a recursive estimator's parameter
trajectories."""

from __future__ import annotations

import numpy as np

from blockid.data.dataset import Dataset
from blockid.models.block_state_space import BlockStateSpace
from blockid.plotting import report_figures as figures
from blockid.plotting.html import encode_png
from blockid.plotting.linear import linear_dynamics, linear_figure, pole_rows
from blockid.plotting.notebook import linear_summary, parameter_parts
from blockid.plotting.uncertainty import free_covariance
from blockid.reporting.entries import Entry, heading
from blockid.reporting.html import figure, paragraph, section, table

__all__ = ["blocks_section", "histories_section", "linear_section", "parameters_section"]

_NO_UNCERTAINTY = (
    "No uncertainty available: the fit carries no parameter standard errors, so no "
    "confidence band is drawn."
)


def parameters_section(entries: list[Entry]) -> str:
    """Per model: every estimated parameter, its value, standard error and relative
    standard error, and what the table leaves out (fixed parameters, operating point);
    for a state space, what does not depend on its state basis, the matrices folded
    (:func:`~blockid.plotting.notebook.parameter_parts`)."""
    parts = [
        paragraph(
            "The parameters each fit estimated, in full precision. Standard errors assume "
            "white noise on the output (the output-error noise model; an ARX model's, "
            "white equation error): with process noise they are too small. A relative "
            "standard error near or above 100 % means the data hardly determine the "
            "parameter. A state space's matrices depend on its state basis: it is "
            "summarised by what does not (poles, static gains, Hankel singular values, "
            "Markov parameters), its matrices folded below that."
        )
    ]
    shown = 0
    for e in entries:
        if e.model is None:
            continue
        found = parameter_parts(e.model, e.fit)
        if not found:
            continue
        shown += 1
        parts.append(heading(e))
        parts += found
    if not shown:
        parts.append(paragraph("No model was identified."))
    return section("parameters", "Parameters", parts)


def _units(ts: float | None) -> str:
    if ts:
        return (
            f"time in seconds, frequency in hertz up to the Nyquist frequency "
            f"{0.5 / ts:.4g} Hz (sampling time {ts:g} s)"
        )
    return "time in samples, frequency in rad/sample up to pi (no sampling time given)"


def linear_section(entries: list[Entry]) -> str:
    """Per model and linear transfer function: its static gain, delay and slowest pole,
    a table of its poles and zeros, and a figure of the z-plane, the step response and
    the Bode plot."""
    parts = [
        paragraph(
            "The linear dynamics of each model: every linear block of a block-oriented "
            "model (input side first; it acts on the signal between the blocks, relative "
            "to the operating point), an ARX model with one input and one output, the "
            "forward path of a feedback model, or the linear part of a state-space model. "
            "Poles at z = 0 are part of the delay; a pole close to a zero nearly cancels. "
            "A pole's time constant is that of its envelope |p|^k; a negative real pole "
            "alternates its sign every sample: a mode at the Nyquist frequency (period 2 "
            "samples), named so."
        )
    ]
    shown = 0
    for e in entries:
        if e.model is None:
            continue
        systems = linear_dynamics(e.model)
        if not systems:
            signals = len(getattr(e.model, "inputs", ())) + len(getattr(e.model, "outputs", ()))
            if signals > 2:
                text = "Several inputs or outputs: no single transfer function is drawn."
                parts += [heading(e), paragraph(text)]
            continue
        shown += 1
        parts.append(heading(e))
        for g, text in zip(systems, linear_summary(e.model), strict=True):
            parts.append(paragraph(text))
            parts.append(table(["", "value", "|z|", "time constant", "oscillation"], pole_rows(g)))
        parts.append(
            figure(
                encode_png(linear_figure(systems)),
                f"{e.label}: linear dynamics",
                f"{e.label}: for each linear transfer function, its poles (x) and zeros (o) "
                "in the z-plane with the unit circle, its response to a unit step from rest "
                "(the static gain G(1) dashed) and its frequency response G(exp(j w)) "
                f"(magnitude and phase); {_units(systems[0].dt)}.",
            )
        )
    if not shown:
        parts.append(paragraph("No model with a linear transfer function was identified."))
    return section("linear", "Linear dynamics", parts)


def _band_text(e: Entry, models: list) -> str:
    if not models:
        return _NO_UNCERTAINTY
    source = (
        "the parameter covariance"
        if free_covariance(e.fit) is not None
        else "the standard errors (independent normals)"
    )
    return (
        f"Shaded: 95 % band over {len(models)} parameter draws from {source}, where it is "
        f"narrower than {figures.BAND_LIMIT:g} times the curve's range."
    )


#: What the right-hand panels of the blocks' figures show.
_DEVIATION = (
    "Right: the curve minus its least-squares straight line over that range, which shows "
    "the nonlinearity at its own scale (the band there is that of each drawn curve's own "
    "deviation: how sure the shape is, whatever the gain)."
)


def blocks_section(
    entries: list[Entry], estimation: Dataset, est_text: str, draws: dict[int, list]
) -> str:
    """Per block-oriented model: its nonlinear blocks over the range their inputs take
    on the estimation data, and their deviation from the best straight line."""
    parts = []
    for e in entries:
        model = e.model
        if isinstance(model, BlockStateSpace):
            parts += _channel_blocks(e, estimation, est_text, draws.get(id(e), []))
            continue
        blocks = getattr(model, "blocks", None)
        if blocks is None or all(b.role == "linear" for b in blocks):
            continue
        if len(model.inputs) != 1 or tuple(model.inputs) != tuple(estimation.inputs):
            continue
        u = np.concatenate([x.u[:, 0] for x in estimation.experiments])
        models = draws.get(id(e), [])
        fig, notes = figures.blocks_figure(model, u, models)
        parts.append(heading(e))
        parts.append(
            figure(
                encode_png(fig),
                f"{e.label}: identified nonlinear blocks",
                f"{e.label}: identified nonlinear blocks, estimated on the estimation range "
                f"{est_text}; each curve is drawn over the range its input takes when the "
                "estimation input is simulated, the axes fitted to the curve. "
                f"{_DEVIATION} {_band_text(e, models)}" + "".join(f" {n}" for n in notes),
            )
        )
    if not parts:
        parts.append(paragraph("No model with a nonlinear block was identified."))
    return section("blocks", "Identified nonlinearities", parts)


def _channel_blocks(e: Entry, estimation: Dataset, est_text: str, models: list) -> list[str]:
    """A model with a block per channel: a row of panels per block."""
    u = np.vstack([x.u for x in estimation.experiments])
    drawn = figures.channel_blocks_figure(e.model, u, models)
    if drawn is None:
        return []
    fig, notes = drawn
    return [
        heading(e),
        figure(
            encode_png(fig),
            f"{e.label}: identified nonlinear blocks",
            f"{e.label}: one row per block (the channel in its title), estimated on the "
            f"estimation range {est_text}; each curve drawn over the range its argument "
            "takes when the estimation input is simulated from rest. An input block maps "
            "its input (in its units) to the linear core's input (normalised: the gain "
            "between block and core is the core's); an output block maps the core's "
            f"output (normalised) to the output in its units. {_DEVIATION} "
            f"{_band_text(e, models)}" + "".join(f" {n}" for n in notes),
        ),
    ]


def histories_section(entries: list[Entry], est_text: str) -> str:
    """The parameter trajectories recursive estimators recorded."""
    parts = []
    for e in entries:
        history = getattr(e.fit, "history", None) or {}
        theta = history.get("theta")
        if theta is None or not len(theta) or "names" not in history:
            continue
        n = np.asarray(theta).shape
        fig = figures.history_figure(history)
        parts.append(heading(e))
        parts.append(
            figure(
                encode_png(fig),
                f"{e.label}: parameter trajectories",
                f"{e.label}: parameter estimates of the recursive estimator {e.method}, "
                f"recorded at {n[0]} updates over all passes through the estimation range "
                f"{est_text} (one-step regressions); one panel per group of parameters, "
                "the y axes fitted to the estimates after the first 5 % of the updates "
                "(the start-up transient may leave the frame).",
            )
        )
    if not parts:
        parts.append(
            paragraph(
                "No recursive estimator recorded parameter trajectories (they are drawn "
                "for the recursive methods, such as key-term-rls and aw-rls)."
            )
        )
    return section("trajectories", "Parameter trajectories of recursive estimators", parts)
