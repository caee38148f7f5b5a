"""Empty, reversed and out-of-range sample ranges: a clear error naming the range."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from blockid.cli.main import app
from blockid.data import Dataset, parse_range
from blockid.errors import DataError, ParameterError


def _data(n: int = 50) -> Dataset:
    t = np.arange(n, dtype=float)
    return Dataset.from_arrays(t, 2.0 * t, inputs=["u"], outputs=["y"])


@pytest.mark.parametrize("text", ["10:10", "0:0", "20:10"])
def test_parse_range_refuses_an_empty_or_reversed_range_by_name(text):
    with pytest.raises(ParameterError) as info:
        parse_range(text, "--estimation")
    message = str(info.value)
    assert message.startswith("--estimation expects START:STOP")
    assert f"'{text}' is empty" in message
    assert "STOP must be larger than START" in message


@pytest.mark.parametrize(("start", "stop"), [(10, 10), (0, 0), (20, 10)])
def test_select_refuses_an_empty_or_reversed_range_by_name(start, stop):
    with pytest.raises(DataError) as info:
        _data().select(start, stop, what="--validation")
    assert str(info.value) == (
        f"--validation {start}:{stop} is empty: the stop index must be larger than the start"
    )


@pytest.mark.parametrize(("start", "stop"), [(0, 51), (50, None), (60, 70), (49, 51)])
def test_select_refuses_a_range_beyond_the_record(start, stop):
    text = f"{start}:{'' if stop is None else stop}"
    with pytest.raises(DataError) as info:
        _data().select(start, stop)
    message = str(info.value)
    assert f"range {text} does not fit experiment" in message
    assert "has 50 samples (indices 0 to 49; a valid range is within 0:50)" in message


def test_select_at_the_boundaries_keeps_exactly_those_samples():
    data = _data()
    assert data.select(0, 50).signal("u")[0].tolist() == list(range(50))
    assert data.select(49, None).signal("y")[0].tolist() == [98.0]
    assert data.select(10, 11).signal("u")[0].tolist() == [10.0]
    assert data.select(None, 1).signal("u")[0].tolist() == [0.0]


def test_cli_reports_the_empty_range_on_one_line(tmp_path):
    path = tmp_path / "d.csv"
    pd.DataFrame({"u": np.arange(50.0), "y": np.arange(50.0)}).to_csv(path, index=False)
    r = CliRunner().invoke(
        app, ["fit", str(path), "-u", "u", "-y", "y", "--estimation", "10:10", "--json"]
    )
    assert r.exit_code == 2
    assert r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: --estimation expects START:STOP")
    assert "'10:10' is empty" in lines[0]
