"""blockid.cli.main: the command tree's own options."""

from __future__ import annotations

from typer.testing import CliRunner

from blockid.cli.main import app

runner = CliRunner()


def test_version():
    from blockid import __version__

    r = runner.invoke(app, ["--version"])
    assert r.exit_code == 0 and r.stdout.strip() == f"blockid {__version__}"
