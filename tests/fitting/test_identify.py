"""identify(): choosing on estimation data only, by free-run simulation."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from blockid import errors
from blockid.blocks import DeadZone
from blockid.cli.main import app
from blockid.data import Dataset
from blockid.fitting.identify import identify
from blockid.models import ARX, Hammerstein

FAST = dict(budget=60.0, max_order=3, max_delay=2, screen_nfev=15, finalists=2)


def dead_zone_record(n=1200, seed=0, noise=0.01):
    plant = Hammerstein("u", "y", input_block=DeadZone(-0.3, 0.3, 1.0, 1.0),
                        na=2, nb=2, nk=1, a=[-1.2, 0.5], b=[1.0, 0.4])  # fmt: skip
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1, 1, n // 4), 4)
    y = plant.simulate(u)[:, 0] + noise * rng.standard_normal(u.size)
    return Dataset.from_arrays(u, y, ["u"], ["y"])


def test_a_dead_zone_plant_gets_a_nonlinear_model_that_beats_the_linear_one():
    data = dead_zone_record()
    result = identify(data, structures=["arx", "hammerstein"], **FAST)
    best = result.selected
    linear = min(s.rmse for s in result.ranked if s.candidate.structure == "arx")
    assert best.candidate.structure == "hammerstein"
    assert best.rmse < 0.5 * linear  # measured about 0.2
    assert best.candidate.options["nk"] == 1
    assert result.on == "estimation" and any("optimistic" in n for n in result.notes)


def test_validation_data_never_change_the_choice():
    data = dead_zone_record()
    val1 = dead_zone_record(seed=1)
    val2 = Dataset.from_arrays(
        val1.experiments[0].u, 10 * val1.experiments[0].y, ["u"], ["y"]
    )  # a wildly different record
    r1 = identify(data, val1, structures=["arx", "hammerstein"], **FAST)
    r2 = identify(data, val2, structures=["arx", "hammerstein"], **FAST)
    assert r1.selected.candidate == r2.selected.candidate
    assert np.array_equal(r1.model.free_parameters(), r2.model.free_parameters())
    assert r1.on == "validation"
    assert r1.simulation.metrics["rmse"]["y"] < r2.simulation.metrics["rmse"]["y"]


def test_parsimony_among_near_ties_and_the_json_document():
    rng = np.random.default_rng(2)
    plant = ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [-0.7]}}, b={"y": {"u": [0.5]}})
    u = rng.standard_normal(1500)
    y = plant.simulate(u)[:, 0] + 0.01 * rng.standard_normal(1500)
    result = identify(Dataset.from_arrays(u, y, ["u"], ["y"]), structures=["arx"], **FAST)
    assert result.selected.candidate.orders() == {"na": 1, "nb": 1, "nk": 1}
    doc = json.loads(json.dumps(result.to_dict(), allow_nan=False))
    assert doc["selected"]["structure"] == "arx"
    assert doc["models"][0]["structure"] == "arx" and doc["search"]["candidates"] > 10
    assert set(doc["selected"]["simulation"]) >= {"rmse", "fit_percent"}


def test_bad_requests():
    data = dead_zone_record(300)
    with pytest.raises(errors.ParameterError, match="unknown"):
        identify(data, structures=["narx"])
    with pytest.raises(errors.ParameterError, match="budget"):
        identify(data, budget=0)


def test_cli_refuses_overlapping_ranges_and_writes_the_model(tmp_path):
    data = dead_zone_record(800)
    path = tmp_path / "d.csv"
    e = data.experiments[0]
    np.savetxt(path, np.column_stack((e.u[:, 0], e.y[:, 0])), delimiter=",", header="u,y",
               comments="")  # fmt: skip
    runner = CliRunner()
    base = ["identify", str(path), "-u", "u", "-y", "y"]
    r = runner.invoke(app, [*base, "--estimation", "0:600", "--validation", "500:800"])
    assert r.exit_code == 2 and "overlap" in r.stderr
    out = tmp_path / "m.json"
    r = runner.invoke(app, [*base, "--estimation", "0:600", "--validation", "600:800",
                            "--structures", "arx", "--budget", "30", "-o", str(out), "--json"])  # fmt: skip
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["selected"]["scored_on"] == "validation"
    assert json.loads(out.read_text())["model"]["structure"] == "arx"


def test_output_error_order_scan_is_carried_to_the_block_structures():
    """The grid around the best ARX orders: na - 1 .. na + 1, nb = na + 1, delays from
    the ARX one down by up to 3. On a plant measured with coloured output noise, the
    scan's output-error fits are scored (stage 'screen') and the block structures are
    screened on the best scanned orders."""
    from scipy.signal import lfilter

    from blockid.fitting.identify import OUTPUT_ERROR, _output_error_orders

    grid = _output_error_orders((4, 5, 2), max_order=4, nfev=7)
    assert [(c.options["na"], c.options["nb"], c.options["nk"]) for c in grid] == [
        (3, 4, 2), (4, 5, 2), (3, 4, 1), (4, 5, 1), (3, 4, 0), (4, 5, 0),
    ]  # fmt: skip
    assert all(c.structure == OUTPUT_ERROR and c.options["max_nfev"] == 7 for c in grid)
    rng = np.random.default_rng(3)
    u = np.repeat(rng.uniform(-1, 1, 500), 3)
    noise = np.convolve(rng.standard_normal(u.size), np.ones(8) / 8, mode="same")
    y = lfilter([0.0, 0.0, 0.2, 0.3, 0.1], [1.0, -1.5, 0.7], u) + 0.05 * noise
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    result = identify(data, structures=["arx", "output-error", "hammerstein"], **FAST)
    scores = result.ranked + result.rejected
    arx = min((s for s in scores if s.candidate.structure == "arx"), key=lambda s: s.rmse)
    a = arx.candidate.options
    scan = _output_error_orders((a["na"], a["nb"], a["nk"]), 3, 15)
    assert a["nk"] >= 1 and any(c.options["nk"] < a["nk"] for c in scan)
    assert all(c in [s.candidate for s in scores] for c in scan)  # every scan fit scored
    from blockid.fitting.identify import _ranked

    o = _ranked([s for s in scores if s.candidate in scan], 0.02)[0].candidate.options
    hammerstein = [s.candidate.options for s in scores if s.candidate.structure == "hammerstein"]
    from blockid.fitting.registry import STRUCTURES

    nk = max(o["nk"], STRUCTURES["hammerstein"].min_delay)
    assert any((h["na"], h["nk"]) == (o["na"], nk) for h in hammerstein)


def test_the_richer_nonlinearity_grows_while_the_hold_out_improves():
    """_grow steps the degree by 2 while each step lowers the hold-out RMSE by more than
    the tie; it stops at the first step that does not (here r2 = 9 is not better than
    7) and never goes above 9."""
    from blockid.fitting.identify import Candidate, Score, _grow

    class FakeSearch:
        def __init__(self, rmse):
            self.rmse, self.tried = rmse, []

        def left(self):
            return 100.0

        def tell(self, *args):
            pass

        def run(self, candidate, data, stage):
            self.tried.append(candidate.options["r2"])
            score = Score(candidate, stage=stage)
            score.rmse = self.rmse[candidate.options["r2"]]
            return score

    winner = Score(Candidate("wiener", {"na": 2, "nb": 2, "nk": 1, "r2": 3}), stage="final")
    winner.rmse = 1.0
    search = FakeSearch({5: 0.8, 7: 0.5, 9: 0.499})
    best = _grow(winner, search, None, 0.02)
    assert search.tried == [5, 7, 9] and best.candidate.options["r2"] == 7
    search = FakeSearch({5: 0.99, 7: 0.1})
    assert _grow(winner, search, None, 0.02) is winner and search.tried == [5]
