"""identify on periodic data records the measured distortion level (issue 34 item 3):
a linear plant gets the note that nonlinear candidates cannot be justified, a nonlinear
one does not; non-periodic data get no record."""

from __future__ import annotations

import json

import numpy as np
from scipy.signal import lfilter

from blockid.data import Dataset
from blockid.data.dataset import Experiment
from blockid.design import multisine
from blockid.workflows.distortion import distortion_record
from blockid.workflows.identify import identify

NOTE = "nonlinear candidates cannot be justified by the data"


def _periodic(cubic: float, realisations: int = 3, periods: int = 3) -> Dataset:
    """A second-order plant after ``w = u + cubic u**3``, a multisine of ``realisations``
    x ``periods`` periods of 256 samples, output noise of standard deviation 0.01."""
    x = multisine(256, f_max=0.4, periods=periods, realisations=realisations, seed=4)
    rng = np.random.default_rng(5)
    experiments = []
    for m, u in enumerate(x.signals):
        y = lfilter([0, 0.5, 0.3], [1, -1.2, 0.5], u + cubic * u**3)
        experiments.append(Experiment(f"r{m}", u, y + 0.01 * rng.standard_normal(u.size)))
    return Dataset(("u",), ("y",), 1.0, experiments)


def test_a_linear_plant_gets_the_note_and_a_nonlinear_one_its_distortion():
    notes: list[str] = []
    linear = distortion_record(_periodic(0.0), notes)
    assert linear["method"] == "robust" and linear["detected"] is False
    assert linear["realisations"] == 3 and len(linear["bands"]) >= 4
    assert len(notes) == 1 and notes[0].startswith(NOTE)
    assert all(b["detected"] is False for b in linear["bands"] if b["lines"])
    notes = []
    cubic = distortion_record(_periodic(0.3), notes)
    assert cubic["detected"] is True and notes == []
    margins = [b["margin_db"] for b in cubic["bands"] if b["margin_db"] is not None]
    assert max(margins) > 20  # the cubic stands far above the noise
    json.dumps(cubic)  # plain JSON types


def test_data_that_do_not_repeat_or_of_several_signals_get_no_record():
    rng = np.random.default_rng(0)
    u = rng.standard_normal(1500)
    noise = Dataset.from_arrays(u, lfilter([0, 0.5], [1, -0.8], u), ["u"], ["y"])
    notes: list[str] = []
    assert distortion_record(noise, notes) is None and notes == []
    two = Dataset(("u1", "u2"), ("y",), 1.0, [Experiment("e", rng.standard_normal((400, 2)),
                                                          rng.standard_normal((400, 1)))])  # fmt: skip
    assert distortion_record(two, notes) is None


def test_identify_records_it_and_chooses_as_before():
    """The note and the record; the nonlinear structures searched all the same."""
    data = _periodic(0.0)
    result = identify(data, structures=["arx", "hammerstein"], effort="quick", jobs=1)
    assert any(n.startswith(NOTE) for n in result.notes)
    record = result.search["distortion"]
    assert record["detected"] is False and record["method"] == "robust"
    searched = {s.candidate.structure for s in result.ranked}
    assert "hammerstein" in searched  # never skipped
    assert json.loads(json.dumps(result.to_dict()))["search"]["distortion"] == record
