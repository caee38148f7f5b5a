"""``blockid design`` driven as a user would: the summary, the JSON document, the file
read back by ``blockid fit --experiment-column``, no file replaced without --force, and
one-line errors that name the flag."""

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from blockid.cli.main import app
from blockid.design import multisine

runner = CliRunner()

ODD = ["odd-multisine", "--fs", "1000", "--samples", "1000", "--f-min", "10", "--f-max", "200"]


def _run(*args, code=0):
    r = runner.invoke(app, ["design", *map(str, args)])
    assert r.exit_code == code, r.output
    return r


def test_the_summary_shows_each_realisation_s_crest_factors_and_the_lines():
    r = _run(*ODD, "--realisations", "2", "--crest-iterations", "50", "--seed", "3")
    out = r.stdout
    x = multisine(1000, sampling_time=1e-3, f_min=10, f_max=200, odd=True, realisations=2,
                  crest_iterations=50, seed=3)  # fmt: skip
    assert "odd random-phase multisine: 2 realisations x 1 period x 1000 samples" in out
    for r_, (after, before) in enumerate(zip(x.crest_factor, x.crest_factor_start, strict=True)):
        assert f"{after:.3f}" in out and f"{before:.3f}" in out, r_
    assert f"excited lines ({len(x.lines)}): 11, " in out
    assert f"odd lines left out ({len(x.left_out)}): " in out
    assert "no file written" in out


def test_json_is_the_library_s_document():
    doc = json.loads(_run(*ODD, "--rms", "0.2", "--json").stdout)
    x = multisine(1000, sampling_time=1e-3, f_min=10, f_max=200, odd=True, rms=0.2)
    expected = json.loads(json.dumps(x.to_dict()))
    assert {k: v for k, v in doc.items() if k not in ("out", "columns")} == expected
    assert doc["out"] is None and doc["columns"] == ["t", "realisation", "period", "u"]


def test_the_written_file_is_fitted_one_experiment_per_realisation(tmp_path):
    out = tmp_path / "design.csv"
    _run("multisine", "--ts", "0.01", "--samples", "128", "--f-max", "20", "--periods", "2",
         "--realisations", "3", "--name", "valve", "-o", out)  # fmt: skip
    frame = pd.read_csv(out)
    assert list(frame.columns) == ["t", "realisation", "period", "valve"]
    valve = frame["valve"].to_numpy()
    frame["flow"] = np.concatenate([[0.0], 0.7 * valve[:-1]])  # what the plant answered
    frame.to_csv(out, index=False)
    r = runner.invoke(app, ["fit", str(out), "-u", "valve", "-y", "flow", "--time-column", "t",
                            "--experiment-column", "realisation", "--na", "1", "--nb", "1",
                            "--nk", "1", "--json"])  # fmt: skip
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["model"]["sampling_time"] == 0.01
    assert doc["estimation"]["n_samples"] == 3 * 2 * 128


def test_an_existing_file_is_kept_without_force(tmp_path):
    out = tmp_path / "u.csv"
    out.write_text("old")
    r = _run("prbs", "--order", "5", "-o", out, code=2)
    assert "u.csv exists; pass --force to replace it" in r.stderr and out.read_text() == "old"
    _run("prbs", "--order", "5", "-o", out, "--force")
    assert len(pd.read_csv(out)) == 31


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["multisine", "--fs", "1000", "--samples", "100", "--f-max", "600"],
         "f_max = 600 Hz is above the Nyquist frequency 500 Hz (half the sampling frequency "
         "1000 Hz); lower f_max or sample faster (option --f-max)"),
        (["multisine", "--samples", "100", "--f-min", "0.3", "--f-max", "0.2"],
         "f_min = 0.3 Hz is above f_max = 0.2 Hz; give f_min <= f_max (option --f-min)"),
        (["odd-multisine", "--samples", "100", "--f-min", "0.101", "--f-max", "0.109"],
         "no line of the frequency grid lies in the band (option --f-max)"),
        (["multisine", "--samples", "100", "--rms", "0"], "rms must be a finite number > 0"),
        (["prbs", "--order", "25"], "order must be 2..24"),
        (["prbs", "--order", "5", "--realisations", "2"], "prbs takes no realisations"),
        (["multisine"], "multisine needs samples (samples in one period) (option --samples)"),
        (["multisine", "--samples", "100", "--fs", "10", "--ts", "0.2"], "--fs 10 and --ts 0.2"),
        (["multisine", "--samples", "100", "--name", "t"], "--name 't' would clash"),
        (["sine"], "unknown excitation 'sine'"),
    ],
    ids=lambda v: " ".join(v)[:40] if isinstance(v, list) else None,
)  # fmt: skip
def test_bad_input_is_one_line_naming_the_flag(args, message):
    r = _run(*args, code=2)
    assert r.stderr.count("\n") == 1 and r.stderr.startswith("error: ")
    if "no line" in message:
        head, tail = message.split(" (option")
        assert head in r.stderr and r.stderr.rstrip().endswith("(option" + tail)
    else:
        assert message in r.stderr, r.stderr
