"""The report's model sections (reporting/model_sections.py): each model's parameters
with their standard errors, its linear dynamics, its blocks' deviation from a line."""

from __future__ import annotations

import numpy as np
import pytest

from blockid.plotting.linear import linear_dynamics, pole_rows
from reporting.page import Report, _number


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
