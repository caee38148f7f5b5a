"""The report's sections with the right numbers: parameters and standard errors, linear
dynamics, the zoom on long records, the identify search with its linear baseline, and
text that is never cut (the HTML parsed as a reader sees it, tests/reporting/page.py)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from blockid.data import Dataset
from blockid.plotting.report_figures import zoom_window
from blockid.reporting import build_report
from reporting.page import Report


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
