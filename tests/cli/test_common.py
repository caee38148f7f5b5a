"""blockid.cli._common: the checks every command makes before any work."""

from __future__ import annotations

import pytest

from blockid.cli._common import refuse_figures
from blockid.errors import ParameterError


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
