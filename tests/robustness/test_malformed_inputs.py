"""Malformed input, as a user would give it, gets one readable line and exit status 2.

Each case is one command line on a folder of files (a good record, a model file, a
network model file and the case's own bad file). The checks, for every case: exit
status 2, the expected words on stderr (the message names the problem), no traceback,
one line, and every file that existed before is byte-for-byte unchanged afterwards.
The cases cover files, columns, values, ranges, orders, model files, options and
networks (issue 11).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from blockid.cli.main import app
from blockid.models import ARX, Network, save_model

runner = CliRunner()

N = 300
DT = 0.05


def _record(seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(N)
    plant = ARX(["u"], ["y"], 2, 2, 1, a={"y": {"y": [-1.2, 0.35]}}, b={"y": {"u": [1.0, 0.4]}})
    y = plant.simulate(u)[:, 0] + 0.01 * rng.standard_normal(N)
    return np.arange(N) * DT, u, y


def _csv(path: Path, header: str, rows: list[str]) -> None:
    path.write_text(header + "\n" + "\n".join(rows) + "\n")


def _good_rows() -> list[str]:
    t, u, y = _record()
    return [f"{t[k]:.2f},{float(u[k])!r},{float(y[k])!r}" for k in range(N)]


def _with_cell(row: int, column: int, text: str) -> Callable[[Path], None]:
    """A copy of good.csv as bad.csv with one cell replaced."""

    def make(d: Path) -> None:
        rows = [r.split(",") for r in _good_rows()]
        rows[row][column] = text
        _csv(d / "bad.csv", "t,u,y", [",".join(r) for r in rows])

    return make


def _model_doc(d: Path) -> dict:
    return json.loads((d / "model.json").read_text())


def _bad_model(change: Callable[[dict], None]) -> Callable[[Path], None]:
    def make(d: Path) -> None:
        doc = _model_doc(d)
        change(doc)
        (d / "bad.json").write_text(json.dumps(doc))

    return make


def _nan_parameter(doc: dict) -> None:
    doc["model"]["parameters"]["y"]["a"]["y"][0] = float("nan")  # written as NaN


def _cyclic_network(d: Path) -> None:
    s1 = ARX(["v2"], ["v1"], 1, 1, 1, a={"v1": {"v1": [-0.5]}}, b={"v1": {"v2": [0.5]}})
    s2 = ARX(["v1"], ["v2"], 1, 1, 1, a={"v2": {"v2": [-0.5]}}, b={"v2": {"v1": [0.5]}})
    doc = json.loads((d / "network.json").read_text())
    doc["model"]["subsystems"] = [
        {"name": "S1", "model": s1.to_dict()},
        {"name": "S2", "model": s2.to_dict()},
    ]
    (d / "bad.json").write_text(json.dumps(doc))


def _folder_with_a_file(name: str) -> Callable[[Path], None]:
    def make(d: Path) -> None:
        (d / name).mkdir()
        (d / name / "keep.txt").write_text("mine")

    return make


@dataclass
class Case:
    id: str
    args: list[str]
    expect: list[str]
    make: Callable[[Path], None] | None = None
    marks: list = field(default_factory=list)


G = ["good.csv", "-u", "u", "-y", "y"]
ARX_FIT = ["fit", *G, "--structure", "arx", "--na", "2", "--nb", "2", "--nk", "1", "--json"]

CASES = [
    # ------------------------------------------------------------------ files
    Case(
        "file missing",
        ["fit", "nope.csv", "-u", "u", "-y", "y", "--json"],
        ["nope.csv does not exist"],
    ),
    Case(
        "file misspelt",
        ["fit", "god.csv", "-u", "u", "-y", "y", "--json"],
        ["did you mean 'good.csv'"],
    ),
    Case(
        "file empty",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        ["bad.csv is empty"],
        lambda d: (d / "bad.csv").write_text(""),
    ),
    Case(
        "file is a folder",
        ["fit", "sub.csv", "-u", "u", "-y", "y", "--json"],
        ["is a folder"],
        lambda d: (d / "sub.csv").mkdir(),
    ),
    Case(
        "file type unknown",
        ["fit", "data.xlsx", "-u", "u", "-y", "y", "--json"],
        ["unknown data file type '.xlsx'"],
        lambda d: (d / "data.xlsx").write_text("x"),
    ),
    Case(
        "file header only",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        ["header but no data rows"],
        lambda d: (d / "bad.csv").write_text("t,u,y\n"),
    ),
    Case(
        "file ragged rows",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        ["expected 3 fields in line 3, saw 4"],
        lambda d: _csv(d / "bad.csv", "t,u,y", ["0,1,2", "0.05,1,2,7", "0.1,1,2"]),
    ),
    Case(
        "file not a .mat",
        ["fit", "bad.mat", "-u", "u", "-y", "y", "--json"],
        ["bad.mat is not a MATLAB .mat file"],
        lambda d: (d / "bad.mat").write_text("hello"),
    ),
    Case(
        "file not parquet",
        ["fit", "bad.parquet", "-u", "u", "-y", "y", "--json"],
        ["not a readable Parquet file"],
        lambda d: (d / "bad.parquet").write_text("hello"),
    ),
    Case(
        "file given twice",
        ["fit", "good.csv", "good.csv", "-u", "u", "-y", "y", "--json"],
        ["listed twice"],
    ),
    # ------------------------------------------------------------------ columns
    Case(
        "column missing",
        ["fit", "good.csv", "-u", "U", "-y", "y", "--json"],
        ["no column 'U'", "did you mean 'u'"],
    ),
    Case(
        "column duplicated",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        ["column 'u' appears 2 times", "columns 2 and 3"],
        lambda d: _csv(d / "bad.csv", "t,u,u,y", ["0,1,2,3", "0.05,1,2,3", "0.1,1,2,3"]),
    ),
    Case(
        "column grouped header",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        [
            "grouped header",
            "'u' (column 3) is followed by 2 columns without a name",
            "columns 4 to 5",
        ],
        lambda d: _csv(
            d / "bad.csv",
            '"r",,"u",,,"y",,,',
            [",".join(str(k + j) for j in range(8)) + "," for k in range(20)],
        ),
    ),
    Case(
        "column no header",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        ["add a line of column names"],
        lambda d: _csv(d / "bad.csv", "0,1,2", ["0.05,1,2", "0.1,1,2"]),
    ),
    Case(
        "column input and output",
        ["fit", "good.csv", "-u", "u", "-y", "u", "--json"],
        ["both as an input and as an output"],
    ),
    Case(
        "column input twice",
        ["fit", "good.csv", "-u", "u", "-u", "u", "-y", "y", "--json"],
        ["input signal 'u' is listed twice"],
    ),
    Case(
        "column time missing",
        [*ARX_FIT, "--time-column", "time"],
        ["no column 'time'", "available columns: 't'"],
    ),
    # ------------------------------------------------------------------ values
    Case(
        "value not a number",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        ["column 'u', data row 5 (line 6): 'abc' is not a number"],
        _with_cell(4, 1, "abc"),
    ),
    Case(
        "value empty",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        ["column 'y', data row 8 (line 9) is empty"],
        _with_cell(7, 2, ""),
    ),
    Case(
        "value NaN",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        ["column 'u', data row 3", "missing value"],
        _with_cell(2, 1, "NaN"),
    ),
    Case(
        "value infinite",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        ["column 'y', data row 2", "is infinite"],
        _with_cell(1, 2, "inf"),
    ),
    Case(
        "value decimal comma",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        ["decimal comma"],
        lambda d: _csv(d / "bad.csv", "t;u;y", ["0;1,5;2", "0.05;1;2"]),
    ),
    Case(
        "time not increasing",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--time-column", "t", "--json"],
        ["time column 't' does not increase"],
        _with_cell(10, 0, "0.01"),
    ),
    Case(
        "time not uniform",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--time-column", "t", "--json"],
        ["not uniformly sampled"],
        _with_cell(10, 0, "0.52"),
    ),
    Case(
        "ts contradicts time column",
        [*ARX_FIT, "--ts", "0.1"],
        ["sampling_time 0.1 disagrees with column 't'", "steps by 0.05", "--ts"],
    ),
    Case(
        "ts contradicts named time column",
        [*ARX_FIT, "--ts", "0.1", "--time-column", "t"],
        ["sampling_time 0.1 disagrees with time column 't'"],
    ),
    Case("ts negative", [*ARX_FIT, "--ts", "-1"], ["positive number of seconds"]),
    Case(
        "input constant",
        [
            "fit",
            "bad.csv",
            "-u",
            "u",
            "-y",
            "y",
            "--structure",
            "arx",
            "--na",
            "2",
            "--nb",
            "2",
            "--nk",
            "1",
            "--json",
        ],
        ["input 'u' is constant over the estimation data", "u at lag 2"],
        lambda d: _csv(
            d / "bad.csv",
            "t,u,y",
            [f"{k * DT:.2f},0.5,{float(np.sin(0.3 * k))!r}" for k in range(N)],
        ),
    ),
    # ------------------------------------------------------------------ ranges
    Case("range empty", [*ARX_FIT, "--estimation", "10:5"], ["is empty"]),
    Case(
        "range not a range", [*ARX_FIT, "--estimation", "abc"], ["--estimation expects START:STOP"]
    ),
    Case(
        "range too long",
        [*ARX_FIT, "--estimation", "0:5000"],
        ["does not fit experiment", "300 samples"],
    ),
    Case("range negative", [*ARX_FIT, "--estimation", "-5:10"], ["negative"]),
    Case(
        "range overlap identify",
        ["identify", *G, "--estimation", "0:200", "--validation", "150:300", "--json"],
        ["--estimation 0:200 and --validation 150:300 overlap"],
    ),
    Case(
        "range overlap compare",
        [
            "compare",
            *G,
            "--estimation",
            "0:200",
            "--validation",
            "150:300",
            "--structures",
            "arx",
            "--json",
        ],
        ["overlap"],
        marks=[],
    ),
    Case(
        "range simulate beyond",
        ["simulate", "model.json", "good.csv", "--range", "250:400", "--json"],
        ["--range 250:400 does not fit"],
    ),
    # ------------------------------------------------------------------ orders
    Case(
        "order nb zero",
        ["fit", *G, "--structure", "arx", "--na", "2", "--nb", "0", "--json"],
        ["nb is 0 for every input", "--nb"],
    ),
    Case("order negative", ["fit", *G, "--structure", "arx", "--na", "-1", "--json"], ["na"]),
    Case(
        "order too large",
        ["fit", *G, "--structure", "arx", "--na", "400", "--json"],
        ["looks back 400 samples"],
    ),
    # ------------------------------------------------------------------ model files
    Case(
        "model missing",
        ["simulate", "none.json", "good.csv", "--json"],
        ["model file none.json does not exist"],
    ),
    Case(
        "model not JSON",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["not valid JSON"],
        lambda d: (d / "bad.json").write_text("{oops"),
    ),
    Case(
        "model other format",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["not a blockid model file"],
        lambda d: (d / "bad.json").write_text('{"format": "other"}'),
    ),
    Case(
        "model version",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["version 99"],
        _bad_model(lambda doc: doc.update(version=99)),
    ),
    Case(
        "model NaN parameter",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["non-finite parameter", "parameters.y.a.y[0] is nan"],
        _bad_model(_nan_parameter),
    ),
    Case(
        "model unknown structure",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["unknown model structure 'magic'"],
        _bad_model(lambda doc: doc["model"].update(structure="magic")),
    ),
    Case(
        "model incomplete",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["damaged or incomplete"],
        _bad_model(lambda doc: doc["model"].pop("orders")),
    ),
    Case(
        "model signals not in data",
        ["simulate", "network.json", "good.csv", "--json"],
        ["no column 'u1'"],
    ),
    # ------------------------------------------------------------------ options
    Case("option nothing to do", ["fit", *G], ["nothing to do"]),
    Case(
        "option output exists",
        ["fit", *G, "--structure", "arx", "-o", "model.json"],
        ["model.json exists; pass --force"],
    ),
    Case(
        "option table exists",
        ["simulate", "model.json", "good.csv", "-o", "good.csv"],
        ["good.csv exists; pass --force"],
    ),
    Case(
        "option table type",
        ["simulate", "model.json", "good.csv", "-o", "out.xlsx"],
        ["unknown table type"],
    ),
    Case("option structure unknown", ["fit", *G, "--structure", "magic", "--json"], ["magic"]),
    Case(
        "option method unknown",
        ["fit", *G, "--structure", "arx", "--method", "magic", "--json"],
        ["magic"],
    ),
    Case(
        "option forgetting out of range",
        ["fit", *G, "--structure", "arx", "--method", "rls", "--forgetting", "1.5", "--json"],
        ["forgetting"],
    ),
    Case(
        "option demo folder not empty",
        ["demo", "--plot", "out", "--json"],
        ["out exists and is not empty", "--force"],
        _folder_with_a_file("out"),
    ),
    Case(
        "option demo old flag not empty",
        ["demo", "--output-dir", "out", "--json"],
        ["not empty"],
        _folder_with_a_file("out"),
    ),
    Case(
        "option reproduce folder not empty",
        ["reproduce", "windtunnel", "--plot", "out", "--json"],
        ["not empty"],
        _folder_with_a_file("out"),
    ),
    Case(
        "option reproduce old flag not empty",
        ["reproduce", "electrohydraulic", "--figures", "out", "--json"],
        ["not empty"],
        _folder_with_a_file("out"),
    ),
    # ------------------------------------------------------------------ networks
    Case(
        "network spec unreadable",
        ["fit-network", "net.csv", "-s", "S1 u1 v1", "--json"],
        ["cannot read subsystem"],
    ),
    Case(
        "network option not key=value",
        ["fit-network", "net.csv", "-s", "S1: u1 -> v1 | arx na", "--json"],
        ["must be key=value"],
    ),
    Case(
        "network signal missing",
        ["fit-network", "net.csv", "-s", "S1: u9 -> v1 | arx na=1 nb=1 nk=1", "--json"],
        ["no column 'u9'"],
    ),
    Case(
        "network signal made twice",
        [
            "fit-network",
            "net.csv",
            "-s",
            "S1: u1 -> v1 | arx na=1 nb=1 nk=1",
            "-s",
            "S2: u1 -> v1 | arx na=1 nb=1 nk=1",
            "--json",
        ],
        ["'v1' is made by subsystem 'S1' and by 'S2'"],
    ),
    Case(
        "network cyclic model file",
        ["simulate", "bad.json", "net.csv", "--json"],
        ["cycle: 'S1' -> v1 -> 'S2' -> v2 -> 'S1'"],
        _cyclic_network,
    ),
    Case(
        "network cyclic spec",
        [
            "fit-network",
            "net.csv",
            "-s",
            "S1: v2 -> v1 | arx na=1 nb=1 nk=1",
            "-s",
            "S2: v1 -> v2 | arx na=1 nb=1 nk=1",
            "--json",
        ],
        ["cycle"],
    ),
]


@pytest.fixture
def folder(tmp_path, monkeypatch):
    """good.csv (t, u, y), net.csv (t, u1, v1, v2), model.json (ARX u -> y) and
    network.json (u1 -> v1 -> y1), in the working folder of the command."""
    _csv(tmp_path / "good.csv", "t,u,y", _good_rows())
    t, u, y = _record(1)
    v2 = np.roll(y, 1)
    _csv(
        tmp_path / "net.csv",
        "t,u1,v1,v2",
        [f"{t[k]:.2f},{float(u[k])!r},{float(y[k])!r},{float(v2[k])!r}" for k in range(N)],
    )
    plant = ARX(["u"], ["y"], 2, 2, 1, a={"y": {"y": [-1.2, 0.35]}}, b={"y": {"u": [1.0, 0.4]}})
    save_model(plant, tmp_path / "model.json")
    s1 = ARX(["u1"], ["v1"], 1, 1, 1, a={"v1": {"v1": [-0.5]}}, b={"v1": {"u1": [0.5]}})
    s3 = ARX(["v1"], ["y1"], 1, 1, 1, a={"y1": {"y1": [-0.5]}}, b={"y1": {"v1": [1.0]}})
    save_model(Network([("S1", s1), ("S3", s3)]), tmp_path / "network.json")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _snapshot(root: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()
    }


def test_at_least_forty_cases_over_every_kind():
    assert len(CASES) >= 40
    kinds = {c.id.split()[0] for c in CASES}
    assert {"file", "column", "value", "range", "order", "model", "option", "network"} <= kinds


@pytest.mark.parametrize("case", [pytest.param(c, id=c.id, marks=c.marks) for c in CASES])
def test_malformed_input(case, folder):
    if case.make is not None:
        case.make(folder)
    before = _snapshot(folder)
    r = runner.invoke(app, case.args)
    err = r.stderr
    assert r.exit_code == 2, f"exit {r.exit_code}; stderr: {err}; exception: {r.exception!r}"
    assert "Traceback" not in err and "Traceback" not in r.stdout
    assert isinstance(r.exception, SystemExit)
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    for words in case.expect:
        assert words.lower() in err.lower(), f"{words!r} not in {err!r}"
    after = _snapshot(folder)
    assert {k: after.get(k) for k in before} == before, "an existing file was changed"
