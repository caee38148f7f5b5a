"""The command line, driven as a user would (typer's CliRunner)."""

import json
import os

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from blockid.cli.main import app
from blockid.models import load_model

import reference

runner = CliRunner()


@pytest.fixture
def tito_csv(tmp_path, rng):
    plant = reference.tito_arx(inputs=("u1", "u2"))
    u = rng.standard_normal((1200, 2))
    y = plant.simulate(u) + 0.001 * rng.standard_normal((1200, 2))
    path = tmp_path / "tito.csv"
    pd.DataFrame(
        {"t": np.arange(1200) * 0.05, "u1": u[:, 0], "u2": u[:, 1], "y1": y[:, 0], "y2": y[:, 1]}
    ).to_csv(path, index=False)
    return path


FIT = ["fit", "-u", "u1", "-u", "u2", "-y", "y1", "-y", "y2", "--na", "2", "--nb", "2", "--nk", "1"]


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


def test_damaged_model_file(tmp_path, tito_csv):
    bad = tmp_path / "m.json"
    bad.write_text('{"format": "blockid-model", "version": 99, "model": {}}')
    r = runner.invoke(app, ["simulate", str(bad), str(tito_csv)])
    assert r.exit_code == 2 and "version 99" in r.stderr
    bad.write_text('{"format": "blockid-model", "vers')
    r = runner.invoke(app, ["simulate", str(bad), str(tito_csv)])
    assert r.exit_code == 2 and "not valid JSON (line 1" in r.stderr


def test_bad_order_text(tito_csv):
    r = runner.invoke(
        app, [*FIT[:1], str(tito_csv), *FIT[1:3], "-y", "y1", "--na", "two", "--json"]
    )
    assert r.exit_code == 2 and "na='two'" in r.stderr and "(option --na)" in r.stderr


def test_version():
    from blockid import __version__

    r = runner.invoke(app, ["--version"])
    assert r.exit_code == 0 and r.stdout.strip() == f"blockid {__version__}"


@pytest.fixture
def cubic_csv(tmp_path):
    from reference import squared_state_record

    data = squared_state_record(600)
    e = data.experiments[0]
    path = tmp_path / "cubic.csv"
    pd.DataFrame({"u": e.u[:, 0], "y": e.y[:, 0]}).to_csv(path, index=False)
    return path


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


def test_a_negative_seed_is_one_readable_line(tmp_path):
    """``example-data --seed -1`` once ended in NumPy's traceback from the random
    generator; nothing is written."""
    out = tmp_path / "x.csv"
    r = runner.invoke(app, ["example-data", "electrohydraulic", "-o", str(out), "--seed", "-1"])
    assert r.exit_code == 2 and "--seed" in r.stderr and "Traceback" not in r.output
    assert not out.exists()


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
@pytest.mark.parametrize("command", ["fit", "export"])
def test_a_standard_output_that_cannot_be_written_is_one_readable_line(command, cubic_csv,
                                                                       tmp_path):  # fmt: skip
    """stdout on a full device (``> /dev/full``) once ended in a traceback; now one line
    on stderr naming it, exit 1, and no second error from the interpreter's last flush."""
    import subprocess
    import sys

    model = tmp_path / "m.json"
    fit = ["fit", str(cubic_csv), "-u", "u", "-y", "y", "--structure", "arx", "--na", "2",
           "--nb", "2", "--nk", "1"]  # fmt: skip
    runner.invoke(app, [*fit, "-o", str(model)])
    args = [*fit, "--json"] if command == "fit" else ["export", str(model), "--to", "python"]
    with open("/dev/full", "w") as full:
        run = subprocess.run([sys.executable, "-m", "blockid.cli.main", *args], stdout=full,
                             stderr=subprocess.PIPE, text=True, timeout=300)  # fmt: skip
    assert run.returncode == 1
    assert run.stderr.strip().splitlines() == [
        "error: cannot write standard output: No space left on device"
    ]


@pytest.mark.parametrize("command", ["fit", "identify"])
def test_a_model_file_is_not_written_under_a_table_s_name(command, cubic_csv, tmp_path):
    """``-o m.csv`` once wrote JSON under a .csv name; now refused before any work,
    naming the .json it should be, and nothing is written."""
    out = tmp_path / "m.csv"
    extra = (
        ["--structure", "arx", "--na", "2", "--nb", "2", "--nk", "1"] if command == "fit" else []
    )
    r = runner.invoke(app, [command, str(cubic_csv), "-u", "u", "-y", "y", "-o", str(out), *extra])
    assert r.exit_code == 2 and "a model file is JSON, not .csv" in r.stderr
    assert str(tmp_path / "m.json") in r.stderr and not out.exists()


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


def test_identify_passes_on_the_selected_model_s_warnings(tmp_path):
    """The selected model's warnings (here: a fitted pole at -0.97, a Nyquist-frequency
    mode of the plant) on stderr, with --json too, and in the document (issue 37)."""
    rng = np.random.default_rng(1)
    u = np.repeat(rng.uniform(-1.0, 1.0, 60), 10)
    y = np.zeros(u.size)
    for t in range(1, u.size):
        y[t] = -0.97 * y[t - 1] + u[t - 1]
    data = tmp_path / "nyquist.csv"
    pd.DataFrame({"u": u, "y": y + 0.01 * rng.standard_normal(u.size)}).to_csv(data, index=False)
    args = ["identify", str(data), "-u", "u", "-y", "y", "--structures", "arx", "--effort",
            "quick", "-q", "--json"]  # fmt: skip
    r = runner.invoke(app, args)
    assert r.exit_code == 0, r.output
    (note,) = json.loads(r.stdout)["selected"]["warnings"]
    assert "Nyquist" in note and f"warning: {note}" in r.stderr


@pytest.mark.parametrize("command", ["fit", "identify"])
def test_an_output_that_could_not_be_written_is_refused_before_any_work(
    command, cubic_csv, tmp_path, monkeypatch
):
    """``-o missing/m.json`` once ran the whole search and then failed to write; now
    refused first, naming the folder, and the search never starts."""
    import blockid.fitting
    from blockid.workflows import identify as search

    def never(*a, **k):
        raise AssertionError("the work started")

    monkeypatch.setattr(blockid.fitting, "fit_model", never)
    monkeypatch.setattr(search, "identify", never)
    extra = (
        ["--structure", "arx", "--na", "2", "--nb", "2", "--nk", "1"] if command == "fit" else []
    )
    out = tmp_path / "missing" / "m.json"
    r = runner.invoke(app, [command, str(cubic_csv), "-u", "u", "-y", "y", "-o", str(out), *extra])
    assert r.exit_code == 2, r.output
    assert f"folder {tmp_path / 'missing'} does not exist" in r.stderr
    assert "nothing was computed" in r.stderr and not out.parent.exists()
