"""Bad input to ``fit``, ``compare`` and ``fit-network`` (:mod:`blockid.cli.fit`): one
table of :class:`~cli.bad_input.Case` per command, each refused in one readable line
with exit status 2, no file written or changed (:func:`cli.bad_input.refused`)."""

from __future__ import annotations

import gzip
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from cli.bad_input import (
    DT,
    B,
    Case,
    G,
    N,
    bad_csv,
    figures,
    first_rows,
    folder_with_a_file,
    good_rows,
    params,
    refused,
    with_cell,
    write,
    write_csv,
)

ARX_ORDERS = ["--structure", "arx", "--na", "2", "--nb", "2", "--nk", "1"]
ARX_FIT = ["fit", *G, *ARX_ORDERS, "--json"]
ARX_BAD = ["fit", *B, *ARX_ORDERS, "--json"]
COMPARE = ["compare", *G, "--estimation", "0:200", "--validation", "200:300"]
NET_FIT = ["fit-network", "net.csv", "-s", "S1: u1 -> v1 | arx na=1 nb=1 nk=1"]


def _with_column(column: int, values: Callable[[int], str]) -> Callable[[Path], None]:
    """A copy of good.csv as bad.csv with every cell of one column replaced."""

    def make(d: Path) -> None:
        rows = [r.split(",") for r in good_rows()]
        for k, row in enumerate(rows):
            row[column] = values(k)
        write_csv(d / "bad.csv", "t,u,y", [",".join(r) for r in rows])

    return make


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


