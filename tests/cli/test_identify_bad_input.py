"""Bad input to ``identify`` (:mod:`blockid.cli.identify`): a table of
:class:`~cli.bad_input.Case`, each refused in one readable line with exit status 2, no
file written or changed (:func:`cli.bad_input.refused`)."""

from __future__ import annotations

import pytest

from cli.bad_input import Case, G, figures, params, refused

IDENTIFY = [
    # ------------------------------------------------------------------ files
    Case(
        "file validation data missing",
        ["identify", *G, "--validation-data", "val.csv", "--json"],
        ["val.csv does not exist"],
    ),
    # ------------------------------------------------------------------ columns
    Case(
        "column identify input missing",
        ["identify", "good.csv", "-u", "input", "-y", "y", "--json"],
        ["no column 'input'"],
    ),
    # ------------------------------------------------------------------ ranges
    Case(
        "range overlap identify",
        ["identify", *G, "--estimation", "0:200", "--validation", "150:300", "--json"],
        ["--estimation 0:200 and --validation 150:300 overlap"],
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
    # ------------------------------------------------------------------ options
    Case(
        "option identify plot figures exist",
        ["identify", *G, "--plot", "figs", "--json"],
        ["figs/simulation.png", "pass --force"],
        figures("figs", "simulation.png"),
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
]


@pytest.mark.parametrize("case", params(IDENTIFY))
def test_refused(case, workdir):
    refused(case, workdir)
