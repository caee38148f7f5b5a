"""Malformed input, as a user would give it, gets one readable line and exit status 2.

Each case is one command line on a folder of files (a good record, a model file, a
network model file and the case's own bad file). The checks, for every case: exit
status 2, the expected words on stderr (the message names the problem), no traceback,
one line, and every file that existed before is byte-for-byte unchanged afterwards.
The cases cover files, columns, values, sampling times, ranges, orders, model files,
options, exports and networks, on every command (issues 11 and 21); ``stream`` reads its
samples from the case's ``input``.
"""

from __future__ import annotations

import gzip
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


def _write(name: str, content: str | bytes) -> Callable[[Path], None]:
    """A file ``name`` holding ``content`` (bytes as they are, text as UTF-8)."""

    def make(d: Path) -> None:
        if isinstance(content, bytes):
            (d / name).write_bytes(content)
        else:
            (d / name).write_text(content, encoding="utf-8")

    return make


def _bad_csv(header: str, rows: list[str], encoding: str = "utf-8") -> Callable[[Path], None]:
    def make(d: Path) -> None:
        (d / "bad.csv").write_bytes((header + "\n" + "\n".join(rows) + "\n").encode(encoding))

    return make


def _with_column(column: int, values: Callable[[int], str]) -> Callable[[Path], None]:
    """A copy of good.csv as bad.csv with every cell of one column replaced."""

    def make(d: Path) -> None:
        rows = [r.split(",") for r in _good_rows()]
        for k, row in enumerate(rows):
            row[column] = values(k)
        _csv(d / "bad.csv", "t,u,y", [",".join(r) for r in rows])

    return make


def _first_rows(n: int) -> Callable[[Path], None]:
    return _bad_csv("t,u,y", _good_rows()[:n])


