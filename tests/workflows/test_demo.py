"""The built-in demo (workflows/demo.py): the records, the best model of every structure
and results.json it keeps, each model reproducing the MSE reported for it."""

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from blockid.cli.main import app
from blockid.models import load_model


def test_demo_keeps_data_models_figures_and_results(tmp_path):
    out = tmp_path / "demo"
    r = CliRunner().invoke(app, ["demo", "--output-dir", str(out), "--json"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert json.loads((out / "results.json").read_text()) == doc
    names = {p.name for p in out.iterdir()}
    assert {
        "electrohydraulic_estimation.csv",
        "electrohydraulic_validation.csv",
        "electrohydraulic_validation.png",
        "results.json",
    } <= names
    assert set(doc["best"]) == {"hammerstein-wiener", "hammerstein", "wiener", "arx"}
    assert {f"model_{s}.json" for s in doc["best"]} <= names
    # Every saved model is the best of its structure: loaded from its file and run free
    # on the validation record the demo wrote, it reproduces the MSE results.json
    # reports for that structure (computed here from the arrays, not by blockid).
    validation = pd.read_csv(out / "electrohydraulic_validation.csv")
    u = validation["current"].to_numpy()
    y = validation["velocity"].to_numpy()
    for structure, best in doc["best"].items():
        model = load_model(out / f"model_{structure}.json")
        assert model.inputs == ("current",) and model.outputs == ("velocity",)
        saved = json.loads((out / f"model_{structure}.json").read_text())
        assert saved["estimation"] == {"estimator": best["estimator"]}
        lag = model.max_lag
        y_sim = model.simulate(u, y[:lag])[:, 0]
        mse = float(np.mean((y[lag:] - y_sim[lag:]) ** 2))
        assert mse == pytest.approx(best["mse"]["velocity"], rel=1e-9), structure
        # and it is the lowest of that structure's rows in the table
        rows = [row for row in doc["table"] if row["model"] == structure and "mse" in row]
        assert best["mse"]["velocity"] == min(row["mse"]["velocity"] for row in rows)
