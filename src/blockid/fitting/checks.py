"""Checks every identified model passes before it is returned to the user.

The papers' recursive algorithms can diverge or converge to wrong answers on ordinary
data; blockid reports that instead of handing out a bad model. A model is accepted when

* all parameters are finite,
* its linear block is stable with a margin: every pole inside the circle of radius
  ``1 - STABILITY_MARGIN`` (0.999), or ``1 - 1/n`` on an experiment of ``n`` samples
  when that is wider (:func:`stability_margin`: a mode that slow is an integrator for
  all the record shows). A pole on the unit circle (e.g. at -1, an
  undamped oscillation at the Nyquist frequency) can look harmless on estimation data
  and ring on any other record,
* its free-run simulation on the estimation data is finite and does not explode,
and
* that simulation is not worse than a plain linear ARX of the same orders fitted by
  least squares (at most ``max_mse_ratio`` = 1.1 times its MSE). A block-oriented model
  contains the linear one; if it simulates worse, the estimator failed (e.g. AW-RLS
  stalled on a wrong backlash that still beat a linear model by a margin).

Two more looks do not reject the model but warn. :func:`rest_notes`: its free run from
rest (its zero state) on the estimation input strays from the measured output by more
than ``MAX_REST_RATIO`` (5) times their difference at the first sample plus the
output's range (:func:`blockid.evaluation.trust.rest_ratio`): a fit can match the data
from measured initial outputs and still run away from rest (a Wiener fit of paper B's
arm with an output cubic of 9704 x^3 does), so it should be started from measured
outputs; ``identify`` rejects such candidates. And (:func:`linear_block_notes`): a
static block that is affine to within ``LINEARITY_TOLERANCE`` of its output spread over
the estimation data makes the block-oriented model a linear one in disguise (a
Hammerstein fit that stayed at its ARX start, input-block coefficients ~1e-19; a block
affine by its form, such as a degree-1 polynomial carrying an input offset, is not
noted). A fitted linear block with a pole within twice the stability margin of the
unit circle (``|p| >= 1 - 2 margin``) sits on the margin the fit enforces: near
+1 the plant probably integrates, and an explicit integrator (``integrator=1``, a block
whose pole at 1 is not fitted) is the model to try. Three more warn before a model
misleads: a free run on the estimation data whose output leaves the measured output's
range (:func:`output_range_warnings`), poles on or near the unit circle or at the
Nyquist frequency (:func:`pole_warnings`), both with the limits of
:mod:`blockid.evaluation.plausibility` that ``simulate`` applies too, and static or
hysteretic blocks that have degenerated over the ranges their arguments covered
(:func:`degenerate_block_notes`: edges that coincide, edges far outside the range,
slopes that vanish, each block judging itself by
:meth:`~blockid.blocks.base.Block.degeneracy`). The notes belong in the result's
``settings["warnings"]``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from blockid.data.dataset import Dataset
from blockid.errors import DataError, EstimationError
from blockid.evaluation.metrics import metrics_by_output
from blockid.fitting.arx import least_squares
from blockid.models.arx import ARX

__all__ = [
    "refuse_constant_inputs",
    "LINEARITY_TOLERANCE",
    "STABILITY_MARGIN",
    "margin_for",
    "stability_margin",
    "refuse_unstable",
    "simulation_mse",
    "linear_baseline",
    "check_model",
    "degenerate_block_notes",
    "linear_block_notes",
    "margin_notes",
    "output_range_warnings",
    "pole_warnings",
    "rest_notes",
]

#: Poles must lie inside the circle of radius ``1 - STABILITY_MARGIN`` on records of up
#: to ``1 / STABILITY_MARGIN`` samples; on longer ones inside ``1 - 1 / n``
#: (:func:`stability_margin`).
STABILITY_MARGIN = 1e-3


def refuse_constant_inputs(data: Dataset) -> None:
    """A :class:`~blockid.errors.DataError` naming every input that takes one value
    over all of ``data``: no model learns from it how the outputs respond (an ARX fit
    took it for an offset and returned a model with exit 0; ``identify`` reported that
    no linear model simulated stably). Anything but a Dataset is left to the fitter's
    own check."""
    if not isinstance(data, Dataset):
        return
    constant = []
    for name in data.inputs:
        values = np.concatenate([np.ravel(v) for v in data.signal(name)])
        if values.size and np.ptp(values) == 0.0:
            constant.append(
                f"input {name!r} is constant over the estimation data ({values[0]:.6g} at "
                "every sample)"
            )
    if not constant:
        return
    several = len(data.inputs) > len(constant)
    raise DataError(
        "; ".join(constant) + ": a model cannot learn how the outputs respond to a constant "
        "input; use data in which it varies"
        + (", or leave it out of the inputs (-u)" if several else "")
    )


def margin_for(n_samples: int) -> float:
    """The stability margin a fit keeps on a record of ``n_samples`` samples:
    :data:`STABILITY_MARGIN`, or ``1 / n_samples`` when that is smaller.

    A pole at ``1 - 1/n`` has a time constant of ``n`` samples: over the record it cannot
    be told from an integrator, and a fit is allowed to go that far. A fixed 0.999 is a
    time constant of 1 000 samples, which on a plant sampled fast was a leak the fit
    pressed against (EMPS, 1 kHz: a position that must hold for seconds; linear
    state-space fits pinned at 0.999 tested 41 and 36 mm, at ``1 - 1/n`` 21 and 7.0 mm).

    >>> margin_for(500), margin_for(25_000)
    (0.001, 4e-05)
    """
    return STABILITY_MARGIN if n_samples <= 0 else min(STABILITY_MARGIN, 1.0 / n_samples)


def stability_margin(data: Dataset) -> float:
    """:func:`margin_for` the longest experiment of ``data``."""
    return margin_for(max((e.n_samples for e in data.experiments), default=0))


def refuse_unstable(model: Any, data: Dataset, message: str, **fields: Any) -> None:
    """Raise :class:`EstimationError` with ``message`` unless ``model`` is stable within
    the :func:`stability_margin` of ``data``. ``message`` is a :meth:`str.format`
    template: ``{rho}`` the largest pole magnitude, ``{limit}`` the limit ``1 - margin``
    and the ``fields`` by name (``{method}``)."""
    margin = stability_margin(data)
    if not model.is_stable(margin):
        rho = float(np.max(np.abs(model.poles())))
        raise EstimationError(message.format(rho=rho, limit=1 - margin, **fields))


#: A static block whose largest deviation from its best affine fit over the estimation
#: data is below this fraction of its output spread counts as linear.
LINEARITY_TOLERANCE = 1e-6


def simulation_mse(model: Any, data: Dataset) -> float:
    """Free-run MSE over all experiments (first ``max_lag`` samples of each skipped)."""
    errs = []
    for e in data.experiments:
        y_sim = model.simulate(e.u, e.y[: model.max_lag])
        errs.append((e.y[model.max_lag :] - y_sim[model.max_lag :]).ravel())
    err = np.concatenate(errs)
    return float(np.mean(err**2)) if np.all(np.isfinite(err)) else float("inf")


def linear_baseline(data: Dataset, na: int, nb: int, nk: int) -> ARX | None:
    """Least-squares ARX of the same orders with an operating-point offset (or None)."""
    u_off = np.mean(np.vstack([e.u for e in data.experiments]), axis=0)
    y_off = np.mean(np.vstack([e.y for e in data.experiments]), axis=0)
    model = ARX(data.inputs, data.outputs, na, nb, nk, input_offset=u_off, output_offset=y_off)
    try:
        for i in range(len(model.outputs)):
            model.set_parameter_vector(i, least_squares(model, data, i))
    except EstimationError:
        return None
    return model if model.is_stable() else None


def check_model(
    model: Any,
    data: Dataset,
    method: str,
    *,
    max_mse_ratio: float | None = 1.1,
    advice: str | None = None,
) -> dict[str, dict[str, float]]:
    """Raise :class:`EstimationError` if ``model`` fails a check; else return its
    free-run metrics on ``data``. ``advice``: what to try instead when the model does
    worse than the linear baseline (default: by the method's name).

    Parameters
    ----------
    model : ChainModel
        A block-oriented model (``free_parameters``, ``is_stable``, ``poles``,
        ``linear_orders``; the baseline ARX has the orders of its linear part).
    data : Dataset
        The estimation data.
    method : str
        Named in the error messages.
    max_mse_ratio : float or None
        Allowed free-run MSE relative to the linear baseline; None skips that check.
    """
    theta = model.free_parameters()
    if not np.all(np.isfinite(theta)):
        raise EstimationError(f"{method} diverged: the parameter estimates are not finite")
    refuse_unstable(
        model,
        data,
        "{method} returned a linear block that is unstable or on the edge of stability "
        "(largest pole magnitude {rho:.10g}, limit {limit:.10g}); its "
        "simulation would diverge or ring, so no model is returned. See docs/convergence.md",
        method=method,
    )
    mse = simulation_mse(model, data)
    y_all = np.vstack([e.y for e in data.experiments])
    if not np.isfinite(mse) or mse > 1e6 * (float(np.var(y_all)) + 1e-300):
        raise EstimationError(
            f"{method} returned a model whose free-run simulation explodes on the estimation "
            "data; no model is returned. See docs/convergence.md"
        )
    if max_mse_ratio is not None:
        base = linear_baseline(data, *model.linear_orders())
        if base is not None:
            base_mse = simulation_mse(base, data)
            if mse > max_mse_ratio * base_mse:
                advice = advice or (
                    "the structure or orders may not suit these data: try others, or "
                    "compare structures with 'blockid compare'"
                    if method.startswith("simulation-error")
                    else "use the default method (simulation-error), add refine=True, or see "
                    "docs/convergence.md"
                )
                raise EstimationError(
                    f"{method} did not converge to a useful model: its free-run MSE on the "
                    f"estimation data, {mse:.4g}, is {mse / base_mse:.3g} times that of a "
                    f"linear ARX of the same orders ({base_mse:.4g}); {advice}"
                )
    y = np.vstack([e.y[model.max_lag :] for e in data.experiments])
    y_sim = np.vstack(
        [model.simulate(e.u, e.y[: model.max_lag])[model.max_lag :] for e in data.experiments]
    )
    return metrics_by_output(y, y_sim, data.outputs)


def rest_notes(model: Any, data: Dataset) -> list[str]:
    """A warning when the model's free run from rest runs away (module notes)."""
    from blockid.evaluation.trust import MAX_REST_RATIO, rest_ratio

    with np.errstate(all="ignore"):
        ratio = max(rest_ratio(model, e.u, e.y) for e in data.experiments)
    if ratio <= MAX_REST_RATIO:
        return []
    how = "is not finite" if not np.isfinite(ratio) else f"strays {ratio:.3g} times"
    return [
        f"the model's free run from rest on the estimation input {how} further from the "
        f"measured output than its start and the output's range explain (limit "
        f"{MAX_REST_RATIO:g}): it fits from measured initial outputs but runs away from "
        "rest; start its simulations from measured outputs (blockid simulate "
        "--initial-samples N), or try lower orders or another block"
    ]


def output_range_warnings(model: Any, data: Dataset) -> list[str]:
    """Warnings when the model's free run on ``data`` (from the first ``max_lag``
    measured outputs, as the fit's metrics) leaves the measured output's range by more
    than :data:`~blockid.evaluation.plausibility.MAX_OUTPUT_EXCURSION` of its width."""
    from blockid.evaluation.plausibility import output_range_notes

    skip = model.max_lag
    with np.errstate(all="ignore"):
        y_hat = np.vstack([model.simulate(e.u, e.y[:skip])[skip:] for e in data.experiments])
    y = np.vstack([e.y[skip:] for e in data.experiments])
    return output_range_notes(y, y_hat, data.outputs, "free run", "on the estimation data")


def pole_warnings(model: Any, data: Dataset) -> list[str]:
    """Warnings for the model's fitted poles (:meth:`~blockid.models.base.Model.fitted_poles`)
    on or outside the unit circle (an ARX fitted with ``allow_unstable``), within twice
    the stability margin of it (a chain's linear blocks get :func:`margin_notes`
    instead, with its advice on integrators), or at the Nyquist frequency
    (:func:`~blockid.evaluation.plausibility.pole_notes`)."""
    from blockid.evaluation.plausibility import pole_notes

    noted = bool(getattr(model, "linear_blocks", ()))
    return pole_notes(
        model.fitted_poles(), 2.0 * stability_margin(data), near_noted=noted,
        unstable_advice="use it to predict one step ahead only (blockid predict), or fit "
        "it again without allow_unstable for a model that simulates",
    )  # fmt: skip


def degenerate_block_notes(model: Any) -> list[str]:
    """Warnings for the nonlinear blocks that have degenerated over the ranges their
    arguments covered in estimation (:meth:`~blockid.models.base.Model.block_ranges`),
    as each block judges itself (:meth:`~blockid.blocks.base.Block.degeneracy`)."""
    return [
        f"the {name} ({block.kind}) {clause}"
        for name, block, (low, high) in model.block_ranges()
        for clause in block.degeneracy(low, high)
    ]


def margin_notes(model: Any, margin: float, integrating: Sequence[str] = ()) -> list[str]:
    """Warnings for fitted linear blocks with a pole on the stability margin ``margin``
    (:func:`stability_margin` of the estimation data).

    A pole with ``|p| >= 1 - 2 margin`` sits where the fit's stability bound stops it.
    Near +1 (within ``2 margin``) the plant probably integrates: a pole at the margin is
    a leak that lets a simulated position drift; the note suggests an
    explicit integrator with one of the structures ``integrating`` (those that take one:
    :func:`blockid.fitting.dispatch` reads them from the registry, above this module).
    Integrators themselves pass :meth:`is_stable` and give no note. Models without
    linear blocks (ARX, networks) give none.
    """
    linear = getattr(model, "linear_blocks", ())
    integrates = sum(getattr(b, "integrates", 0) for b in getattr(model, "blocks", ()))
    near = 2.0 * margin
    notes = []
    for k, block in enumerate(linear):
        if block.is_stable(near):
            continue
        poles = np.asarray(block.poles(), dtype=complex)
        at_one = np.abs(poles - 1.0) <= near
        index = np.argmin(np.abs(poles - 1.0)) if at_one.any() else np.argmax(np.abs(poles))
        worst = complex(poles[int(index)])
        shown = f"{worst.real:.6g}" if worst.imag == 0 else f"{worst:.6g}"
        which = f"linear block {k + 1} of {len(linear)}" if len(linear) > 1 else "linear block"
        text = (
            f"the {which} has a pole at {shown} (magnitude {abs(worst):.6g}), within "
            f"{near:g} of the unit circle: it sits on the stability margin the fit keeps "
            f"(|p| < {1 - margin:.10g}). "
        )
        if at_one.any() and integrates < 2:
            n = integrates + 1
            text += (
                "The plant probably integrates (position from force, level from flow), and "
                "a pole held just inside 1 leaks, so a simulation drifts: try an explicit "
                f"integrator, integrator={n} (--integrator {n}), with "
                + (", ".join(integrating) or "a structure that takes one")
            )
        else:
            text += (
                "The model is nearly undamped there and may ring or drift on other data; "
                "check it on validation data"
            )
        notes.append(text)
    return notes


def _affine_by_form(block: Any, s: np.ndarray) -> bool:
    """True for a block linear in its parameters whose regressors are affine in its
    input (a degree-1 polynomial: an input offset and gain): linear by choice."""
    if not block.linear_in_parameters:
        return False
    # a property of the block's form over the range of s: a grid (with 0, where
    # two-segment blocks switch) stands for the data, whatever their length
    lo, hi = float(np.min(s)), float(np.max(s))
    grid = np.linspace(lo, hi, 257)
    s = np.union1d(grid, [0.0]) if lo < 0.0 < hi else grid
    G = np.asarray(block.regressors(s), dtype=float)
    design = np.column_stack([np.ones_like(s), s])
    coef = np.linalg.lstsq(design, G, rcond=None)[0]
    return float(np.max(np.abs(G - design @ coef), initial=0.0)) <= LINEARITY_TOLERANCE * (
        float(np.max(np.ptp(G, axis=0), initial=0.0)) + 1e-300
    )


def _affine_deviation(s: np.ndarray, out: np.ndarray) -> float:
    """Largest deviation of ``out`` from its least-squares affine fit in ``s`` (closed
    form: a few vectors of the data's length, not a design matrix)."""
    s_mean, out_mean = float(np.mean(s)), float(np.mean(out))
    ds = s - s_mean
    variance = float(np.dot(ds, ds))
    slope = float(np.dot(ds, out - out_mean)) / variance if variance > 0 else 0.0
    return float(np.max(np.abs(out - out_mean - slope * ds), initial=0.0))


def linear_block_notes(model: Any, data: Dataset, integrating: Sequence[str] = ()) -> list[str]:
    """Warnings for the static blocks of a chain that are linear over ``data``, and for
    fitted poles on the stability margin (:func:`margin_notes`, which names the
    structures ``integrating``).

    Each static block is evaluated on the signal that enters it over every experiment
    (simulated from rest, as :meth:`~blockid.models.block.ChainModel.block_inputs`
    gives it); when the largest deviation of its output from the best affine fit is
    below :data:`LINEARITY_TOLERANCE` times the output spread, the model behaves as
    a linear one on these data. Models without blocks (ARX, networks) give none.

    Returns
    -------
    list of str
        One note per such block, meant for ``settings["warnings"]``.
    """
    notes = margin_notes(model, stability_margin(data), integrating)
    blocks = getattr(model, "blocks", ())
    if not blocks or not hasattr(model, "block_inputs"):  # ARX, networks, feedback loops
        return notes
    static = [i for i, block in enumerate(blocks) if block.role == "static"]
    if not static:
        return notes
    inputs: dict[int, list[np.ndarray]] = {i: [] for i in static}
    for e in data.experiments:
        entering = model.block_inputs(e.u)
        for i in static:
            inputs[i].append(entering[i])
    for i in static:
        s = np.concatenate(inputs[i])
        out = blocks[i].run(s)
        if not (np.all(np.isfinite(s)) and np.all(np.isfinite(out))):
            continue
        if _affine_by_form(blocks[i], s):
            continue
        spread = float(np.ptp(out))
        deviation = _affine_deviation(s, out)
        if deviation > LINEARITY_TOLERANCE * spread:
            continue
        where = (
            "input block"
            if i == 0
            else "output block"
            if i == len(blocks) - 1
            else f"block {i + 1}"
        )
        notes.append(
            f"the {where} ({blocks[i].kind}) is linear over the estimation data (largest "
            f"deviation from a straight line {deviation:.3g}, output spread {spread:.3g}): "
            f"the {model.structure} model behaves as a linear one here, e.g. a fit that "
            "stayed at its linear start. Compare with a linear model (structure arx or "
            "output-error), or use data that show the nonlinearity"
        )
    return notes
