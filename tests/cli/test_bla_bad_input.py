"""Bad input to ``bla`` (:mod:`blockid.cli.bla`): a table of :class:`~cli.bad_input.Case`,
each refused in one readable line with exit status 2, no file written or changed
(:func:`cli.bad_input.refused`). Edge cases it accepts are in a second table
(:func:`cli.bad_input.accepted`)."""

from __future__ import annotations

import numpy as np
import pytest

from cli.bad_input import PER, Accepted, Case, accepted, files, params, refused, table, write

GOOD = ["good.csv", "-u", "u", "-y", "y"]


BLA = [
    # ------------------------------------------------------------------ data
    Case(
        "bla empty file",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["bad.csv is empty"],
        write("bad.csv", ""),
    ),  # fmt: skip
    Case(
        "bla header only",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["no data rows"],
        write("bad.csv", "t,u,y\n"),
    ),  # fmt: skip
    Case(
        "bla constant input",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["input", "constant"],
        table("bad.csv", lambda k: 1.0, np.sin),
    ),  # fmt: skip
    Case(
        "bla zero input and output",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["constant"],
        table("bad.csv", lambda k: 0.0, lambda k: 0.0),
    ),  # fmt: skip
    Case(
        "bla nan cell",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["column 'u'", "line 7"],
        table("bad.csv", lambda k: np.nan if k == 5 else np.sin(k), np.cos),
    ),  # fmt: skip
    Case(
        "bla inf cell",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["column 'u'", "infinite"],
        table("bad.csv", lambda k: np.inf if k == 5 else np.sin(k), np.cos),
    ),  # fmt: skip
    Case(
        "bla text column",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["'x0' is not a number"],
        write("bad.csv", "t,u,y\n" + "".join(f"{k},x{k},{k}\n" for k in range(50))),
    ),  # fmt: skip
    Case("bla column missing", ["bla", "per.csv", "-u", "U", "-y", "y"], ["no column 'U'"]),
    Case("bla two inputs", ["bla", *PER, "-u", "t"], ["one input to one output"]),
    Case(
        "bla experiment column is the input",
        ["bla", "per.csv", "-u", "u", "-y", "y", "--experiment-column", "u"],
        ["experiment_column 'u'"],
    ),  # fmt: skip
    Case("bla range past the end", ["bla", *PER, "--range", "500:"], ["--range 500:"]),
    Case("bla ts zero", ["bla", *PER, "--ts", "0"], ["--ts"]),
    # ------------------------------------------------------------------ periods
    Case("bla period zero", ["bla", *GOOD, "--period", "0"], ["period", "--period"]),
    Case("bla period negative", ["bla", *GOOD, "--period", "-5"], ["period", "--period"]),
    Case(
        "bla period of two samples",
        ["bla", *GOOD, "--period", "2"],
        ["period of 2 samples", "--period"],
    ),  # fmt: skip
    Case(
        "bla one sample a period",
        ["bla", *GOOD, "--periods", "300"],
        ["period of 1 samples", "--periods"],
    ),  # fmt: skip
    Case(
        "bla period longer than the record",
        ["bla", *GOOD, "--period", "301"],
        ["300 samples", "--period"],
    ),  # fmt: skip
    Case("bla period huge", ["bla", *GOOD, "--period", "99999999999999999"], ["--period"]),
    Case("bla periods zero", ["bla", *GOOD, "--periods", "0"], ["--periods"]),
    Case(
        "bla periods do not divide",
        ["bla", *GOOD, "--periods", "7"],
        ["not a whole number of 7 periods", "--period"],
    ),  # fmt: skip
    Case(
        "bla period and periods disagree",
        ["bla", *GOOD, "--period", "100", "--periods", "2"],
        ["make 200 samples", "--periods"],
    ),  # fmt: skip
    Case("bla one period one realisation", ["bla", *GOOD, "--period", "300"], ["no variance"]),
    Case(
        "bla every period transient",
        ["bla", *PER, "--transient-periods", "3"],
        ["drop every period", "--transient-periods"],
    ),  # fmt: skip
    Case(
        "bla transient periods negative",
        ["bla", *PER, "--transient-periods", "-1"],
        ["--transient-periods"],
    ),  # fmt: skip
    Case(
        "bla found period does not divide",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["repeats every 6 samples", "welch", "--method"],
        table("bad.csv", np.sin, lambda k: 3.0, n=200),
    ),  # fmt: skip
    Case(
        "bla no period for robust",
        ["bla", *GOOD, "--method", "robust"],
        ["no period found", "--period"],
    ),  # fmt: skip
    Case(
        "bla welch with a period",
        ["bla", *PER, "--method", "welch", "--period", "64"],
        ["--period", "robust"],
    ),  # fmt: skip
    Case("bla method unknown", ["bla", *GOOD, "--method", "Welch"], ["--method 'Welch'"]),
    # ------------------------------------------------------------------ options
    Case("bla bands zero", ["bla", *PER, "--bands", "0"], ["bands must be >= 1", "--bands"]),
    Case("bla bands text", ["bla", *PER, "--bands", "abc"], ["LOW:HIGH", "--bands"]),
    Case("bla bands reversed", ["bla", *PER, "--bands", "5:3"], ["0 <= LOW < HIGH"]),
    Case("bla bands above nyquist", ["bla", *PER, "--bands", "60:80"], ["holds no line"]),
    Case("bla bands nan", ["bla", *PER, "--bands", "nan:5"], ["--bands"]),
    Case(
        "bla bands overlap", ["bla", *PER, "--bands", "1:30,20:40"], ["overlap", "--bands"]
    ),  # fmt: skip
    Case("bla bands semicolons", ["bla", *PER, "--bands", "10:20;30:40"], ["--bands"]),
    Case("bla confidence zero", ["bla", *PER, "--confidence", "0"], ["--confidence"]),
    Case("bla confidence one", ["bla", *PER, "--confidence", "1"], ["--confidence"]),
    Case("bla confidence two", ["bla", *PER, "--confidence", "2"], ["--confidence"]),
    Case("bla confidence nan", ["bla", *PER, "--confidence", "nan"], ["--confidence"]),
    Case("bla segment too small", ["bla", *GOOD, "--segment", "4"], [">= 8", "--segment"]),
    Case(
        "bla segment longer than the record",
        ["bla", *GOOD, "--segment", "301"],
        ["at most 300", "--segment"],
    ),  # fmt: skip
    Case("bla segment the whole record", ["bla", *GOOD, "--segment", "300"], ["--segment"]),
    Case(
        "bla one row",
        ["bla", "bad.csv", "-u", "u", "-y", "y"],
        ["more data"],
        write("bad.csv", "t,u,y\n0,1,2\n"),
    ),  # fmt: skip
    Case("bla fit one number", ["bla", *PER, "--fit", "2"], ["NA,NB", "--fit"]),
    Case("bla fit negative", ["bla", *PER, "--fit", "-1,2"], ["--fit"]),
    Case("bla fit no numerator", ["bla", *PER, "--fit", "0,0"], ["NB must be 1"]),
    Case(
        "bla fit orders above the lines",
        ["bla", *PER, "--fit", "50,50"],
        ["too few for 50 + 50", "--fit"],
    ),  # fmt: skip
    Case("bla fit huge order", ["bla", *PER, "--fit", "99999999999,1"], ["--fit"]),
    # ------------------------------------------------------------------ outputs
    Case(
        "bla output exists",
        ["bla", *PER, "-o", "old.json"],
        ["old.json exists", "--force"],
        files("old.json"),
    ),  # fmt: skip
    Case(
        "bla output folder missing",
        ["bla", *PER, "-o", "missing/out.json"],
        ["folder missing does not exist"],
    ),  # fmt: skip
    Case(
        "bla output under a file",
        ["bla", *PER, "-o", "afile/out.json"],
        ["afile is a file"],
        files("afile"),
    ),  # fmt: skip
    Case("bla output named csv", ["bla", *PER, "-o", "out.csv"], ["JSON", "out.json"]),
    Case("bla output over the data", ["bla", *PER, "-o", "per.csv", "--force"], ["JSON"]),
    Case(
        "bla figure exists",
        ["bla", *PER, "--plot", "figs"],
        ["figs/bla.png", "--force"],
        files("figs/bla.png"),
    ),  # fmt: skip
    Case(
        "bla figure folder is a file",
        ["bla", *PER, "--plot", "afile"],
        ["afile is a file"],
        files("afile"),
    ),  # fmt: skip
]