FIT = [
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
        lambda d: write_csv(d / "bad.csv", "t,u,y", ["0,1,2", "0.05,1,2,7", "0.1,1,2"]),
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
        folder_with_a_file("records"),
    ),
    Case(
        "file only a byte-order mark",
        ["fit", *B, "--json"],
        ["bad.csv is empty"],
        write("bad.csv", b"\xef\xbb\xbf"),
    ),
    Case(
        "file only whitespace",
        ["fit", *B, "--json"],
        ["bad.csv is empty"],
        write("bad.csv", "  \n\t\n   \n"),
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
        write("bad.csv", bytes(range(256)) * 64),
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
        write("bad.csv", "<!DOCTYPE html>\n<html><body>Not found</body></html>\n"),
    ),
    Case(
        "file unclosed quote",
        ["fit", *B, "--json"],
        ["bad.csv could not be parsed"],
        bad_csv("t,u,y", ["0,1,2", '0.05,"1.5,2', "0.1,1,2"]),
    ),
    Case(
        "file very wide rows",
        ["fit", *B, "--json"],
        ["line 2 has 500 fields but the header names only 3 columns"],
        bad_csv("t,u,y", [",".join(["1"] * 500)] * 20),
    ),
    Case(
        "file semicolon header comma rows",
        ["fit", *B, "--json"],
        ["line 2 has 3 fields but the header names only 1 columns"],
        bad_csv("t;u;y", [f"{k * DT:.2f},1,2" for k in range(20)]),
    ),
    Case(
        "file tab and comma mixed",
        ["fit", *B, "--json"],
        ["bad.csv"],
        bad_csv("t\tu\ty", [f"{k * DT:.2f}\t1,5\t2" for k in range(20)]),
    ),
    Case(
        "file no suffix",
        ["fit", "data", "-u", "u", "-y", "y", "--json"],
        ["unknown data file type '(no suffix)'"],
        write("data", "t,u,y\n0,1,2\n"),
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
        bad_csv("t,u,z", good_rows()),
    ),
    Case(
        "file second file other sampling time",
        ["fit", "good.csv", *B, *ARX_ORDERS, "--json", "--time-column", "t"],
        ["sampling time", "bad.csv"],
        _with_column(0, lambda k: f"{k * 0.1:.2f}"),
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
        lambda d: write_csv(d / "bad.csv", "t,u,u,y", ["0,1,2,3", "0.05,1,2,3", "0.1,1,2,3"]),
    ),
    Case(
        "column grouped header",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        [
            "grouped header",
            "'u' (column 3) is followed by 2 columns without a name",
            "columns 4 to 5",
        ],
        lambda d: write_csv(
            d / "bad.csv",
            '"r",,"u",,,"y",,,',
            [",".join(str(k + j) for j in range(8)) + "," for k in range(20)],
        ),
    ),
    Case(
        "column no header",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        ["add a line of column names"],
        lambda d: write_csv(d / "bad.csv", "0,1,2", ["0.05,1,2", "0.1,1,2"]),
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
        lambda d: write_csv(d / "bad.csv", "T,U,Y", good_rows()),
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
        lambda d: write_csv(d / "bad.csv", "t,,y", good_rows()),
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
        lambda d: write_csv(
            d / "bad.csv", "t,u,y,run", [f"{r},{'ab'[k % 2]}" for k, r in enumerate(good_rows())]
        ),
    ),
    Case(
        "column latin-1 header",
        ["fit", *B, "--json"],
        ["no column 'u'", "'Strom_\u00b5A'", "'Spannung_\u00e4'"],
        bad_csv("t,Strom_\u00b5A,Spannung_\u00e4", good_rows(), "latin-1"),
    ),
    Case(
        "column windows-1252 header",
        ["fit", "bad.csv", "-u", "Druck", "-y", "y", "--json"],
        ["no column 'Druck'", "did you mean 'Druck_\u20ac'"],
        bad_csv("t,Druck_\u20ac,y", good_rows(), "cp1252"),
    ),
    Case("column input not given", ["fit", "good.csv", "-y", "y", "--json"], ["--input"]),
    # ------------------------------------------------------------------ values
    Case(
        "value not a number",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        ["column 'u', data row 5 (line 6): 'abc' is not a number"],
        with_cell(4, 1, "abc"),
    ),
    Case(
        "value empty",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        ["column 'y', data row 8 (line 9) is empty"],
        with_cell(7, 2, ""),
    ),
    Case(
        "value NaN",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        ["column 'u', data row 3", "missing value"],
        with_cell(2, 1, "NaN"),
    ),
    Case(
        "value infinite",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        ["column 'y', data row 2", "is infinite"],
        with_cell(1, 2, "inf"),
    ),
    Case(
        "value decimal comma",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--json"],
        ["decimal comma"],
        lambda d: write_csv(d / "bad.csv", "t;u;y", ["0;1,5;2", "0.05;1;2"]),
    ),
    Case(
        "time not increasing",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--time-column", "t", "--json"],
        ["time column 't' does not increase"],
        with_cell(10, 0, "0.01"),
    ),
    Case(
        "time not uniform",
        ["fit", "bad.csv", "-u", "u", "-y", "y", "--time-column", "t", "--json"],
        ["not uniformly sampled"],
        with_cell(10, 0, "0.52"),
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
        lambda d: write_csv(
            d / "bad.csv",
            "t,u,y",
            [f"{k * DT:.2f},0.5,{float(np.sin(0.3 * k))!r}" for k in range(N)],
        ),
    ),
    Case(
        "value huge hammerstein",
        ["fit", *B, "--structure", "hammerstein", "--json"],
        ["column 'u', data row 5 (line 6)", "too large", "rescale"],
        with_cell(4, 1, "1e300"),
    ),
    Case(
        "value huge arx",
        ARX_BAD,
        ["column 'y', data row 8 (line 9)", "too large"],
        with_cell(7, 2, "1e300"),
    ),
    Case(
        "value huge negative wiener",
        ["fit", *B, "--structure", "wiener", "--json"],
        ["column 'y', data row 3", "too large"],
        with_cell(2, 2, "-1e300"),
    ),
    Case(
        "value word",
        ["fit", *B, "--json"],
        ["column 'y', data row 21 (line 22): 'high' is not a number"],
        with_cell(20, 2, "high"),
    ),
    Case(
        "value boolean among numbers",
        ["fit", *B, "--json"],
        ["column 'u', data row 7 (line 8): 'True' is not a number"],
        with_cell(6, 1, "True"),
    ),
    Case(
        "value thousands separator",
        ["fit", *B, "--json"],
        ["column 'u', data row 2 (line 3): '1,234.5' is not a number"],
        with_cell(1, 1, '"1,234.5"'),
    ),
    Case(
        "value unit suffix",
        ["fit", *B, "--json"],
        ["'1.5V' is not a number"],
        with_cell(11, 1, "1.5V"),
    ),
    Case(
        "value hexadecimal",
        ["fit", *B, "--json"],
        ["'0x1F' is not a number"],
        with_cell(12, 2, "0x1F"),
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
        with_cell(14, 1, "NA"),
    ),
    Case(
        "value minus infinity",
        ["fit", *B, "--json"],
        ["column 'u', data row 16", "is infinite"],
        with_cell(15, 1, "-inf"),
    ),
    Case("value one row only", ARX_BAD, ["needs more than 2 samples", "has only 1"], first_rows(1)),
    Case(
        "value two rows only", ARX_BAD, ["needs more than 2 samples", "has only 2"], first_rows(2)
    ),
    Case(
        "value one row hammerstein",
        ["fit", *B, "--structure", "hammerstein", "--na", "2", "--nb", "2", "--nk", "1", "--json"],
        ["hammerstein", "has only 1"],
        first_rows(1),
    ),
    Case("ts zero", [*ARX_FIT, "--ts", "0"], ["positive number of seconds", "--ts"]),
    Case("ts nan", [*ARX_FIT, "--ts", "nan"], ["positive number of seconds", "--ts"]),
    Case("ts infinite", [*ARX_FIT, "--ts", "inf"], ["--ts", "inf"]),
    Case("ts a word", [*ARX_FIT, "--ts", "fast"], ["invalid value for '--ts'", "valid number"]),
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
    # ------------------------------------------------------------------ options
    Case("option nothing to do", ["fit", *G], ["nothing to do"]),
    Case(
        "option output exists",
        ["fit", *G, "--structure", "arx", "-o", "model.json"],
        ["model.json exists; pass --force"],
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
        figures("figs", "simulation.png", "blocks.png"),
    ),
    Case(
        "option fit plot is a file",
        [*ARX_FIT, "--plot", "good.csv"],
        ["good.csv is a file, not a folder", "--plot"],
    ),
]

