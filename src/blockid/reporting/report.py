"""One self-contained HTML report of an identification: data, scores, figures, provenance.

:func:`build_report` turns a :class:`~blockid.workflows.compare.CompareResult` and/or an
:class:`~blockid.workflows.identify.IdentifyResult` with the data they came from into one
HTML page: figures are embedded PNGs, CSS is inline, there are no scripts and no
references to anything outside the file, so it opens anywhere without a network.

Sections: data overview (signals, ranges, sampling time, sample counts, the records with
the estimation and validation ranges shaded); comparison (free-run and one-step metrics
of every model on the validation data, failures with their reasons); measured against
simulated output and its residual for each model; the residual tests (whiteness,
independence of the inputs, a verdict) of each model; the identified nonlinear blocks, with
95 % bands when the fit carries parameter standard errors; parameter trajectories of the
recursive estimators; and the provenance (command, SHA-256 of the data files, versions,
date). Every caption says on which data and range a curve is, and whether it is a
free-run simulation or a one-step prediction.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from blockid.data.dataset import Dataset
from blockid.data.io import write_text_atomic
from blockid.data.ranges import parse_range
from blockid.plotting import report_figures as figures
from blockid.plotting.html import encode_png
from blockid.plotting.report_figures import zoom_title
from blockid.plotting.uncertainty import fit_draws, output_bands
from blockid.reporting.bla_section import bla_section
from blockid.reporting.entries import Entry, heading, predicts_by_free_run
from blockid.reporting.html import figure, page, paragraph, section, table
from blockid.reporting.model_sections import (
    blocks_section,
    histories_section,
    linear_section,
    parameters_section,
)
from blockid.reporting.provenance import Provenance
from blockid.reporting.residual_section import residuals_section
from blockid.reporting.search import LinearBaseline, baseline_entry, linear_baseline, search_section

__all__ = ["build_report", "write_report"]


def _entries(compare: Any, identify: Any, baseline: LinearBaseline | None) -> list[Entry]:
    out = []
    if identify is not None:
        out.append(
            Entry(
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
        extra = None if baseline is None else baseline_entry(baseline, identify.on)
        if extra is not None:
            out.append(extra)
    for m in [] if compare is None else compare.models:
        out.append(
            Entry(
                f"{m.structure} ({m.method})",
                m.method,
                m.fit,
                m.simulation,
                m.one_step,
                m.error,
                m.one_step_error,
                residuals=m.residuals,
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
                encode_png(fig),
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
                    encode_png(fig),
                    f"the {what} data",
                    f"Measured {what} data (range {_range_text(ranges[what], d)}).",
                )
            )
    return section("data", "Data overview", parts)


#: The one-step cells of a model whose one-step prediction is its free run.
_SAME_AS_FREE_RUN = "= free run"


def _free_run_note(e: Entry) -> str:
    why = (
        "its model has a noise model, yet predicts one step ahead exactly as it runs free"
        if getattr(e.model, "has_noise_model", False)
        else "the model has no noise model (a state space fitted as output error has no "
        "predictor gain K), so the best it can predict one step ahead from measured past "
        "outputs is its free run from the same initial state"
    )
    return (
        f"{e.label}: one-step prediction = free run, sample for sample: {why}. Its one-step "
        f"columns say '{_SAME_AS_FREE_RUN}' rather than repeat the free-run numbers."
    )


def _metrics_rows(entries: list[Entry], outputs: tuple[str, ...]) -> tuple[list, list]:
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
            if predicts_by_free_run(e.simulation, e.one_step):
                one_step = [_SAME_AS_FREE_RUN] * 3
            else:
                one_step = [
                    one[k][output] if one else "n/a" for k in ("mse", "rmse", "fit_percent")
                ]
            row = [e.label, output, _n_parameters(e.fit.model), sim["mse"][output]]
            rows.append([*row, sim["rmse"][output], sim["fit_percent"][output], *one_step])
            classes.append("best" if e is best and len(scored) > 1 else e.row)
    return rows, classes


def _comparison(entries: list[Entry], outputs: tuple[str, ...], where: str) -> str:
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
            f"outputs ('{_SAME_AS_FREE_RUN}' where a model has no one-step predictor but its "
            "free run). Fit % = 100 (1 - |y - y_model| / |y - mean(y)|). Shaded green: the "
            "highest free-run fit % of an output; red: a model whose estimator failed"
            + ("; blue: the linear baseline." if any(e.row == "baseline" for e in entries) else ".")
        ),
        table(header, rows, classes),
    ]
    for e in entries:
        if e.error:
            parts.append(paragraph(f"{e.label} failed: {e.error}", "note"))
        if e.one_step_error:
            parts.append(paragraph(f"{e.label}: no one-step prediction: {e.one_step_error}"))
        if predicts_by_free_run(e.simulation, e.one_step):
            parts.append(paragraph(_free_run_note(e)))
        settings = getattr(e.fit, "settings", None) or {}
        # the fit's own warnings (a refinement stopped at its evaluation limit, ...), then
        # the scores' (each once)
        notes = [*settings.get("warnings", []), *(e.simulation.warnings if e.simulation else [])]
        for note in dict.fromkeys(notes):
            parts.append(paragraph(f"warning: {e.label}: {note}", "note"))
    scored = [e for e in entries if e.simulation is not None]
    if len(scored) > 1:
        for output in outputs:
            bars = [
                (
                    e.label,
                    e.simulation.metrics["fit_percent"][output],
                    None
                    if e.one_step is None or predicts_by_free_run(e.simulation, e.one_step)
                    else e.one_step.metrics["fit_percent"][output],
                )
                for e in scored
            ]
            parts.append(
                figure(
                    encode_png(figures.comparison_figure(bars, output, where)),
                    f"fit % of {output} per model",
                    f"Fit % of {output} on the {where}, free-run simulation (orange) and "
                    "one-step prediction (blue), per model (no blue bar where a model has "
                    "no one-step prediction, or none but its free run).",
                )
            )
    return section("comparison", "Comparison of the models", parts)


def _zoom_text(e: Entry, first: int) -> str:
    """The caption's sentence on the zoom (empty when the record is short)."""
    output = e.simulation
    exps = output.data.experiments
    shown = [
        zoom_title(w, first, output.data.sampling_time)
        + (f" in experiment {x.name!r}" if len(exps) > 1 else "")
        for x, y_hat in zip(exps, output.outputs, strict=True)
        if (w := figures.zoom_window(x.y, output.skip, y_hat)) is not None
    ]
    if not shown:
        return ""
    return (
        f" The record is longer than {figures.MAX_POINTS} samples, so the full view draws "
        "each pixel column's minimum to maximum (the measurement by its edges, over the "
        f"model's filled band), and the third panel zooms on {', '.join(shown)} (shaded "
        "grey above, between two lines): four periods of the output's dominant "
        "frequency, 200 to 600 samples, where the model errs most (the largest sum of "
        "squared errors over such a window), so that measured (dark) and simulated "
        "output can be told apart."
    )


