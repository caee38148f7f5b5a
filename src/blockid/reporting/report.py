"""One self-contained HTML report of an identification: data, scores, figures, provenance.

:func:`build_report` turns a :class:`~blockid.workflows.compare.CompareResult` and/or an
:class:`~blockid.fitting.identify.IdentifyResult` with the data they came from into one
HTML page: figures are embedded PNGs, CSS is inline, there are no scripts and no
references to anything outside the file, so it opens anywhere without a network.

Sections: data overview (signals, ranges, sampling time, sample counts, the records with
the estimation and validation ranges shaded); comparison (free-run and one-step metrics
of every model on the validation data, failures with their reasons); measured against
simulated output and its residual for each model; the identified nonlinear blocks, with
95 % bands when the fit carries parameter standard errors; parameter trajectories of the
recursive estimators; and the provenance (command, SHA-256 of the data files, versions,
date). Every caption says on which data and range a curve is, and whether it is a
free-run simulation or a one-step prediction.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from blockid.data.dataset import Dataset
from blockid.data.io import write_text_atomic
from blockid.data.ranges import parse_range
from blockid.reporting import figures
from blockid.reporting.html import figure, page, paragraph, section, table
from blockid.reporting.provenance import Provenance
from blockid.reporting.uncertainty import (
    free_covariance,
    free_standard_errors,
    sampled_band,
    sampled_models,
)

__all__ = ["build_report", "write_report"]

_MODE = {"simulation": "free-run simulation", "one-step": "one-step prediction"}
_BAND_DRAWS = 200
_NO_UNCERTAINTY = (
    "No uncertainty available: the fit carries no parameter standard errors, so no "
    "confidence band is drawn."
)


@dataclass
class _Entry:
    """One model of the report, whichever workflow produced it."""

    label: str
    method: str
    fit: Any
    simulation: Any
    one_step: Any
    error: str | None = None
    one_step_error: str | None = None
    on: str = "validation"
    notes: list[str] = field(default_factory=list)


def _entries(compare: Any, identify: Any) -> list[_Entry]:
    out = []
    if identify is not None:
        out.append(
            _Entry(
                f"identify: {identify.selected.candidate.label}",
                identify.fit.method,
                identify.fit,
                identify.simulation,
                identify.one_step,
                None,
                identify.one_step_error,
                identify.on,
            )
        )
    for m in [] if compare is None else compare.models:
        out.append(
            _Entry(
                f"{m.structure} ({m.method})",
                m.method,
                m.fit,
                m.simulation,
                m.one_step,
                m.error,
                m.one_step_error,
            )
        )
    return out


def _range(text: str | None, what: str) -> tuple[int, int | None] | None:
    return None if text is None else parse_range(text, what)


def _range_text(text: str | None, data: Dataset | None) -> str:
    """``"A:B"`` as given, or ``"all samples"``; with the sample count of the data."""
    shown = text if text is not None else "all samples"
    if data is None:
        return shown
    counts = sorted({e.n_samples for e in data.experiments})
    each = " per experiment" if data.n_experiments > 1 else ""
    return f"{shown} ({'/'.join(map(str, counts))} samples{each})"


def _n_parameters(model: Any) -> int | None:
    if hasattr(model, "free_parameters"):
        return int(np.asarray(model.free_parameters()).size)
    if hasattr(model, "n_parameters"):
        return int(sum(model.n_parameters(i) for i in range(len(model.outputs))))
    return None


# ----------------------------------------------------------------------------- sections
def _overview(
    data: Dataset | None,
    estimation: Dataset,
    validation: Dataset | None,
    ranges: dict[str, str | None],
) -> str:
    shown = data if data is not None else estimation
    rows = []
    for name in [*shown.inputs, *shown.outputs]:
        x = np.concatenate(shown.signal(name))
        role = "input" if name in shown.inputs else "output"
        rows.append([name, role, float(x.min()), float(x.max()), float(x.mean()), float(x.std())])
    ts = shown.sampling_time
    parts = [
        paragraph(
            f"Source: {shown.source or 'in-memory data'}. Sampling time: "
            + (f"{ts:g} s" if ts else "not given (time axes in samples)")
            + f". {shown.n_experiments} experiment(s), {shown.n_samples} samples in all: "
            + ", ".join(f"{e.name!r} {e.n_samples}" for e in shown.experiments)
            + "."
        ),
        paragraph(
            f"Estimation range: {_range_text(ranges['estimation'], estimation)}. "
            f"Validation range: {_range_text(ranges['validation'], validation)}. Ranges are "
            "0-based sample indices within each experiment, stop excluded."
        ),
        table(["signal", "role", "min", "max", "mean", "std"], rows),
    ]
    est_rng = _range(ranges["estimation"], "--estimation")
    val_rng = _range(ranges["validation"], "--validation")
    if est_rng is not None and val_rng is not None and validation is not None:
        est_stop = est_rng[1] if est_rng[1] is not None else np.inf
        val_stop = val_rng[1] if val_rng[1] is not None else np.inf
        if est_rng[0] < val_stop and val_rng[0] < est_stop:
            parts.append(
                paragraph(
                    "The estimation and validation ranges overlap: the validation scores "
                    "are partly on data the models were fitted to.",
                    "note",
                )
            )
    if data is not None:
        fig = figures.overview_figure(data, est_rng, val_rng)
        parts.append(
            figure(
                figures.encode_png(fig),
                "the measured records",
                "Measured records (inputs blue, outputs red), the estimation range shaded "
                "green and the validation range orange.",
            )
        )
    else:
        for what, d in (("estimation", estimation), ("validation", validation)):
            if d is None:
                continue
            fig = figures.overview_figure(d, None, None)
            parts.append(
                figure(
                    figures.encode_png(fig),
                    f"the {what} data",
                    f"Measured {what} data (range {_range_text(ranges[what], d)}).",
                )
            )
    return section("data", "Data overview", parts)


def _metrics_rows(entries: list[_Entry], outputs: tuple[str, ...]) -> tuple[list, list]:
    rows, classes = [], []
    for output in outputs:
        scored = [e for e in entries if e.simulation is not None]
        best = max(scored, key=lambda e: e.simulation.metrics["fit_percent"][output], default=None)
        for e in entries:
            if e.simulation is None:
                rows.append([e.label, output, "failed", "", "", "", "", "", ""])
                classes.append("failed")
                continue
            sim = e.simulation.metrics
            one = e.one_step.metrics if e.one_step is not None else None
            rows.append(
                [
                    e.label,
                    output,
                    _n_parameters(e.fit.model),
                    sim["mse"][output],
                    sim["rmse"][output],
                    sim["fit_percent"][output],
                    one["mse"][output] if one else "n/a",
                    one["rmse"][output] if one else "n/a",
                    one["fit_percent"][output] if one else "n/a",
                ]
            )
            classes.append("best" if e is best and len(scored) > 1 else None)
    return rows, classes


def _comparison(entries: list[_Entry], outputs: tuple[str, ...], where: str) -> str:
    header = [
        "model",
        "output",
        "parameters",
        "free-run MSE",
        "free-run RMSE",
        "free-run fit %",
        "one-step MSE",
        "one-step RMSE",
        "one-step fit %",
    ]
    rows, classes = _metrics_rows(entries, outputs)
    parts = [
        paragraph(
            f"Scores on the {where}. Free-run simulation: the model runs from the inputs "
            "alone, its own past outputs fed back (initial conditions: the first measured "
            "samples, left out of the scores). One-step prediction: from measured past "
            "outputs. Fit % = 100 (1 - |y - y_model| / |y - mean(y)|). Shaded green: the "
            "highest free-run fit % of an output; red: a model whose estimator failed."
        ),
        table(header, rows, classes),
    ]
    for e in entries:
        if e.error:
            parts.append(paragraph(f"{e.label} failed: {e.error}", "note"))
        if e.one_step_error:
            parts.append(paragraph(f"{e.label}: no one-step prediction: {e.one_step_error}"))
        for note in [] if e.simulation is None else e.simulation.warnings:
            parts.append(paragraph(f"warning: {e.label}: {note}", "note"))
    scored = [e for e in entries if e.simulation is not None]
    if len(scored) > 1:
        for output in outputs:
            bars = [
                (
                    e.label,
                    e.simulation.metrics["fit_percent"][output],
                    None if e.one_step is None else e.one_step.metrics["fit_percent"][output],
                )
                for e in scored
            ]
            parts.append(
                figure(
                    figures.encode_png(figures.comparison_figure(bars, output)),
                    f"fit % of {output} per model",
                    f"Fit % of {output} on the {where}, free-run simulation (orange) and "
                    "one-step prediction (blue), per model.",
                )
            )
    return section("comparison", "Comparison of the models", parts)


def _identify_search(identify: Any) -> str:
    sel = identify.selected
    search = getattr(identify, "search", {}) or {}
    cut = (
        " The time limit cut the search: candidates not fitted by then were left out, "
        "and another run may choose differently."
        if search.get("cut_by_time_limit")
        else ""
    )
    parts = [
        paragraph(
            f"identify() chose {sel.candidate.label} by its cross-validated free-run RMSE "
            f"on the estimation data ({identify.holdout}; folds combined by their "
            f"{search.get('rule', 'geometric-mean').replace('-', ' ')}); "
            f"among near-ties the model with the fewest parameters wins. "
            f"{len(identify.ranked)} candidates scored, {len(identify.rejected)} rejected, "
            f"in {identify.seconds:.1f} s (effort {search.get('effort', '?')}). The chosen "
            "model was refitted on all estimation data; validation data were not used to "
            f"choose.{cut}"
        )
    ]
    for flag in sel.flags:
        parts.append(paragraph(f"Flag on the chosen model: {flag}", "note"))
    rows = [
        [s.candidate.label, s.stage, s.n_parameters, s.rmse, s.fit_percent, s.seconds]
        for s in identify.ranked[:20]
    ]
    parts.append(
        table(
            [
                "candidate (best first)",
                "stage",
                "parameters",
                "CV RMSE",
                "CV fit %",
                "seconds",
            ],
            rows,
            ["best"] + [None] * (len(rows) - 1),
        )  # fmt: skip
    )
    if len(identify.ranked) > 20:
        parts.append(paragraph(f"... and {len(identify.ranked) - 20} more candidates."))
    if identify.rejected:
        parts.append("<h3>Rejected candidates</h3>")
        parts.append(
            table(
                ["candidate", "stage", "reason"],
                [[s.candidate.label, s.stage, s.reason] for s in identify.rejected],
                ["failed"] * len(identify.rejected),
            )
        )
    for note in identify.notes:
        parts.append(paragraph(note, "note"))
    return section("search", "Search of identify()", parts)


def _output_bands(e: _Entry, draws: list[Any]) -> tuple[list[Any], str]:
    """95 % bands of the free-run simulation per experiment, and what they are."""
    output = e.simulation
    record = (getattr(e.fit, "settings", None) or {}).get("covariance")
    if record is not None:
        from blockid.errors import BlockidError
        from blockid.evaluation.uncertainty import ParameterCovariance, simulation_band

        try:
            cov = ParameterCovariance.from_dict(record)
            bands = [
                simulation_band(e.fit.model, cov, x.u, x.y[: output.skip])
                for x in output.data.experiments
            ]
            return [(b.lower, b.upper) for b in bands], (
                " Shaded: 95 % confidence band of the noise-free output, from the parameter "
                "covariance linearised along the simulation (as 'blockid simulate --band')."
            )
        except (BlockidError, ValueError, KeyError, TypeError, np.linalg.LinAlgError):
            pass
    if draws:
        bands = [
            sampled_band(draws[:100], lambda m, x=x: m.simulate(x.u, x.y[: output.skip]))
            for x in output.data.experiments
        ]
        if any(b is not None for b in bands):
            return bands, (
                f" Shaded: 95 % band of the simulated output over {min(len(draws), 100)} "
                "parameter draws from the standard errors."
            )
    return [], " No uncertainty available for this model (no parameter standard errors)."


def _outputs(entries: list[_Entry], ranges: dict[str, str | None], draws: dict[int, list]) -> str:
    parts = []
    for e in entries:
        if e.simulation is None:
            continue
        rng = ranges[e.on]
        first = 0 if rng is None else parse_range(rng, f"--{e.on}")[0]
        where = f"{e.on} range {rng}" if rng is not None else f"{e.on} data"
        bands, band = _output_bands(e, draws.get(id(e), []))
        fig = figures.validation_figure(e.simulation, first, bands, where)
        parts.append(f"<h3>{_h(e.label)}</h3>")
        parts.append(
            figure(
                figures.encode_png(fig),
                f"{e.label}: measured and simulated output",
                f"{e.label}: free-run simulation on the {where} — measured output (grey) "
                f"and model output (orange) above, residual (measured minus simulated) "
                f"below; all {e.simulation.data.n_samples} samples drawn, the first "
                f"{e.simulation.skip} of each experiment are initial conditions copied from "
                f"the measurement.{band}",
            )
        )
    if not parts:
        parts.append(paragraph("No model was identified."))
    return section("outputs", "Measured and simulated output", parts)


def _blocks(
    entries: list[_Entry], estimation: Dataset, est_text: str, draws: dict[int, list]
) -> str:
    parts = []
    for e in entries:
        model = getattr(e.fit, "model", None)
        blocks = getattr(model, "blocks", None)
        if blocks is None or all(b.role == "linear" for b in blocks):
            continue
        if len(model.inputs) != 1 or tuple(model.inputs) != tuple(estimation.inputs):
            continue
        u = np.concatenate([x.u[:, 0] for x in estimation.experiments])
        models = draws.get(id(e), [])
        fig, notes = figures.blocks_figure(model, u, models)
        source = (
            "the parameter covariance"
            if free_covariance(e.fit) is not None
            else "the standard errors (independent normals)"
        )
        band = (
            f"Shaded: 95 % band over {len(models)} parameter draws from {source}."
            if models
            else _NO_UNCERTAINTY
        )
        parts.append(f"<h3>{_h(e.label)}</h3>")
        parts.append(
            figure(
                figures.encode_png(fig),
                f"{e.label}: identified nonlinear blocks",
                f"{e.label}: identified nonlinear blocks, estimated on the estimation range "
                f"{est_text}; each curve is drawn over the range its input takes when the "
                f"estimation input is simulated. {band}",
            )
        )
        parts += [paragraph(n, "note") for n in notes]
    if not parts:
        parts.append(paragraph("No model with a nonlinear block was identified."))
    return section("blocks", "Identified nonlinearities", parts)


def _histories(entries: list[_Entry], est_text: str) -> str:
    parts = []
    for e in entries:
        history = getattr(e.fit, "history", None) or {}
        theta = history.get("theta")
        if theta is None or not len(theta) or "names" not in history:
            continue
        n = np.asarray(theta).shape
        fig = figures.history_figure(history)
        parts.append(f"<h3>{_h(e.label)}</h3>")
        parts.append(
            figure(
                figures.encode_png(fig),
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


def _provenance(provenance: Provenance | None) -> str:
    if provenance is None:
        return section("provenance", "Provenance", [paragraph("Not recorded.")])
    parts = [
        "<p>Command:</p>",
        f"<pre>{_h(provenance.command)}</pre>",
        paragraph(f"Made on {provenance.date} (UTC)."),
    ]
    if provenance.files:
        parts.append(
            table(
                ["data file", "bytes", "SHA-256"],
                [[f.path, f.size, f.sha256] for f in provenance.files],
            )
        )
    else:
        parts.append(paragraph("No data file (the data were passed in memory)."))
    parts.append(table(["software", "version"], list(provenance.versions.items())))
    return section("provenance", "Provenance", parts)


def _h(text: str) -> str:
    from html import escape

    return escape(text)


def _summary(entries: list[_Entry], outputs: tuple[str, ...]) -> str:
    scored = [e for e in entries if e.simulation is not None]
    if not scored:
        return paragraph("No model was identified: see the failures below.", "note")

    def mean_fit(e: _Entry) -> float:
        return float(np.mean([e.simulation.metrics["fit_percent"][o] for o in outputs]))

    best = max(scored, key=mean_fit)
    fits = ", ".join(f"{best.simulation.metrics['fit_percent'][o]:.1f} % on {o}" for o in outputs)
    failed = len(entries) - len(scored)
    return paragraph(
        f"{len(entries)} model(s); best by free-run simulation on the {best.on} data: "
        f"{best.label}, fit {fits}."
        + (f" {failed} estimator(s) failed (reasons below)." if failed else "")
    )


# ----------------------------------------------------------------------------- public
def build_report(
    *,
    estimation: Dataset,
    validation: Dataset | None = None,
    compare: Any = None,
    identify: Any = None,
    data: Dataset | None = None,
    estimation_range: str | None = None,
    validation_range: str | None = None,
    provenance: Provenance | None = None,
    title: str = "blockid identification report",
) -> str:
    """The HTML text of a self-contained report (see the module docstring).

    Parameters
    ----------
    estimation, validation : Dataset
        The data the models were fitted on and scored on.
    compare : CompareResult, optional
        From :func:`blockid.workflows.compare_structures`.
    identify : IdentifyResult, optional
        From :func:`blockid.identify`. At least one of ``compare`` and ``identify``.
    data : Dataset, optional
        The whole record the ranges were taken from, drawn in the data overview with the
        ranges shaded (without it the two data sets are drawn apart).
    estimation_range, validation_range : str, optional
        The ranges as typed (``"0:1100"``); None: all samples of ``estimation`` /
        ``validation``.
    provenance : Provenance, optional
        From :func:`blockid.reporting.collect_provenance`.
    title : str

    Returns
    -------
    str
        The HTML document.
    """
    if compare is None and identify is None:
        from blockid.errors import ParameterError

        raise ParameterError("build_report needs a compare or an identify result")
    ranges = {"estimation": estimation_range, "validation": validation_range}
    entries = _entries(compare, identify)
    outputs = tuple(estimation.outputs)
    where = (
        f"validation range {validation_range}"
        if validation_range is not None
        else "validation data"
    )
    if identify is not None and identify.on != "validation":
        where = "estimation data (no validation data were given)"
    draws = {}
    for e in entries:
        if e.fit is None:
            continue
        cov = free_covariance(e.fit)
        se = None if cov is not None else free_standard_errors(e.fit)
        if cov is not None or se is not None:
            draws[id(e)] = sampled_models(e.fit.model, se, n=_BAND_DRAWS, covariance=cov)
    import matplotlib

    with matplotlib.rc_context({"font.size": 8}):
        sections = [_overview(data, estimation, validation, ranges)]
        if identify is not None:
            sections.append(_identify_search(identify))
        sections += [
            _comparison(entries, outputs, where),
            _outputs(entries, ranges, draws),
            _blocks(entries, estimation, _range_text(estimation_range, None), draws),
            _histories(entries, _range_text(estimation_range, None)),
            _provenance(provenance),
        ]
    nav = [("data", "Data overview")]
    if identify is not None:
        nav.append(("search", "Search of identify()"))
    nav += [
        ("comparison", "Comparison of the models"),
        ("outputs", "Measured and simulated output"),
        ("blocks", "Identified nonlinearities"),
        ("trajectories", "Parameter trajectories"),
        ("provenance", "Provenance"),
    ]
    header = [
        f"<h1>{_h(title)}</h1>",
        paragraph(
            f"Inputs {', '.join(estimation.inputs)}; outputs {', '.join(outputs)}. "
            + (f"Made {provenance.date} with: {provenance.command}" if provenance else "")
        ),
        _summary(entries, outputs),
        "<nav><ol>"
        + "".join(f'<li><a href="#{a}">{_h(t)}</a></li>' for a, t in nav)
        + "</ol></nav>",
    ]
    return page(title, header + sections)


def write_report(html: str, path: str | Path, overwrite: bool = False) -> Path:
    """Write the report atomically; an existing file is replaced only with ``overwrite``."""
    return write_text_atomic(html, path, overwrite=overwrite)
