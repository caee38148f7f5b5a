"""One report of the built-in example, made once through the command line and shared."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

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
@dataclass
class Compared:
    data: object
    est: object
    val: object
    result: object
    html: str


@pytest.fixture(scope="session")
def compared() -> Compared:
    """ARX and Hammerstein models of the example, fitted with standard errors, and the
    report of them (library level, no provenance)."""
    from blockid.data import Dataset
    from blockid.reporting import build_report
    from blockid.workflows import compare_structures
    from blockid.workflows.examples import example_record

    record = example_record("electrohydraulic")
    data = Dataset.from_frame(record.frame, ["current"], ["velocity"], time_column="t")
    est, val = data.select(0, 1100), data.select(1100, 2200)
    options = dict(na=3, nb=3, nk=8, standard_errors=True)
    result = compare_structures(est, val, ["arx", "hammerstein"], options=options)
    assert all(m.fit is not None for m in result.models)
    html = build_report(compare=result, data=data, estimation=est, validation=val,
                        estimation_range="0:1100", validation_range="1100:2200")  # fmt: skip
    return Compared(data, est, val, result, html)
