"""``blockid residuals`` (cli/residuals.py) on an ARX plant with white equation noise:
the plant's own model leaves a white residual independent of the input and the table
says so; a model that misses a pole does not."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from blockid.cli.main import app
from blockid.models import ARX, save_model


def _arx(a):
    return ARX(["u"], ["y"], na=len(a), nb=1, nk=1, a={"y": {"y": a}}, b={"y": {"u": [1.0]}})


@pytest.fixture
def files(tmp_path):
    rng = np.random.default_rng(4)
    n = 1500
    u, e = rng.standard_normal(n), 0.3 * rng.standard_normal(n)
    y = np.zeros(n)
    for t in range(2, n):  # y = 1.2 y(t-1) - 0.5 y(t-2) + u(t-1) + e(t)
        y[t] = 1.2 * y[t - 1] - 0.5 * y[t - 2] + u[t - 1] + e[t]
    data = tmp_path / "d.csv"
    data.write_text("u,y\n" + "".join(f"{a},{b}\n" for a, b in zip(u, y, strict=True)))
    right = save_model(_arx([-1.2, 0.5]), tmp_path / "right.json")
    wrong = save_model(_arx([-0.7]), tmp_path / "wrong.json")
    return data, right, wrong


def test_the_plant_s_model_passes_and_the_table_says_white_and_independent(files):
    data, right, _ = files
    result = CliRunner().invoke(app, ["residuals", str(right), str(data), "--lags", "10"])
    assert result.exit_code == 0, result.output
    assert "residual of the one-step prediction on" in result.stdout
    assert "1498 samples, lags up to 10, 99% bounds" in result.stdout  # 2 initial samples
    assert "verdict: the model passes: white and independent of the inputs at 99%" in result.stdout
    assert "NOT" not in result.stdout
    assert "white" in result.stdout and "independent" in result.stdout


def test_a_model_missing_a_pole_leaves_a_coloured_residual_in_the_json(files):
    data, right, wrong = files
    runner = CliRunner()
    docs = {
        name: json.loads(runner.invoke(app, ["residuals", str(m), str(data), "--json"]).stdout)
        for name, m in (("right", right), ("wrong", wrong))
    }
    assert docs["right"]["passed"] and not docs["wrong"]["passed"]
    assert not docs["wrong"]["whiteness"]["y"]["white"]
    assert docs["wrong"]["model"] == str(wrong) and docs["wrong"]["range"] is None
    assert docs["right"]["lags"] == list(range(26))  # --lags defaults to 25
