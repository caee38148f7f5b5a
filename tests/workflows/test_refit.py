"""blockid.workflows.refit: the chosen candidate fitted on all estimation data, held
against what its folds found, refitted longer or refined from a fold's model when it
falls short."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from blockid.data import Dataset
from blockid.workflows.identify import identify

from reference import SMALL, dead_zone_record, scored


def test_a_refit_stopped_short_of_the_cross_validated_score_is_fitted_longer():
    """A refit on all data that stopped at max_nfev and simulates its own data more than
    10 % worse than the candidate's cross-validated score is fitted again with three
    times the evaluations (Silverbox: PNLSS stopped at 150 evaluations at 0.56 mV on its
    own data against 0.22 cross-validated; 245 evaluations reach 0.22)."""
    from blockid.workflows.refit import _refit
    from blockid.workflows.search_space import Candidate

    data = dead_zone_record()
    short = Candidate("hammerstein", {"na": 2, "nb": 2, "nk": 1, "input_block": "dead-zone",
                                      "max_nfev": 1})  # fmt: skip
    notes = []
    first, _ = _refit(short, data, 0.0098, 10, notes)  # 0.0106 on its own data: within 10 %
    assert notes == []
    notes = []
    longer, _ = _refit(short, data, 0.009, 10, notes)  # 0.0106 > 1.1 x 0.009
    assert len(notes) == 1 and "max_nfev = 3" in notes[0]
    own = longer.estimation_metrics["rmse"]["y"]
    assert own < 0.95 * first.estimation_metrics["rmse"]["y"]  # measured 0.00982 vs 0.01057


def test_a_refit_far_short_of_the_cross_validated_score_is_refused_whatever_stopped_it():
    """Own-data error more than twice the cross-validated one after every retry: the
    refit did not find what the folds found (Bouc-Wen: 164 um against 15 um, stopped by
    ftol at its linear start), so it is refused with the numbers, whatever stopped it;
    identify then fits the next candidate."""
    from blockid.errors import EstimationError
    from blockid.workflows.refit import REFIT_FAILED, _fell_short, _refit
    from blockid.workflows.search_space import Candidate

    data = dead_zone_record()
    converged = Candidate("hammerstein", {"na": 2, "nb": 2, "nk": 1, "input_block": "dead-zone",
                                          "max_nfev": 30})  # fmt: skip
    fit, own = _refit(converged, data, 0.0098, 10, [])
    assert "max_nfev" not in str(fit.settings.get("stop_reason"))  # it converged
    assert own == pytest.approx(fit.estimation_metrics["rmse"]["y"], rel=0.05)
    with pytest.raises(EstimationError, match="did not find what the folds found"):
        _fell_short(fit, own, own / 2.5, REFIT_FAILED)
    _fell_short(fit, own, own / 1.5, REFIT_FAILED)  # within the factor: no error


def test_when_every_refit_falls_short_the_first_is_returned_with_a_note():
    """The refusal must not turn a search into an error: with the factor set so that every
    refit falls short, the best candidate's refit comes back, said so in the notes."""
    data = dead_zone_record(600)
    result = identify(data, structures=["hammerstein"], effort=SMALL, jobs=1, refit_failed=1e-9)
    refused = [n for n in result.notes if "did not find what the folds found" in n]
    assert refused[0].startswith(result.selected.candidate.label)  # the first one tried
    assert result.selected.candidate.structure == "hammerstein"
    assert any("every candidate's refit failed" in n for n in result.notes)
    assert sum("did not find what the folds found" in n for n in result.notes) >= 2


def test_a_refit_worse_than_a_start_from_a_folds_model_is_replaced(monkeypatch):
    """The refit on all data is one start of a nonconvex fit; the folds' models refined
    on all data are others, and the lowest free-run error on the estimation data wins.
    Here the direct fit is made to stop after one evaluation: a warm start replaces it,
    with a note and the numbers in the JSON."""
    import json

    from blockid.workflows import refit as module

    real = module._refit

    def stunted(candidate, data, cv_rmse, n_init, notes):
        return real(candidate.with_options(max_nfev=1), data, math.inf, n_init, notes)

    monkeypatch.setattr(module, "_refit", stunted)
    data = dead_zone_record(600)
    result = identify(data, structures=["hammerstein"], effort=SMALL, jobs=1)
    warm = result.search["warm_starts"][0]
    assert warm["chosen"].startswith("the model fitted without fold")
    direct, *starts = warm["starts"]
    assert direct["start"] == "the direct fit"
    assert len(starts) == len(result.search["folds"])  # SMALL allows 4, 3 folds
    # chosen by the free run from every fold's start, the search's geometry
    best = min(starts, key=lambda s: s["fold_starts_rmse"])
    assert warm["chosen"] == best["start"] and best["fold_starts_rmse"] == warm["fold_starts_rmse"]
    assert warm["fold_starts_rmse"] < 0.5 * direct["fold_starts_rmse"]
    note = next(n for n in result.notes if "refined on all of them from its models" in n)
    assert note.endswith(f"{warm['chosen']} is returned")
    assert result.fit.settings["initial"] == warm["chosen"]
    own = result.fit.model.simulate(data.experiments[0].u)[:, 0] - data.experiments[0].y[:, 0]
    assert np.sqrt(np.mean(own[10:] ** 2)) < 0.02  # the plant's noise is 0.01
    json.dumps(result.to_dict(), allow_nan=False)
    # the warm starts in two workers (the direct fit stays here): the same model, bit for bit
    two = identify(data, structures=["hammerstein"], effort=SMALL, jobs=2)
    assert two.search["warm_starts"] == result.search["warm_starts"]
    assert np.array_equal(two.fit.model.free_parameters(), result.fit.model.free_parameters())


