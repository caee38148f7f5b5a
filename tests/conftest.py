from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import matplotlib
import pytest
import typer
from typer.testing import CliRunner

matplotlib.use("Agg")

# Worker processes (identify's pool) import the functions of a test module by its name,
# ``tests.<folder>.<module>`` (``--import-mode=importlib``), and start from this
# process's path: the checkout's root must be on it, as ``python -m pytest`` puts it and
# the ``pytest`` script does not.
_ROOT = str(Path(__file__).resolve().parent.parent)
if _ROOT not in sys.path:
    sys.path.append(_ROOT)


@pytest.fixture
def rng():
    import numpy as np

    return np.random.default_rng(12345)


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    """Twenty small ARX records for ``fleet``, one corrupt (:func:`reference.fleet_records`)."""
    from reference import fleet_records

    return fleet_records(tmp_path_factory.mktemp("logs"))


@pytest.fixture(scope="module")
def cluster():
    """A local dask cluster of two worker processes for the module (its start-up is most of
    the time of the tests that use it): its scheduler's address."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        dashboard_address=":0",
        silence_logs=50,
    ) as running:
        yield running.scheduler_address


#: The report of the built-in example: three structures with paper B's key-term RLS
#: (ARX falls back to least squares), so that it has blocks and parameter trajectories.
ARGS = [
    "-u", "current", "-y", "velocity", "--time-column", "t",
    "--estimation", "0:1100", "--validation", "1100:2200",
    "--structures", "arx,hammerstein,hammerstein-wiener", "--method", "key-term-rls",
    "--na", "3", "--nb", "3", "--nk", "8", "--r1", "3", "--r2", "3",
    "--passes", "60", "--forgetting", "0.98:200,1",
]  # fmt: skip


def cli_app() -> typer.Typer:
    """The blockid app, with ``report`` registered if main.py does not yet."""
    from blockid.cli import main
    from blockid.cli.report import report

    if any(c.name == "report" for c in main.app.registered_commands):
        return main.app
    app = typer.Typer(rich_markup_mode=None)
    app.callback()(lambda: None)
    app.command("report")(report)
    return app


@pytest.fixture(scope="session")
def report_app() -> typer.Typer:
    return cli_app()


@pytest.fixture(scope="session")
def report_args() -> list[str]:
    """The options of the example's report, after DATA."""
    return list(ARGS)


@dataclass
class ExampleReport:
    folder: Path
    data: Path
    path: Path
    html: str
    output: str


@pytest.fixture(scope="session")
def example_report(tmp_path_factory: pytest.TempPathFactory) -> ExampleReport:
    from blockid.workflows.examples import example_record

    folder = tmp_path_factory.mktemp("report")
    data = folder / "arm.csv"
    example_record("electrohydraulic").frame.to_csv(data, index=False)
    path = folder / "report.html"
    result = CliRunner().invoke(cli_app(), ["report", str(data), *ARGS, "-o", str(path)])
    assert result.exit_code == 0, result.output
    return ExampleReport(folder, data, path, path.read_text(encoding="utf-8"), result.output)


# ------------------------------------------------------------------ library level
@pytest.fixture(scope="session")
def hammerstein():
    """The example's Hammerstein model by key-term RLS: ``(data, est, val, result)``."""
    from blockid.data import Dataset
    from blockid.workflows import compare_structures
    from blockid.workflows.examples import example_record

    record = example_record("electrohydraulic")
    data = Dataset.from_frame(record.frame, ["current"], ["velocity"], time_column="t")
    est, val = data.select(*record.estimation), data.select(*record.validation)
    options = dict(na=3, nb=3, nk=8, r1=3, passes=60, forgetting="0.98:200,1")
    result = compare_structures(est, val, ["hammerstein"], method="key-term-rls", options=options)
    assert result.models[0].fit is not None, result.models[0].error
    return data, est, val, result
