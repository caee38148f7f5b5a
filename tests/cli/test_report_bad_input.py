"""Bad input to ``report`` (:mod:`blockid.cli.report`): a table of
:class:`~cli.bad_input.Case`, each refused in one readable line with exit status 2 and
no file touched (:func:`cli.bad_input.refused`)."""

from __future__ import annotations

import pytest

from cli.bad_input import Case, G, params, refused

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


@pytest.mark.parametrize("case", params(REPORT))
def test_refused(case, workdir):
    refused(case, workdir)
