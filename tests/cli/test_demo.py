import json

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
    for structure in doc["best"]:  # every saved model loads and is the best of its structure
        model = load_model(out / f"model_{structure}.json")
        assert model.inputs == ("current",) and model.outputs == ("velocity",)
