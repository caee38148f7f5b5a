"""Bad input to ``report`` (:mod:`blockid.cli.report`): a table of
:class:`~cli.bad_input.Case`, each refused in one readable line with exit status 2, no
file written or changed (:func:`cli.bad_input.refused`). Edge cases of the report's BLA
section that it accepts are in a second table (:func:`cli.bad_input.accepted`)."""

from __future__ import annotations

import numpy as np
import pytest

from cli.bad_input import Accepted, Case, G, accepted, params, refused, table

REPORT_ARGS = ["report", "bad.csv", "-u", "u", "-y", "y", "--estimation", "0:40", "--validation",
               "40:60", "--structures", "arx", "--na", "1", "--nb", "1", "--nk", "1", "-o", "r.html"]  # fmt: skip


REPORT = [
    # ------------------------------------------------------------------ columns
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
    # ------------------------------------------------------------------ ranges
    Case(
        "range report overlap",
        ["report", *G, "--estimation", "0:200", "--validation", "100:300"],
        ["overlap"],
    ),
    # ------------------------------------------------------------------ options
    Case(
        "option report output exists",
        ["report", *G, "--estimation", "0:200", "--validation", "200:300", "-o", "good.csv"],
        ["good.csv exists; pass --force"],
    ),
]

REPORT_ACCEPTED = [
    Accepted(
        "report square wave input",
        REPORT_ARGS,
        ["Best linear approximation"],
        table("bad.csv", lambda k: 1.0 if k % 2 else -1.0, np.cos, n=60),
    ),  # fmt: skip
    Accepted(
        "report period of four samples",
        REPORT_ARGS,
        ["Best linear approximation"],
        table("bad.csv", lambda k: [1, -1, 2, 0.5][k % 4], np.cos, n=60),
    ),  # fmt: skip
]


@pytest.mark.parametrize("case", params(REPORT))
def test_refused(case, workdir):
    refused(case, workdir)


@pytest.mark.parametrize("case", params(REPORT_ACCEPTED))
def test_accepted(case, workdir):
    accepted(case, workdir)
