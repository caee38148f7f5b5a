"""The report of state-space models says what they are: a pole at z = -0.999 named a
mode at the Nyquist frequency, one-step columns that do not repeat the free run of a
model without a noise model, basis-free quantities instead of the entries of A, B and C
(folded away), and a block state space's blocks with their deviation from a line and
bands (the HTML parsed as a reader sees it, tests/reporting/page.py)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from blockid.plotting.uncertainty import free_covariance, sampled_models
from blockid.reporting import build_report
from reporting.conftest import DEN, NUM, TS
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


def _main(html: str, label: str) -> str:
    """The HTML of ``label``'s part of the parameters section, outside any fold."""
    section = re.search(r'<section id="parameters">.*?</section>', html, re.S).group(0)
    part = section.split(f"<h3>{label}</h3>")[1].split("<h3>")[0]
    return re.sub(r"<details>.*?</details>", "", part, flags=re.S)


def test_the_parameters_are_basis_free_quantities_the_matrices_folded(state_space_report):
    """No A[i,j] rows (an arbitrary basis, relative SEs of thousands of per cent) in the
    main table: the static gain, poles, Hankel singular values and Markov parameters,
    with standard errors by the delta method; the matrices folded, values only."""
    model, result, html = state_space_report
    main = Report(f'<section id="parameters"><h3>x</h3>{_main(html, OE)}</section>')
    (quantities, parameters) = main.part("parameters", "x").tables
    names = [r[0] for r in quantities[1:]] + [r[0] for r in parameters[1:]]
    assert not any(re.match(r"[ABCE]\[", n) for n in names), names
    assert [r[0] for r in parameters[1:]] == ["D[0,0]"]  # basis-free: the feedthrough
    values = {r[0]: float(r[1]) for r in quantities[1:]}
    assert values["static gain y / u"] == pytest.approx(
        np.polyval(NUM, 1.0) / np.polyval(DEN, 1.0), rel=1e-5
    )
    assert values["|p| of pole -0.999"] == pytest.approx(0.999, rel=1e-6)
    assert values["Markov parameter h(1) y / u"] == pytest.approx(
        (model.C @ model.B).item(), rel=1e-5
    )
    assert values["Markov parameter h(2) y / u"] == pytest.approx(
        (model.C @ model.A @ model.B).item(), rel=1e-5
    )
    hankel = [v for n, v in values.items() if n.startswith("Hankel singular value")]
    assert len(hankel) == 3 and hankel == sorted(hankel, reverse=True)
    # the delta method's standard error of the static gain against parameter draws
    fit = result.models[0].fit
    drawn = sampled_models(model, n=400, seed=1, covariance=free_covariance(fit))
    gains = [m.transfer_function() for m in drawn]
    spread = np.std([np.polyval(n_[0] if n_.ndim > 1 else n_, 1.0) / np.polyval(d, 1.0)
                     for n_, d in gains])  # fmt: skip
    (gain_row,) = [r for r in quantities[1:] if r[0] == "static gain y / u"]
    assert float(gain_row[2]) == pytest.approx(spread, rel=0.2)
    # the fold: every matrix row, labelled as basis-dependent, without standard errors
    section = re.search(r'<section id="parameters">.*?</section>', html, re.S).group(0)
    fold = re.search(r"<details>.*?</details>", section.split(f"<h3>{OE}</h3>")[1], re.S)
    folded = Report(f'<section id="f"><h3>x</h3>{fold.group(0)}</section>').part("f", "x")
    assert folded.tables[0][0] == ["matrix row", "values (fitted basis)"]
    rows = [r[0] for r in folded.tables[0][1:]]
    assert rows == ["A[0,:]", "A[1,:]", "A[2,:]", "B[0,:]", "B[1,:]", "B[2,:]", "C[0,:]"]
    assert "depend on the basis" in fold.group(0)
    assert any("no standard errors are shown" in p for p in folded.paragraphs)


def test_a_block_state_space_gets_deviation_panels_and_bands_in_the_report():
    from blockid.workflows import compare_structures

    from reference import mimo_hw_record

    data, _ = mimo_hw_record(n=600)
    est, val = data.select(0, 400), data.select(400, 600)
    options = dict(nx=3, input_block="polynomial", output_block={"y2": "polynomial"},
                   standard_errors=True)  # fmt: skip
    result = compare_structures(est, val, ["block-state-space"], options=options)
    html = build_report(compare=result, estimation=est, validation=val)
    page = Report(html)
    (part,) = page.sections["blocks"][1:]
    (caption,) = part.captions
    assert "Right: the curve minus its least-squares straight line" in caption
    assert "95 % band over 200 parameter draws from the parameter covariance" in caption
    assert "No uncertainty band is drawn" not in caption
    # the main parameter table holds the blocks' coefficients, not the core's matrices
    main = _main(html, part.title)
    assert "input u1: " in main and "A[0,0]" not in main
