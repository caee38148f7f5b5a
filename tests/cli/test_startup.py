"""Start-up: a command that fails on its arguments answers before it imports the
numerical stack, and reading a CSV file does not import numba (issue: every command
that read data took 2.5-4 s even to print a one-line error).

Each case runs the real command line in a fresh interpreter and lists, at exit, which
of NumPy, pandas, SciPy, numba and matplotlib it imported.
"""

import json
import subprocess
import sys

import pytest

HEAVY = ("numpy", "pandas", "scipy", "numba", "matplotlib")
_RUN = (
    "import atexit, json, sys\n"
    "atexit.register(lambda: sys.stderr.write('\\nIMPORTED ' + json.dumps("
    f"[m for m in {HEAVY!r} if m in sys.modules]) + '\\n'))\n"
    "from blockid.cli.main import app\n"
    "sys.argv = ['blockid', *sys.argv[1:]]\n"
    "app()\n"
)


def _run(args, cwd):
    proc = subprocess.run(
        [sys.executable, "-c", _RUN, *map(str, args)],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=120,
    )
    marker = proc.stderr.rsplit("IMPORTED ", 1)
    assert len(marker) == 2, proc.stderr
    return proc.returncode, marker[0].strip(), json.loads(marker[1])


@pytest.fixture
def folder(tmp_path):
    (tmp_path / "data.csv").write_text("t,u,y\n0,1,2\n1,2,3\n2,3,4\n")
    (tmp_path / "model.json").write_text("{not json")
    (tmp_path / "taken.json").write_text("{}")
    return tmp_path


ARGUMENT_ERRORS = [
    (["fit", "missing.csv", "-u", "u", "-y", "y", "-o", "m.json"], "missing.csv does not exist"),
    (["fit", "data.csv", "-u", "u", "-y", "y"], "give -o MODEL.json"),
    (["fit", "data.csv", "-u", "u", "-y", "y", "-o", "taken.json"], "taken.json exists"),
    (["fit", "data.csv", "-u", "u", "-y", "y", "--json", "--na", "-1"], "na must hold"),
    (["fit", "data.csv", "-u", "u", "-y", "y", "--json", "--structure", "nope"], "'nope'"),
    (["fit", "data.csv", "-u", "u", "-y", "y", "--json", "--estimation", "5"], "START:STOP"),
    (["fit", "data.xlsx", "-u", "u", "-y", "y", "--json"], "unknown data file type"),
    (
        [
            "fit",
            "data.csv",
            "-u",
            "u",
            "-y",
            "y",
            "--json",
            "--structure",
            "hammerstein",
            "--forgetting",
            "0.99",
            "--method",
            "nope",
        ],
        "nope",
    ),  # fmt: skip
    (["identify", "data.csv", "-u", "u", "-y", "y", "--effort", "huge"], "effort='huge'"),
    (["identify", "data.csv", "-u", "u", "-y", "y", "--jobs", "0"], "jobs must be"),
    (["identify", "data.csv", "-u", "u", "-y", "y", "--structures", "nope"], "nope"),
    (
        ["compare", "data.csv", "-u", "u", "-y", "y", "--estimation", "0:2", "--validation", "1:3"],
        "overlap",
    ),  # fmt: skip
    (["simulate", "missing.json", "data.csv"], "missing.json does not exist"),
    (["simulate", "model.json", "data.csv"], "not valid JSON"),
    (["export", "model.json"], "not valid JSON"),
    (["stream", "-u", "u", "-y", "y", "--structure", "nope"], "'nope'"),
    (["example-data", "nope", "-o", "x.csv"], "unknown example"),
    (["example-data", "electrohydraulic", "-o", "x.xlsx"], "unknown table type"),
    (["orders", "data.csv", "-u", "u", "-y", "y", "--noise", "abc"], "--noise"),
    (["design", "multisine", "--samples", "100", "--f-max", "0.7"], "Nyquist frequency 0.5 Hz"),
    (["design", "odd-multisine", "--samples", "8", "--f-min", "0.25", "--f-max", "0.3"], "odd"),
    (["design", "prbs", "--order", "30"], "order must be 2..24"),
    (["design", "prbs", "--order", "5", "-o", "taken.json"], "taken.json exists"),
    (["design", "prbs", "--order", "5", "-o", "x.xlsx"], "unknown table type"),
]


@pytest.mark.parametrize(("args", "message"), ARGUMENT_ERRORS, ids=lambda v: " ".join(v)[:40])
def test_an_argument_error_answers_before_the_numerical_stack(folder, args, message):
    code, stderr, imported = _run(args, folder)
    assert code == 2, stderr
    assert message in stderr
    assert imported == [], f"{' '.join(args)} imported {imported} before failing"


def test_reading_a_csv_file_does_not_import_numba(folder):
    code, stderr, imported = _run(["fit", "data.csv", "-u", "nope", "-y", "y", "--json"], folder)
    assert code == 2 and "no column 'nope'" in stderr
    assert "pandas" in imported  # it did read the file
    assert "numba" not in imported and "scipy" not in imported
