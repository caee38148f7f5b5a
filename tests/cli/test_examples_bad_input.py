"""Bad input to ``demo``, ``reproduce`` and ``example-data`` (:mod:`blockid.cli.examples`):
one table of :class:`~cli.bad_input.Case` per command, each refused in one readable line
with exit status 2, no file written or changed (:func:`cli.bad_input.refused`)."""

from __future__ import annotations

import pytest

from cli.bad_input import Case, folder_with_a_file, params, refused

DEMO = [
    # ------------------------------------------------------------------ options
    Case(
        "option demo folder not empty",
        ["demo", "--plot", "out", "--json"],
        ["out exists and is not empty", "--force"],
        folder_with_a_file("out"),
    ),
    Case(
        "option demo old flag not empty",
        ["demo", "--output-dir", "out", "--json"],
        ["not empty"],
        folder_with_a_file("out"),
    ),
    Case(
        "option demo plot is a file",
        ["demo", "--plot", "good.csv", "--json"],
        ["good.csv is a file, not a folder"],
    ),
]

REPRODUCE = [
    # ------------------------------------------------------------------ options
    Case(
        "option reproduce folder not empty",
        ["reproduce", "windtunnel", "--plot", "out", "--json"],
        ["not empty"],
        folder_with_a_file("out"),
    ),
    Case(
        "option reproduce old flag not empty",
        ["reproduce", "electrohydraulic", "--figures", "out", "--json"],
        ["not empty"],
        folder_with_a_file("out"),
    ),
    Case(
        "option reproduce bandwidth a word",
        ["reproduce", "electrohydraulic", "--validation-bandwidth", "fast", "--json"],
        ["--validation-bandwidth must be a frequency in Hz or 'none', got 'fast'"],
    ),
]

EXAMPLE_DATA = [
    # ------------------------------------------------------------------ options
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
]


@pytest.mark.parametrize("case", params(DEMO, REPRODUCE, EXAMPLE_DATA))
def test_refused(case, workdir):
    refused(case, workdir)
