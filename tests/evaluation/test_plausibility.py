"""blockid.evaluation.plausibility: an output beyond the measured range, a diverged
output, poles on, near or beyond the unit circle or at the Nyquist frequency."""

from __future__ import annotations

import numpy as np

from blockid.evaluation.plausibility import (
    DIVERGED_EXCURSION,
    MAX_OUTPUT_EXCURSION,
    POLE_MARGIN,
    divergence,
    output_excursion,
    output_range_notes,
    pole_notes,
)

Y = np.array([[0.0], [10.0]])  # a 0-10 V measured output


def test_output_excursion_is_in_widths_of_the_measured_range():
    y = np.array([[0.0, 1.0], [10.0, 1.0]])  # the second output is constant
    excess = output_excursion(y, np.array([[-2.0, 5.0], [25.0, 1.0]]))
    assert excess[0] == 1.5 and np.isnan(excess[1])  # a constant output is not judged
    assert output_excursion(Y, np.array([[np.nan], [1.0]]))[0] == np.inf


def test_the_output_range_warning_starts_above_its_limit():
    edge = 10.0 + 10.0 * MAX_OUTPUT_EXCURSION
    assert output_range_notes(Y, np.array([[0.0], [0.99 * edge]]), ["y"]) == []
    # the polynomial state space: 57 V on a 0-10 V record
    (note,) = output_range_notes(Y, np.array([[0.0], [58.0]]), ["y"], "free run")
    assert "free run of 'y' reaches [0, 58] against the measured range [0, 10]" in note
    assert "by 4.8 times its width" in note and "fit on data that cover" in note


def test_divergence_names_the_output_and_an_unstable_pole():
    assert divergence(Y, np.array([[0.0], [50.0]]), ["y"]) is None
    below = 10.0 + 0.9 * 10.0 * DIVERGED_EXCURSION
    assert divergence(Y, np.array([[0.0], [below]]), ["y"]) is None
    far = divergence(Y, np.array([[0.0], [3.9e67]]), ["y"], np.array([1.05, 0.5]))
    assert "'y' reaches 3.9e+67" in far and "a pole at 1.05" in far
    inf = divergence(Y, np.array([[0.0], [np.inf]]), ["y"])
    assert "not finite in 1 of 2 samples" in inf and "pole" not in inf


def test_pole_notes_name_one_pole_of_each_kind():
    assert pole_notes(np.array([0.5, 0.9 + 0.1j, 0.9 - 0.1j])) == []
    (unstable,) = pole_notes(np.array([1.05, 0.5]))
    assert "unstable" in unstable and "outside the unit circle" in unstable
    assert "doubling every 14.2 samples" in unstable
    (near,) = pole_notes(np.array([1.0 - POLE_MARGIN / 2]))
    assert "within 0.001 of the unit circle" in near and "time constant of 1999 samples" in near
    (nyquist,) = pole_notes(np.array([-0.97, 0.3]))
    assert "-0.97, within 0.05 of -1" in nyquist and "Nyquist" in nyquist
    # a pole near -1 on the margin is named once, as the Nyquist mode it is (it does
    # not drift, and an integrator is no cure); not at all when noted elsewhere
    (once,) = pole_notes(np.array([-(1.0 - POLE_MARGIN / 2)]))
    assert "Nyquist" in once and "integrator" not in once and "drifts" not in once
    (both,) = pole_notes(np.array([-0.9995, 0.5]))  # the report's state space
    assert "-0.9995, within 0.05 of -1" in both and "time constant" not in both
    assert len(pole_notes(np.array([-0.9995, 0.9995]))) == 2  # a slow mode and a Nyquist one
    assert pole_notes(np.array([-(1.0 - POLE_MARGIN / 2)]), near_noted=True) == []
    assert len(pole_notes(np.array([1.02, -0.98]))) == 2  # unstable, and a Nyquist mode


def test_the_limits_are_the_ones_docs_cli_states():
    from pathlib import Path

    from blockid.evaluation.plausibility import NYQUIST_MARGIN

    doc = (Path(__file__).parents[2] / "docs" / "cli.md").read_text()
    assert f"{MAX_OUTPUT_EXCURSION:g} (`evaluation.plausibility.MAX_OUTPUT_EXCURSION`)" in doc
    assert f"{POLE_MARGIN:g} (`POLE_MARGIN`)" in doc
    assert f"within {NYQUIST_MARGIN:g} of −1 (`NYQUIST_MARGIN`)" in doc
    assert DIVERGED_EXCURSION == 1e6 and "more than 10⁶ widths" in doc
