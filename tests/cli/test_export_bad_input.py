"""Bad input to ``export`` (:mod:`blockid.cli.export`): a table of
:class:`~cli.bad_input.Case`, each refused in one readable line with exit status 2, no
file written or changed (:func:`cli.bad_input.refused`)."""

from __future__ import annotations

import pytest

from cli.bad_input import (
    Case,
    bad_model,
    folder_with_a_file,
    nan_parameter,
    parameter,
    params,
    refused,
    write,
)

EXPORT = [
    # ------------------------------------------------------------------ model files
    Case(
        "model parameter nested list",
        ["export", "bad.json"],
        ["parameters.y.a.y must be a list of numbers", "[[-1.2, 0.35]]"],
        bad_model(lambda doc: parameter(doc, "a", [[-1.2, 0.35]])),
    ),
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
        folder_with_a_file("out"),
    ),
    Case("export model missing", ["export", "none.json"], ["model file none.json does not exist"]),
    Case(
        "export model not JSON",
        ["export", "bad.json", "--to", "scipy-json"],
        ["bad.json is not valid JSON"],
        write("bad.json", "model: arx\n"),
    ),
    Case(
        "export model NaN parameter",
        ["export", "bad.json", "--to", "python"],
        ["non-finite parameter", "parameters.y.a.y[0] is nan"],
        bad_model(nan_parameter),
    ),
    Case(
        "export data file as model",
        ["export", "good.csv", "--json"],
        ["good.csv is not valid JSON"],
    ),
]


@pytest.mark.parametrize("case", params(EXPORT))
def test_refused(case, workdir):
    refused(case, workdir)
