"""What a BLA result gives out: the summary, the table, the JSON document, the
report's entry."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import signal

from blockid.data import Dataset, Experiment
from blockid.data.io import json_safe
from blockid.design import multisine
from blockid.evaluation import best_linear_approximation


@pytest.fixture(scope="module")
def odd_bla():
    """A Wiener plant with a cubic, 4 realisations of an odd multisine, 3 periods each
    (the first dropped), sampled at 100 Hz."""
    x = multisine(256, sampling_time=0.01, f_max=30, odd=True, periods=3, realisations=4,
                  seed=3)  # fmt: skip
    b, a = signal.butter(2, 0.4)
    rng = np.random.default_rng(0)
    exps = []
    for m, u in enumerate(x.signals):
        v = signal.lfilter(b, a, u)
        exps.append(Experiment(f"r{m}", u, v + 0.3 * v**3 + 0.01 * rng.standard_normal(u.size)))
    data = Dataset(("force",), ("position",), 0.01, exps, source="bench.csv")
    return best_linear_approximation(data, transient_periods=1, bands=2)


def test_the_summary_names_the_data_the_method_and_the_verdict(odd_bla):
    text = odd_bla.summary()
    first = text.splitlines()[0]
    assert first == (
        "BLA force -> position on bench.csv: robust method (periods and realisations of a "
        "periodic excitation), 4 realisation(s) x 2 period(s) of 256 samples, 1 transient "
        "period(s) dropped"
    )
    assert "even lines dB (noise)" in text and "odd lines dB (noise)" in text
    assert text.splitlines()[-1] == odd_bla.verdict
    title, columns, rows, lines = odd_bla.summary_table()
    # the two bands asked for, then the empty lines above the excitation up to Nyquist
    assert len(rows) == 3 and all(len(r) == len(columns) for r in rows)
    assert rows[0][0] == f"{odd_bla.bands[0].low:.4g} - {odd_bla.bands[0].high:.4g}"
    assert rows[2][:3] == ["29.69 - 49.61", "0", "-"]


def test_the_json_document_is_plain_and_complete(odd_bla):
    doc = json.loads(json.dumps(json_safe(odd_bla.to_dict()), allow_nan=False))
    g = np.array(doc["g_real"]) + 1j * np.array(doc["g_imag"])
    np.testing.assert_allclose(g, odd_bla.g)
    assert doc["lines"] == odd_bla.lines.tolist() and doc["periods"] == 2
    assert doc["verdict"] == odd_bla.verdict and len(doc["bands"]) == 3
    band = doc["bands"][0]
    assert set(band) >= {"low_hz", "high_hz", "g_db", "noise_db", "distortion_db", "margin_db",
                         "p_value", "detected", "nonexcited"}  # fmt: skip
    assert set(doc["nonexcited"]["kind"]) == {"even", "odd"}
    assert doc["coherence"] is None and doc["segments"] is None


def test_the_table_has_a_row_a_line(odd_bla):
    frame = odd_bla.to_frame()
    assert len(frame) == odd_bla.g.size
    np.testing.assert_allclose(frame["g_db"], 20 * np.log10(np.abs(odd_bla.g)))
    np.testing.assert_allclose(frame["std"], np.sqrt(odd_bla.var_total))
    assert frame["frequency_hz"].iloc[0] == pytest.approx(odd_bla.lines[0] / 2.56)


def test_the_report_entry_is_small(odd_bla):
    entry = odd_bla.report_entry()
    assert set(entry) == {"title", "verdict", "notes", "columns", "rows", "bands"}
    assert entry["verdict"] == odd_bla.verdict


def test_frequencies_are_named_in_cycles_per_sample_without_a_sampling_time():
    """Without a sampling time the frequencies are cycles per sample, and every label
    (the band column, the verdict, the figure's axis, the JSON) says so; with one, Hz."""
    import matplotlib.pyplot as plt

    from blockid.data import Dataset
    from blockid.design import multisine
    from blockid.evaluation.bla import best_linear_approximation

    u = multisine(256, f_max=0.2, periods=3, seed=2).signals[0]
    y = u + 0.2 * u**3 + 1e-3 * np.random.default_rng(0).standard_normal(u.size)
    bare = best_linear_approximation(Dataset.from_arrays(u, y), transient_periods=1)
    assert bare.unit == "cycles/sample" and bare.to_dict()["unit"] == "cycles/sample"
    assert bare.summary_table()[1][0] == "band (cycles/sample)"
    assert " Hz" not in bare.verdict and "cycles/sample" in bare.verdict
    fig = bare.plot()
    assert fig.axes[-1].get_xlabel() == "frequency (cycles/sample)"
    plt.close(fig)
    timed = best_linear_approximation(
        Dataset.from_arrays(u, y, sampling_time=0.001), transient_periods=1
    )
    assert timed.unit == "Hz" and timed.summary_table()[1][0] == "band (Hz)"
    assert " Hz" in timed.verdict
