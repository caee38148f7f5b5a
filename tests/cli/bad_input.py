"""Bad input, as a user would give it: the machinery of the bad-input tables.

Each command's table of :class:`Case` sits beside that command's tests, in
``tests/cli/test_<module>_bad_input.py`` (``fit``, ``compare`` and ``fit-network`` in
``test_fit_bad_input.py`` for :mod:`blockid.cli.fit`, and so on);
``tests/cli/test_bad_input.py`` checks the tables as a whole. Each case is one command
line run in :func:`workdir` (a folder holding a good record, a model file, a network
model file and the case's own bad file, made by :attr:`Case.make`). :func:`refused`
checks, for every case: exit status 2, the expected words on stderr (the message names
the problem), no traceback, one line, and every file that existed before is
byte-for-byte unchanged afterwards. The cases cover files, columns, values, sampling
times, ranges, orders, model files, options, exports and networks, on every command
(issues 11 and 21); ``stream`` reads its samples from the case's ``input``.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from blockid.cli.main import app
from blockid.models import ARX, Network, save_model

runner = CliRunner()

N = 300
DT = 0.05


@dataclass
class Case:
    id: str
    args: list[str]
    expect: list[str]
    make: Callable[[Path], None] | None = None
    marks: list = field(default_factory=list)
    #: Text on standard input (``stream``).
    input: str | None = None


#: The good record and the bad one, as ``fit`` and ``orders`` read them.
G = ["good.csv", "-u", "u", "-y", "y"]
B = ["bad.csv", "-u", "u", "-y", "y"]


def params(*tables: Iterable[Case]) -> list:
    """The cases of ``tables`` as pytest parameters, named by their ids."""
    return [pytest.param(c, id=c.id, marks=c.marks) for table in tables for c in table]


def record(seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(N)
    plant = ARX(["u"], ["y"], 2, 2, 1, a={"y": {"y": [-1.2, 0.35]}}, b={"y": {"u": [1.0, 0.4]}})
    y = plant.simulate(u)[:, 0] + 0.01 * rng.standard_normal(N)
    return np.arange(N) * DT, u, y


def write_csv(path: Path, header: str, rows: list[str]) -> None:
    path.write_text(header + "\n" + "\n".join(rows) + "\n")


def good_rows() -> list[str]:
    t, u, y = record()
    return [f"{t[k]:.2f},{float(u[k])!r},{float(y[k])!r}" for k in range(N)]


def with_cell(row: int, column: int, text: str) -> Callable[[Path], None]:
    """A copy of good.csv as bad.csv with one cell replaced."""

    def make(d: Path) -> None:
        rows = [r.split(",") for r in good_rows()]
        rows[row][column] = text
        write_csv(d / "bad.csv", "t,u,y", [",".join(r) for r in rows])

    return make


def model_doc(d: Path) -> dict:
    return json.loads((d / "model.json").read_text())


def bad_model(change: Callable[[dict], None]) -> Callable[[Path], None]:
    def make(d: Path) -> None:
        doc = model_doc(d)
        change(doc)
        (d / "bad.json").write_text(json.dumps(doc))

    return make


def nan_parameter(doc: dict) -> None:
    doc["model"]["parameters"]["y"]["a"]["y"][0] = float("nan")  # written as NaN


def folder_with_a_file(name: str) -> Callable[[Path], None]:
    def make(d: Path) -> None:
        (d / name).mkdir()
        (d / name / "keep.txt").write_text("mine")

    return make


def write(name: str, content: str | bytes) -> Callable[[Path], None]:
    """A file ``name`` holding ``content`` (bytes as they are, text as UTF-8)."""

    def make(d: Path) -> None:
        if isinstance(content, bytes):
            (d / name).write_bytes(content)
        else:
            (d / name).write_text(content, encoding="utf-8")

    return make


def bad_csv(header: str, rows: list[str], encoding: str = "utf-8") -> Callable[[Path], None]:
    def make(d: Path) -> None:
        (d / "bad.csv").write_bytes((header + "\n" + "\n".join(rows) + "\n").encode(encoding))

    return make


def first_rows(n: int) -> Callable[[Path], None]:
    return bad_csv("t,u,y", good_rows()[:n])


def figures(folder: str, *names: str) -> Callable[[Path], None]:
    """A folder holding figures of an earlier run."""

    def make(d: Path) -> None:
        (d / folder).mkdir()
        for name in names:
            (d / folder / name).write_bytes(b"\x89PNG earlier figure")

    return make


def parameter(doc: dict, key: str, value: object) -> None:
    doc["model"]["parameters"]["y"][key]["y" if key == "a" else "u"] = value


def snapshot(root: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()
    }


def workdir(tmp_path: Path) -> Path:
    """good.csv (t, u, y), net.csv (t, u1, v1, v2), model.json (ARX u -> y) and
    network.json (u1 -> v1 -> y1) in ``tmp_path``; the ``workdir`` fixture of
    ``tests/cli/conftest.py`` makes it the working folder of the command."""
    write_csv(tmp_path / "good.csv", "t,u,y", good_rows())
    t, u, y = record(1)
    v2 = np.roll(y, 1)
    write_csv(
        tmp_path / "net.csv",
        "t,u1,v1,v2",
        [f"{t[k]:.2f},{float(u[k])!r},{float(y[k])!r},{float(v2[k])!r}" for k in range(N)],
    )
    plant = ARX(["u"], ["y"], 2, 2, 1, a={"y": {"y": [-1.2, 0.35]}}, b={"y": {"u": [1.0, 0.4]}})
    save_model(plant, tmp_path / "model.json")
    s1 = ARX(["u1"], ["v1"], 1, 1, 1, a={"v1": {"v1": [-0.5]}}, b={"v1": {"u1": [0.5]}})
    s3 = ARX(["v1"], ["y1"], 1, 1, 1, a={"y1": {"y1": [-0.5]}}, b={"y1": {"v1": [1.0]}})
    save_model(Network([("S1", s1), ("S3", s3)]), tmp_path / "network.json")
    return tmp_path


def refused(case: Case, folder: Path) -> None:
    """Run ``case`` in ``folder``: exit 2 with one readable line, no file changed."""
    if case.make is not None:
        case.make(folder)
    before = snapshot(folder)
    r = runner.invoke(app, case.args, input=case.input)
    err = r.stderr
    assert r.exit_code == 2, f"exit {r.exit_code}; stderr: {err}; exception: {r.exception!r}"
    assert "Traceback" not in err and "Traceback" not in r.stdout
    assert isinstance(r.exception, SystemExit)
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert "\ufffd" not in err, "the message shows a replacement character"
    for words in case.expect:
        assert words.lower() in err.lower(), f"{words!r} not in {err!r}"
    after = snapshot(folder)
    assert {k: after.get(k) for k in before} == before, "an existing file was changed"