def _outputs(entries: list[Entry], ranges: dict[str, str | None], draws: dict[int, list]) -> str:
    parts = []
    for e in entries:
        if e.simulation is None:
            continue
        rng = ranges[e.on]
        first = 0 if rng is None else parse_range(rng, f"--{e.on}")[0]
        where = f"{e.on} range {rng}" if rng is not None else f"{e.on} data"
        bands, band = output_bands(e.fit, e.simulation, draws.get(id(e), []))
        fig = figures.validation_figure(e.simulation, first, bands, where)
        parts.append(heading(e))
        parts.append(
            figure(
                encode_png(fig),
                f"{e.label}: measured and simulated output",
                f"{e.label}: free-run simulation on the {where} — measured output (dark, "
                "thin, on top) and model output (orange, wide, under it) above, residual "
                f"(measured minus simulated) "
                f"below; all {e.simulation.data.n_samples} samples drawn, the first "
                f"{e.simulation.skip} of each experiment are initial conditions copied from "
                f"the measurement.{band}{_zoom_text(e, first)}",
            )
        )
    if not parts:
        parts.append(paragraph("No model was identified."))
    return section("outputs", "Measured and simulated output", parts)


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
                wrap=(0, 2),
            )
        )
    else:
        parts.append(paragraph("No data file (the data were passed in memory)."))
    parts.append(table(["software", "version"], list(provenance.versions.items())))
    return section("provenance", "Provenance", parts)


def _h(text: str) -> str:
    from html import escape

    return escape(text)


def _summary(entries: list[Entry], outputs: tuple[str, ...]) -> str:
    scored = [e for e in entries if e.simulation is not None]
    if not scored:
        return paragraph("No model was identified: see the failures below.", "note")

    def mean_fit(e: Entry) -> float:
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
    baseline = None
    if identify is not None:
        identify = _with_standard_errors(identify, estimation)
        baseline = linear_baseline(identify, estimation)
    entries = _entries(compare, identify, baseline)
    outputs = tuple(estimation.outputs)
    where = (
        f"validation range {validation_range}"
        if validation_range is not None
        else "validation data"
    )
    if identify is not None and identify.on != "validation":
        where = "estimation data (no validation data were given)"
    draws = {id(e): fit_draws(e.fit) for e in entries if e.fit is not None}
    est_text = _range_text(estimation_range, None)
    import matplotlib

    with matplotlib.rc_context({"font.size": 8}):
        sections = [_overview(data, estimation, validation, ranges)]
        sections.append(bla_section(estimation, f"estimation data ({est_text})", entries))
        if identify is not None:
            sections.append(search_section(identify, baseline))
        sections += [
            _comparison(entries, outputs, where),
            _outputs(entries, ranges, draws),
            residuals_section(entries),
            parameters_section(entries),
            linear_section(entries),
            blocks_section(entries, estimation, est_text, draws),
            histories_section(entries, est_text),
            _provenance(provenance),
        ]
    nav = [("data", "Data overview"), ("bla", "Best linear approximation")]
    if identify is not None:
        nav.append(("search", "Search of identify()"))
    nav += [
        ("comparison", "Comparison of the models"),
        ("outputs", "Measured and simulated output"),
        ("residuals", "Residual tests"),
        ("parameters", "Parameters"),
        ("linear", "Linear dynamics"),
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


def _with_standard_errors(identify: Any, estimation: Dataset) -> Any:
    """``identify`` with standard errors on its fit (computed on the estimation data it
    was refitted on, :func:`~blockid.evaluation.uncertainty.with_standard_errors`) when
    it carries none, for the report's parameter table and bands; unchanged when they
    cannot be computed."""
    from dataclasses import replace

    from blockid.errors import BlockidError
    from blockid.evaluation.uncertainty import with_standard_errors

    fit = identify.fit
    if "covariance" in (getattr(fit, "settings", None) or {}):
        return identify
    try:
        with np.errstate(all="ignore"):
            return replace(identify, fit=with_standard_errors(fit, estimation))
    except (BlockidError, ValueError, np.linalg.LinAlgError):
        return identify


def write_report(html: str, path: str | Path, overwrite: bool = False) -> Path:
    """Write the report atomically; an existing file is replaced only with ``overwrite``."""
    return write_text_atomic(html, path, overwrite=overwrite)
