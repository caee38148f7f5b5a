"""``blockid orders`` driven as a user would (typer's CliRunner)."""

import json

import numpy as np
import pandas as pd
import pytest
import typer
from scipy.signal import lfilter
from typer.testing import CliRunner

from blockid.cli.orders import orders

runner = CliRunner()

# cli/main.py registers the command; this test builds the same registration on its own
app = typer.Typer(add_completion=False, rich_markup_mode=None)
app.command("orders")(orders)


@app.callback()
def _root() -> None:
    """Test app."""


@pytest.fixture
def arx_csv(tmp_path):
    rng = np.random.default_rng(4)
    u = rng.uniform(-1, 1, 1500)
    y = lfilter([0.0, 1.0, 0.5], [1.0, -1.2, 0.5], u)  # ARX(2,2,1)
    path = tmp_path / "arx.csv"
    pd.DataFrame({"t": np.arange(1500) * 0.1, "u": u, "y": y, "c": 1.0}).to_csv(path, index=False)
    return path


def test_table_and_recommendation(arx_csv):
    r = runner.invoke(app, ["orders", str(arx_csv), "-u", "u", "-y", "y", "--time-column", "t"])
    assert r.exit_code == 0, r.output
    assert "false nearest neighbours, % of 1494 samples: u -> y" in r.stdout
    assert "na=4" in r.stdout and "nb=4" in r.stdout
    assert "recommended: na=2 nb=2 nk=1 (0.0 % false neighbours" in r.stdout
    assert "delay scan at na=2, nb=2" in r.stdout


def test_json_is_one_document(arx_csv):
    args = ["orders", str(arx_csv), "-u", "u", "-y", "y", "--estimation", "0:1000"]
    r = runner.invoke(app, [*args, "--max-na", "3", "--max-nb", "2", "--max-nk", "2", "--json"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["recommended"] == {"na": 2, "nb": 2, "nk": 1}
    assert doc["settings"]["n_reference"] == 1000 - 3
    assert len(doc["table"]) == 4 * 2 * 3
    assert doc["evidence"]["delay_scan"]["1"] == 0.0


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["-u", "nope"], "nope"),
        (["-u", "c"], "signal 'c' is constant"),
        (["-u", "u", "--max-na", "-1"], "max_na must be an integer >= 0, got -1 (option --max-na)"),
        (["-u", "u", "--noise", "-1"], "(option --noise)"),
        (["-u", "u", "--estimation", "0:20"], "samples with a full regressor"),
    ],
)
def test_errors_are_one_line(arx_csv, extra, message):
    r = runner.invoke(app, ["orders", str(arx_csv), "-y", "y", *extra])
    assert r.exit_code == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and message in lines[0]


def test_two_outputs_are_refused_not_silently_cut_to_the_last(arx_csv):
    """``-y y -y u`` once analysed ``u`` alone without a word."""
    r = runner.invoke(app, ["orders", str(arx_csv), "-u", "u", "-y", "y", "-y", "u"])
    assert r.exit_code == 2 and "one output at a time, got 2 (y, u)" in r.stderr
