"""The cases of issue 11's "Why" list that are not malformed input: a constant output,
a Hammerstein model that is linear, H-RLS on noise-free data, ranges that overlap,
a cyclic network, and the figures of ``fit``, ``simulate`` and ``predict``."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from blockid.blocks import Polynomial
from blockid.blocks.linear import LinearBlock
from blockid.data import Dataset, check_disjoint
from blockid.errors import EstimationError, OrderError, ParameterError
from blockid.evaluation.metrics import fit_percent, json_safe
from blockid.fitting.arx import fit_arx
from blockid.fitting.checks import linear_block_notes
from blockid.models import ARX, Network, save_model
from blockid.models.block import ChainModel
from blockid.models.network import check_wiring

runner = CliRunner()
N = 300


def _app():
    from blockid.cli.main import app

    return app


@pytest.fixture
def constant_output(tmp_path, monkeypatch):
    rng = np.random.default_rng(3)
    t = np.arange(N) * 0.05
    u = rng.standard_normal(N)
    (tmp_path / "const.csv").write_text(
        "t,u,y\n" + "".join(f"{t[k]:.2f},{float(u[k])!r},1.5\n" for k in range(N))
    )
    model = ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [-0.5]}}, b={"y": {"u": [0.2]}})
    save_model(model, tmp_path / "model.json")
    monkeypatch.chdir(tmp_path)
    return tmp_path


FIT = ["fit", "const.csv", "-u", "u", "-y", "y", "--structure", "arx", "--allow-unstable"]


def test_constant_output_fit_json_and_model_file(constant_output):
    r = runner.invoke(_app(), [*FIT, "--json", "-o", "m.json"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    record = doc["estimation"]["one_step_on_estimation_data"]
    assert record["fit_percent"] == {"y": None}
    assert json.loads((constant_output / "m.json").read_text()) == doc


@pytest.mark.parametrize("command", ["simulate", "predict"])
def test_constant_output_simulate_json(constant_output, command):
    r = runner.invoke(_app(), [command, "model.json", "const.csv", "--json"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["metrics"]["fit_percent"] == {"y": None}
    assert any("fit_percent of output 'y' is undefined" in w for w in doc["warnings"])


def test_constant_output_compare_json(constant_output):
    args = ["compare", "const.csv", "-u", "u", "-y", "y", "--estimation", "0:150"]
    r = runner.invoke(_app(), [*args, "--validation", "150:", "--structures", "arx", "--json"])
    assert r.exit_code == 0, r.output
    model = json.loads(r.stdout)["models"][0]
    assert model["simulation"]["fit_percent"] == {"y": None}


def test_fit_percent_undefined_is_nan_and_json_null():
    y = np.full(4, 2.0)
    assert np.isnan(fit_percent(y, y + [0.0, 0.0, 0.0, 1.0])[0])
    assert json.dumps(json_safe({"a": [np.float64("nan"), -np.inf, 1.0]}), allow_nan=False) == (
        '{"a": [null, null, 1.0]}'
    )


def test_nb_zero_for_every_input_is_refused_but_some_zero_is_fine():
    rng = np.random.default_rng(0)
    u = rng.standard_normal((200, 2))
    data = Dataset.from_arrays(u, u[:, 0] + 0.1 * rng.standard_normal(200))
    with pytest.raises(OrderError, match="nb is 0 for every input of output 'y1'") as info:
        fit_arx(data, 1, [[0, 0]], 1)
    assert info.value.parameter == "nb"
    fit_arx(data, 1, [[1, 0]], 1)  # one of two inputs left out: allowed


def test_constant_input_names_the_signal_and_lag():
    rng = np.random.default_rng(0)
    data = Dataset.from_arrays(np.full(200, 0.5), rng.standard_normal(200), ["u"], ["y"])
    with pytest.raises(EstimationError, match=r"u at lag 2 .*input 'u' is constant"):
        fit_arx(data, 1, 2, 1)


def _hrls_data(n):
    plant = ARX(
        ["u1", "u2"],
        ["y"],
        2,
        2,
        1,
        a={"y": {"y": [-1.2, 0.35]}},
        b={"y": {"u1": [1.0, 0.4], "u2": [0.5, -0.2]}},
    )
    u = np.random.default_rng(0).standard_normal((n, 2))
    return Dataset.from_arrays(u, plant.simulate(u), ["u1", "u2"], ["y"])


def test_hrls_on_noise_free_data_is_accepted_when_it_predicts_to_the_floor():
    # one-step MSE ~3e-9 of var(y) against a least-squares optimum of ~1e-31
    result = fit_arx(_hrls_data(1300), 2, 2, 1, method="hierarchical-rls", forgetting=0.95)
    assert result.model.parameter_vector(0) == pytest.approx(
        [-1.2, 0.35, 1, 0.4, 0.5, -0.2], abs=1e-3
    )


def test_hrls_advice_fits_the_forgetting_used():
    with pytest.raises(EstimationError, match="forgetting 0.95 was used") as info:
        fit_arx(_hrls_data(600), 2, 2, 1, method="hierarchical-rls", forgetting=0.95)
    assert "below 1" not in str(info.value)
    with pytest.raises(EstimationError, match="needs a forgetting factor below 1"):
        fit_arx(_hrls_data(600), 2, 2, 1, method="hierarchical-rls", forgetting=1.0)


def test_overlapping_ranges_are_refused():
    check_disjoint("0:100", "100:")
    check_disjoint((200, None), (0, 200))
    with pytest.raises(ParameterError, match=r"overlap \(samples 50:100 are in both\)"):
        check_disjoint("0:100", "50:")
    with pytest.raises(ParameterError, match=r"samples 10: are in both"):
        check_disjoint(":", "10:")


def test_cyclic_network_is_named():
    s1 = ARX(["v2"], ["v1"], 1, 1, 1)
    s2 = ARX(["v1"], ["v2"], 1, 1, 1)
    with pytest.raises(OrderError, match=r"cycle: 'S1' -> v1 -> 'S2' -> v2 -> 'S1'"):
        Network([("S1", s1), ("S2", s2)])
    with pytest.raises(OrderError, match=r"'S' -> y -> 'S'"):
        check_wiring([("S", ["y"], ["y"])])


def _chain(coefficients):
    return ChainModel(
        "u",
        "y",
        [Polynomial(coefficients, constant=False), LinearBlock(1, 1, 1, a=[-0.5], b=[1.0])],
    )


def test_linear_input_block_is_noted_not_refused():
    u = np.random.default_rng(1).uniform(-2, 2, 400)
    data = Dataset.from_arrays(u, np.zeros(400), ["u"], ["y"])
    notes = linear_block_notes(_chain([1.0, 1e-19, 1e-19]), data)
    assert len(notes) == 1 and "input block (polynomial) is linear" in notes[0]
    assert linear_block_notes(_chain([1.0, 0.3, -0.1]), data) == []
    assert linear_block_notes(ARX(["u"], ["y"], 1, 1, 1), data) == []


def test_simulate_and_predict_plot_the_whole_record(constant_output):
    for command, name in (("simulate", "simulation.png"), ("predict", "prediction.png")):
        r = runner.invoke(_app(), [command, "model.json", "const.csv", "--plot", "figs"])
        assert r.exit_code == 0, r.output
        assert (constant_output / "figs" / name).stat().st_size > 1000


def test_fit_figure_title_says_how_much_it_shows():
    from blockid.evaluation import evaluate
    from blockid.plotting.figures import plot_model_output

    model = ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [-0.5]}}, b={"y": {"u": [1.0]}})
    u = np.random.default_rng(0).standard_normal(5000)
    data = Dataset.from_arrays(u, model.simulate(u), ["u"], ["y"])
    fig = plot_model_output(evaluate(model, data))
    assert "all 5000 samples" in fig.axes[0].get_title()
    assert fig.axes[0].lines[0].get_xdata().size == 5000
    fig = plot_model_output(evaluate(model, data), max_samples=1000)
    assert "every 5th of 5000 samples" in fig.axes[0].get_title()


def test_demo_refuses_a_non_empty_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "mine.txt").write_text("keep")
    r = runner.invoke(_app(), ["demo", "--plot", "out"])
    assert r.exit_code == 2 and "not empty" in r.stderr
    assert (tmp_path / "out" / "mine.txt").read_text() == "keep"
