"""Paper A's claim on the simulated tunnel: the block-oriented network beats the
conventional linear model, and the actuator parameters are recovered."""

import json
from functools import cache

import pytest
from typer.testing import CliRunner

from blockid.cli.main import app
from blockid.workflows.reproduce_windtunnel import reproduce_windtunnel

DEFAULT = "default (LS, simulation error, LS)"


@cache
def _reproduction(seed):
    """One reproduction per seed for the tests of this file (each takes seconds)."""
    return reproduce_windtunnel(seed=seed)


BLOCK_S3 = "S3 block model (LS, simulation error, block state space)"


@pytest.mark.parametrize("seed", [0, 1])
def test_block_oriented_beats_conventional_and_recovers_actuators(seed):
    result = _reproduction(seed)
    rows = {(r["condition"], r["model"], r["estimator"]): r for r in result.table}
    for condition in ("110kPa", "130kPa"):
        conv = rows[(condition, "conventional", "least squares")]
        for estimator in (DEFAULT, BLOCK_S3):
            block = rows[(condition, "block-oriented", estimator)]
            for metric in ("rmse", "max_abs_error"):
                for y in ("y1", "y2"):
                    assert block[metric][y] < conv[metric][y], (condition, estimator, metric, y)
        est = result.parameters[condition][DEFAULT]
        truth = result.truth[condition]
        assert est["S1"]["a"][0] == pytest.approx(truth["S1"]["a"][0], rel=0.05)
        assert est["S1"]["b"][0] == pytest.approx(truth["S1"]["b"][0], rel=0.05)
        for key in ("m_left", "c_left", "m_right", "c_right"):
            assert est["S2"][key] == pytest.approx(truth["S2"][key], rel=0.05), key


def test_failed_paper_estimator_is_shown_not_hidden():
    result = _reproduction(0)
    paper_rows = [r for r in result.table if r["estimator"].startswith("paper")]
    assert len(paper_rows) == 2
    for row in paper_rows:  # either a full row of numbers or the reason it failed
        assert ("rmse" in row) != ("error" in row)


def test_cli_json_is_one_document(tmp_path):
    r = CliRunner().invoke(
        app, ["reproduce", "windtunnel", "--seed", "0", "--figures", str(tmp_path), "--json"]
    )
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert {"table", "parameters", "truth", "paper"} <= set(doc)
    assert {row["model"] for row in doc["table"]} == {"block-oriented", "conventional"}
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "windtunnel_110kPa_validation.png",
        "windtunnel_130kPa_validation.png",
    ]
