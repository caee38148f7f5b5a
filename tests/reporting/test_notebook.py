"""The notebook view of an identify result (reporting/notebook.py): its summary and
figures."""

from __future__ import annotations

import dataclasses

from reporting.conftest import LONG_REASON
from reporting.page import IMG, Report


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
