"""Paper B's ranking on the simulated arm (issue: reproduction). The 10-seed picture,
including the seeds where it does not hold, is in docs/reproduction.md and
benchmarks/electrohydraulic_ranking.py; here the first seeds guard against regressions."""

import json

import pytest
from typer.testing import CliRunner

from blockid.cli.main import app
from blockid.workflows.reproduce_electrohydraulic import reproduce_electrohydraulic


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_hw_best_and_two_segment_models_far_better(seed):
    result = reproduce_electrohydraulic(seed=seed)
    mse = {s: b["mse"]["velocity"] for s, b in result.best.items()}
    assert set(mse) == {"hammerstein-wiener", "hammerstein", "wiener", "arx"}
    assert mse["hammerstein-wiener"] <= 0.9 * mse["hammerstein"]  # at least 10 % below
    for two_segment in ("hammerstein-wiener", "hammerstein"):
        assert mse[two_segment] < 0.5 * min(mse["wiener"], mse["arx"])  # a wide margin


def test_every_row_names_its_estimator_and_failures_are_explained():
    result = reproduce_electrohydraulic(seed=0)
    assert len(result.table) == 8  # 4 structures x (paper, default)
    for row in result.table:
        assert row["estimator"].startswith(("paper", "default"))
        assert ("mse" in row) != ("error" in row)
        if "error" in row:
            assert "docs/convergence.md" in row["error"] or "did not" in row["error"]


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
