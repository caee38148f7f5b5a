"""The floors of blockid (blockid/floors.py): every package has one, they follow the
pipeline, and docs/architecture.md states the same table. The imports themselves are
checked against it in tests/test_architecture.py."""

from pathlib import Path

import blockid
from blockid.floors import FLOORS

SRC = Path(blockid.__file__).parent


def test_the_docs_state_the_floors_of_the_table():
    """docs/architecture.md's diagram names every package on its floor: the floor in
    columns 0-6 of a line, the packages in columns 7-25."""
    import re

    doc = (SRC.parents[1] / "docs" / "architecture.md").read_text()
    start = doc.index("floor  package")
    stated, floor = {}, None
    for line in doc[start : doc.index("```", start)].splitlines()[1:]:
        if line[:7].strip():
            floor = int(line[:7])
        for name in re.findall(r"[_a-z]+", line[7:26]):
            stated[name] = floor
    assert stated == FLOORS


def test_every_package_and_top_level_module_has_a_floor():
    """A package without a floor would escape the import check (its layer is None)."""
    found = {p.stem for p in SRC.glob("*.py") if p.name != "__init__.py"}
    found |= {p.parent.name for p in SRC.glob("*/__init__.py")}
    assert found == set(FLOORS)


def test_the_floors_follow_the_pipeline():
    """data -> blocks -> models -> estimators -> evaluation -> fitting -> plotting ->
    workflows and reporting -> cli, each strictly above the one before (STYLE.md)."""
    pipeline = [
        ("errors", "_kernels"),
        ("data", "design"),
        ("blocks",),
        ("models", "plants"),
        ("estimators",),
        ("evaluation",),
        ("fitting",),
        ("plotting",),
        ("workflows", "reporting"),
        ("cli",),
    ]
    floors = [{FLOORS[name] for name in step} for step in pipeline]
    assert all(len(f) == 1 for f in floors), floors
    assert [f.pop() for f in floors] == list(range(len(pipeline)))