BLA_ACCEPTED = [
    Accepted("bla bands partly above nyquist", ["bla", *PER, "--bands", "1:100"], ["1 - 100"]),
    Accepted("bla bands sharing an edge", ["bla", *PER, "--bands", "1:20,20:48"], ["20 - 48"]),
    Accepted("bla more bands than lines", ["bla", *PER, "--bands", "1000"], ["lines"]),
    Accepted("bla confidence tiny", ["bla", *PER, "--confidence", "1e-300"], ["distortion"]),
    Accepted("bla fit delay beyond the period", ["bla", *PER, "--fit", "1,1,100"], ["z^-100"]),
    Accepted("bla fit no poles", ["bla", *PER, "--fit", "0,1"], ["b_0"]),
    Accepted(
        "bla output replaced with force",
        ["bla", *PER, "-o", "old.json", "--force"],
        ["results written to old.json"],
        files("old.json"),
    ),  # fmt: skip
    Accepted("bla figure in new folders", ["bla", *PER, "--plot", "a/b"], ["a/b/bla.png"]),
]


@pytest.mark.parametrize("case", params(BLA))
def test_refused(case, workdir):
    refused(case, workdir)


@pytest.mark.parametrize("case", params(BLA_ACCEPTED))
def test_accepted(case, workdir):
    accepted(case, workdir)
