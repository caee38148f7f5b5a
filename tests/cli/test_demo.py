import json

from typer.testing import CliRunner

from blockid.cli.main import app


def test_demo_writes_its_files_and_recovers_s1(tmp_path):
    r = CliRunner().invoke(app, ["demo", "--output-dir", str(tmp_path / "demo"), "--json"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert abs(doc["s1"]["a"][0] + 0.62) < 0.62 * 0.01
    assert abs(doc["s1"]["b"][0] - 0.39) < 0.39 * 0.01
    names = {p.name for p in (tmp_path / "demo").iterdir()}
    assert {
        "windtunnel_estimation.csv",
        "s1_exhaust_valve.json",
        "flow_field_simulation.png",
    } <= names
