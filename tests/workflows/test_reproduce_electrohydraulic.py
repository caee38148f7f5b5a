"""Paper B's ranking on the simulated arm (issue: reproduction). The 30-seed picture,
including the seeds where it does not hold, is in docs/reproduction.md and
benchmarks/electrohydraulic_ranking.py; here the first five seeds guard against
regressions."""

import json

import pytest
from typer.testing import CliRunner

from blockid.cli.main import app
from blockid.workflows.reproduce_electrohydraulic import reproduce_electrohydraulic


@pytest.mark.parametrize(
    "seed", [0, *(pytest.param(s, marks=pytest.mark.slow) for s in range(1, 5))]
)  # seeds 1-4: the reproduction over several seeds, in the slow group
def test_paper_b_ordering(seed):
    """On every seed 0-4 (best estimator per structure): H-W lowest and at least 10 %
    below Hammerstein; both two-segment models below half of Wiener's and ARX's error.
    (Seeds 0-9: 9 of 10 hold; seeds 10-29: 17 of 20, docs/reproduction.md.)"""
    mse = {s: b["mse"]["velocity"] for s, b in reproduce_electrohydraulic(seed).best.items()}
    assert set(mse) == {"hammerstein-wiener", "hammerstein", "wiener", "arx"}
    hw, ham = mse["hammerstein-wiener"], mse["hammerstein"]
    assert hw < min(ham, mse["wiener"], mse["arx"])
    assert hw <= 0.9 * ham
    assert max(hw, ham) <= 0.5 * min(mse["wiener"], mse["arx"])


def test_every_row_names_its_estimator_and_failures_are_explained():
    result = reproduce_electrohydraulic(seed=0)
    assert len(result.table) == 8  # 4 structures x (paper, default)
    for row in result.table:
        assert row["estimator"].startswith(("paper", "default"))
        assert ("mse" in row) != ("error" in row)
    errors = {row["model"]: row["error"] for row in result.table if "error" in row}
    # seed 0: paper B's key-term RLS fails on three structures, each for its own reason
    assert set(errors) == {"hammerstein-wiener", "hammerstein", "wiener"}
    assert "did not converge in 20 passes" in errors["hammerstein-wiener"]
    assert "did not converge in 20 passes" in errors["hammerstein"]
    assert "the linear block is unstable" in errors["wiener"]


def test_cli_json(tmp_path):
    r = CliRunner().invoke(
        app, ["reproduce", "electrohydraulic", "--figures", str(tmp_path), "--json"]
    )
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert {"table", "best", "hw_reduction", "parameters", "paper"} <= set(doc)
    assert set(doc["parameters"]["hammerstein-wiener"]["default (simulation error)"]) == {
        "f",
        "p",
        "a",
        "b",
        "q",
    }
    assert (tmp_path / "electrohydraulic_validation.png").exists()


def _run_bandwidth(tmp_path, value):
    args = ["reproduce", "electrohydraulic", "--plot", str(tmp_path), "--force"]
    return CliRunner().invoke(app, [*args, "--json", "--validation-bandwidth", value])


@pytest.mark.slow  # three reproductions of paper B (about 13 s)
def test_cli_validation_bandwidth(tmp_path):
    default = reproduce_electrohydraulic(seed=0)
    assert default.validation_bandwidth == 0.5
    for value, expected in (("none", None), ("0.3", 0.3)):
        r = _run_bandwidth(tmp_path, value)
        assert r.exit_code == 0, r.output
        doc = json.loads(r.stdout)
        assert doc["validation_bandwidth"] == expected
        # another validation command is another validation record: other errors
        assert doc["best"]["hammerstein"]["mse"] != default.best["hammerstein"]["mse"]


def test_cli_validation_bandwidth_refuses_what_is_not_a_frequency(tmp_path):
    for bad, message in (
        ("abc", "--validation-bandwidth must be a frequency in Hz or 'none'"),
        ("12", "bandwidth must be a frequency from 0.0364 Hz"),  # checked by the plant
        ("0", "bandwidth must be a frequency from 0.0364 Hz"),
    ):
        r = _run_bandwidth(tmp_path, bad)
        assert r.exit_code == 2 and message in r.output, r.output
        assert len(r.output.strip().splitlines()) == 1
