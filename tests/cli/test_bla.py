"""``blockid bla`` driven as a user would: a designed odd multisine, the plant's
response logged beside it, the summary and verdict, the figure and the JSON file, and
one-line errors that name the flag."""

import json

import numpy as np
import pandas as pd
from scipy import signal
from typer.testing import CliRunner

from blockid.blocks.backlash import Backlash
from blockid.cli.main import app

runner = CliRunner()


def _run(*args, code=0):
    r = runner.invoke(app, [*map(str, args)])
    assert r.exit_code == code, r.output
    return r


def _experiment(tmp_path, cubic: float) -> str:
    """``blockid design`` writes the excitation; a Wiener plant (low-pass, then ``x +
    cubic x³``) answers it with a little noise; the response goes in column y."""
    design = tmp_path / "excitation.csv"
    _run("design", "odd-multisine", "--fs", "100", "--samples", "256", "--f-max", "30",
         "--periods", "3", "--realisations", "4", "--seed", "5", "-o", design)  # fmt: skip
    frame = pd.read_csv(design)
    b, a = signal.butter(2, 0.4)
    rng = np.random.default_rng(0)
    y = []
    for _, rows in frame.groupby("realisation"):
        x = signal.lfilter(b, a, rows["u"].to_numpy())
        y.append(x + cubic * x**3 + 0.005 * rng.standard_normal(x.size))
    frame["y"] = np.concatenate(y)
    path = tmp_path / "measured.csv"
    frame.to_csv(path, index=False)
    return path


BASE = ("-u", "u", "-y", "y", "--time-column", "t", "--experiment-column", "realisation")


def test_a_nonlinear_plant_is_said_worth_a_nonlinear_model(tmp_path):
    data = _experiment(tmp_path, cubic=0.5)
    r = _run("bla", data, *BASE, "--transient-periods", "1", "--plot", tmp_path / "figs",
             "-o", tmp_path / "bla.json")  # fmt: skip
    out = r.stdout
    assert (
        "robust method (periods and realisations of a periodic excitation), 4 realisation(s)" in out
    )
    assert "x 2 period(s) of 256 samples, 1 transient period(s) dropped" in out
    assert "even lines dB (noise)" in out and "odd lines dB (noise)" in out
    assert "nonlinear distortion dominates the noise by" in out and "worth trying" in out
    assert (tmp_path / "figs" / "bla.png").exists()
    doc = json.loads((tmp_path / "bla.json").read_text())
    assert doc["odd_design"] and all(b["detected"] for b in doc["bands"] if b["lines"])


def test_a_linear_plant_is_said_to_need_no_nonlinear_model(tmp_path):
    data = _experiment(tmp_path, cubic=0.0)
    doc = json.loads(_run("bla", data, *BASE, "--transient-periods", "1", "--json").stdout)
    assert doc["verdict"].startswith("no nonlinear distortion above the noise in any band")


def test_errors_are_one_line_and_name_the_flag(tmp_path):
    data = _experiment(tmp_path, cubic=0.0)
    r = _run("bla", data, *BASE, "--period", "200", code=2)
    assert r.stderr.count("\n") == 1 and r.stderr.startswith("error: experiment '1' holds 768")
    assert r.stderr.rstrip().endswith("(option --period)")
    r = _run("bla", data, *BASE, "--confidence", "2", code=2)
    assert "confidence must lie between 0 and 1" in r.stderr and "(option --confidence)" in r.stderr
    r = _run("bla", data, *BASE, "--segment", "64", "--period", "256", code=2)
    assert "period and segment do not go together" in r.stderr


def test_by_default_distortion_outside_the_excited_band_is_found(tmp_path):
    """One realisation of a multisine over 5-20 Hz (fs 100 Hz) through a backlash: the
    default command tests the empty lines below and above the band, drops the first
    period as the transient, and says a nonlinear model is worth trying."""
    design = tmp_path / "excitation.csv"
    _run("design", "multisine", "--fs", "100", "--samples", "1024", "--f-min", "5",
         "--f-max", "20", "--periods", "4", "--seed", "3", "-o", design)  # fmt: skip
    frame = pd.read_csv(design)
    b, a = signal.butter(2, 0.4)
    play = Backlash(1.0, 0.1, 1.0, 0.1).simulate(frame["u"].to_numpy())
    noise = 0.01 * np.random.default_rng(0).standard_normal(len(frame))
    frame["y"] = signal.lfilter(b, a, play) + noise
    frame.to_csv(tmp_path / "measured.csv", index=False)
    doc = json.loads(_run("bla", tmp_path / "measured.csv", "-u", "u", "-y", "y",
                          "--time-column", "t", "--json").stdout)  # fmt: skip
    assert doc["transient_periods"] == 1 and doc["periods"] == 3
    below, above = doc["bands"][0], doc["bands"][-1]
    assert below["lines"] == above["lines"] == 0 and above["high_hz"] == 511 * 100 / 1024
    assert doc["verdict"].startswith("one realisation: the distortion at the excited lines")
    assert "nonlinear distortion dominates the noise by" in doc["verdict"]
    assert "worth trying" in doc["verdict"]
