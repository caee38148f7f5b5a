"""``blockid export`` (cli/export.py): the module it writes reproduces ``blockid
simulate``, SciPy's transfer functions as JSON, --force, and its refusals."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import typer
from typer.testing import CliRunner

from blockid.blocks import (
    Backlash,
)
from blockid.cli.export import export
from blockid.models import (
    BacklashModel,
    save_model,
)
from plants_for_options import PLANTS, record

from reference import _load


# ----------------------------------------------------------------------------- command
def _app() -> typer.Typer:
    app = typer.Typer()
    app.command("export")(export)

    @app.callback()
    def _root() -> None:
        """Test root."""

    return app


def test_export_command_reproduces_blockid_simulate(tmp_path):
    from blockid.cli.main import app as blockid
    from blockid.fitting import fit_model

    plant = PLANTS["hammerstein-wiener"]()
    data = record(plant, 400, snr_db=40.0, seed=3, mean=0.2)
    fit = fit_model(data, "hammerstein-wiener", na=2, nb=2, nk=1, r1=2, r2=2, max_nfev=10)
    model_file = save_model(fit.model, tmp_path / "hw.json", fit.estimation_record())
    validation = record(plant, 300, snr_db=40.0, seed=4, mean=0.2)
    validation.to_frame().to_csv(tmp_path / "val.csv", index=False)

    runner = CliRunner()
    out = tmp_path / "hw_model.py"
    result = runner.invoke(_app(), ["export", str(model_file), "--to", "python", "-o", str(out)])
    assert result.exit_code == 0, result.output
    result = runner.invoke(
        blockid,
        ["simulate", str(model_file), str(tmp_path / "val.csv"), "--out", str(tmp_path / "s.csv")],
    )
    assert result.exit_code == 0, result.output
    table = pd.read_csv(tmp_path / "s.csv")
    e = validation.experiments[0]
    module = _load(out)
    got = module.simulate(table["u"].to_numpy(), table["y"].to_numpy()[: fit.model.max_lag])
    np.testing.assert_allclose(got[:, 0], table["y_sim"].to_numpy(), rtol=0, atol=1e-10)
    np.testing.assert_allclose(got, fit.model.simulate(e.u, e.y[:2]), atol=1e-10)

    again = runner.invoke(_app(), ["export", str(model_file), "-o", str(out)])
    assert again.exit_code == 2 and "--force" in again.output
    forced = runner.invoke(_app(), ["export", str(model_file), "-o", str(out), "--force"])
    assert forced.exit_code == 0


def test_export_command_scipy_json_and_errors(tmp_path):
    from scipy import signal

    model = PLANTS["wiener-hammerstein"]()
    model_file = save_model(model, tmp_path / "wh.json")
    runner = CliRunner()
    result = runner.invoke(_app(), ["export", str(model_file), "--to", "scipy-json"])
    assert result.exit_code == 0, result.output
    doc = json.loads(result.output)
    for tf, block in zip(doc["transfer_functions"], model.linear_blocks, strict=True):
        _, (step,) = signal.dstep(signal.dlti(tf["num"], tf["den"], dt=True), n=20)
        np.testing.assert_allclose(step[:, 0], block.simulate(np.ones(20)), atol=1e-12)
    bad = runner.invoke(_app(), ["export", str(model_file), "--to", "matlab"])
    assert bad.exit_code == 2 and "--to must be one of" in bad.output
    missing = runner.invoke(_app(), ["export", str(tmp_path / "none.json")])
    assert missing.exit_code == 2 and "does not exist" in missing.output


def test_backlash_model_with_fitted_shape_round_trips_through_the_file(tmp_path):
    model = BacklashModel(
        "u", "y", input_block=Backlash(0.9, 0.8, 1.1, 0.85), na=2, nb=1, nk=1, a=[-1.0, 0.17]
    )
    u = 5 * np.sin(np.linspace(0, 20, 400))
    model_file = save_model(model, tmp_path / "b.json")
    out = tmp_path / "b.py"
    assert CliRunner().invoke(_app(), ["export", str(model_file), "-o", str(out)]).exit_code == 0
    module = _load(out)
    y0 = model.simulate(u)[:2]
    np.testing.assert_allclose(module.simulate(u, y0), model.simulate(u, y0), atol=1e-10)
