"""blockid.cli.identify: ``identify`` driven as a user would (typer's CliRunner)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
from typer.testing import CliRunner

from blockid.cli.main import app

runner = CliRunner()


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
