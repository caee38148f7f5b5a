"""One report of the built-in example, made once through the command line and shared."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
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


# ------------------------------------------------------------------ state space
TS = 0.01
#: G(z) = 0.05 (z + 7.8)(z - 0.5) / ((z + 0.999)(z - 0.9)(z - 0.8)): a mode at the
#: Nyquist frequency that decays with a time constant of 1000 samples, and a far zero.
NUM = 0.05 * np.polymul([1.0, 7.8], [1.0, -0.5])
DEN = np.poly([-0.999, 0.9, 0.8])


def _score(structure_method: str, model, est, val, standard_errors: bool):
    from blockid.evaluation.uncertainty import with_standard_errors
    from blockid.evaluation.validate import score_model
    from blockid.fitting.result import FitResult
    from blockid.workflows.compare import ModelScore

    fit = FitResult(model, structure_method, {}, {}, est.n_samples, metrics_mode="simulation")
    if standard_errors:
        fit = with_standard_errors(fit, est)
    simulation, one_step, error = score_model(model, val)
    return ModelScore("state-space", structure_method, fit, simulation, one_step, None, error)


@pytest.fixture(scope="session")
def state_space_report():
    """``(model, result, html)``: the plant :data:`NUM` / :data:`DEN` as an output-error
    state space (no noise model) with its covariance, and the same with a predictor gain
    K (a noise model), scored on 1000 validation samples, in one report."""
    from scipy.signal import tf2ss

    from blockid.data import Dataset
    from blockid.models.state_space import StateSpace
    from blockid.reporting import build_report
    from blockid.workflows.compare import CompareResult

    A, B, C, D = tf2ss(NUM, DEN)
    model = StateSpace(["u"], ["y"], A, B, C, D, sampling_time=TS)
    rng = np.random.default_rng(3)
    u = rng.standard_normal(2000)
    y = model.simulate(u)[:, 0] + 0.01 * rng.standard_normal(u.size)
    data = Dataset.from_arrays(u, y, ["u"], ["y"], sampling_time=TS)
    est, val = data.select(0, 1000), data.select(1000, 2000)
    with_k = model.replace(K=np.full((3, 1), 0.1))
    result = CompareResult([
        _score("simulation-error", model, est, val, True),
        _score("subspace", with_k, est, val, False),
    ])  # fmt: skip
    html = build_report(compare=result, data=data, estimation=est, validation=val,
                        estimation_range="0:1000", validation_range="1000:2000")  # fmt: skip
    return model, result, html
