"""The HTML report: self-contained, every figure a valid PNG, provenance recorded."""

from __future__ import annotations

import base64
import hashlib
import platform
import re
import struct

import numpy as np
import pytest

from reporting.page import IMG

from reference import _with_errors


def _png_size(raw: bytes) -> tuple[int, int]:
    assert raw[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    assert raw[12:16] == b"IHDR"
    assert raw[-8:-4] == b"IEND", "truncated PNG"
    return struct.unpack(">II", raw[16:24])


def test_report_embeds_at_least_four_valid_png_figures(example_report):
    html = example_report.html
    images = IMG.findall(html)
    assert len(images) >= 4
    assert html.count("<img") == len(images), "every image is an embedded PNG"
    for text in images:
        raw = base64.b64decode(text, validate=True)
        width, height = _png_size(raw)
        assert width >= 300 and height >= 150
        assert len(raw) > 5000, "a figure with content, not an empty canvas"


def test_report_has_no_external_reference(example_report):
    html = example_report.html.lower()
    for needle in ("http://", "https://", 'src="//', "href=\"//", "<script", "<link", "@import",
                   "url(", "<iframe", "<object", "<embed"):  # fmt: skip
        assert needle not in html, needle
    # links are anchors within the page only
    assert all(h.startswith("#") for h in re.findall(r'href="([^"]*)"', html))
    assert all(s.startswith("data:image/png;base64,") for s in re.findall(r'src="([^"]*)"', html))


def test_report_records_command_hash_and_versions(example_report):
    import numpy
    import pandas
    import scipy

    from blockid import __version__

    html = example_report.html
    digest = hashlib.sha256(example_report.data.read_bytes()).hexdigest()
    assert digest in html
    assert f"blockid report {example_report.data}" in html
    assert "--validation 1100:2200" in html and "--method key-term-rls" in html
    for version in (__version__, numpy.__version__, scipy.__version__, pandas.__version__):
        assert f"<td>{version}</td>" in html
    assert platform.python_version() in html


def test_report_sections_and_captions(example_report):
    html = example_report.html
    for title in ("Data overview", "Best linear approximation", "Comparison of the models", "Measured and simulated output",
                  "Identified nonlinearities", "Parameter trajectories of recursive estimators",
                  "Provenance"):  # fmt: skip
        assert f"<h2>{title}</h2>" in html
    assert "free-run simulation on the validation range 1100:2200" in html
    assert "estimation range 0:1100" in html
    assert "Sampling time: 0.05 s" in html
    # the command asks for standard errors: bands from the parameter covariance
    assert "95 % confidence band of the noise-free output" in html
    assert "parameter draws from the parameter covariance" in html
    assert (
        "recursive estimator key-term-rls, recorded at" in html
    )  # a recursive estimator's trajectories
    assert html.count("<figcaption>") == len(IMG.findall(html))


def test_confidence_bands_are_drawn_from_standard_errors(hammerstein):
    from blockid.reporting import build_report

    data, est, val, result = hammerstein
    theta = result.models[0].fit.model.free_parameters()
    banded = _with_errors(result, 0.02 * np.abs(theta) + 1e-4)
    html = build_report(compare=banded, data=data, estimation=est, validation=val)
    assert "95 % band over 200 parameter draws" in html
    assert "95 % band of the simulated output" in html
    assert "No uncertainty available" not in html
    assert "validation data" in html  # no range text given: said so, not invented


def test_report_of_an_identify_result(hammerstein):
    from blockid.evaluation import evaluate
    from blockid.reporting import build_report
    from blockid.workflows.identify import Candidate, IdentifyResult, Score

    data, est, val, result = hammerstein
    fit = result.models[0].fit
    chosen = Score(Candidate("hammerstein", {"na": 3, "nb": 3, "nk": 8}), rmse=0.02,
                   fit_percent=75.0, n_parameters=13, stage="final")  # fmt: skip
    rejected = Score(Candidate("wiener", {"r2": 3}), stage="screen", reason="unstable")
    identified = IdentifyResult(
        selected=chosen, fit=fit, ranked=[chosen], rejected=[rejected],
        simulation=evaluate(fit.model, val, "simulation"),
        one_step=evaluate(fit.model, val, "one-step"), one_step_error=None,
        on="validation", seconds=1.5, holdout="4 contiguous folds (blocked cross-validation)",
        search={"effort": "quick", "cut_by_time_limit": True},
    )  # fmt: skip
    html = build_report(
        identify=identified, data=data, estimation=est, validation=val,
        estimation_range="0:1100", validation_range="1100:2200",
    )  # fmt: skip
    assert "<h2>Search of identify()</h2>" in html
    assert "identify: hammerstein(na=3, nb=3, nk=8)" in html
    assert "<td>unstable</td>" in html
    assert "effort quick" in html and "The time limit cut the search" in html
    assert "free-run simulation on the validation range 1100:2200" in html
    # data, BLA, the model against the BLA, output, residual tests, linear dynamics,
    # blocks (one model and no ARX in the search: no bar chart, no search figure, no
    # linear baseline)
    assert len(IMG.findall(html)) == 7
    assert "Linear baseline: none, the search scored no ARX model" in html
    apart = build_report(identify=identified, estimation=est, validation=val)  # no record
    assert "Measured estimation data" in apart and "Measured validation data" in apart
    assert "free-run simulation on the validation data" in apart


def test_build_report_needs_a_result(hammerstein):
    from blockid.errors import ParameterError
    from blockid.reporting import build_report

    with pytest.raises(ParameterError, match="compare or an identify"):
        build_report(estimation=hammerstein[1])


def test_a_fit_stopped_at_its_evaluation_limit_is_named_in_the_report():
    """The fit's own warnings reach the comparison section, as on stderr and in the
    model file (issue 36: a fit that stops at ``max_nfev`` says so)."""
    from blockid.reporting import build_report
    from blockid.workflows import compare_structures

    from reference import squared_state_record

    data = squared_state_record(800)
    est, val = data.select(0, 500), data.select(500, 800)
    result = compare_structures(est, val, ["polynomial-state-space"],
                                options={"nx": 2, "degree": 2, "max_nfev": 3})  # fmt: skip
    html = build_report(compare=result, estimation=est, validation=val)
    assert "stopped at its evaluation limit (max_nfev = 3" in html
