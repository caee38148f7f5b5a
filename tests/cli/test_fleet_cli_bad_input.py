"""Bad input to ``fleet`` (:mod:`blockid.cli.fleet_cli`): a table of
:class:`~cli.bad_input.Case`, each refused in one readable line with exit status 2, no
file written or changed (:func:`cli.bad_input.refused`)."""

from __future__ import annotations

import pytest

from cli.bad_input import Case, G, params, refused

FLEET = [
    # ------------------------------------------------------------------ values
    Case(
        "ts zero fleet",
        ["fleet", *G, "-o", "out", "--ts", "0", "--json"],
        ["positive number of seconds"],
    ),
    # ------------------------------------------------------------------ options
    Case(
        "option fleet no file matches",
        ["fleet", "logs/*.csv", "-u", "u", "-y", "y", "-o", "out", "--json"],
        ["no file matches 'logs/*.csv'"],
    ),
    Case(
        "option fleet structure unknown",
        ["fleet", *G, "-o", "out", "--structure", "nope", "--json"],
        ["structure='nope' is unknown"],
    ),
    Case(
        "option fleet workers zero",
        ["fleet", *G, "-o", "out", "--workers", "0", "--json"],
        ["invalid value for '--workers'", "greater than or equal to 1"],
    ),
    Case(
        "option fleet option not used",
        ["fleet", *G, "-o", "out", "--structure", "arx", "--r1", "3", "--json"],
        ["r1 not used by arx", "--r1"],
    ),
]


@pytest.mark.parametrize("case", params(FLEET))
def test_refused(case, workdir):
    refused(case, workdir)
