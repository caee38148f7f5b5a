"""blockid.cli.fit: ``fit``, ``compare`` and ``fit-network`` driven as a user would
(typer's CliRunner)."""

from __future__ import annotations

import json

from typer.testing import CliRunner

from blockid.cli.main import app

runner = CliRunner()


FIT = ["fit", "const.csv", "-u", "u", "-y", "y", "--structure", "arx", "--allow-unstable"]


def test_constant_output_fit_json_and_model_file(constant_output):
    r = runner.invoke(app, [*FIT, "--json", "-o", "m.json"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    record = doc["estimation"]["one_step_on_estimation_data"]
    assert record["fit_percent"] == {"y": None}
    assert json.loads((constant_output / "m.json").read_text()) == doc


def test_constant_output_compare_json(constant_output):
    args = ["compare", "const.csv", "-u", "u", "-y", "y", "--estimation", "0:150"]
    r = runner.invoke(app, [*args, "--validation", "150:", "--structures", "arx", "--json"])
    assert r.exit_code == 0, r.output
    model = json.loads(r.stdout)["models"][0]
    assert model["simulation"]["fit_percent"] == {"y": None}
