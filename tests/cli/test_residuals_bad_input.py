"""Bad input to ``residuals`` (:mod:`blockid.cli.residuals`): a table of
:class:`~cli.bad_input.Case`, each refused in one readable line with exit status 2, no
file written or changed (:func:`cli.bad_input.refused`). Edge cases it accepts are in a
second table (:func:`cli.bad_input.accepted`)."""

from __future__ import annotations

import numpy as np
import pytest

from cli.bad_input import Accepted, Case, accepted, files, params, refused, rows, table, write

ONE_STEP_TS = ["residuals", "model_ts.json", "bad.csv", "--ts", "0.1"]


RESIDUALS = [
    Case(
        "residuals other columns",
        ["residuals", "model.json", "bad.csv"],
        ["no column 'u'"],
        write("bad.csv", "t,a,b\n0,1,2\n0.05,1,2\n"),
    ),  # fmt: skip
    Case(
        "residuals one row",
        ["residuals", "model.json", "bad.csv"],
        ["only 1"],
        write("bad.csv", "t,u,y\n0,1,2\n"),
    ),  # fmt: skip
    Case(
        "residuals too short for the lags",
        ["residuals", "model.json", "good.csv", "--range", "0:30"],
        ["too few", "--lags"],
    ),  # fmt: skip
    Case(
        "residuals lags zero", ["residuals", "model.json", "good.csv", "--lags", "0"], ["--lags"]
    ),  # fmt: skip
    Case(
        "residuals lags above the record",
        ["residuals", "model.json", "good.csv", "--lags", "100000"],
        ["--lags"],
    ),  # fmt: skip
    Case(
        "residuals constant input",
        ["residuals", "model.json", "bad.csv"],
        ["constant"],
        table("bad.csv", lambda k: 1.0, np.sin),
    ),  # fmt: skip
    Case(
        "residuals confidence one",
        ["residuals", "model.json", "good.csv", "--confidence", "1"],
        ["--confidence"],
    ),  # fmt: skip
    Case(
        "residuals mode unknown",
        ["residuals", "model.json", "good.csv", "--mode", "free"],
        ["--mode 'free'"],
    ),  # fmt: skip
    Case(
        "residuals other sampling time",
        ONE_STEP_TS,
        ["0.05", "--ts"],
        write("bad.csv", "u,y\n" + "".join(f"{np.sin(k)!r},{np.cos(k)!r}\n" for k in range(100))),
    ),  # fmt: skip
    Case(
        "residuals time column of another step",
        ["residuals", "model_ts.json", "bad.csv", "--time-column", "t"],
        ["0.05", "0.1"],
        lambda d: (d / "bad.csv").write_text(
            "t,u,y\n" + rows(np.sin(np.arange(100.0)), np.cos(np.arange(100.0)), dt=0.1)
        ),
    ),  # fmt: skip
    Case("residuals model is a table", ["residuals", "good.csv", "good.csv"], ["not valid JSON"]),
    Case("residuals model missing", ["residuals", "nope.json", "good.csv"], ["does not exist"]),
    Case(
        "residuals figure exists",
        ["residuals", "model.json", "good.csv", "--plot", "figs"],
        ["figs/residuals.png"],
        files("figs/residuals.png"),
    ),  # fmt: skip
]

RESIDUALS_ACCEPTED = [
    Accepted(
        "residuals constant output",
        ["residuals", "model.json", "bad.csv"],
        ["verdict"],
        table("bad.csv", np.sin, lambda k: 2.0),
    ),  # fmt: skip
]


@pytest.mark.parametrize("case", params(RESIDUALS))
def test_refused(case, workdir):
    refused(case, workdir)


@pytest.mark.parametrize("case", params(RESIDUALS_ACCEPTED))
def test_accepted(case, workdir):
    accepted(case, workdir)
