"""Bad input, as a user would give it: the machinery of the bad-input tables.

Each command's table of :class:`Case` sits beside that command's tests, in
``tests/cli/test_<module>_bad_input.py`` (``fit``, ``compare`` and ``fit-network`` in
``test_fit_bad_input.py`` for :mod:`blockid.cli.fit`, and so on);
``tests/cli/test_bad_input.py`` checks the tables as a whole. Each case is one command
line run in :func:`workdir`: a noise record (good.csv), a periodic record (per.csv: an
odd multisine of 2 realisations x 3 periods of 64 samples through a low-pass and a
cubic), a record of a network (net.csv), an ARX model file without a sampling time
(model.json) and at 0.05 s (model_ts.json), a network model file (network.json), and
the case's own bad file, made by :attr:`Case.make`.

:func:`refused` checks, for every case: exit status 2, the expected words on stderr (the
message names the problem and the flag), no traceback, one line, and no file written or
changed. The cases cover files, columns, values, sampling times, ranges, orders, model
files, options, exports and networks, on every command (issues 11 and 21), and the
measurement commands attacked as a careless or hostile user would (issue 37, items 5
and 6); ``stream`` reads its samples from the case's ``input``. Some commands also have
a table of :class:`Accepted` edge cases, which :func:`accepted` checks: exit status 0,
no traceback, no NaN or infinity printed, every file that existed unchanged unless
``--force`` names it.
"""

from __future__ import annotations

import json
import re
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


@dataclass
class Accepted:
    id: str
    args: list[str]
    #: Words that must be in the standard output (or in the file named ``-o``).
    expect: list[str]
    make: Callable[[Path], None] | None = None
    #: Words that must be on standard error (a warning); none expected otherwise.
    warns: list[str] | None = None
    marks: list = field(default_factory=list)


#: The good record and the bad one, as ``fit`` and ``orders`` read them.
G = ["good.csv", "-u", "u", "-y", "y"]
B = ["bad.csv", "-u", "u", "-y", "y"]
#: The periodic record, as ``bla`` reads it.
PER = ["per.csv", "-u", "u", "-y", "y", "--time-column", "t", "--experiment-column", "realisation"]


def params(*tables: Iterable[Case | Accepted]) -> list:
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


def rows(u: np.ndarray, y: np.ndarray, dt: float = 0.05) -> str:
    return "".join(f"{k * dt:.2f},{float(u[k])!r},{float(y[k])!r}\n" for k in range(u.size))


def table(name: str, u: Callable[[int], float], y: Callable[[int], float], n: int = 100):
    """``name`` with columns t, u, y of ``n`` rows from the two functions of the row."""
    k = np.arange(n)
    return write(name, "t,u,y\n" + rows(np.array([u(i) for i in k]), np.array([y(i) for i in k])))


def files(*names: str) -> Callable[[Path], None]:
    """Files and folders of an earlier run: ``old.json``, ``afile``, ``figs/bla.png``..."""

    def make(d: Path) -> None:
        for name in names:
            path = d / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(b"earlier")

    return make


def workdir(tmp_path: Path) -> Path:
    """good.csv (t, u, y), per.csv (t, realisation, u, y), net.csv (t, u1, v1, v2),
    model.json (ARX u -> y), model_ts.json (the same at 0.05 s) and network.json
    (u1 -> v1 -> y1) in ``tmp_path``; the ``workdir`` fixture of ``tests/cli/conftest.py``
    makes it the working folder of the command."""
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
    plant.sampling_time = 0.05
    save_model(plant, tmp_path / "model_ts.json")
    s1 = ARX(["u1"], ["v1"], 1, 1, 1, a={"v1": {"v1": [-0.5]}}, b={"v1": {"u1": [0.5]}})
    s3 = ARX(["v1"], ["y1"], 1, 1, 1, a={"y1": {"y1": [-0.5]}}, b={"y1": {"v1": [1.0]}})
    save_model(Network([("S1", s1), ("S3", s3)]), tmp_path / "network.json")
    from scipy import signal

    from blockid.design import multisine

    rng = np.random.default_rng(0)
    rng.standard_normal(2 * N)  # the draws of good.csv (record(0)), as before
    x = multisine(64, sampling_time=0.01, f_max=30.0, odd=True, periods=3, realisations=2,
                  seed=5)  # fmt: skip
    frame = x.to_frame("u")
    b, a = signal.butter(2, 0.4)
    out = [signal.lfilter(b, a, r["u"].to_numpy()) for _, r in frame.groupby("realisation")]
    v = np.concatenate(out)
    frame["y"] = v + 0.3 * v**3 + 0.005 * rng.standard_normal(v.size)
    frame.to_csv(tmp_path / "per.csv", index=False)
    return tmp_path


def refused(case: Case, folder: Path) -> None:
    """Run ``case`` in ``folder``: exit 2 with one readable line, no file written or
    changed."""
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
    assert after == before, "a file was written or changed"


def accepted(case: Accepted, folder: Path) -> None:
    """Run ``case`` in ``folder``: exit 0, the expected words, no NaN or infinity printed,
    no existing file changed but the one ``--force`` names."""
    if case.make is not None:
        case.make(folder)
    before = snapshot(folder)
    r = runner.invoke(app, case.args)
    assert r.exit_code == 0, f"stderr: {r.stderr}; exception: {r.exception!r}"
    assert "Traceback" not in r.stderr and "Traceback" not in r.stdout
    text = r.stdout
    if "-o" in case.args and case.args[0] == "report":
        text = re.sub(r"base64,[A-Za-z0-9+/=]+", "", (folder / "r.html").read_text())
    for words in case.expect:
        assert words in text, f"{words!r} not in the output"
    for bad in (" nan ", " inf ", "NaN", "Infinity"):
        assert bad not in text, f"{bad!r} in the output"
    if case.warns is None:
        assert r.stderr == "", r.stderr
    else:
        assert all(w in r.stderr for w in case.warns), r.stderr
        assert "free run" not in r.stderr, r.stderr
    after = snapshot(folder)
    forced = case.args[case.args.index("-o") + 1] if "--force" in case.args else None
    assert {k: after[k] for k in before if k != forced} == {
        k: v for k, v in before.items() if k != forced
    }, "an existing file was changed"
