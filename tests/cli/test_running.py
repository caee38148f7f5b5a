"""blockid.cli.running: ``simulate`` and ``predict`` driven as a user would (typer's
CliRunner)."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from blockid.cli.main import app

runner = CliRunner()


@pytest.mark.parametrize("command", ["simulate", "predict"])
def test_constant_output_simulate_json(constant_output, command):
    r = runner.invoke(app, [command, "model.json", "const.csv", "--json"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["metrics"]["fit_percent"] == {"y": None}
    assert any("fit_percent of output 'y' is undefined" in w for w in doc["warnings"])


def test_simulate_and_predict_plot_the_whole_record(constant_output):
    for command, name in (("simulate", "simulation.png"), ("predict", "prediction.png")):
        r = runner.invoke(app, [command, "model.json", "const.csv", "--plot", "figs"])
        assert r.exit_code == 0, r.output
        assert (constant_output / "figs" / name).stat().st_size > 1000
