"""The report's sections with the right numbers: parameters and standard errors, linear
dynamics, the zoom on long records, the identify search with its linear baseline, and
text that is never cut (the HTML parsed as a reader sees it, tests/reporting/page.py)."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

from blockid.data import Dataset
from blockid.evaluation import evaluate
from blockid.fitting import fit_model
from blockid.plotting.linear import linear_dynamics, pole_rows
from blockid.plotting.report_figures import zoom_window
from blockid.reporting import build_report
from blockid.workflows.identify import Candidate, IdentifyResult, Score
from reporting.page import Report

IMG = re.compile(r'<img src="data:image/png;base64,([A-Za-z0-9+/=]+)"')


def _number(text: str) -> float:
    return float(text)


def test_the_parameter_table_holds_each_models_parameters_and_errors(compared):
    page = Report(compared.html)
    assert [p.title for p in page.sections["parameters"][1:]] == [
        "arx (batch)",
        "hammerstein (simulation-error)",
    ]
    for m in compared.result.models:
        part = page.part("parameters", f"{m.structure} ({m.method})")
        (rows,) = part.tables
        assert rows[0] == ["parameter", "value", "standard error", "relative SE [%]"]
        model = m.fit.model
        if hasattr(model, "free_parameters"):
            names, values = model.free_parameter_names(), model.free_parameters()
        else:  # ARX
            names, values = model.parameter_names(0), model.parameter_vector(0)
        assert [r[0] for r in rows[1:]] == list(names)
        np.testing.assert_allclose([_number(r[1]) for r in rows[1:]], values, rtol=1e-5)
        cov = np.array(m.fit.settings["covariance"]["matrix"], float)
        errors = [_number(r[2]) for r in rows[1:]]
        np.testing.assert_allclose(errors, np.sqrt(np.diag(cov)), rtol=1e-5)
        assert any(p.startswith("Standard errors: from the parameter covariance")
                   for p in part.paragraphs)  # fmt: skip
    hammerstein = page.part("parameters", "hammerstein (simulation-error)")
    assert any("1 parameter(s) of the model are fixed" in p for p in hammerstein.paragraphs)


def test_the_linear_dynamics_hold_each_blocks_gain_poles_and_zeros(compared):
    page = Report(compared.html)
    for m in compared.result.models:
        part = page.part("linear", f"{m.structure} ({m.method})")
        (g,) = linear_dynamics(m.fit.model)
        assert part.paragraphs[0].startswith(
            f"{g.name}: static gain {g.static_gain():.4g}, delay 8 samples (0.4 s), stable"
        )
        (rows,) = part.tables
        expected = [[str(c) if not isinstance(c, float) else f"{c:.4g}" for c in r]
                    for r in pole_rows(g)]  # fmt: skip
        assert rows[1:] == expected
        (caption,) = part.captions
        assert "frequency in hertz up to the Nyquist frequency 10 Hz" in caption
    hammerstein = compared.result.models[1].fit.model
    assert hammerstein.linear.static_gain() == pytest.approx(
        linear_dynamics(hammerstein)[0].static_gain()
    )


def test_the_blocks_show_their_deviation_from_a_straight_line(compared):
    page = Report(compared.html)
    (caption,) = page.part("blocks", "hammerstein (simulation-error)").captions
    assert "the curve minus its least-squares straight line" in caption
    assert "95 % band over 200 parameter draws from the parameter covariance" in caption
    assert "TwoSegmentPolynomial" not in compared.html


def test_the_zoom_appears_only_on_long_records(compared):
    short = Report(compared.html)
    for part in short.sections["outputs"][1:]:
        assert all("zooms on" not in c for c in part.captions)
    rng = np.random.default_rng(2)
    n = 8000
    u = np.repeat(rng.uniform(-1, 1, n // 20), 20)
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = 1.5 * y[k - 1] - 0.7 * y[k - 2] + u[k - 1] + 0.05 * rng.standard_normal()
    data = Dataset.from_arrays(u, y, ["u"], ["y"], sampling_time=0.01)
    est, val = data.select(0, 4000), data.select(4000, n)
    from blockid.workflows import compare_structures

    result = compare_structures(est, val, ["arx"], options=dict(na=2, nb=1, nk=1))
    html = build_report(compare=result, data=data, estimation=est, validation=val,
                        estimation_range="0:4000", validation_range="4000:8000")  # fmt: skip
    (caption,) = Report(html).part("outputs", "arx (batch)").captions
    found = re.search(r"zooms on samples (\d+) to (\d+) of the record \(t = ([\d.]+) to", caption)
    assert found, caption
    start, stop = int(found.group(1)), int(found.group(2))
    assert 4000 <= start < stop < n and 200 <= stop - start + 1 <= 600
    assert float(found.group(3)) == pytest.approx(start * 0.01)
    # the window where the model errs most, the caption says so
    sim = result.models[0].simulation
    window = zoom_window(sim.data.experiments[0].y, sim.skip, sim.outputs[0])
    assert (start, stop + 1) == (4000 + window[0], 4000 + window[1])
    assert "where the model errs most" in caption


# ------------------------------------------------------------------ identify
LONG_REASON = (
    "its free run from rest strays 22.2 times further from the measured output than its "
    "start and the output's range explain (limit 5) " * 6
).strip()


@pytest.fixture(scope="module")
def identified(compared):
    """An identify result around the example's Hammerstein fit, with an ARX candidate
    in its search and a rejected one whose reason is long."""
    fit = compared.result.models[1].fit
    chosen = Score(Candidate("hammerstein", {"na": 3, "nb": 3, "nk": 8}), stage="finalists",
                   rmse=0.02, fit_percent=75.0, n_parameters=13)  # fmt: skip
    arx = Score(Candidate("arx", {"na": 3, "nb": 3, "nk": 8, "center": True}), stage="linear orders",
                rmse=0.05, fit_percent=40.0, n_parameters=6)  # fmt: skip
    other = Score(Candidate("wiener", {"na": 2, "nb": 2, "nk": 8}), stage="structures",
                  rmse=0.03, fit_percent=60.0, n_parameters=8)  # fmt: skip
    long_label = Candidate("hammerstein-wiener", {"na": 2, "nb": 2, "nk": 10,
                           "input_block": "two-segment-polynomial:degree=3",
                           "output_block": "polynomial:degree=3", "center": False})  # fmt: skip
    rejected = [Score(long_label, stage="nonlinearity", reason=LONG_REASON)]
    return IdentifyResult(
        selected=chosen, fit=fit, ranked=[chosen, other, arx], rejected=rejected,
        simulation=evaluate(fit.model, compared.val, "simulation"),
        one_step=evaluate(fit.model, compared.val, "one-step"), one_step_error=None,
        on="validation", seconds=1.5, holdout="3 contiguous folds (blocked cross-validation)",
        search={"effort": "quick"},
    )  # fmt: skip


def test_the_identify_report_shows_a_linear_baseline(compared, identified):
    html = build_report(identify=identified, data=compared.data, estimation=compared.est,
                        validation=compared.val, estimation_range="0:1100",
                        validation_range="1100:2200")  # fmt: skip
    page = Report(html)
    (rows,) = page.sections["comparison"][0].tables
    (classes,) = page.sections["comparison"][0].classes
    label = "linear baseline: arx(na=3, nb=3, nk=8, center=True)"
    (row,) = [r for r in rows if r[0] == label]
    assert classes[rows.index(row)] in ("baseline", "best")
    # the same ARX refitted on the same estimation data, run free on the same validation data
    refit = fit_model(compared.est, "arx", na=3, nb=3, nk=8, center=True)
    expected = evaluate(refit.model, compared.val, "simulation").metrics
    assert _number(row[5]) == pytest.approx(expected["fit_percent"]["velocity"], rel=1e-3)
    assert _number(row[4]) == pytest.approx(expected["rmse"]["velocity"], rel=1e-3)
    search = page.sections["search"][0]
    baseline = next(p for p in search.paragraphs if p.startswith("Linear baseline:"))
    assert "ranked 3 of 3 with a cross-validated RMSE of 0.05" in baseline
    assert f"fit {expected['fit_percent']['velocity']:.1f} %" in baseline
    # the chosen fit had no standard errors: the report computed them for its table
    chosen = page.part("parameters", "identify: hammerstein(na=3, nb=3, nk=8)")
    assert chosen.tables[0][1][2] not in ("n/a", "")
    assert page.part("linear", label).tables  # the baseline's dynamics are shown too
    # the search figure, and the long reason in full, not cut
    assert any(c.startswith("Every scored candidate (3)") for c in search.captions)
    (rejected,) = page.part("search", "Rejected candidates").tables
    assert rejected[1][2] == LONG_REASON
    assert rejected[1][0] == identified.rejected[0].candidate.label


def _every_text(html: str) -> list[str]:
    return [t for t in Report(html).texts if t.strip()]


def test_no_text_of_a_report_is_cut(compared, identified, example_report):
    html = build_report(identify=identified, compare=compared.result, data=compared.data,
                        estimation=compared.est, validation=compared.val)  # fmt: skip
    for page in (html, compared.html, example_report.html):
        assert "…" not in page and "&hellip;" not in page
        for text in _every_text(page):
            stripped = text.strip()
            # the only ellipsis: the count of candidates left out of a table
            assert not stripped.endswith("..."), stripped
            if stripped.startswith("..."):
                assert re.fullmatch(r"\.\.\. and \d+ more candidates.*", stripped), stripped
    # every model's label is whole wherever it appears
    for m in identified.ranked + identified.rejected:
        assert m.candidate.label in html


def test_the_notebook_summary_of_an_identify_result(identified):
    from blockid.reporting.notebook import identify_figures, identify_html

    html = identify_html(identified)
    assert identified._repr_html_() == html  # the notebook's hook shows this summary
    page = Report(f"<section id='summary'>{html}</section>")
    text = " ".join(" ".join(page.texts).split())
    assert "identify() chose hammerstein(na=3, nb=3, nk=8) (stage finalists, 13 parameters" in text
    assert (
        "Linear baseline: the best ARX model, arx(na=3, nb=3, nk=8, center=True), ranked 3" in text
    )
    fit = identified.simulation.metrics["fit_percent"]["velocity"]
    assert f"velocity: fit {fit:.1f} %" in text
    best, rejected, params = page.sections["summary"][0].tables
    assert [r[0] for r in best[1:]] == [s.candidate.label for s in identified.ranked]
    assert rejected[1][2] == LONG_REASON
    model = identified.fit.model
    assert [r[0] for r in params[1:]] == model.free_parameter_names()
    assert len(IMG.findall(html)) == 1  # the static curves
    figures = identify_figures(identified)
    assert list(figures) == ["search", "output", "blocks", "linear"]
    assert dataclasses.is_dataclass(identified)
    assert list(identified.plot()) == list(figures)
