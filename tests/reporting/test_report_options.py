"""Every option of ``blockid report``, off its default, reaches the library.

As ``tests/cli/test_every_command_option.py`` does for the other commands: the command
runs on a small record with :func:`~blockid.workflows.compare_structures` recorded and
:func:`~blockid.reporting.build_report` replaced by a recorder (the report itself is
tested in ``test_report.py``). An option of ``report`` without a check fails here.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
import typer
from typer.testing import CliRunner

import blockid.reporting
import blockid.workflows
from blockid.cli._options import cli_options
from blockid.models import ARX

N, DT = 240, 0.5


def _plant(u: str, y: str) -> ARX:
    return ARX([u], [y], na=2, nb=2, nk=1, a={y: {y: [-1.2, 0.35]}}, b={y: {u: [1.0, 0.4]}})


@pytest.fixture
def csv(tmp_path) -> Path:
    rng = np.random.default_rng(3)
    u, u2 = rng.uniform(-1, 1, (2, N))
    frame = pd.DataFrame(
        {
            "t": np.arange(N) * DT,
            "e": ["a"] * (N // 2) + ["b"] * (N - N // 2),
            "u": u,
            "u2": u2,
            "y": _plant("u", "y").simulate(u)[:, 0] + 0.01 * rng.standard_normal(N),
            "y2": _plant("u2", "y2").simulate(u2)[:, 0] + 0.01 * rng.standard_normal(N),
        }
    )
    path = tmp_path / "data.csv"
    frame.to_csv(path, index=False)
    return path


@pytest.fixture
def calls(monkeypatch) -> dict[str, list]:
    seen: dict[str, list] = {}
    real = blockid.workflows.compare_structures

    def compare(*args: Any, **kwargs: Any) -> Any:
        seen.setdefault("compare", []).append((args, kwargs))
        return real(*args, **kwargs)

    def build(**kwargs: Any) -> str:
        seen.setdefault("build", []).append(kwargs)
        return "<!DOCTYPE html>\n<p>report</p>\n"

    monkeypatch.setattr(blockid.workflows, "compare_structures", compare)
    monkeypatch.setattr(blockid.reporting, "build_report", build)
    return seen


class Run:
    def __init__(self, app: typer.Typer, csv: Path, calls: dict[str, list]) -> None:
        self.app, self.csv, self.calls = app, csv, calls
        self.out = csv.parent / "report.html"

    def __call__(
        self, *args: Any, code: int = 0, out: bool = True, data: Path | None = None
    ) -> Any:
        base = ["report", str(data or self.csv), "-u", "u", "-y", "y", "--estimation", "0:160",
                "--validation", "160:240", "--structures", "arx"]  # fmt: skip
        extra = ["-o", str(self.out)] if out else []
        result = CliRunner().invoke(self.app, [*base, *map(str, args), *extra])
        assert result.exit_code == code, result.output
        return result

    def compared(self) -> tuple[Any, Any, dict[str, Any]]:
        assert len(self.calls["compare"]) == 1
        (est, val), kwargs = self.calls["compare"][0]
        return est, val, kwargs

    def built(self) -> dict[str, Any]:
        assert len(self.calls["build"]) == 1
        return self.calls["build"][0]


def inputs(run: Run) -> None:
    run("-u", "u2")
    est, val, _ = run.compared()
    assert est.inputs == val.inputs == ("u", "u2")


def outputs(run: Run) -> None:
    run("-y", "y2")
    est, val, _ = run.compared()
    assert est.outputs == val.outputs == ("y", "y2")


def estimation(run: Run) -> None:
    run("--estimation", "20:100")
    est, val, _ = run.compared()
    assert est.n_samples == 80 and val.n_samples == 80
    assert run.built()["estimation_range"] == "20:100"


def validation(run: Run) -> None:
    run("--validation", "200:240")
    est, val, _ = run.compared()
    assert val.n_samples == 40 and run.built()["validation_range"] == "200:240"
    assert run.built()["data"].n_samples == N  # the whole record for the overview


def structures(run: Run) -> None:
    run("--structures", "arx,output-error", "--na", "2", "--nb", "2", "--nk", "1",
        "--max-nfev", "3")  # fmt: skip
    _, _, kwargs = run.compared()
    assert kwargs["structures"] == ["arx", "output-error"]
    assert kwargs["options"]["max_nfev"] == "3"  # a generated estimator flag arrives


def method(run: Run) -> None:
    run("--method", "rls")
    _, _, kwargs = run.compared()
    assert kwargs["method"] == "rls"
    assert kwargs["options"]["record_history"] is True  # trajectories for the report
    assert kwargs["options"]["standard_errors"] is True  # and confidence bands


def out(run: Run) -> None:
    target = run.csv.parent / "elsewhere.html"
    run("-o", target, out=False)
    assert target.read_text().startswith("<!DOCTYPE html>")


def ts(run: Run) -> None:
    untimed = run.csv.parent / "untimed.csv"  # no time column to disagree with
    pd.read_csv(run.csv).drop(columns="t").to_csv(untimed, index=False)
    run("--ts", "0.25", data=untimed)
    est, _, _ = run.compared()
    assert est.sampling_time == 0.25


def time_column(run: Run) -> None:
    run("--time-column", "t")
    est, _, _ = run.compared()
    assert est.sampling_time == DT


def experiment_column(run: Run) -> None:
    run("--experiment-column", "e", "--estimation", "0:80", "--validation", "80:120")
    est, _, _ = run.compared()
    assert est.n_experiments == 2


def force(run: Run) -> None:
    run.out.write_text("old")
    refused = run(code=2)
    assert "exists; pass --force" in refused.output and run.out.read_text() == "old"
    assert "compare" not in run.calls  # refused before any work
    run("--force")
    assert run.out.read_text().startswith("<!DOCTYPE html>")


def json_out(run: Run) -> None:
    doc = json.loads(run("--json").stdout)
    assert doc["report"] == str(run.out) and doc["bytes"] == run.out.stat().st_size
    assert doc["models"][0]["structure"] == "arx"


def quiet(run: Run) -> None:
    """On a terminal the report shows its progress on stderr; ``--quiet`` shows none,
    and the report is written either way."""
    import io
    import sys
    from unittest import mock

    from rich.console import Console

    from blockid.cli import _common

    class OnATerminal:
        class stderr:
            @staticmethod
            def isatty() -> bool:
                return True

        def __getattr__(self, name: str) -> Any:
            return getattr(sys, name)

    def shown(*args: str) -> str:
        text = io.StringIO()
        console = Console(file=text, force_terminal=True, width=200)
        with mock.patch.object(_common, "sys", OnATerminal()):
            with mock.patch.object(_common, "stderr", console):
                run(*args, "--force")
        assert run.out.exists()
        return text.getvalue()

    text = shown()
    assert "comparing the structures" in text and "writing the report" in text, text
    assert shown("--quiet") == ""
    assert shown("-q") == ""


CHECKS: dict[str, Callable[[Run], None]] = {
    f.__name__: f
    for f in (
        inputs,
        outputs,
        estimation,
        validation,
        structures,
        method,
        out,
        ts,
        time_column,
        experiment_column,
        force,
        json_out,
        quiet,
    )  # fmt: skip
}


def _own_options(app: typer.Typer) -> list[str]:
    command = typer.main.get_command(app).commands["report"]
    generated = {o.name for o in cli_options()}
    return [
        p.name for p in command.params if p.param_type_name == "option" and p.name not in generated
    ]


def test_every_report_option_has_a_check(report_app):
    assert sorted(_own_options(report_app)) == sorted(CHECKS)


@pytest.mark.parametrize("option", sorted(CHECKS))
def test_report_option_off_its_default_arrives(option, report_app, csv, calls):
    CHECKS[option](Run(report_app, csv, calls))
