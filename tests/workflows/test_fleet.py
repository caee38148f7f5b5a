""":func:`blockid.workflows.fleet.fit_fleet` on a 2-worker cluster (the command:
``tests/cli/test_fleet_cli.py``).

Twenty small ARX records, one corrupt (a non-numeric cell): 19 model files and one
error row; a rerun writes nothing; ``force`` rewrites; every model equals the fit of its
record alone. One local cluster serves the module (its start-up is most of the time);
the default path, a cluster started by the call itself, runs once on two records.
"""

from __future__ import annotations

import pandas as pd
import pytest

from blockid.data import read_data
from blockid.fitting import fit_model
from blockid.models import load_model
from blockid.workflows.fleet import fit_fleet

from reference import CORRUPT, FLEET_ORDERS


def _mtimes(folder):
    return {p.name: p.stat().st_mtime_ns for p in folder.glob("loop*.json")}


def test_a_fleet_run_rerun_and_forced_run(records, cluster, tmp_path):
    out = tmp_path / "models"
    run = fit_fleet(records, out, "arx", ["u"], ["y"], options=FLEET_ORDERS, scheduler=cluster)
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
        alone = fit_model(read_data([path], ["u"], ["y"]), "arx", **FLEET_ORDERS)
        saved = load_model(out / f"{path.stem}.json")
        assert saved.to_dict() == alone.model.to_dict()
        assert row["rmse_y"] == alone.estimation_metrics["rmse"]["y"]
        assert row["fit_percent_y"] == alone.estimation_metrics["fit_percent"]["y"]

    before = _mtimes(out)
    again = fit_fleet(records, out, "arx", ["u"], ["y"], options=FLEET_ORDERS, scheduler=cluster)
    assert again.counts() == {"ok": 0, "error": 1, "skipped": 19}
    assert _mtimes(out) == before  # no model file rewritten
    skipped = [r for r in again.rows if r["status"] == "skipped"]
    assert [r["rmse_y"] for r in skipped] == [r["rmse_y"] for r in run.rows if r["status"] == "ok"]

    forced = fit_fleet(
        records, out, "arx", ["u"], ["y"], options=FLEET_ORDERS, scheduler=cluster, force=True
    )
    assert forced.counts() == {"ok": 19, "error": 1, "skipped": 0}
    after = _mtimes(out)
    assert after.keys() == before.keys()
    assert all(after[name] != before[name] for name in before)


def test_a_cluster_of_its_own(records, tmp_path):
    """The default: a local cluster of ``jobs`` processes, started and closed here."""
    pytest.importorskip("distributed")
    run = fit_fleet(records[:2], tmp_path, "arx", ["u"], ["y"], options=FLEET_ORDERS, jobs=1)
    assert run.workers == 1 and run.counts()["ok"] == 2


def test_jobs_is_identify_s_name_checked_alike_and_workers_still_works(records, tmp_path):
    """One name for the worker processes: ``jobs``, checked as identify checks it (more
    than MAX_JOBS refused, not cut); ``workers``, its old name, warns and works."""
    from blockid.errors import ParameterError
    from blockid.workflows.effort import MAX_JOBS

    pytest.importorskip("distributed")
    records = records[:1]
    with pytest.raises(ParameterError, match=f"jobs={MAX_JOBS + 1} is more worker processes"):
        fit_fleet(
            records, tmp_path / "a", "arx", ["u"], ["y"], options=FLEET_ORDERS, jobs=MAX_JOBS + 1
        )
    with pytest.raises(ParameterError, match="not also workers"):
        fit_fleet(
            records, tmp_path / "b", "arx", ["u"], ["y"], options=FLEET_ORDERS, jobs=1, workers=1
        )
    with pytest.warns(DeprecationWarning, match="now fleet\\(jobs="):
        run = fit_fleet(
            records, tmp_path / "c", "arx", ["u"], ["y"], options=FLEET_ORDERS, workers=1
        )
    assert run.workers == 1 and run.counts()["ok"] == 1
