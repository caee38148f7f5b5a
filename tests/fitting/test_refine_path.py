"""``refine=True`` / ``blockid fit --refine`` after key-term RLS: it changes the model,
and the change is the one promised (a lower free-run error), recorded as such.

Key-term RLS minimises the one-step (equation) error: with output noise at 20 dB it
converges to a biased Hammerstein model. The refinement on free-run simulation error
started from it must end at the noise floor.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from blockid.blocks import TwoSegmentPolynomial
from blockid.cli.main import app
from blockid.data import Dataset
from blockid.fitting import fit_model
from blockid.models import Hammerstein, model_from_document

A = [-1.5, 0.7]  # poles 0.75 +- 0.37j


def _plant() -> Hammerstein:
    block = TwoSegmentPolynomial([0.0, 1.0, 0.3, -0.1], [0.0, -0.4, 0.2, 0.05])
    return Hammerstein("u", "y", input_block=block, na=2, nb=2, nk=1, a=A, b=[1.0, 0.4])


@pytest.fixture(scope="module")
def noisy():
    """3000 samples of white input, output noise at 20 dB SNR; and the noise variance."""
    rng = np.random.default_rng(5)
    u = rng.uniform(-1.5, 1.5, 3000)
    y = _plant().simulate(u)[:, 0]
    noise = rng.standard_normal(y.size) * np.std(y) * 0.1
    return u, y + noise, float(np.var(noise))


def free_run_mse(model, u: np.ndarray, y: np.ndarray) -> float:
    """Free run from the first max_lag measured outputs; those samples skipped."""
    lag = model.max_lag
    y_sim = model.simulate(u, y[:lag])[:, 0]
    return float(np.mean((y[lag:] - y_sim[lag:]) ** 2))


ORDERS = dict(na=2, nb=2, nk=1, r1=3)


def test_refine_after_key_term_rls_lowers_the_free_run_error(noisy):
    u, y, noise_var = noisy
    data = Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"])
    plain = fit_model(data, "hammerstein", method="key-term-rls", **ORDERS)
    refined = fit_model(data, "hammerstein", method="key-term-rls", refine=True, **ORDERS)
    assert plain.method == "key-term-rls"
    assert refined.method == "key-term-rls+refine"
    assert refined.settings["started_from"] == "key-term-rls"
    assert refined.metrics_mode == "simulation"
    mse_plain = free_run_mse(plain.model, u, y)
    mse_refined = free_run_mse(refined.model, u, y)
    # measured: 0.32 biased key-term fit vs 0.063 = the noise variance
    assert mse_plain > 3.0 * noise_var
    assert mse_refined < 0.5 * mse_plain
    assert mse_refined < 1.02 * noise_var
    # the refined model is the plant's, the biased one is not
    np.testing.assert_allclose(refined.model.a, A, atol=0.01)
    assert np.max(np.abs(plain.model.a - A)) > 0.05
    # what the result reports is that model's free-run error
    assert refined.estimation_metrics["mse"]["y"] == pytest.approx(mse_refined, rel=1e-9)


def test_cli_refine_writes_the_refined_model(noisy, tmp_path):
    u, y, noise_var = noisy
    path = tmp_path / "noisy.csv"
    pd.DataFrame({"u": u, "y": y}).to_csv(path, index=False)
    base = ["fit", str(path), "-u", "u", "-y", "y", "--structure", "hammerstein"]
    base += ["--method", "key-term-rls", "--na", "2", "--nb", "2", "--nk", "1", "--r1", "3"]
    runner = CliRunner()
    plain = runner.invoke(app, [*base, "--json"])
    refined = runner.invoke(app, [*base, "--refine", "--json"])
    assert plain.exit_code == 0 and refined.exit_code == 0, refined.output
    doc_plain, doc_refined = json.loads(plain.stdout), json.loads(refined.stdout)
    assert doc_plain["estimation"]["method"] == "key-term-rls"
    assert doc_refined["estimation"]["method"] == "key-term-rls+refine"
    assert doc_refined["estimation"]["settings"]["started_from"] == "key-term-rls"
    data = pd.read_csv(path)  # what the command read
    u_csv, y_csv = data["u"].to_numpy(), data["y"].to_numpy()
    mse_plain = free_run_mse(model_from_document(doc_plain), u_csv, y_csv)
    mse_refined = free_run_mse(model_from_document(doc_refined), u_csv, y_csv)
    assert mse_refined < 0.5 * mse_plain
    assert mse_refined < 1.02 * noise_var
    reported = doc_refined["estimation"]["simulation_on_estimation_data"]["mse"]["y"]
    assert reported == pytest.approx(mse_refined, rel=1e-9)
