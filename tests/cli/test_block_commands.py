"""fit/compare/example-data for the block-oriented structures, as a user runs them."""

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from blockid.blocks import Polynomial, TwoSegmentPolynomial
from blockid.cli.main import app
from blockid.models import HammersteinWiener, load_model

runner = CliRunner()


def hw_plant(a=(-1.2, 0.5)):
    return HammersteinWiener(
        "u",
        "y",
        input_block=TwoSegmentPolynomial([0.0, 1.0, 0.3, -0.1], [0.0, -0.4, 0.2, 0.05]),
        output_block=Polynomial([1.0, 0.2, 0.1], constant=False),
        na=2,
        nb=2,
        nk=1,
        a=list(a),
        b=[1.0, 0.4],
    )


@pytest.fixture
def hw_csv(tmp_path):
    true = hw_plant()
    rng = np.random.default_rng(5)
    u = rng.uniform(-1.5, 1.5, 4000)
    y = true.simulate(u)[:, 0]
    y += 0.01 * np.std(y) * rng.standard_normal(y.size)  # 40 dB
    path = tmp_path / "hw.csv"
    pd.DataFrame({"u": u, "y": y}).to_csv(path, index=False)
    return path, true


def fit_args(path, structure: str, options: str) -> list[str]:
    """``blockid fit PATH -u u -y y --structure STRUCTURE`` and the options (split on spaces)."""
    return ["fit", str(path), "-u", "u", "-y", "y", "--structure", structure, *options.split()]


def test_fit_hw_recovers_parameters_and_writes_figures(hw_csv, tmp_path):
    path, true = hw_csv
    out = tmp_path / "hw.json"
    r = runner.invoke(
        app,
        [
            *fit_args(
                str(path),
                "hammerstein-wiener",
                "--na 2 --nb 2 --nk 1 --r1 3 --r2 3 --estimation 0:3000 -o",
            ),
            str(out),
            "--plot",
            str(tmp_path / "figs"),
        ],
    )
    assert r.exit_code == 0, r.output
    model = load_model(out)
    np.testing.assert_allclose(
        model.free_parameters(), true.free_parameters(), rtol=0.05, atol=0.01
    )
    assert {p.name for p in (tmp_path / "figs").iterdir()} == {"simulation.png", "blocks.png"}
    doc = json.loads(out.read_text())
    assert set(doc["model"]["parameters"]) == {"f", "p", "a", "b", "q"}
    assert doc["estimation"]["method"] == "simulation-error"


def test_compare_ranks_hw_first_and_prints_json(hw_csv):
    path, _ = hw_csv
    r = runner.invoke(
        app,
        [
            "compare",
            str(path),
            "-u",
            "u",
            "-y",
            "y",
            "--estimation",
            "0:3000",
            "--validation",
            "3000:4000",
            "--na",
            "2",
            "--nb",
            "2",
            "--nk",
            "1",
            "--r1",
            "3",
            "--r2",
            "3",
            "--json",
        ],
    )
    assert r.exit_code == 0, r.output
    models = json.loads(r.stdout)["models"]
    assert [m["structure"] for m in models] == [
        "arx",
        "hammerstein",
        "wiener",
        "hammerstein-wiener",
    ]
    mse = {m["structure"]: m["simulation"]["mse"]["y"] for m in models}
    assert mse["hammerstein-wiener"] < min(mse["hammerstein"], mse["wiener"], mse["arx"])
    for m in models:
        assert set(m["simulation"]) == {"mse", "rmse", "mae", "max_abs_error", "fit_percent"}


def test_paper_method_records_parameter_trajectories(hw_csv, tmp_path):
    """Key-term RLS converges for a Hammerstein model on white input (docs/convergence.md);
    --plot then draws its parameter trajectories and the file keeps the method."""
    path, _ = hw_csv
    r = runner.invoke(
        app,
        [
            *fit_args(
                str(path),
                "hammerstein",
                "--method key-term-rls --na 2 --nb 2 --nk 1 --r1 3 --json --plot",
            ),
            str(tmp_path / "figs"),
        ],
    )
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["estimation"]["method"] == "key-term-rls"
    assert {p.name for p in (tmp_path / "figs").iterdir()} == {
        "simulation.png",
        "blocks.png",
        "parameters.png",
    }


