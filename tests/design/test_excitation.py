"""An excitation's table: written, read back by blockid's own reader with
--time-column t --experiment-column realisation, bit for bit; its JSON document."""

import json

from blockid.data import read_data, write_table
from blockid.design import crest_factor, multisine, prbs


def test_the_table_reads_back_one_experiment_per_realisation_bit_for_bit(tmp_path):
    x = multisine(64, sampling_time=0.01, f_min=2, f_max=30, odd=True, periods=3,
                  realisations=2, crest_iterations=5, seed=3)  # fmt: skip
    frame = x.to_frame("force")
    assert list(frame.columns) == ["t", "realisation", "period", "force"]
    frame["y"] = 0.8 * frame["force"] + 0.1 * frame["force"] ** 2  # a measured response
    path = write_table(frame, tmp_path / "design.csv")
    data = read_data(path, ["force"], ["y"], time_column="t", experiment_column="realisation")
    assert data.sampling_time == 0.01
    assert [e.name for e in data.experiments] == ["1", "2"]
    for experiment, signal in zip(data.experiments, x.signals, strict=True):
        assert experiment.u[:, 0].tobytes() == signal.tobytes()
        assert experiment.n_samples == 3 * 64


def test_the_period_column_counts_periods_within_each_realisation():
    frame = prbs(3, clock=2, periods=2).to_frame()
    assert frame["period"].tolist() == [1] * 14 + [2] * 14
    assert frame["t"].iloc[-1] == 27.0 and set(frame["realisation"]) == {1}


def test_the_document_holds_the_measured_properties():
    x = multisine(128, sampling_time=0.5, f_max=0.4, rms=2.0, realisations=2, seed=1)
    doc = json.loads(json.dumps(x.to_dict()))
    assert doc["kind"] == "multisine" and doc["resolution_hz"] == 1 / 64
    assert doc["lines"] == list(range(1, 26)) and doc["frequencies_hz"][-1] == 25 / 64
    assert [s["crest_factor"] for s in doc["signals"]] == crest_factor(x.signals).tolist()
    assert all(abs(s["rms"] - 2.0) < 1e-12 for s in doc["signals"])
    assert doc["signals"][0]["crest_factor_start"] == doc["signals"][0]["crest_factor"]
    assert doc["settings"]["band_hz"] == [1 / 64, 25 / 64]
