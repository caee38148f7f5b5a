"""The report of state-space models says what they are: a pole at z = -0.999 named a
mode at the Nyquist frequency, and one-step columns that do not repeat the free run of a
model without a noise model (the HTML parsed as a reader sees it,
tests/reporting/page.py)."""

from __future__ import annotations

import numpy as np
import pytest

from reporting.conftest import TS
from reporting.page import Report

OE, WITH_K = "state-space (simulation-error)", "state-space (subspace)"


def test_a_pole_at_minus_one_is_named_a_nyquist_mode(state_space_report):
    """Not 'slowest pole |p| = 0.999 (time constant ...)' with an empty oscillation
    cell: a mode at the Nyquist frequency, period 2 samples."""
    _, _, html = state_space_report
    part = Report(html).part("linear", OE)
    sentence = part.paragraphs[0]
    assert "least damped pole p = -0.999 is a mode at the Nyquist frequency" in sentence
    assert "its sign alternates every sample (period 2 samples)" in sentence
    assert "slowest pole |p|" not in sentence
    assert "gain at the Nyquist frequency |G(-1)|" in sentence
    rows = part.tables[0]
    (nyquist,) = [r for r in rows if r[:2] == ["pole", "-0.999"]]
    assert nyquist[3] == f"{-TS / np.log(0.999):.4g} s"  # the envelope's time constant
    assert nyquist[4] == f"{0.5 / TS:.4g} Hz: the Nyquist frequency, period 2 samples"
    (slow,) = [r for r in rows if r[:2] == ["pole", "0.9"]]
    assert slow[4] == "none"  # a positive real pole does not oscillate


def test_one_step_columns_say_when_a_model_predicts_by_its_free_run(state_space_report):
    """An output-error state space has no noise model: its one-step prediction is its
    free run, so its one-step cells say so instead of repeating the free-run numbers;
    one with a predictor gain K keeps its own one-step numbers."""
    _, result, html = state_space_report
    oe, with_k = result.models
    np.testing.assert_array_equal(oe.one_step.outputs[0], oe.simulation.outputs[0])
    page = Report(html)
    part = page.sections["comparison"][0]
    header, *rows = part.tables[0]
    assert header[6:] == ["one-step MSE", "one-step RMSE", "one-step fit %"]
    (oe_row,) = [r for r in rows if r[0] == OE]
    assert oe_row[6:] == ["= free run"] * 3
    assert float(oe_row[3]) == pytest.approx(oe.simulation.metrics["mse"]["y"], rel=1e-3)
    (k_row,) = [r for r in rows if r[0] == WITH_K]
    assert float(k_row[6]) == pytest.approx(with_k.one_step.metrics["mse"]["y"], rel=1e-3)
    assert float(k_row[6]) != pytest.approx(float(k_row[3]), rel=1e-3)
    notes = [p for p in part.paragraphs if p.startswith(f"{OE}: one-step prediction")]
    assert len(notes) == 1 and "the model has no noise model" in notes[0]
    assert not any(p.startswith(f"{WITH_K}: one-step prediction") for p in part.paragraphs)
