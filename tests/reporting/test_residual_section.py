"""The report's residual tests (reporting.residual_section): per model the verdict, the
table of tests and the figure of the correlations with their bounds; an under-modelled
ARX fails, the right one passes."""

from __future__ import annotations

from blockid.evaluation import evaluate
from blockid.fitting import fit_model
from blockid.reporting import build_report
from blockid.reporting.entries import Entry
from blockid.reporting.residual_section import residuals_section
from blockid.workflows import compare_structures
from reporting.page import Report

from reference import fourth_order_arx_halves


def test_the_report_flags_an_under_modelled_arx_with_its_figure():
    est, val = fourth_order_arx_halves()
    result = compare_structures(est, val, ["arx"], options={"na": 1, "nb": 2, "nk": 1})
    html = build_report(compare=result, estimation=est, validation=val)
    parts = Report(html).sections["residuals"]
    model = next(p for p in parts if p.title == "arx (batch)")
    verdict = next(t for t in model.paragraphs if t.startswith("Verdict:"))
    assert "fails" in verdict and "correlates with past u" in verdict
    rows = {r[0]: r for r in model.tables[0][1:]}
    assert rows["whiteness of y"][-1] == "not white"
    assert rows["u -> residual of y (lags >= 0)"][-1] == "not independent"
    assert float(rows["whiteness of y"][2]) < 1e-6
    assert "autocorrelation" in model.captions[0] and "99 % bounds" in model.captions[0]
    assert 'href="#residuals"' in html


def test_the_right_model_passes_and_an_entry_without_an_analysis_gets_one():
    est, val = fourth_order_arx_halves()
    fit = fit_model(est, "arx", na=4, nb=2, nk=1)
    entry = Entry("arx(4, 2, 1)", "batch", fit, evaluate(fit.model, val), None)
    html = residuals_section([entry])
    part = next(p for p in Report(f"<body>{html}</body>").sections["residuals"] if p.title)
    verdict = next(t for t in part.paragraphs if t.startswith("Verdict:"))
    assert "passes: white and independent of the inputs" in verdict
    assert [r[-1] for r in part.tables[0][1:]] == ["white", "independent"]
    assert html.count("data:image/png;base64,") == 1
