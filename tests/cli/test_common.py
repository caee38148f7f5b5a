"""blockid.cli._common: the checks every command makes before any work, and the one line
an error of the command's own output ends in."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from blockid.cli._common import refuse_figures
from blockid.cli.main import app
from blockid.errors import ParameterError
from cli.bad_input import PER

runner = CliRunner()


def test_any_figure_the_command_would_write_is_refused_not_the_first_only(tmp_path):
    names = ["fit.png", "blocks.png", "residuals.png"]
    refuse_figures(tmp_path, names, force=False)  # an empty folder: nothing to replace
    (tmp_path / "residuals.png").write_bytes(b"mine")
    with pytest.raises(ParameterError, match=r"residuals\.png exist\(s\); pass --force"):
        refuse_figures(tmp_path, names, force=False)
    refuse_figures(tmp_path, names, force=True)
    assert (tmp_path / "residuals.png").read_bytes() == b"mine"  # only checked here
    (tmp_path / "other.png").write_bytes(b"")  # a figure of another command: not ours
    refuse_figures(tmp_path, names[:2], force=False)
    with pytest.raises(ParameterError, match="is a file, not a folder"):
        refuse_figures(tmp_path / "other.png", names, force=True)


#: A standard output on a full device (``> /dev/full``), where there is one.
needs_a_full_device = pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")


def _to_a_full_device(args: list[str], timeout: float) -> subprocess.CompletedProcess:
    """``blockid ARGS > /dev/full`` in a fresh interpreter (its stderr captured)."""
    with open("/dev/full", "w") as full:
        return subprocess.run([sys.executable, "-m", "blockid.cli.main", *args], stdout=full,
                              stderr=subprocess.PIPE, text=True, timeout=timeout)  # fmt: skip


@needs_a_full_device
@pytest.mark.parametrize(
    "args",
    [
        ["bla", *PER, "--json"],
        ["design", "multisine", "--samples", "64"],
        ["residuals", "model.json", "good.csv"],
    ],  # fmt: skip
    ids=["bla", "design", "residuals"],
)
def test_a_full_standard_output_is_one_line(args, workdir):
    """``> /dev/full``: one line naming standard output, exit 1, no traceback."""
    run = _to_a_full_device(args, timeout=120)
    assert run.returncode == 1
    assert run.stderr.strip().splitlines() == [
        "error: cannot write standard output: No space left on device"
    ]


@needs_a_full_device
@pytest.mark.parametrize("command", ["fit", "export"])
def test_a_standard_output_that_cannot_be_written_is_one_readable_line(command, cubic_csv,
                                                                       tmp_path):  # fmt: skip
    """stdout on a full device (``> /dev/full``) once ended in a traceback; now one line
    on stderr naming it, exit 1, and no second error from the interpreter's last flush."""
    model = tmp_path / "m.json"
    fit = ["fit", str(cubic_csv), "-u", "u", "-y", "y", "--structure", "arx", "--na", "2",
           "--nb", "2", "--nk", "1"]  # fmt: skip
    runner.invoke(app, [*fit, "-o", str(model)])
    args = [*fit, "--json"] if command == "fit" else ["export", str(model), "--to", "python"]
    run = _to_a_full_device(args, timeout=300)
    assert run.returncode == 1
    assert run.stderr.strip().splitlines() == [
        "error: cannot write standard output: No space left on device"
    ]


@pytest.mark.parametrize("command", ["fit", "identify"])
def test_a_model_file_is_not_written_under_a_table_s_name(command, cubic_csv, tmp_path):
    """``-o m.csv`` once wrote JSON under a .csv name; now refused before any work,
    naming the .json it should be, and nothing is written."""
    out = tmp_path / "m.csv"
    extra = (
        ["--structure", "arx", "--na", "2", "--nb", "2", "--nk", "1"] if command == "fit" else []
    )
    r = runner.invoke(app, [command, str(cubic_csv), "-u", "u", "-y", "y", "-o", str(out), *extra])
    assert r.exit_code == 2 and "a model file is JSON, not .csv" in r.stderr
    assert str(tmp_path / "m.json") in r.stderr and not out.exists()


@pytest.mark.parametrize("command", ["fit", "identify"])
def test_an_output_that_could_not_be_written_is_refused_before_any_work(
    command, cubic_csv, tmp_path, monkeypatch
):
    """``-o missing/m.json`` once ran the whole search and then failed to write; now
    refused first, naming the folder, and the search never starts."""
    import blockid.fitting
    from blockid.workflows import identify as search

    def never(*a, **k):
        raise AssertionError("the work started")

    monkeypatch.setattr(blockid.fitting, "fit_model", never)
    monkeypatch.setattr(search, "identify", never)
    extra = (
        ["--structure", "arx", "--na", "2", "--nb", "2", "--nk", "1"] if command == "fit" else []
    )
    out = tmp_path / "missing" / "m.json"
    r = runner.invoke(app, [command, str(cubic_csv), "-u", "u", "-y", "y", "-o", str(out), *extra])
    assert r.exit_code == 2, r.output
    assert f"folder {tmp_path / 'missing'} does not exist" in r.stderr
    assert "nothing was computed" in r.stderr and not out.parent.exists()
