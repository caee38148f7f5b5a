"""blockid.cli._common: the checks every command makes before any work, and the one line
an error of the command's own output ends in."""

from __future__ import annotations

from pathlib import Path

import pytest

from blockid.cli._common import refuse_figures
from blockid.errors import ParameterError
from cli.bad_input import PER


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


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
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
    import subprocess
    import sys

    with open("/dev/full", "w") as full:
        run = subprocess.run([sys.executable, "-m", "blockid.cli.main", *args], stdout=full,
                             stderr=subprocess.PIPE, text=True, timeout=120)  # fmt: skip
    assert run.returncode == 1
    assert run.stderr.strip().splitlines() == [
        "error: cannot write standard output: No space left on device"
    ]
