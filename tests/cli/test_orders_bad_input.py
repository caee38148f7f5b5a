"""Bad input to ``orders`` (:mod:`blockid.cli.orders`): a table of
:class:`~cli.bad_input.Case`, each refused in one readable line with exit status 2, no
file written or changed (:func:`cli.bad_input.refused`)."""

from __future__ import annotations

import pytest

from cli.bad_input import B, Case, G, first_rows, folder_with_a_file, params, refused, with_cell

ORDERS = [
    # ------------------------------------------------------------------ files
    Case(
        "file folder as data orders",
        ["orders", "records", "-u", "u", "-y", "y", "--json"],
        ["records is a folder"],
        folder_with_a_file("records"),
    ),
    # ------------------------------------------------------------------ columns
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
    # ------------------------------------------------------------------ values
    Case(
        "value huge orders",
        ["orders", *B, "--json"],
        ["column 'u', data row 10", "too large"],
        with_cell(9, 1, "1e300"),
    ),
    Case(
        "value two rows orders",
        ["orders", *B, "--json"],
        ["0 samples with a full regressor", "at least 80"],
        first_rows(2),
    ),
    Case(
        "ts negative orders",
        ["orders", *G, "--ts", "-0.05", "--json"],
        ["positive number of seconds"],
    ),
    # ------------------------------------------------------------------ ranges
    Case(
        "range orders beyond the record",
        ["orders", *G, "--estimation", "100:1000", "--json"],
        ["--estimation 100:1000 does not fit"],
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
    # ------------------------------------------------------------------ options
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
]


@pytest.mark.parametrize("case", params(ORDERS))
def test_refused(case, workdir):
    refused(case, workdir)
