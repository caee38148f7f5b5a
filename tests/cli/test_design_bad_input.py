"""Bad input to ``design`` (:mod:`blockid.cli.design`): a table of
:class:`~cli.bad_input.Case`, each refused in one readable line with exit status 2, no
file written or changed (:func:`cli.bad_input.refused`). Edge cases it accepts are in a
second table (:func:`cli.bad_input.accepted`)."""

from __future__ import annotations

import pytest

from cli.bad_input import Accepted, Case, accepted, files, params, refused

DESIGN = [
    Case("design kind unknown", ["design", "sine"], ["unknown excitation 'sine'"]),
    Case("design samples missing", ["design", "multisine"], ["needs samples", "--samples"]),
    Case("design samples one", ["design", "multisine", "--samples", "1"], ["--samples"]),
    Case("design samples two", ["design", "multisine", "--samples", "2"], ["no line"]),
    Case(
        "design samples huge", ["design", "multisine", "--samples", "99999999999"], ["--samples"]
    ),  # fmt: skip
    Case(
        "design periods huge",
        ["design", "multisine", "--samples", "64", "--periods", "100000000"],
        ["--periods"],
    ),  # fmt: skip
    Case(
        "design realisations huge",
        ["design", "multisine", "--samples", "64", "--realisations", "100000000"],
        ["--realisations"],
    ),  # fmt: skip
    Case(
        "design prbs longest and slowest",
        ["design", "prbs", "--order", "24", "--clock", "1000", "--periods", "1000"],
        ["samples"],
    ),  # fmt: skip
    Case(
        "design f-max above nyquist",
        ["design", "multisine", "--samples", "64", "--f-max", "0.6"],
        ["Nyquist", "--f-max"],
    ),  # fmt: skip
    Case(
        "design f-max zero",
        ["design", "multisine", "--samples", "64", "--f-max", "0"],
        ["no line", "--f-max"],
    ),  # fmt: skip
    Case(
        "design band between lines",
        ["design", "multisine", "--samples", "64", "--f-min", "0.301", "--f-max", "0.31"],
        ["no line"],
    ),  # fmt: skip
    Case(
        "design f-min above f-max",
        ["design", "multisine", "--samples", "64", "--f-min", "0.4", "--f-max", "0.3"],
        ["f_min", "--f-min"],
    ),  # fmt: skip
    Case(
        "design f-max nan",
        ["design", "multisine", "--samples", "64", "--f-max", "nan"],
        ["--f-max"],
    ),  # fmt: skip
    Case("design fs zero", ["design", "multisine", "--samples", "64", "--fs", "0"], ["--fs"]),
    Case(
        "design fs and ts disagree",
        ["design", "multisine", "--samples", "64", "--fs", "10", "--ts", "0.2"],
        ["disagree"],
    ),  # fmt: skip
    Case(
        "design rms zero", ["design", "multisine", "--samples", "64", "--rms", "0"], ["--rms"]
    ),  # fmt: skip
    Case(
        "design rms overflows",
        ["design", "multisine", "--samples", "64", "--rms", "1e308"],
        ["--rms"],
    ),  # fmt: skip
    Case(
        "design rms underflows",
        ["design", "multisine", "--samples", "64", "--rms", "1e-320"],
        ["--rms"],
    ),  # fmt: skip
    Case(
        "design crest iterations negative",
        ["design", "multisine", "--samples", "64", "--crest-iterations", "-1"],
        ["--crest-iterations"],
    ),  # fmt: skip
    Case(
        "design crest iterations endless",
        ["design", "multisine", "--samples", "64", "--crest-iterations", "100000000"],
        ["--crest-iterations"],
    ),  # fmt: skip
    Case(
        "design group one",
        ["design", "odd-multisine", "--samples", "64", "--group", "1"],
        ["--group"],
    ),  # fmt: skip
    Case("design prbs order 25", ["design", "prbs", "--order", "25"], ["2..24", "--order"]),
    Case(
        "design prbs levels equal",
        ["design", "prbs", "--order", "5", "--levels", "1,1"],
        ["LOW < HIGH", "--levels"],
    ),  # fmt: skip
    Case(
        "design prbs levels overflow",
        ["design", "prbs", "--order", "5", "--levels", "-1e200,1e300"],
        ["--levels"],
    ),  # fmt: skip
    Case(
        "design prbs realisations",
        ["design", "prbs", "--order", "5", "--realisations", "2"],
        ["prbs takes no realisations"],
    ),  # fmt: skip
    Case(
        "design random-binary clock does not divide",
        ["design", "random-binary", "--samples", "64", "--clock", "100"],
        ["whole number of bits"],
    ),  # fmt: skip
    Case(
        "design seed negative",
        ["design", "multisine", "--samples", "64", "--seed", "-1"],
        ["--seed"],
    ),  # fmt: skip
    Case(
        "design name empty", ["design", "multisine", "--samples", "64", "--name", ""], ["--name"]
    ),  # fmt: skip
    Case(
        "design name clashes", ["design", "multisine", "--samples", "64", "--name", "t"], ["clash"]
    ),  # fmt: skip
    Case(
        "design output exists",
        ["design", "multisine", "--samples", "64", "-o", "old.csv"],
        ["old.csv exists"],
        files("old.csv"),
    ),  # fmt: skip
    Case(
        "design output folder missing",
        ["design", "multisine", "--samples", "64", "-o", "missing/x.csv"],
        ["does not exist"],
    ),  # fmt: skip
]

DESIGN_ACCEPTED = [
    Accepted("design three samples", ["design", "multisine", "--samples", "3"], ["lines (1"]),
    Accepted(
        "design crest iterations at the limit",
        ["design", "multisine", "--samples", "16", "--crest-iterations", "10000"],
        ["crest factor"],
    ),  # fmt: skip
    Accepted(
        "design rms large", ["design", "multisine", "--samples", "64", "--rms", "1e100"], ["1e+100"]
    ),  # fmt: skip
    Accepted(
        "design f-max at nyquist",
        ["design", "multisine", "--samples", "64", "--f-max", "0.5"],
        ["every line"],
    ),  # fmt: skip
]


@pytest.mark.parametrize("case", params(DESIGN))
def test_refused(case, workdir):
    refused(case, workdir)


@pytest.mark.parametrize("case", params(DESIGN_ACCEPTED))
def test_accepted(case, workdir):
    accepted(case, workdir)