def test_paper_method_failure_is_one_line(tmp_path):
    """Key-term RLS on a held (piecewise-constant) command: reported, no model file."""
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(-1, 1, 100), 40)
    true = hw_plant(a=(-1.6, 0.64))
    path = tmp_path / "held.csv"
    pd.DataFrame({"u": u, "y": true.simulate(u)[:, 0]}).to_csv(path, index=False)
    out = tmp_path / "m.json"
    args = [
        *fit_args(
            str(path),
            "hammerstein-wiener",
            "--method key-term-rls --na 2 --nb 2 --nk 1 --r1 3 --r2 3 -o",
        ),
        str(out),
    ]
    r = runner.invoke(app, args)
    assert r.exit_code == 2 and r.stderr.startswith("error: key-term RLS"), r.output
    assert len(r.stderr.strip().splitlines()) == 1 and not out.exists()
    # With --plot the trajectory up to the failure is drawn; still no model file.
    figs = tmp_path / "figs"
    r = runner.invoke(app, [*args, "--plot", str(figs)])
    assert r.exit_code == 2, r.output
    lines = r.stderr.strip().splitlines()
    assert lines[0] == f"parameter trajectories up to the failure written to {figs}/parameters.png"
    assert lines[1].startswith("error: key-term RLS") and len(lines) == 2
    assert [p.name for p in figs.iterdir()] == ["parameters.png"] and not out.exists()


def test_unused_option_is_an_error(hw_csv):
    path, _ = hw_csv
    r = runner.invoke(app, fit_args(str(path), "hammerstein", "--eps1 2 --json"))
    assert r.exit_code == 2 and r.stderr.startswith("error: eps1 not used by hammerstein")
    assert r.stderr.rstrip().endswith("(option --eps1)")


def test_example_data_gives_the_ranges_it_prints(tmp_path):
    out = tmp_path / "wt.csv"
    r = runner.invoke(app, ["example-data", "windtunnel-110kPa", "-o", str(out)])
    assert r.exit_code == 0, r.output
    assert "estimation record 0:1200, validation record 1200:2400" in r.stdout
    frame = pd.read_csv(out)
    assert list(frame.columns) == ["t", "u1", "u2", "v1", "v2", "y1", "y2"] and len(frame) == 2400
    r = runner.invoke(app, ["example-data", "windtunnel-110kPa", "-o", str(out)])
    assert r.exit_code == 2 and "exists" in r.stderr


def test_fit_network_then_simulate_from_external_inputs(tmp_path):
    data = tmp_path / "wt.csv"
    runner.invoke(app, ["example-data", "windtunnel-110kPa", "-o", str(data)])
    net = tmp_path / "net.json"
    r = runner.invoke(
        app,
        [
            "fit-network",
            str(data),
            "--time-column",
            "t",
            "--estimation",
            "0:1200",
            "-s",
            "S1: u1 -> v1 | arx na=1 nb=1 nk=1 method=rls",
            "-s",
            "S2: u2 -> v2 | backlash na=2 nb=1 nk=1",
            "-s",
            "S3: v1,v2 -> y1,y2 | arx na=2 nb=2 nk=1 center=true",
            "-o",
            str(net),
        ],
    )
    assert r.exit_code == 0, r.output
    model = load_model(net)
    assert model.inputs == ("u1", "u2") and model.outputs == ("v1", "v2", "y1", "y2")
    assert model["S2"].parameters["c_left"] == pytest.approx(0.8, rel=0.05)
    r = runner.invoke(
        app,
        ["simulate", str(net), str(data), "--time-column", "t", "--range", "1200:2400", "--json"],
    )
    doc = json.loads(r.stdout)
    assert doc["metrics"]["fit_percent"]["v2"] > 99 and doc["metrics"]["fit_percent"]["y2"] > 60
    r = runner.invoke(app, ["fit-network", str(data), "-s", "S1 u1 v1", "--json"])
    assert r.exit_code == 2 and "expected 'NAME: IN" in r.stderr