COMPARE = [
    # ------------------------------------------------------------------ columns
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
    # ------------------------------------------------------------------ ranges
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
    # ------------------------------------------------------------------ options
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
]

FIT_NETWORK = [
    # ------------------------------------------------------------------ columns
    Case(
        "column network signal case",
        ["fit-network", "net.csv", "-s", "S1: u1 -> V1 | arx na=1 nb=1 nk=1", "--json"],
        ["no column 'V1'", "did you mean 'v1'"],
    ),
    # ------------------------------------------------------------------ values
    Case(
        "ts nan fit-network",
        [*NET_FIT, "--ts", "nan", "--json"],  # fmt: skip
        ["positive number of seconds"],
    ),
    # ------------------------------------------------------------------ ranges
    Case(
        "range fit-network reversed",
        [*NET_FIT, "--estimation", "50:10", "--json"],
        ["--estimation", "'50:10' is empty"],
    ),
    # ------------------------------------------------------------------ orders
    Case(
        "order network na a word",
        ["fit-network", "net.csv", "-s", "S1: u1 -> v1 | arx na=x nb=1 nk=1", "--json"],
        ["na='x'", "whole number"],
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


@pytest.mark.parametrize("case", params(FIT, COMPARE, FIT_NETWORK))
def test_refused(case, workdir):
    refused(case, workdir)
