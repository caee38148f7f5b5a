"""Bad input to ``stream`` (:mod:`blockid.cli.streaming`): a table of
:class:`~cli.bad_input.Case`, each refused in one readable line with exit status 2, no
file written or changed (:func:`cli.bad_input.refused`). ``stream`` reads its samples
from the case's ``input``."""

from __future__ import annotations

import pytest

from cli.bad_input import Case, good_rows, params, refused, write

GOOD_TEXT = "t,u,y\n" + "\n".join(good_rows()) + "\n"


STREAM = [
    # ------------------------------------------------------------------ columns
    Case(
        "column stream header lacks the input",
        ["stream", "-u", "u", "-y", "y"],
        ["header line has columns t, x, y", "u missing"],
        input="t,x,y\n0,1,2\n0.05,1,2\n",
    ),
    # ------------------------------------------------------------------ model files
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
        write("bad.json", '{"format": "blockid-model", '),
        input=GOOD_TEXT,
    ),
    Case(
        "model stream start other signals",
        ["stream", "-u", "u", "-y", "y", "--model", "network.json"],
        ["initial must be a ARX model", "Network"],
        input=GOOD_TEXT,
    ),
    # ------------------------------------------------------------------ options
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
]


@pytest.mark.parametrize("case", params(STREAM))
def test_refused(case, workdir):
    refused(case, workdir)
