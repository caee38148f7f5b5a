"""blockid.workflows.effort: the efforts are what docs/identify.md's table says."""

from __future__ import annotations

from pathlib import Path

import pytest

from blockid.errors import ParameterError
from blockid.workflows.effort import EFFORTS, check_search

DOC = Path(__file__).parents[2] / "docs" / "identify.md"


def _table() -> dict[str, list[str]]:
    """The Effort table of docs/identify.md: row title -> cells (quick, standard,
    thorough), "the same" read as the cell before it."""
    text = DOC.read_text()
    start = text.index("### Effort")
    rows = {}
    for line in text[start:].splitlines()[3:]:
        if not line.startswith("|"):
            break
        cells = [c.strip() for c in line.strip("|").split("|")]
        values = cells[1:]
        for i, v in enumerate(values):
            if v == "the same":
                values[i] = values[i - 1]
        rows[cells[0]] = values
    return rows


def test_the_docs_table_is_the_efforts():
    rows = _table()
    for i, name in enumerate(("quick", "standard", "thorough")):
        e = EFFORTS[name]
        assert rows["folds (short / long record)"][i] == f"{e.folds} / {e.folds_long}"
        assert rows["finalists, their iterations"][i] == f"{e.finalists}, {e.final_nfev}"
        assert rows["richer-nonlinearity steps"][i] == str(e.grow_steps)
        loops = rows["loop blocks, a loop per output: saturation, dead zone"][i]
        assert loops == ("also one input and one output" if e.loop_single
                         else "several inputs or outputs only")  # fmt: skip
        share = rows["structures raced on a long record: the share carried past the first fold"]
        assert share[i] == {1: "none", 2: "half", 3: "a third"}[e.race]
    plans = rows["polynomial state space: (degree, monomials)"]
    assert EFFORTS["quick"].state_plans == EFFORTS["standard"].state_plans  # "the same"
    assert plans[0] == ", ".join(f"({d}, {m})" for d, m in EFFORTS["quick"].state_plans)


def test_the_search_arguments_are_checked_before_any_work():
    assert check_search(None, "standard")[0] is EFFORTS["standard"]
    with pytest.raises(ParameterError, match="effort='huge' is unknown"):
        check_search(None, "huge")
    with pytest.raises(ParameterError, match="jobs must be a whole number"):
        check_search(None, "quick", jobs=0)
    with pytest.raises(ParameterError, match="unknown"):
        check_search(["narx"], "quick")


def test_more_jobs_than_identify_starts_is_refused_not_cut():
    """The cap on worker processes is an error that names it (it cut 100 to 64 silently)."""
    from blockid.errors import ParameterError
    from blockid.workflows.effort import MAX_JOBS, check_search

    check_search(None, "quick", jobs=MAX_JOBS)
    with pytest.raises(ParameterError, match=r"jobs=65 .* give 64 or fewer, or a dask cluster"):
        check_search(None, "quick", jobs=MAX_JOBS + 1)