def _parquet(rows: int | None = None, truncate: bool = False) -> Callable[[Path], None]:
    """good.csv as bad.parquet (its first ``rows`` rows), or the file cut in half."""

    def make(d: Path) -> None:
        import pandas as pd

        frame = pd.read_csv(d / "good.csv").iloc[:rows]
        frame.to_parquet(d / "bad.parquet", index=False)
        if truncate:
            data = (d / "bad.parquet").read_bytes()
            (d / "bad.parquet").write_bytes(data[: len(data) // 2])

    return make


def _mat(**variables: object) -> Callable[[Path], None]:
    def make(d: Path) -> None:
        from scipy.io import savemat

        savemat(d / "bad.mat", variables)

    return make


def _chain_model(change: Callable[[dict], None]) -> Callable[[Path], None]:
    """A Hammerstein model file (u -> y) as bad.json, edited by ``change``."""

    def make(d: Path) -> None:
        from blockid.blocks import TwoSegmentPolynomial
        from blockid.models import Hammerstein

        block = TwoSegmentPolynomial([0.0, 1.0], [0.0, -0.5])
        model = Hammerstein("u", "y", input_block=block, na=1, nb=1, nk=1, a=[-0.5])
        save_model(model, d / "bad.json")
        doc = json.loads((d / "bad.json").read_text())
        change(doc)
        (d / "bad.json").write_text(json.dumps(doc))

    return make


def _state_space_model(change: Callable[[dict], None]) -> Callable[[Path], None]:
    """A linear state-space model file (u -> y, two states) as bad.json, edited."""

    def make(d: Path) -> None:
        from blockid.models import StateSpace

        A, B, C, D = [[0.5, 0.1], [0.0, 0.3]], [[1.0], [0.5]], [[1.0, 0.0]], [[0.0]]
        save_model(StateSpace(["u"], ["y"], A, B, C, D), d / "bad.json")
        doc = json.loads((d / "bad.json").read_text())
        change(doc["model"])
        (d / "bad.json").write_text(json.dumps(doc))

    return make


def _figures(folder: str, *names: str) -> Callable[[Path], None]:
    """A folder holding figures of an earlier run."""

    def make(d: Path) -> None:
        (d / folder).mkdir()
        for name in names:
            (d / folder / name).write_bytes(b"\x89PNG earlier figure")

    return make


def _parameter(doc: dict, key: str, value: object) -> None:
    doc["model"]["parameters"]["y"][key]["y" if key == "a" else "u"] = value


@dataclass
class Case:
    id: str
    args: list[str]
    expect: list[str]
    make: Callable[[Path], None] | None = None
    marks: list = field(default_factory=list)
    #: Text on standard input (``stream``).
    input: str | None = None


G = ["good.csv", "-u", "u", "-y", "y"]
B = ["bad.csv", "-u", "u", "-y", "y"]
ARX_ORDERS = ["--structure", "arx", "--na", "2", "--nb", "2", "--nk", "1"]
ARX_FIT = ["fit", *G, *ARX_ORDERS, "--json"]
ARX_BAD = ["fit", *B, *ARX_ORDERS, "--json"]
COMPARE = ["compare", *G, "--estimation", "0:200", "--validation", "200:300"]
NET_FIT = ["fit-network", "net.csv", "-s", "S1: u1 -> v1 | arx na=1 nb=1 nk=1"]
GOOD_TEXT = "t,u,y\n" + "\n".join(_good_rows()) + "\n"

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
    Case(
        "file folder as data",
        ["fit", "records", "-u", "u", "-y", "y", "--json"],
        ["records is a folder, not a data file", "records/*.csv"],
        _folder_with_a_file("records"),
    ),
    Case(
        "file folder as data simulate",
        ["simulate", "model.json", "records", "--json"],
        ["records is a folder"],
        _folder_with_a_file("records"),
    ),
    Case(
        "file folder as data orders",
        ["orders", "records", "-u", "u", "-y", "y", "--json"],
        ["records is a folder"],
        _folder_with_a_file("records"),
    ),
    Case(
        "file only a byte-order mark",
        ["fit", *B, "--json"],
        ["bad.csv is empty"],
        _write("bad.csv", b"\xef\xbb\xbf"),
    ),
    Case(
        "file only whitespace",
        ["fit", *B, "--json"],
        ["bad.csv is empty"],
        _write("bad.csv", "  \n\t\n   \n"),
    ),
    Case(
        "file byte-order mark and a wrong column",
        ["fit", "bad.csv", "-u", "U", "-y", "y", "--json"],
        ["no column 'U'", "'t', 'u', 'y'"],
        lambda d: (d / "bad.csv").write_bytes(b"\xef\xbb\xbf" + (d / "good.csv").read_bytes()),
    ),
    Case(
        "file binary garbage",
        ["fit", *B, "--json"],
        ["bad.csv is not a text file", "NUL bytes"],
        _write("bad.csv", bytes(range(256)) * 64),
    ),
    Case(
        "file gzip named csv",
        ["fit", *B, "--json"],
        ["bad.csv is not a text file", "compressed"],
        lambda d: (d / "bad.csv").write_bytes(gzip.compress((d / "good.csv").read_bytes())),
    ),
    Case(
        "file utf-16 text",
        ["fit", *B, "--json"],
        ["bad.csv is not a text file", "UTF-16"],
        lambda d: (d / "bad.csv").write_bytes((d / "good.csv").read_text().encode("utf-16")),
    ),
    Case(
        "file html page",
        ["fit", *B, "--json"],
        ["no column 'u'"],
        _write("bad.csv", "<!DOCTYPE html>\n<html><body>Not found</body></html>\n"),
    ),
    Case(
        "file unclosed quote",
        ["fit", *B, "--json"],
        ["bad.csv could not be parsed"],
        _bad_csv("t,u,y", ["0,1,2", '0.05,"1.5,2', "0.1,1,2"]),
    ),
    Case(
        "file very wide rows",
        ["fit", *B, "--json"],
        ["line 2 has 500 fields but the header names only 3 columns"],
        _bad_csv("t,u,y", [",".join(["1"] * 500)] * 20),
    ),
    Case(
        "file semicolon header comma rows",
        ["fit", *B, "--json"],
        ["line 2 has 3 fields but the header names only 1 columns"],
        _bad_csv("t;u;y", [f"{k * DT:.2f},1,2" for k in range(20)]),
    ),
    Case(
        "file tab and comma mixed",
        ["fit", *B, "--json"],
        ["bad.csv"],
        _bad_csv("t\tu\ty", [f"{k * DT:.2f}\t1,5\t2" for k in range(20)]),
    ),
    Case(
        "file no suffix",
        ["fit", "data", "-u", "u", "-y", "y", "--json"],
        ["unknown data file type '(no suffix)'"],
        _write("data", "t,u,y\n0,1,2\n"),
    ),
    Case(
        "file truncated parquet",
        ["fit", "bad.parquet", "-u", "u", "-y", "y", "--json"],
        ["bad.parquet is not a readable Parquet file"],
        _parquet(truncate=True),
    ),
    Case(
        "file parquet without rows",
        ["fit", "bad.parquet", "-u", "u", "-y", "y", "--json"],
        ["bad.parquet has columns but no data rows"],
        _parquet(rows=0),
    ),
    Case(
        "file mat no numeric variable",
        ["fit", "bad.mat", "-u", "u", "-y", "y", "--json"],
        ["bad.mat", "no variable 'u'", "note"],
        _mat(note="measured on the test bench"),
    ),
    Case(
        "file mat text variable",
        ["fit", "bad.mat", "-u", "u", "-y", "y", "--json"],
        ["variable 'u' is a char array"],
        _mat(u="not a signal", y=np.zeros(N)),
    ),
    Case(
        "file mat shapes differ",
        ["fit", "bad.mat", "-u", "u", "-y", "y", "--json"],
        ["variables have different shapes", "'u' is 1 x 300", "'y' is 1 x 200"],
        _mat(u=np.ones(N), y=np.ones(200)),
    ),
    Case(
        "file mat three dimensions",
        ["fit", "bad.mat", "-u", "u", "-y", "y", "--json"],
        ["variable 'u' has 3 dimensions"],
        _mat(u=np.ones((10, 3, 2)), y=np.ones(10)),
    ),
    Case(
        "file mat empty variable",
        ["fit", "bad.mat", "-u", "u", "-y", "y", "--json"],
        ["variable 'u' is empty"],
        _mat(u=np.zeros(0), y=np.ones(10)),
    ),
    Case(
        "file second file lacks a column",
        ["fit", "good.csv", "bad.csv", "-u", "u", "-y", "y", "--json"],
        ["bad.csv", "no column 'y'"],
        _bad_csv("t,u,z", _good_rows()),
    ),
    Case(
        "file second file other sampling time",
        ["fit", "good.csv", *B, *ARX_ORDERS, "--json", "--time-column", "t"],
        ["sampling time", "bad.csv"],
        _with_column(0, lambda k: f"{k * 0.1:.2f}"),
    ),
    Case(
        "file validation data missing",
        ["identify", *G, "--validation-data", "val.csv", "--json"],
        ["val.csv does not exist"],
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
    Case(
        "column case mismatch output",
        ["fit", "good.csv", "-u", "u", "-y", "Y", "--json"],
        ["no column 'Y'", "did you mean 'y'"],
    ),
    Case(
        "column case mismatch header",
        ["fit", *B, "--json"],
        ["no column 'u'", "did you mean 'U'"],
        lambda d: _csv(d / "bad.csv", "T,U,Y", _good_rows()),
    ),
    Case(
        "column empty name",
        ["fit", "good.csv", "-u", "", "-y", "y", "--json"],
        ["input signal names must be non-empty"],
    ),
    Case(
        "column blank name",
        ["fit", "good.csv", "-u", "u", "-y", "  ", "--json"],
        ["no column", "available columns: 't', 'u', 'y'"],
    ),
    Case(
        "column empty header cell",
        ["fit", *B, "--json"],
        ["no column 'u'", "'t', 'y'"],
        lambda d: _csv(d / "bad.csv", "t,,y", _good_rows()),
    ),
    Case(
        "column time not numeric",
        [*ARX_BAD, "--time-column", "t"],
        ["column 't', data row 1 (line 2): 'sample 0' is not a number"],
        _with_column(0, lambda k: f"sample {k}"),
    ),
    Case("column time is the input", [*ARX_FIT, "--time-column", "u"], ["'u'", "time"]),
    Case(
        "column experiment missing", [*ARX_FIT, "--experiment-column", "run"], ["no column 'run'"]
    ),
    Case(
        "column experiment interleaved",
        [*ARX_BAD, "--experiment-column", "run"],
        ["'run'", "a"],
        lambda d: _csv(
            d / "bad.csv", "t,u,y,run", [f"{r},{'ab'[k % 2]}" for k, r in enumerate(_good_rows())]
        ),
    ),
    Case(
        "column latin-1 header",
        ["fit", *B, "--json"],
        ["no column 'u'", "'Strom_\u00b5A'", "'Spannung_\u00e4'"],
        _bad_csv("t,Strom_\u00b5A,Spannung_\u00e4", _good_rows(), "latin-1"),
    ),
    Case(
        "column windows-1252 header",
        ["fit", "bad.csv", "-u", "Druck", "-y", "y", "--json"],
        ["no column 'Druck'", "did you mean 'Druck_\u20ac'"],
        _bad_csv("t,Druck_\u20ac,y", _good_rows(), "cp1252"),
    ),
    Case("column input not given", ["fit", "good.csv", "-y", "y", "--json"], ["--input"]),
    Case(
        "column orders input missing",
        ["orders", "good.csv", "-u", "x", "-y", "y", "--json"],
        ["no column 'x'"],
    ),
    Case(
        "column orders output misspelt",
        ["orders", "good.csv", "-u", "u", "-y", "Y", "--json"],
        ["did you mean 'y'"],
    ),
    Case(
        "column compare output missing",
        [
            "compare",
            "good.csv",
            "-u",
            "u",
            "-y",
            "out",
            "--estimation",
            "0:200",
            "--validation",
            "200:300",
            "--json",
        ],  # fmt: skip
        ["no column 'out'"],
    ),
    Case(
        "column identify input missing",
        ["identify", "good.csv", "-u", "input", "-y", "y", "--json"],
        ["no column 'input'"],
    ),
    Case(
        "column report input missing",
        [
            "report",
            "good.csv",
            "-u",
            "v",
            "-y",
            "y",
            "--estimation",
            "0:200",
            "--validation",
            "200:300",
        ],  # fmt: skip
        ["no column 'v'"],
    ),
    Case(
        "column stream header lacks the input",
        ["stream", "-u", "u", "-y", "y"],
        ["header line has columns t, x, y", "u missing"],
        input="t,x,y\n0,1,2\n0.05,1,2\n",
    ),
    Case(
        "column network signal case",
        ["fit-network", "net.csv", "-s", "S1: u1 -> V1 | arx na=1 nb=1 nk=1", "--json"],
        ["no column 'V1'", "did you mean 'v1'"],
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
        ["input 'u' is constant over the estimation data", "(0.5 at every sample)"],
        lambda d: _csv(
            d / "bad.csv",
            "t,u,y",
            [f"{k * DT:.2f},0.5,{float(np.sin(0.3 * k))!r}" for k in range(N)],
        ),
    ),
    Case(
        "value huge hammerstein",
        ["fit", *B, "--structure", "hammerstein", "--json"],
        ["column 'u', data row 5 (line 6)", "too large", "rescale"],
        _with_cell(4, 1, "1e300"),
    ),
    Case(
        "value huge arx",
        ARX_BAD,
        ["column 'y', data row 8 (line 9)", "too large"],
        _with_cell(7, 2, "1e300"),
    ),
    Case(
        "value huge negative wiener",
        ["fit", *B, "--structure", "wiener", "--json"],
        ["column 'y', data row 3", "too large"],
        _with_cell(2, 2, "-1e300"),
    ),
    Case(
        "value huge simulate",
        ["simulate", "model.json", "bad.csv", "--json"],
        ["column 'u', data row 4", "too large"],
        _with_cell(3, 1, "1e300"),
    ),
    Case(
        "value huge orders",
        ["orders", *B, "--json"],
        ["column 'u', data row 10", "too large"],
        _with_cell(9, 1, "1e300"),
    ),
    Case(
        "value word",
        ["fit", *B, "--json"],
        ["column 'y', data row 21 (line 22): 'high' is not a number"],
        _with_cell(20, 2, "high"),
    ),
    Case(
        "value boolean among numbers",
        ["fit", *B, "--json"],
        ["column 'u', data row 7 (line 8): 'True' is not a number"],
        _with_cell(6, 1, "True"),
    ),
    Case(
        "value thousands separator",
        ["fit", *B, "--json"],
        ["column 'u', data row 2 (line 3): '1,234.5' is not a number"],
        _with_cell(1, 1, '"1,234.5"'),
    ),
    Case(
        "value unit suffix",
        ["fit", *B, "--json"],
        ["'1.5V' is not a number"],
        _with_cell(11, 1, "1.5V"),
    ),
    Case(
        "value hexadecimal",
        ["fit", *B, "--json"],
        ["'0x1F' is not a number"],
        _with_cell(12, 2, "0x1F"),
    ),
    Case(
        "value mixed types",
        ["fit", *B, "--json"],
        ["column 'u', data row 3 (line 4): 'off' is not a number"],
        _with_column(1, lambda k: ["on", "1.5", "off", "-2"][k % 4] if k else "0.5"),
    ),
    Case(
        "value all NaN column",
        ["fit", *B, "--json"],
        ["column 'y', data row 1 (line 2)"],
        _with_column(2, lambda k: ""),
    ),
    Case(
        "value NA text",
        ["fit", *B, "--json"],
        ["column 'u', data row 15", "missing value"],
        _with_cell(14, 1, "NA"),
    ),
    Case(
        "value minus infinity",
        ["fit", *B, "--json"],
        ["column 'u', data row 16", "is infinite"],
        _with_cell(15, 1, "-inf"),
    ),
    Case(
        "value NaN simulate",
        ["simulate", "model.json", "bad.csv", "--json"],
        ["column 'u', data row 3", "missing value"],
        _with_cell(2, 1, "NaN"),
    ),
    Case(
        "value NaN predict",
        ["predict", "model.json", "bad.csv", "--json"],
        ["column 'y', data row 40", "is empty"],
        _with_cell(39, 2, ""),
    ),
    Case(
        "value one row only", ARX_BAD, ["needs more than 2 samples", "has only 1"], _first_rows(1)
    ),
    Case(
        "value two rows only", ARX_BAD, ["needs more than 2 samples", "has only 2"], _first_rows(2)
    ),
    Case(
        "value one row hammerstein",
        ["fit", *B, "--structure", "hammerstein", "--na", "2", "--nb", "2", "--nk", "1", "--json"],
        ["hammerstein", "has only 1"],
        _first_rows(1),
    ),
    Case(
        "value two rows orders",
        ["orders", *B, "--json"],
        ["0 samples with a full regressor", "at least 80"],
        _first_rows(2),
    ),
    Case(
        "value two rows simulate",
        ["simulate", "model.json", "bad.csv", "--json"],
        ["has only 2"],
        _first_rows(2),
    ),
    Case("ts zero", [*ARX_FIT, "--ts", "0"], ["positive number of seconds", "--ts"]),
    Case("ts nan", [*ARX_FIT, "--ts", "nan"], ["positive number of seconds", "--ts"]),
    Case("ts infinite", [*ARX_FIT, "--ts", "inf"], ["--ts", "inf"]),
    Case("ts a word", [*ARX_FIT, "--ts", "fast"], ["invalid value for '--ts'", "valid number"]),
    Case(
        "ts zero simulate",
        ["simulate", "model.json", "good.csv", "--ts", "0", "--json"],
        ["positive number of seconds"],
    ),
    Case(
        "ts negative orders",
        ["orders", *G, "--ts", "-0.05", "--json"],
        ["positive number of seconds"],
    ),
    Case(
        "ts nan fit-network",
        [*NET_FIT, "--ts", "nan", "--json"],  # fmt: skip
        ["positive number of seconds"],
    ),
    Case(
        "ts zero fleet",
        ["fleet", *G, "-o", "out", "--ts", "0", "--json"],
        ["positive number of seconds"],
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
    Case("range equal ends", [*ARX_FIT, "--estimation", "5:5"], ["--estimation", "'5:5' is empty"]),
    Case("range not numbers", [*ARX_FIT, "--estimation", "a:b"], ["--estimation", "a:b"]),
    Case("range fractional", [*ARX_FIT, "--estimation", "1.5:100"], ["--estimation", "1.5:100"]),
    Case(
        "range one number", [*ARX_FIT, "--estimation", "100"], ["--estimation expects START:STOP"]
    ),
    Case("range three parts", [*ARX_FIT, "--estimation", "0:100:2"], ["START:STOP", "0:100:2"]),
    Case(
        "range start beyond the record",
        [*ARX_FIT, "--estimation", "400:500"],
        ["400:500", "300 samples"],
    ),
    Case("range negative stop", [*ARX_FIT, "--estimation", "0:-10"], ["negative"]),
    Case("range too short for the orders", [*ARX_FIT, "--estimation", "0:3"], ["3 samples"]),
    Case(
        "range simulate reversed",
        ["simulate", "model.json", "good.csv", "--range", "200:100", "--json"],
        ["--range", "'200:100' is empty"],
    ),
    Case(
        "range predict not a range",
        ["predict", "model.json", "good.csv", "--range", "first half", "--json"],
        ["--range expects START:STOP"],
    ),
    Case(
        "range predict beyond the record",
        ["predict", "model.json", "good.csv", "--range", "0:301", "--json"],
        ["--range 0:301 does not fit", "300 samples"],
    ),
    Case(
        "range orders beyond the record",
        ["orders", *G, "--estimation", "100:1000", "--json"],
        ["--estimation 100:1000 does not fit"],
    ),
    Case(
        "range fit-network reversed",
        [*NET_FIT, "--estimation", "50:10", "--json"],
        ["--estimation", "'50:10' is empty"],
    ),
    Case(
        "range compare validation beyond",
        [
            "compare",
            *G,
            "--estimation",
            "0:200",
            "--validation",
            "200:900",
            "--structures",
            "arx",
            "--json",
        ],  # fmt: skip
        ["--validation 200:900 does not fit"],
    ),
    Case(
        "range compare estimation missing",
        ["compare", *G, "--validation", "200:300", "--json"],
        ["--estimation"],
    ),
    Case(
        "range identify validation beyond",
        ["identify", *G, "--estimation", "0:200", "--validation", "200:400", "--json"],
        ["--validation 200:400 does not fit"],
    ),
    Case(
        "range identify estimation empty",
        ["identify", *G, "--estimation", "10:10", "--json"],
        ["--estimation", "'10:10' is empty"],
    ),
    Case(
        "range report overlap",
        ["report", *G, "--estimation", "0:200", "--validation", "100:300"],
        ["overlap"],
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
    Case(
        "order na huge",
        ["fit", *G, "--structure", "arx", "--na", "99999999999", "--json"],
        ["na=99999999999", "has only 300"],
    ),
    Case(
        "order na larger than the record",
        ["fit", *G, "--structure", "arx", "--na", "1000", "--json"],
        ["looks back 1000 samples", "has only 300"],
    ),
    Case(
        "order na fractional",
        ["fit", *G, "--structure", "arx", "--na", "1.5", "--json"],
        ["na='1.5'", "whole number", "--na"],
    ),
    Case(
        "order na a word",
        ["fit", *G, "--structure", "arx", "--na", "two", "--json"],
        ["na='two'", "whole number"],
    ),
    Case(
        "order na empty",
        ["fit", *G, "--structure", "arx", "--na", "", "--json"],
        ["na=''", "whole number"],
    ),
    Case(
        "order nk negative",
        ["fit", *G, "--structure", "arx", "--nk", "-1", "--json"],
        ["nk must hold whole numbers >= 0", "--nk"],
    ),
    Case(
        "order nb too large",
        ["fit", *G, "--structure", "arx", "--na", "2", "--nb", "1000", "--json"],
        ["nb=1000", "has only 300"],
    ),
    Case(
        "order nk too large",
        ["fit", *G, "--structure", "arx", "--nk", "500", "--json"],
        ["nk=500", "has only 300"],
    ),
    Case(
        "order matrix for one output",
        ["fit", *G, "--structure", "arx", "--na", "2,2;2,2", "--json"],
        ["na must be a whole number or a 1x1 matrix", "[[2, 2], [2, 2]]"],
    ),
    Case(
        "order hammerstein na too large",
        ["fit", *G, "--structure", "hammerstein", "--na", "1000", "--json"],
        ["hammerstein with na=1000", "has only 300"],
    ),
    Case(
        "order r1 zero",
        ["fit", *G, "--structure", "hammerstein", "--r1", "0", "--json"],
        ["r1 must be a whole number >= 1, got 0", "--r1"],
    ),
    Case(
        "order r2 fractional",
        ["fit", *G, "--structure", "wiener", "--r2", "2.5", "--json"],
        ["r2 must be a whole number >= 1, got '2.5'"],
    ),
    Case(
        "order integrator three",
        ["fit", *G, "--structure", "output-error", "--integrator", "3", "--json"],
        ["integrator must be a whole number from 0 to 2, got 3"],
    ),
    Case(
        "order nx zero",
        ["fit", *G, "--structure", "state-space", "--nx", "0", "--json"],
        ["nx must be a whole number >= 1, got 0", "--nx"],
    ),
    Case(
        "order nx too large",
        ["fit", *G, "--structure", "state-space", "--nx", "200", "--json"],
        ["nx", "200"],
    ),
    Case(
        "order degree zero",
        ["fit", *G, "--structure", "polynomial-state-space", "--degree", "0", "--json"],
        ["degree must be a whole number from 1 to 5, got 0", "--degree"],
    ),
    Case(
        "order degree too high",
        ["fit", *G, "--structure", "polynomial-state-space", "--degree", "9", "--json"],
        ["degree must be a whole number from 1 to 5, got 9"],
    ),
    Case(
        "order horizon one",
        ["fit", *G, "--structure", "state-space", "--horizon", "1", "--json"],
        ["horizon must be a whole number >= 2, got 1"],
    ),
    Case(
        "order orders max-na negative",
        ["orders", *G, "--max-na", "-1", "--json"],
        ["max_na", "--max-na"],
    ),
    Case(
        "order orders max-nb zero",
        ["orders", *G, "--max-nb", "0", "--json"],
        ["max_nb", "--max-nb"],
    ),
    Case(
        "order orders max-nk too large",
        ["orders", *G, "--max-nk", "1000", "--json"],
        ["longest lag 1003", "--max-nk"],
    ),
    Case(
        "order orders max-na fractional",
        ["orders", *G, "--max-na", "1.5", "--json"],
        ["invalid value for '--max-na'", "valid integer"],
    ),
    Case(
        "order network na a word",
        ["fit-network", "net.csv", "-s", "S1: u1 -> v1 | arx na=x nb=1 nk=1", "--json"],
        ["na='x'", "whole number"],
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
    Case(
        "model truncated",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json is not valid JSON", "damaged"],
        lambda d: (d / "bad.json").write_text((d / "model.json").read_text()[:200]),
    ),
    Case(
        "model empty file",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["model file bad.json is empty"],
        _write("bad.json", ""),
    ),
    Case(
        "model JSON array",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["not a blockid model file"],
        _write("bad.json", "[1, 2, 3]"),
    ),
    Case(
        "model JSON null",
        ["predict", "bad.json", "good.csv", "--json"],
        ["not a blockid model file"],
        _write("bad.json", "null"),
    ),
    Case(
        "model binary",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json is not a text file"],
        _write("bad.json", bytes(range(128, 256)) * 4),
    ),
    Case(
        "model data file given as model",
        ["simulate", "good.csv", "good.csv", "--json"],
        ["good.csv is not valid JSON"],
    ),
    Case(
        "model is a folder",
        ["simulate", "models", "good.csv", "--json"],
        ["models is a folder, not a model file"],
        _folder_with_a_file("models"),
    ),
    Case(
        "model entry null",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "model"],
        _bad_model(lambda doc: doc.update(model=None)),
    ),
    Case(
        "model structure missing",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["unknown model structure None"],
        _bad_model(lambda doc: doc["model"].pop("structure")),
    ),
    Case(
        "model parameters text",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "damaged"],
        _bad_model(lambda doc: _parameter(doc, "a", "abc")),
    ),
    Case(
        "model parameters wrong length",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "a"],
        _bad_model(lambda doc: _parameter(doc, "a", [0.1, 0.2, 0.3, 0.4, 0.5])),
    ),
    Case(
        "model parameter null",
        ["predict", "bad.json", "good.csv", "--json"],
        ["bad.json", "parameters.y.b.u must be a list of numbers", "[None, 0.4]"],
        _bad_model(lambda doc: _parameter(doc, "b", [None, 0.4])),
    ),
    Case(
        "model parameter booleans",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["parameters.y.b.u must be a list of numbers", "[True, False]"],
        _bad_model(lambda doc: _parameter(doc, "b", [True, False])),
    ),
    Case(
        "model parameter nested list",
        ["export", "bad.json"],
        ["parameters.y.a.y must be a list of numbers", "[[-1.2, 0.35]]"],
        _bad_model(lambda doc: _parameter(doc, "a", [[-1.2, 0.35]])),
    ),
    Case(
        "model orders a word",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "na"],
        _bad_model(lambda doc: doc["model"]["orders"].update(na="two")),
    ),
    Case(
        "model unstable diverges",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["the model output is not finite", "diverged"],
        _bad_model(lambda doc: _parameter(doc, "a", [-30.0, 0.0])),
    ),
    Case(
        "model infinite parameter",
        ["predict", "bad.json", "good.csv", "--json"],
        ["non-finite parameter", "parameters.y.b.u[1] is inf"],
        _bad_model(lambda doc: _parameter(doc, "b", [1.0, float("inf")])),
    ),
    Case(
        "model chain with two inputs",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["names 2 inputs", "one input and one output"],
        _chain_model(lambda doc: doc["model"].update(inputs=["u", "u2"])),
    ),
    Case(
        "model chain block unknown",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "magic"],
        _chain_model(lambda doc: doc["model"]["chain"][0].update(kind="magic")),
    ),
    Case(
        "model arx input renamed",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "damaged"],
        _bad_model(lambda doc: doc["model"].update(inputs=["u", "w"])),
    ),
    Case(
        "model outputs empty",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "output"],
        _bad_model(lambda doc: doc["model"].update(outputs=[])),
    ),
    Case(
        "model sampling time negative",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json has sampling_time -1", "positive number of seconds"],
        _bad_model(lambda doc: doc["model"].update(sampling_time=-1)),
    ),
    Case(
        "model state-space matrix shapes",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "B must have shape (2, 1), got (2, 2)"],
        _state_space_model(lambda m: m.update(B=[[1.0, 2.0], [0.5, 0.1]])),
    ),
    Case(
        "model state-space not square",
        ["predict", "bad.json", "good.csv", "--json"],
        ["bad.json", "A must be a square matrix"],
        _state_space_model(lambda m: m.update(A=[[0.5, 0.1]])),
    ),
    Case(
        "model state-space scale zero",
        ["simulate", "bad.json", "good.csv", "--json"],
        ["bad.json", "scales must be positive"],
        _state_space_model(lambda m: m["normalisation"].update(input_scale=[0.0])),
    ),
    Case(
        "model network subsystem damaged",
        ["simulate", "bad.json", "net.csv", "--json"],
        ["bad.json", "subsystem 'S1'", "orders"],
        lambda d: (d / "bad.json").write_text(
            (d / "network.json").read_text().replace('"orders"', '"orderz"', 1)
        ),
    ),
    Case(
        "model stream start missing",
        ["stream", "-u", "u", "-y", "y", "--model", "none.json"],
        ["model file none.json does not exist"],
        input=GOOD_TEXT,
    ),
    Case(
        "model stream start damaged",
        ["stream", "-u", "u", "-y", "y", "--model", "bad.json"],
        ["bad.json is not valid JSON"],
        _write("bad.json", '{"format": "blockid-model", '),
        input=GOOD_TEXT,
    ),
    Case(
        "model stream start other signals",
        ["stream", "-u", "u", "-y", "y", "--model", "network.json"],
        ["initial must be a ARX model", "Network"],
        input=GOOD_TEXT,
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
    Case(
        "option input-block typo",
        ["fit", *G, "--structure", "hammerstein", "--input-block", "polynomal", "--json"],
        ["unknown block 'polynomal'", "did you mean 'polynomial'", "--input-block"],
    ),
    Case(
        "option input-block negative degree",
        [
            "fit",
            *G,
            "--structure",
            "hammerstein",
            "--input-block",
            "polynomial:degree=-1",
            "--json",
        ],  # fmt: skip
        ["degree", "-1", "--input-block"],
    ),
    Case(
        "option input-block unknown key",
        [
            "fit",
            *G,
            "--structure",
            "hammerstein",
            "--input-block",
            "polynomial:degre=3",
            "--json",
        ],  # fmt: skip
        ["degre", "--input-block"],
    ),
    Case(
        "option input-block degree a word",
        [
            "fit",
            *G,
            "--structure",
            "hammerstein",
            "--input-block",
            "polynomial:degree=three",
            "--json",
        ],  # fmt: skip
        ["degree", "three", "--input-block"],
    ),
    Case(
        "option input-block not key=value",
        ["fit", *G, "--structure", "hammerstein", "--input-block", "polynomial:3", "--json"],
        ["must be key=value", "--input-block"],
    ),
    Case(
        "option output-block typo",
        ["fit", *G, "--structure", "wiener", "--output-block", "saturaton", "--json"],
        ["unknown block 'saturaton'", "--output-block"],
    ),
    Case(
        "option block for arx",
        ["fit", *G, "--structure", "arx", "--input-block", "polynomial", "--json"],
        ["input_block not used by arx", "--input-block"],
    ),
    Case(
        "option r1 for wiener",
        ["fit", *G, "--structure", "wiener", "--r1", "3", "--json"],
        ["r1 not used by wiener", "--r1"],
    ),
    Case(
        "option nx for arx",
        ["fit", *G, "--structure", "arx", "--nx", "2", "--json"],
        ["nx not used by arx", "--nx"],
    ),
    Case(
        "option method for another structure",
        ["fit", *G, "--structure", "hammerstein", "--method", "rls", "--json"],
        ["rls", "simulation-error", "key-term-rls"],
    ),
    Case(
        "option forgetting zero",
        ["fit", *G, "--structure", "arx", "--method", "rls", "--forgetting", "0", "--json"],
        ["forgetting", "(0, 1]", "--forgetting"],
    ),
    Case(
        "option forgetting a word",
        ["fit", *G, "--structure", "arx", "--method", "rls", "--forgetting", "slow", "--json"],
        ["cannot read forgetting 'slow'", "--forgetting"],
    ),
    Case(
        "option forgetting schedule typo",
        [
            "fit",
            *G,
            "--structure",
            "arx",
            "--method",
            "rls",
            "--forgetting",
            "0.98:abc,1",
            "--json",
        ],  # fmt: skip
        ["cannot read forgetting '0.98:abc,1'", "--forgetting"],
    ),
    Case(
        "option forgetting schedule out of range",
        [
            "fit",
            *G,
            "--structure",
            "arx",
            "--method",
            "rls",
            "--forgetting",
            "0.9:100,1.2",
            "--json",
        ],  # fmt: skip
        ["1.2", "--forgetting"],
    ),
    Case(
        "option forgetting schedule negative duration",
        [
            "fit",
            *G,
            "--structure",
            "arx",
            "--method",
            "rls",
            "--forgetting",
            "0.9:-5,1",
            "--json",
        ],  # fmt: skip
        ["-5", "--forgetting"],
    ),
    Case(
        "option forgetting with batch",
        ["fit", *G, "--structure", "arx", "--forgetting", "0.9", "--json"],
        ["forgetting not used by arx with method batch", "--forgetting"],
    ),
    Case(
        "option initial-covariance zero",
        [
            "fit",
            *G,
            "--structure",
            "arx",
            "--method",
            "rls",
            "--initial-covariance",
            "0",
            "--json",
        ],  # fmt: skip
        ["initial_covariance must be > 0, got 0", "--initial-covariance"],
    ),
    Case(
        "option passes zero",
        ["fit", *G, "--structure", "arx", "--method", "rls", "--passes", "0", "--json"],
        ["passes must be a whole number >= 1, got 0", "--passes"],
    ),
    Case(
        "option tol negative",
        [
            "fit",
            *G,
            "--structure",
            "hammerstein",
            "--method",
            "key-term-rls",
            "--tol",
            "-1",
            "--json",
        ],  # fmt: skip
        ["tol must be > 0, got -1", "--tol"],
    ),
    Case(
        "option eps2 zero",  # the weight's floor (eps1 = 0 is a constant weight: valid)
        ["fit", *G, "--structure", "arx", "--method", "aw-rls", "--eps2", "0", "--json"],
        ["eps2 must be > 0, got 0", "--eps2"],
    ),
    Case(
        "option max-nfev zero",
        ["fit", *G, "--structure", "hammerstein", "--max-nfev", "0", "--json"],
        ["max_nfev must be a whole number >= 1, got 0", "--max-nfev"],
    ),
    Case(
        "option tail-fraction too large",
        ["fit", *G, "--structure", "hammerstein", "--tail-fraction", "0.95", "--json"],
        ["tail_fraction must be <= 0.9, got 0.95", "--tail-fraction"],
    ),
    Case(
        "option ftol not a number",
        ["fit", *G, "--structure", "hammerstein", "--ftol", "tiny", "--json"],
        ["ftol must be a number, got 'tiny'", "--ftol"],
    ),
    Case(
        "option weighting unknown",
        ["fit", *G, "--structure", "state-space", "--weighting", "pca", "--json"],
        ["weighting must be one of moesp, cva, got 'pca'", "--weighting"],
    ),
    Case(
        "option monomials unknown",
        ["fit", *G, "--structure", "polynomial-state-space", "--monomials", "all", "--json"],
        ["monomials must be one of full, states, inputs", "--monomials"],
    ),
    Case(
        "option margin negative",
        ["fit", *G, "--structure", "polynomial-state-space", "--margin", "-1", "--json"],
        ["margin must be >= 0, got -1", "--margin"],
    ),
    Case(
        "option initial-parameters words",
        [
            "fit",
            *G,
            "--structure",
            "hammerstein",
            "--method",
            "key-term-rls",
            "--initial-parameters",
            "a,b",
            "--json",
        ],  # fmt: skip
        ["initial_parameters must be a number or comma-separated numbers", "--initial-parameters"],
    ),
    Case(
        "option initial-parameters wrong count",
        [
            "fit",
            *G,
            "--structure",
            "hammerstein",
            "--method",
            "key-term-rls",
            "--initial-parameters",
            "1,2,3",
            "--json",
        ],
        ["initial_parameters must be a finite number or 13 finite values", "[1.0, 2.0, 3.0]"],
    ),
    Case("option unknown flag", [*ARX_FIT, "--fast"], ["no such option: --fast"]),
    Case("option value missing", ["fit", *G, "--json", "--na"], ["'--na' requires an argument"]),
    Case(
        "option flag given a value",
        [*ARX_FIT, "--center=maybe"],
        ["--center", "does not take a value"],
    ),
    Case(
        "option fit plot figures exist",
        [*ARX_FIT, "--plot", "figs"],
        ["figs/simulation.png", "pass --force"],
        _figures("figs", "simulation.png", "blocks.png"),
    ),
    Case(
        "option simulate plot figure exists",
        ["simulate", "model.json", "good.csv", "--plot", "figs", "--json"],
        ["figs/simulation.png", "pass --force"],
        _figures("figs", "simulation.png"),
    ),
    Case(
        "option predict plot figure exists",
        ["predict", "model.json", "good.csv", "--plot", "figs", "--json"],
        ["figs/prediction.png", "pass --force"],
        _figures("figs", "prediction.png"),
    ),
    Case(
        "option identify plot figures exist",
        ["identify", *G, "--plot", "figs", "--json"],
        ["figs/simulation.png", "pass --force"],
        _figures("figs", "simulation.png"),
    ),
    Case(
        "option fit plot is a file",
        [*ARX_FIT, "--plot", "good.csv"],
        ["good.csv is a file, not a folder", "--plot"],
    ),
    Case(
        "option simulate band too wide",
        ["simulate", "model.json", "good.csv", "--band", "1.5", "--json"],
        ["--band must be a confidence level between 0 and 1", "1.5"],
    ),
    Case(
        "option simulate band without covariance",
        ["simulate", "model.json", "good.csv", "--band", "0.95", "--json"],
        ["model.json holds no parameter covariance", "standard errors"],
    ),
    Case(
        "option predict band",
        ["predict", "model.json", "good.csv", "--band", "0.95", "--json"],
        ["--band applies to simulate only"],
    ),
    Case(
        "option simulate initial-samples negative",
        ["simulate", "model.json", "good.csv", "--initial-samples", "-1", "--json"],
        ["initial", "-1", "--initial-samples"],
    ),
    Case(
        "option predict output exists",
        ["predict", "model.json", "good.csv", "-o", "model.json"],
        ["model.json exists; pass --force"],
    ),
    Case(
        "option identify effort unknown",
        ["identify", *G, "--effort", "extreme", "--json"],
        ["effort='extreme' is unknown", "quick, standard, thorough", "--effort"],
    ),
    Case(
        "option identify jobs zero",
        ["identify", *G, "--jobs", "0", "--json"],
        ["jobs must be a whole number >= 1, got 0", "--jobs"],
    ),
    Case(
        "option identify time limit negative",
        ["identify", *G, "--time-limit", "-1", "--json"],
        ["time_limit must be a positive number of seconds, got -1", "--time-limit"],
    ),
    Case(
        "option identify structures unknown",
        ["identify", *G, "--structures", "nope", "--json"],
        ["structures ['nope'] are unknown", "--structures"],
    ),
    Case(
        "option identify budget",
        ["identify", *G, "--budget", "10", "--json"],
        ["--budget is gone", "--effort", "--time-limit"],
    ),
    Case(
        "option identify validation twice",
        ["identify", *G, "--validation", "200:300", "--validation-data", "good.csv", "--json"],
        ["give --validation or --validation-data, not both"],
    ),
    Case(
        "option identify output exists",
        ["identify", *G, "-o", "model.json"],
        ["model.json exists; pass --force"],
    ),
    Case(
        "option identify report exists",
        ["identify", *G, "--report", "network.json", "--json"],
        ["network.json exists; pass --force"],
    ),
    Case(
        "option compare structures unknown",
        [*COMPARE, "--structures", "arx,nope", "--json"],
        ["structures ['nope'] are unknown", "--structures"],
    ),
    Case(
        "option compare structures empty",
        [*COMPARE, "--structures", ",", "--json"],
        ["no structure to compare", "--structures"],
    ),
    Case(
        "option compare method none offers",
        [
            *COMPARE,
            "--structures",
            "arx,hammerstein",
            "--method",
            "subspace",
            "--json",
        ],  # fmt: skip
        ["method='subspace' is offered by none of arx, hammerstein", "--method"],
    ),
    Case(
        "option compare report exists",
        [*COMPARE, "--report", "model.json", "--json"],  # fmt: skip
        ["model.json exists; pass --force"],
    ),
    Case(
        "option report output exists",
        ["report", *G, "--estimation", "0:200", "--validation", "200:300", "-o", "good.csv"],
        ["good.csv exists; pass --force"],
    ),
    Case(
        "option example-data unknown",
        ["example-data", "nope", "-o", "out.csv"],
        ["'nope'", "electrohydraulic"],
    ),
    Case(
        "option example-data misspelt",
        ["example-data", "electrohydralic", "-o", "out.csv"],
        ["unknown example 'electrohydralic'", "electrohydraulic"],
    ),
    Case(
        "option example-data output exists",
        ["example-data", "electrohydraulic", "-o", "good.csv"],
        ["good.csv exists; pass --force"],
    ),
    Case(
        "option example-data output type",
        ["example-data", "electrohydraulic", "-o", "out.xlsx"],
        ["unknown table type '.xlsx'"],
    ),
    Case(
        "option fleet no file matches",
        ["fleet", "logs/*.csv", "-u", "u", "-y", "y", "-o", "out", "--json"],
        ["no file matches 'logs/*.csv'"],
    ),
    Case(
        "option fleet structure unknown",
        ["fleet", *G, "-o", "out", "--structure", "nope", "--json"],
        ["structure='nope' is unknown"],
    ),
    Case(
        "option fleet workers zero",
        ["fleet", *G, "-o", "out", "--workers", "0", "--json"],
        ["invalid value for '--workers'", "greater than or equal to 1"],
    ),
    Case(
        "option fleet option not used",
        ["fleet", *G, "-o", "out", "--structure", "arx", "--r1", "3", "--json"],
        ["r1 not used by arx", "--r1"],
    ),
    Case(
        "option orders threshold negative",
        ["orders", *G, "--threshold", "-5", "--json"],
        ["threshold", "-5", "--threshold"],
    ),
    Case(
        "option orders noise negative",
        ["orders", *G, "--noise", "-0.1", "--json"],
        ["noise", "-0.1", "--noise"],
    ),
    Case(
        "option orders noise a word",
        ["orders", *G, "--noise", "lots", "--json"],
        ["--noise must be a fraction", "'lots'"],
    ),
    Case(
        "option stream structure unknown",
        ["stream", "-u", "u", "-y", "y", "--structure", "nope"],
        ["structure='nope' is unknown", "arx"],
        input=GOOD_TEXT,
    ),
    Case(
        "option stream checkpoint without output",
        ["stream", "-u", "u", "-y", "y", "--checkpoint", "10"],
        ["--checkpoint N writes to -o FILE"],
        input=GOOD_TEXT,
    ),
    Case(
        "option stream format unknown",
        ["stream", "-u", "u", "-y", "y", "--format", "xml"],
        ["xml", "csv", "jsonl"],
        input=GOOD_TEXT,
    ),
    Case(
        "option stream output exists",
        ["stream", "-u", "u", "-y", "y", "-o", "model.json"],
        ["model.json exists; pass --force"],
        input=GOOD_TEXT,
    ),
    Case(
        "option stream method unknown",
        ["stream", "-u", "u", "-y", "y", "--method", "magic"],
        ["magic"],
        input=GOOD_TEXT,
    ),
    Case(
        "option stream method not recursive",
        ["stream", "-u", "u", "-y", "y", "--method", "batch"],
        ["batch", "rls"],
        input=GOOD_TEXT,
    ),
    Case(
        "option stream every negative",
        ["stream", "-u", "u", "-y", "y", "--every", "-1"],
        ["invalid value for '--every'", "greater than or equal to 0"],
        input=GOOD_TEXT,
    ),
    Case(
        "option stream one scale",
        ["stream", "-u", "u", "-y", "y", "--input-scale", "2"],
        ["give both input_scale and output_scale, or neither"],
        input=GOOD_TEXT,
    ),
    Case(
        "option stream scale zero",
        ["stream", "-u", "u", "-y", "y", "--input-scale", "0", "--output-scale", "1"],
        ["--input-scale must be a positive number", "got 0"],
        input=GOOD_TEXT,
    ),
    Case(
        "option stream forgetting out of range",
        ["stream", "-u", "u", "-y", "y", "--forgetting", "1.5"],
        ["forgetting", "--forgetting"],
        input=GOOD_TEXT,
    ),
    Case(
        "option stream na a word",
        ["stream", "-u", "u", "-y", "y", "--na", "many"],
        ["na='many'", "--na"],
        input=GOOD_TEXT,
    ),
    Case(
        "option reproduce bandwidth a word",
        ["reproduce", "electrohydraulic", "--validation-bandwidth", "fast", "--json"],
        ["--validation-bandwidth must be a frequency in Hz or 'none', got 'fast'"],
    ),
    Case(
        "option demo plot is a file",
        ["demo", "--plot", "good.csv", "--json"],
        ["good.csv is a file, not a folder"],
    ),
    # ------------------------------------------------------------------ export
    Case(
        "export to unknown",
        ["export", "model.json", "--to", "matlab"],
        ["--to must be one of python, scipy-json, got 'matlab'"],
    ),
    Case(
        "export output exists",
        ["export", "model.json", "-o", "good.csv"],
        ["good.csv exists; pass --force"],
    ),
    Case(
        "export output folder missing",
        ["export", "model.json", "-o", "nowhere/model.py"],
        ["folder nowhere does not exist"],
    ),
    Case(
        "export output is a folder",
        ["export", "model.json", "-o", "out", "--force"],
        ["out", "folder"],
        _folder_with_a_file("out"),
    ),
    Case("export model missing", ["export", "none.json"], ["model file none.json does not exist"]),
    Case(
        "export model not JSON",
        ["export", "bad.json", "--to", "scipy-json"],
        ["bad.json is not valid JSON"],
        _write("bad.json", "model: arx\n"),
    ),
    Case(
        "export model NaN parameter",
        ["export", "bad.json", "--to", "python"],
        ["non-finite parameter", "parameters.y.a.y[0] is nan"],
        _bad_model(_nan_parameter),
    ),
    Case(
        "export data file as model",
        ["export", "good.csv", "--json"],
        ["good.csv is not valid JSON"],
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
        [*NET_FIT, "-s", "S2: u1 -> v1 | arx na=1 nb=1 nk=1", "--json"],
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
    Case(
        "network structure unknown",
        ["fit-network", "net.csv", "-s", "S1: u1 -> v1 | magic na=1", "--json"],
        ["'magic'", "S1"],
    ),
    Case(
        "network option unknown key",
        ["fit-network", "net.csv", "-s", "S1: u1 -> v1 | arx na=1 nb=1 nk=1 speed=2", "--json"],
        ["speed", "S1"],
    ),
    Case(
        "network option not used",
        ["fit-network", "net.csv", "-s", "S1: u1 -> v1 | arx na=1 nb=1 nk=1 r1=3", "--json"],
        ["r1 not used by arx", "S1"],
    ),
    Case(
        "network no arrow",
        ["fit-network", "net.csv", "-s", "S1: u1, v1 | arx na=1 nb=1 nk=1", "--json"],
        ["cannot read subsystem", "->"],
    ),
    Case(
        "network name twice",
        [*NET_FIT, "-s", "S1: v1 -> v2 | arx na=1 nb=1 nk=1", "--json"],
        ["2 subsystems are named 'S1'", "its own name"],
    ),
    Case(
        "network name empty",
        ["fit-network", "net.csv", "-s", ": u1 -> v1 | arx na=1 nb=1 nk=1", "--json"],
        ["cannot read subsystem"],
    ),
    Case(
        "network output is its own input",
        ["fit-network", "net.csv", "-s", "S1: v1 -> v1 | arx na=1 nb=1 nk=1", "--json"],
        ["cycle: 'S1' -> v1 -> 'S1'"],
    ),
    Case(
        "network no outputs",
        ["fit-network", "net.csv", "-s", "S1: u1 -> | arx na=1 nb=1 nk=1", "--json"],
        ["subsystem 'S1' makes no signal"],
    ),
    Case(
        "network block typo",
        [
            "fit-network",
            "net.csv",
            "-s",
            "S1: u1 -> v1 | hammerstein input-block=polynomal",
            "--json",
        ],  # fmt: skip
        ["unknown block 'polynomal'", "S1"],
    ),
    Case(
        "network method unknown",
        ["fit-network", "net.csv", "-s", "S1: u1 -> v1 | arx method=magic", "--json"],
        ["magic", "S1"],
    ),
    Case(
        "network forgetting zero",
        ["fit-network", "net.csv", "-s", "S1: u1 -> v1 | arx method=rls forgetting=0", "--json"],
        ["forgetting", "S1"],
    ),
    Case("network subsystem missing", ["fit-network", "net.csv", "--json"], ["--subsystem"]),
    Case(
        "network output exists", [*NET_FIT, "-o", "model.json"], ["model.json exists; pass --force"]
    ),
    Case(
        "network order too large",
        ["fit-network", "net.csv", "-s", "S1: u1 -> v1 | arx na=500 nb=1 nk=1", "--json"],
        ["subsystem S1", "na=500", "has only 300"],
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


def test_at_least_150_cases_over_every_kind_and_command():
    assert len(CASES) >= 150
    assert len({c.id for c in CASES}) == len(CASES), "case ids must be unique"
    kinds = {c.id.split()[0] for c in CASES}
    assert {
        "file", "column", "value", "ts", "range", "order", "model", "option", "export", "network"
    } <= kinds  # fmt: skip
    commands = {c.args[0] for c in CASES}
    assert {
        "fit", "compare", "identify", "simulate", "predict", "export", "orders", "stream",
        "report", "fit-network", "example-data", "fleet",
    } <= commands  # fmt: skip


@pytest.mark.parametrize("case", [pytest.param(c, id=c.id, marks=c.marks) for c in CASES])
def test_malformed_input(case, folder):
    if case.make is not None:
        case.make(folder)
    before = _snapshot(folder)
    r = runner.invoke(app, case.args, input=case.input)
    err = r.stderr
    assert r.exit_code == 2, f"exit {r.exit_code}; stderr: {err}; exception: {r.exception!r}"
    assert "Traceback" not in err and "Traceback" not in r.stdout
    assert isinstance(r.exception, SystemExit)
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert "\ufffd" not in err, "the message shows a replacement character"
    for words in case.expect:
        assert words.lower() in err.lower(), f"{words!r} not in {err!r}"
    after = _snapshot(folder)
    assert {k: after.get(k) for k in before} == before, "an existing file was changed"
