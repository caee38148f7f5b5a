"""blockid.cli.fleet_cli: ``blockid fleet`` driven as a user would (typer's CliRunner)."""

from __future__ import annotations

import json
import sys

import pytest
from typer.testing import CliRunner

from blockid.cli.main import app
from blockid.workflows.fleet import MISSING_DASK, fit_fleet

from reference import CORRUPT

runner = CliRunner()


def test_the_command(records, cluster, tmp_path):
    out = tmp_path / "cli"
    pattern = str(records[0].parent / "loop*.csv")
    args = ["fleet", pattern, "-u", "u", "-y", "y", "--na", "2", "--nb", "2", "--nk", "1"]
    args += ["--out", str(out), "--scheduler", cluster]
    r = runner.invoke(app, [*args, "--json"])
    assert r.exit_code == 1, r.output  # one record failed
    doc = json.loads(r.stdout)
    assert doc["counts"] == {"ok": 19, "error": 1, "skipped": 0}
    assert doc["records"][CORRUPT]["rmse_y"] is None
    text = runner.invoke(app, args)
    assert "20 records: 0 fitted, 1 failed, 19 skipped" in text.stdout
    assert "loop07.csv" in text.stdout and "'abc' is not a number" in text.stdout
    (failed,) = [line for line in text.stdout.splitlines() if line.startswith("failed:")]
    assert failed.count("loop07.csv") == 1, failed  # the path once, not twice


def test_ctrl_c_says_how_many_model_files_were_written(tmp_path, monkeypatch):
    import blockid.workflows.fleet as fleet_module

    def interrupted(files, out, *args, on_result=None, **kwargs):
        for name in files[:2]:  # two records done, then Ctrl-C
            on_result({"file": name, "status": "ok"})
        raise KeyboardInterrupt

    monkeypatch.setattr(fleet_module, "fit_fleet", interrupted)
    for name in ("a.csv", "b.csv", "c.csv"):
        (tmp_path / name).write_text("u,y\n0,0\n")
    args = ["fleet", str(tmp_path / "*.csv"), "-u", "u", "-y", "y", "-o", str(tmp_path / "o")]
    r = runner.invoke(app, args)
    assert r.exit_code == 130
    assert "interrupted: 2 model file(s) written to" in r.stderr
    assert "no output file was written" not in r.stderr


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--max-nfev", "3"], "max_nfev not used by arx"),
        (["--method", "nope"], "method='nope' does not apply to arx"),
    ],
)
def test_bad_options_are_refused_before_any_work(records, tmp_path, extra, message):
    args = ["fleet", str(records[0]), "-u", "u", "-y", "y", "--out", str(tmp_path / "o")]
    r = runner.invoke(app, [*args, *extra])
    assert r.exit_code == 2 and message in r.stderr
    assert not (tmp_path / "o").exists()


def test_no_matching_file_and_clashing_names(tmp_path):
    r = runner.invoke(app, ["fleet", str(tmp_path / "*.csv"), "-u", "u", "-y", "y", "-o", "x"])
    assert r.exit_code == 2 and "no file matches" in r.stderr
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    clash = [tmp_path / "a" / "r.csv", tmp_path / "b" / "r.csv"]
    with pytest.raises(Exception, match=r"would both be written to r\.json"):
        fit_fleet(clash, tmp_path / "o", "arx", ["u"], ["y"])


def test_without_dask_the_command_says_what_to_install(records, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import fails as if absent
    args = ["fleet", str(records[0]), "-u", "u", "-y", "y", "--out", str(tmp_path)]
    r = runner.invoke(app, args)
    assert r.exit_code == 2
    assert r.stderr.strip() == f"error: {MISSING_DASK}"
    assert MISSING_DASK == "blockid fleet needs dask: pip install 'blockid[fleet]'"
