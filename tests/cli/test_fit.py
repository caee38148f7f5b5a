"""blockid.cli.fit: ``fit``, ``compare`` and ``fit-network`` driven as a user would
(typer's CliRunner)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from blockid.blocks import Polynomial, TwoSegmentPolynomial
from blockid.cli.main import app
from blockid.models import HammersteinWiener, load_model
from cli.conftest import FIT

runner = CliRunner()


CONSTANT_FIT = ["fit", "const.csv", "-u", "u", "-y", "y", "--structure", "arx", "--allow-unstable"]


def test_constant_output_fit_json_and_model_file(constant_output):
    r = runner.invoke(app, [*CONSTANT_FIT, "--json", "-o", "m.json"])
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


def test_fit_json_equals_model_file_and_rls_equals_batch(tito_csv, tmp_path):
    out = tmp_path / "m.json"
    r = runner.invoke(
        app,
        [
            *FIT[:1],
            str(tito_csv),
            *FIT[1:],
            "--method",
            "rls",
            "--forgetting",
            "1",
            "--estimation",
            "0:1000",
            "-o",
            str(out),
            "--json",
        ],
    )
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc == json.loads(out.read_text())
    assert doc["format"] == "blockid-model" and doc["version"] == 1
    assert doc["model"]["parameters"]["y1"]["a"]["y1"] == pytest.approx([-1.2, 0.4], abs=1e-3)
    rb = runner.invoke(
        app,
        [
            *FIT[:1],
            str(tito_csv),
            *FIT[1:],
            "--method",
            "batch",
            "--estimation",
            "0:1000",
            "--json",
        ],
    )
    batch = json.loads(rb.stdout)["model"]["parameters"]

    def flat(p, y):
        return np.concatenate([*p[y]["a"].values(), *p[y]["b"].values()])

    for y in ("y1", "y2"):  # relative to the parameter vector's size: |d theta| / |theta|
        theta_rls, theta_ls = flat(doc["model"]["parameters"], y), flat(batch, y)
        assert np.linalg.norm(theta_rls - theta_ls) <= 1e-8 * np.linalg.norm(theta_ls)


def test_existing_output_is_not_overwritten_without_force(tito_csv, tmp_path):
    out = tmp_path / "m.json"
    out.write_text("precious")
    r = runner.invoke(app, [*FIT[:1], str(tito_csv), *FIT[1:], "-o", str(out)])
    assert r.exit_code == 2 and "exists; pass --force" in r.stderr
    assert out.read_text() == "precious"


def test_figures_are_not_replaced_without_force(tito_csv, tmp_path):
    """Issue 21: ``fit ... --plot figs`` run twice replaced the figures silently."""
    figs = tmp_path / "figs"
    args = [*FIT[:1], str(tito_csv), *FIT[1:], "--time-column", "t", "--plot", str(figs), "--json"]
    assert runner.invoke(app, args).exit_code == 0
    first = (figs / "simulation.png").read_bytes()
    (figs / "simulation.png").write_bytes(b"mine")
    r = runner.invoke(app, args)
    assert r.exit_code == 2 and "simulation.png exist(s); pass --force" in r.stderr
    assert (figs / "simulation.png").read_bytes() == b"mine"
    assert runner.invoke(app, [*args, "--force"]).exit_code == 0
    assert (figs / "simulation.png").read_bytes()[:4] == first[:4] == b"\x89PNG"
    model = tmp_path / "m.json"
    assert runner.invoke(app, [*args, "--force", "-o", str(model)]).exit_code == 0
    sim = ["simulate", str(model), str(tito_csv), "--time-column", "t", "--plot", str(figs)]
    r = runner.invoke(app, sim)
    assert r.exit_code == 2 and "pass --force" in r.stderr
    assert runner.invoke(app, [*sim, "--force"]).exit_code == 0


def test_failed_run_leaves_existing_file_untouched(tito_csv, tmp_path):
    out = tmp_path / "m.json"
    out.write_text("precious")
    r = runner.invoke(
        app,
        [
            *FIT[:1],
            str(tito_csv),
            *FIT[1:],
            "--method",
            "hierarchical-rls",
            "-o",
            str(out),
            "--force",
        ],
    )
    assert r.exit_code == 2 and "did not converge" in r.stderr
    assert out.read_text() == "precious"


@pytest.mark.parametrize(
    ("content", "args", "expected"),
    [
        ("u1,u2,y1,y2\n", [], "header but no data rows"),
        ("", [], "is empty"),
        ("u1,u2,y1,y2\n1,2,3,4\n1,abc,3,4\n", [], "column 'u2'"),
        ("u1,u2,y1,y2\n1,2,3,4\n1,,3,4\n", [], "column 'u2'"),
        ("u1,u2,y1,yy\n1,2,3,4\n", [], "'y2'"),
        ("u1,u2,y1,y2\n" + "1,2,3,4\n" * 50, ["--estimation", "0:100"], "--estimation 0:100"),
        ("u1,u2,y1,y2\n" + "1,2,3,4\n" * 10, ["--na", "20"], "na="),
    ],
)
def test_malformed_input_gives_one_line_and_exit_2(tmp_path, content, args, expected):
    path = tmp_path / "bad.csv"
    path.write_text(content)
    r = runner.invoke(app, [*FIT[:1], str(path), *FIT[1:], *args, "--json"])
    assert r.exit_code == 2
    assert "Traceback" not in r.output
    message = r.stderr.strip()
    assert message.startswith("error:") and len(message.splitlines()) == 1
    if expected != "na=":
        assert expected in message
    else:
        assert "lower the orders" in message
    assert r.stdout == ""


def test_bad_order_text(tito_csv):
    r = runner.invoke(
        app, [*FIT[:1], str(tito_csv), *FIT[1:3], "-y", "y1", "--na", "two", "--json"]
    )
    assert r.exit_code == 2 and "na='two'" in r.stderr and "(option --na)" in r.stderr


def test_fit_quiet_leaves_out_the_parameters_and_a_long_table_is_summarised(cubic_csv, tmp_path):
    """``-q``: no parameter table; without it, a table of more than 60 values (a
    polynomial state space's monomial coefficients) is one line saying where they are;
    a short table is printed in full."""
    base = ["fit", str(cubic_csv), "-u", "u", "-y", "y", "-o", str(tmp_path / "m.json"),
            "--force"]  # fmt: skip
    pnlss = [*base, "--structure", "polynomial-state-space", "--nx", "2", "--degree", "3",
             "--max-nfev", "3"]  # fmt: skip
    loud = runner.invoke(app, pnlss)
    assert loud.exit_code == 0, loud.output
    assert "parameter values, not listed here" in loud.stdout and "E[" not in loud.stdout
    quiet = runner.invoke(app, [*pnlss, "-q"])
    assert quiet.exit_code == 0 and "parameter values" not in quiet.stdout
    assert "free-run simulation" in quiet.stdout  # the scores stay
    arx = runner.invoke(app, [*base, "--structure", "arx", "--na", "2", "--nb", "2", "--nk", "1"])
    assert arx.exit_code == 0 and "arx model" in arx.stdout and "not listed" not in arx.stdout


def test_fit_json_still_prints_the_fit_s_warnings_on_stderr(cubic_csv):
    """A refinement stopped at ``--max-nfev`` warns on stderr with ``--json`` too, and the
    document keeps the warning; stdout holds the JSON alone."""
    r = runner.invoke(app, ["fit", str(cubic_csv), "-u", "u", "-y", "y", "--json",
                            "--structure", "polynomial-state-space", "--nx", "2",
                            "--degree", "2", "--max-nfev", "3"])  # fmt: skip
    assert r.exit_code == 0, r.output
    assert "warning: the refinement stopped at its evaluation limit (max_nfev = 3" in r.stderr
    doc = json.loads(r.stdout)
    assert any("evaluation limit" in w for w in doc["estimation"]["settings"]["warnings"])


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
