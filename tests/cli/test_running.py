"""blockid.cli.running: ``simulate`` and ``predict`` driven as a user would (typer's
CliRunner)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from blockid.cli.main import app
from blockid.models import load_model
from cli.conftest import FIT

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


def test_simulate_and_predict_write_outputs_and_metrics(tito_csv, tmp_path):
    model = tmp_path / "m.json"
    runner.invoke(
        app, [*FIT[:1], str(tito_csv), *FIT[1:], "--estimation", "0:1000", "-o", str(model)]
    )
    sim_csv = tmp_path / "sim.csv"
    r = runner.invoke(
        app,
        [
            "simulate",
            str(model),
            str(tito_csv),
            "--range",
            "1000:1200",
            "-o",
            str(sim_csv),
            "--json",
        ],
    )
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["mode"] == "simulation" and doc["n_samples"] == 200
    assert set(doc["metrics"]) == {"mse", "rmse", "mae", "max_abs_error", "fit_percent"}
    assert doc["metrics"]["fit_percent"]["y1"] > 95
    frame = pd.read_csv(sim_csv)
    assert {"y1_sim", "y2_sim"} <= set(frame.columns) and len(frame) == 200
    # the written simulation equals the library's, from the reloaded model
    m = load_model(model)
    data = pd.read_csv(tito_csv).iloc[1000:1200]
    expected = m.simulate(data[["u1", "u2"]].to_numpy(), data[["y1", "y2"]].to_numpy()[:2])
    np.testing.assert_allclose(frame[["y1_sim", "y2_sim"]].to_numpy(), expected, rtol=1e-12)
    r = runner.invoke(app, ["predict", str(model), str(tito_csv), "--json"])
    pred = json.loads(r.stdout)
    assert pred["mode"] == "one-step"
    assert pred["metrics"]["rmse"]["y1"] < doc["metrics"]["rmse"]["y1"] * 1.5


def test_damaged_model_file(tmp_path, tito_csv):
    bad = tmp_path / "m.json"
    bad.write_text('{"format": "blockid-model", "version": 99, "model": {}}')
    r = runner.invoke(app, ["simulate", str(bad), str(tito_csv)])
    assert r.exit_code == 2 and "version 99" in r.stderr
    bad.write_text('{"format": "blockid-model", "vers')
    r = runner.invoke(app, ["simulate", str(bad), str(tito_csv)])
    assert r.exit_code == 2 and "not valid JSON (line 1" in r.stderr


def test_simulate_refuses_a_diverging_model_in_one_line_and_predict_warns(tmp_path):
    """A model file with a pole outside the unit circle simulated to an RMSE of 3.9e67 with
    exit 0 (issue 37): now one error line, exit 2, no table written; one-step prediction
    still works and warns on stderr, with --json too."""
    from blockid.models import ARX, save_model

    rng = np.random.default_rng(0)
    u = rng.uniform(0.0, 10.0, 3000)
    y = np.zeros(u.size)
    for t in range(1, u.size):
        y[t] = 0.9 * y[t - 1] + 0.1 * u[t - 1]
    data = tmp_path / "d.csv"
    pd.DataFrame({"u": u, "y": y}).to_csv(data, index=False)
    model = tmp_path / "unstable.json"
    save_model(ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [-1.05]}}, b={"y": {"u": [0.1]}}), model)
    table = tmp_path / "sim.csv"
    r = runner.invoke(app, ["simulate", str(model), str(data), "-o", str(table)])
    assert r.exit_code == 2 and r.stdout == ""
    (line,) = r.stderr.strip().splitlines()
    assert line.startswith("error: the model's free-run simulation diverges on")
    assert "a pole at 1.05" in line and not table.exists()
    r = runner.invoke(app, ["predict", str(model), str(data), "--json"])
    assert r.exit_code == 0 and json.loads(r.stdout)["mode"] == "one-step"
    assert "warning: the model is unstable: its linear part has a pole at 1.05" in r.stderr
