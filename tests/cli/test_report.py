"""``blockid report`` (cli/report.py): it refuses to overwrite without --force, prints
JSON, and starts without the heavy libraries."""

from __future__ import annotations

import subprocess
import sys

from typer.testing import CliRunner


def test_the_command_refuses_to_overwrite_without_force(example_report, report_app, report_args):
    before = example_report.path.read_bytes()
    args = ["report", str(example_report.data), *report_args, "-o", str(example_report.path)]
    refused = CliRunner().invoke(report_app, args)
    assert refused.exit_code == 2
    assert "exists; pass --force" in refused.output
    assert example_report.path.read_bytes() == before


def test_the_command_json_and_force(example_report, report_app, report_args, tmp_path):
    import json

    out = tmp_path / "r.html"
    out.write_text("old")
    args = ["report", str(example_report.data), *report_args[:10], "--structures", "arx",
            "--na", "2", "--nb", "2", "--nk", "1", "-o", str(out), "--force", "--json"]  # fmt: skip
    result = CliRunner().invoke(report_app, args)
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert doc["report"] == str(out) and doc["bytes"] == out.stat().st_size
    assert doc["models"][0]["structure"] == "arx"
    assert out.read_text().startswith("<!DOCTYPE html>")


def test_the_command_module_imports_no_heavy_library():
    code = (
        "import sys, blockid.cli.report\n"
        "heavy = [m for m in ('pandas', 'scipy', 'numba', 'matplotlib') if m in sys.modules]\n"
        "assert not heavy, heavy\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
