"""``blockid fleet`` and :func:`blockid.workflows.fleet.fit_fleet` on a 2-worker cluster.

Twenty small ARX records, one corrupt (a non-numeric cell): 19 model files and one
error row; a rerun writes nothing; ``force`` rewrites; every model equals the fit of its
record alone. One local cluster serves the module (its start-up is most of the time);
the default path, a cluster started by the call itself, runs once on two records.
"""

from __future__ import annotations

import json
import sys

import numpy as np
import pandas as pd
import pytest
import typer
from typer.testing import CliRunner

from blockid.cli.fleet_cli import fleet
from blockid.data import read_data
from blockid.fitting import fit_model
from blockid.models import ARX, load_model
from blockid.workflows.fleet import MISSING_DASK, fit_fleet

runner = CliRunner()

# cli/main.py registers the command; this test builds the same registration on its own
app = typer.Typer(add_completion=False, rich_markup_mode=None)
app.command("fleet")(fleet)


@app.callback()
def _root() -> None:
    """Test app."""


ORDERS = {"na": 2, "nb": 2, "nk": 1}
CORRUPT = 7  # the record with a non-numeric cell
N_RECORDS = 20


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    folder = tmp_path_factory.mktemp("logs")
    plant = ARX(["u"], ["y"], **ORDERS, a={"y": {"y": [-1.2, 0.35]}}, b={"y": {"u": [1.0, 0.4]}})
    for i in range(N_RECORDS):
        rng = np.random.default_rng(i)
        u = rng.uniform(-1, 1, 400)
        y = plant.simulate(u)[:, 0] + 0.01 * rng.standard_normal(400)
        frame = pd.DataFrame({"u": u, "y": y}).astype(object)
        if i == CORRUPT:
            frame.loc[100, "u"] = "abc"
        frame.to_csv(folder / f"loop{i:02d}.csv", index=False)
    return sorted(folder.glob("*.csv"))


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as running:
        yield running.scheduler_address


def _mtimes(folder):
    return {p.name: p.stat().st_mtime_ns for p in folder.glob("loop*.json")}


def test_a_fleet_run_rerun_and_forced_run(records, cluster, tmp_path):
    out = tmp_path / "models"
    run = fit_fleet(records, out, "arx", ["u"], ["y"], options=ORDERS, scheduler=cluster)
    assert run.workers == 2
    assert run.counts() == {"ok": 19, "error": 1, "skipped": 0}
    assert len(_mtimes(out)) == 19 and not (out / f"loop{CORRUPT:02d}.json").exists()
    bad = run.rows[CORRUPT]
    assert bad["status"] == "error" and "'abc' is not a number" in bad["error"]
    assert bad["file"] == str(records[CORRUPT])

    summary = pd.read_csv(out / "summary.csv")
    assert list(summary.columns) == [
        "file",
        "structure",
        "method",
        "status",
        "error",
        "seconds",
        "n_samples",
        "rmse_y",
        "fit_percent_y",
    ]
    parquet = pd.read_parquet(out / "summary.parquet")
    pd.testing.assert_frame_equal(parquet, summary.fillna({"error": ""}))  # CSV: "" is NaN
    assert (summary["status"] == "ok").sum() == 19 and set(summary["method"]) == {"batch"}

    # every model is the fit of its record alone
    for path, row in zip(records, run.rows, strict=True):
        if row["status"] != "ok":
            continue
        alone = fit_model(read_data([path], ["u"], ["y"]), "arx", **ORDERS)
        saved = load_model(out / f"{path.stem}.json")
        assert saved.to_dict() == alone.model.to_dict()
        assert row["rmse_y"] == alone.estimation_metrics["rmse"]["y"]
        assert row["fit_percent_y"] == alone.estimation_metrics["fit_percent"]["y"]

    before = _mtimes(out)
    again = fit_fleet(records, out, "arx", ["u"], ["y"], options=ORDERS, scheduler=cluster)
    assert again.counts() == {"ok": 0, "error": 1, "skipped": 19}
    assert _mtimes(out) == before  # no model file rewritten
    skipped = [r for r in again.rows if r["status"] == "skipped"]
    assert [r["rmse_y"] for r in skipped] == [r["rmse_y"] for r in run.rows if r["status"] == "ok"]

    forced = fit_fleet(
        records, out, "arx", ["u"], ["y"], options=ORDERS, scheduler=cluster, force=True
    )
    assert forced.counts() == {"ok": 19, "error": 1, "skipped": 0}
    after = _mtimes(out)
    assert after.keys() == before.keys()
    assert all(after[name] != before[name] for name in before)


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


def test_a_cluster_of_its_own(records, tmp_path):
    """The default: a local cluster of ``jobs`` processes, started and closed here."""
    pytest.importorskip("distributed")
    run = fit_fleet(records[:2], tmp_path, "arx", ["u"], ["y"], options=ORDERS, jobs=1)
    assert run.workers == 1 and run.counts()["ok"] == 2


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


def test_jobs_is_identify_s_name_checked_alike_and_workers_still_works(records, tmp_path):
    """One name for the worker processes: ``jobs``, checked as identify checks it (more
    than MAX_JOBS refused, not cut); ``workers``, its old name, warns and works."""
    from blockid.errors import ParameterError
    from blockid.workflows.effort import MAX_JOBS

    pytest.importorskip("distributed")
    records = records[:1]
    with pytest.raises(ParameterError, match=f"jobs={MAX_JOBS + 1} is more worker processes"):
        fit_fleet(records, tmp_path / "a", "arx", ["u"], ["y"], options=ORDERS, jobs=MAX_JOBS + 1)
    with pytest.raises(ParameterError, match="not also workers"):
        fit_fleet(records, tmp_path / "b", "arx", ["u"], ["y"], options=ORDERS, jobs=1, workers=1)
    with pytest.warns(DeprecationWarning, match="now fleet\\(jobs="):
        run = fit_fleet(records, tmp_path / "c", "arx", ["u"], ["y"], options=ORDERS, workers=1)
    assert run.workers == 1 and run.counts()["ok"] == 1