def test_least_squares_is_refitted_once():
    data = dead_zone_record(600)
    result = identify(data, structures=["arx"], effort=SMALL, jobs=1)
    refit = [s for s in result.search["stages"] if s["stage"] == "refit"]
    assert [s["fits"] for s in refit] == [1] and result.search["warm_starts"] == []


EMPS = Path(__file__).parents[2] / ".." / "shared" / "data" / "emps" / "DATA_EMPS.csv"


@pytest.mark.benchdata
@pytest.mark.skipif(not EMPS.exists(), reason="EMPS data (../shared/data) absent")
def test_on_emps_a_start_from_a_folds_model_finds_what_the_direct_refit_misses():
    """The real record of the fault: the chosen block state space (a dead zone in the
    loop) fitted on all 24 841 samples stalls at 10.1 mm on its own data, while the
    folds reached 5.2 mm on data they never saw; refined on all data from the model
    fitted without fold 1 it reaches 3.0 mm (and tests 3.4 mm on DATA_EMPS_PULSES
    against the published linear model's 5.53)."""
    import pandas as pd

    from blockid.data.folds import fold_plan
    from blockid.workflows.refit import _final_fit, _segment_rmse, _Start
    from blockid.workflows.search_space import Candidate

    frame = pd.read_csv(EMPS)
    data = Dataset.from_arrays(frame["vir"].to_numpy(), frame["qm"].to_numpy(), ["vir"], ["qm"])
    # as the standard search chose it: a candidate of the block state-space stage
    cand = Candidate("block-state-space", {"nx": 2, "loop_block": "dead-zone", "max_nfev": 30})
    plan = fold_plan(data, 3)  # a long record: 3 folds; the search's 50 samples
    parts = tuple(s for f in plan.folds for s in f.test)
    direct = _final_fit(data, _Start(cand, None, None, 50, 0.0051))
    warm = _final_fit(data, _Start(cand, plan.folds[0], None, 50, 0.0051, parts))
    assert not direct.reason and not warm.reason
    # measured 0.0101 against 0.0030 over the whole record; from the folds' starts (the
    # comparison identify makes) 0.0085 against 0.0032
    assert direct.rmse > 0.008 and warm.rmse < 0.5 * direct.rmse
    assert warm.segment_rmse < 0.5 * _segment_rmse(direct.fit.model, data, parts, 50)


def test_a_warm_start_replaces_the_direct_fit_only_when_better_by_more_than_the_tie():
    """Silverbox: a warm start 0.12 % better than the direct fit from the folds' starts
    tested 0.563 mV on the arrow (extrapolation) against the direct fit's 0.396; within
    the search's tie the direct fit stays, beyond it the warm start wins."""
    from dataclasses import dataclass
    from types import SimpleNamespace

    from blockid.workflows.refit import REFIT_FAILED, _final, _Started

    @dataclass
    class Fit:
        settings: dict

    fits = {name: Fit({"who": name}) for name in ("direct", "warm")}

    def search(warm_error):
        results = [
            ("the direct fit", _Started(fits["direct"], 1.0, 1.0)),
            ("the model fitted without fold 1", _Started(fits["warm"], 0.5, warm_error)),
        ]
        return SimpleNamespace(final_fits=lambda score: results, tie=0.02,
                               refit_failed=REFIT_FAILED)  # fmt: skip

    score = scored("hammerstein", [1.0, 1.0, 1.0], max_nfev=30)
    near = 1.0 / 1.019  # 1.9 % better: within the tie
    fit, info = _final(search(near), score, notes := [])
    assert fit is fits["direct"] and info["chosen"] == "the direct fit" and notes == []
    fit, info = _final(search(1.0 / 1.021), score, notes := [])
    assert fit.settings == {"who": "warm", "initial": "the model fitted without fold 1"}
    assert info["chosen"] == "the model fitted without fold 1" and len(notes) == 1


def test_warm_starts_begin_beyond_the_slack_and_come_from_the_best_folds(monkeypatch):
    """The refit's own-data error is held against the folds' pooled error: within
    REFIT_SLACK of it the direct fit stands alone; beyond it the candidate is refined
    from its models of its ``warm_starts`` best folds (by held-back error), not others."""
    from dataclasses import replace

    from blockid.workflows import refit as module
    from blockid.workflows.refit import REFIT_SLACK, _fold_rmse

    data = dead_zone_record(600)
    effort = replace(SMALL, warm_starts=1)
    options = dict(structures=["hammerstein"], effort=effort, jobs=1)
    plain = identify(data, **options)
    pooled = _fold_rmse(plain.selected)
    real = module._refit

    def reporting(factor):
        def refit(candidate, data, cv_rmse, n_init, notes):
            fit, _ = real(candidate, data, cv_rmse, n_init, notes)
            return fit, factor * pooled  # the own-data error the trigger reads

        return refit

    monkeypatch.setattr(module, "_refit", reporting(0.98 * REFIT_SLACK))
    assert identify(data, **options).search["warm_starts"] == []
    monkeypatch.setattr(module, "_refit", reporting(1.02 * REFIT_SLACK))
    warm = identify(data, **options).search["warm_starts"][0]
    (_, start) = [s["start"] for s in warm["starts"]]
    relative = [f.relative for f in plain.selected.folds]
    best = int(np.argmin(relative))
    assert relative.count(relative[best]) == 1 and max(relative) > relative[best]
    assert start == f"the model fitted without {plain.search['folds'][best]['name']}"
