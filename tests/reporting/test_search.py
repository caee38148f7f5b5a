"""The report's search section (reporting/search.py): the identify search with its
linear baseline and the candidates it rejected."""

from __future__ import annotations

import pytest

from blockid.evaluation import evaluate
from blockid.fitting import fit_model
from blockid.reporting import build_report
from reporting.conftest import LONG_REASON
from reporting.page import Report, _number


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
