"""blockid.cli.examples: ``demo``, ``reproduce`` and ``example-data`` driven as a user
would (typer's CliRunner)."""

import pandas as pd
from typer.testing import CliRunner

from blockid.cli.main import app

runner = CliRunner()


def test_the_demo_s_first_screen_says_why_before_a_cell_says_no_model(tmp_path):
    """The paper's estimator returns no model on three of the four structures: the line
    above the table says why there are notes, each such cell says what happened (not
    converged, diverged) with the number of the note below that explains it."""
    r = CliRunner().invoke(app, ["demo", "--output-dir", str(tmp_path / "demo")])
    assert r.exit_code == 0, r.output
    lines = r.stdout.splitlines()
    first_mark = next(k for k, line in enumerate(lines) if "[1]" in line)
    assert any("numbered notes below" in line for line in lines[:first_mark])
    assert not any("│ failed" in line or " failed " in line for line in lines)
    marks = [m for line in lines if "│" in line for m in ("[1]", "[2]", "[3]", "[4]") if m in line]
    for mark in marks:
        assert any(line.startswith(f"{mark} ") for line in lines), mark


def test_demo_refuses_a_non_empty_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "mine.txt").write_text("keep")
    r = CliRunner().invoke(app, ["demo", "--plot", "out"])
    assert r.exit_code == 2 and "not empty" in r.stderr
    assert (tmp_path / "out" / "mine.txt").read_text() == "keep"


def test_a_negative_seed_is_one_readable_line(tmp_path):
    """``example-data --seed -1`` once ended in NumPy's traceback from the random
    generator; nothing is written."""
    out = tmp_path / "x.csv"
    r = runner.invoke(app, ["example-data", "electrohydraulic", "-o", str(out), "--seed", "-1"])
    assert r.exit_code == 2 and "--seed" in r.stderr and "Traceback" not in r.output
    assert not out.exists()


def test_example_data_gives_the_ranges_it_prints(tmp_path):
    out = tmp_path / "wt.csv"
    r = runner.invoke(app, ["example-data", "windtunnel-110kPa", "-o", str(out)])
    assert r.exit_code == 0, r.output
    assert "estimation record 0:1200, validation record 1200:2400" in r.stdout
    frame = pd.read_csv(out)
    assert list(frame.columns) == ["t", "u1", "u2", "v1", "v2", "y1", "y2"] and len(frame) == 2400
    r = runner.invoke(app, ["example-data", "windtunnel-110kPa", "-o", str(out)])
    assert r.exit_code == 2 and "exists" in r.stderr
