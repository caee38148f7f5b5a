"""Blocked cross-validation folds: contiguous, covering, never straddling a record."""

import numpy as np
import pytest

from blockid.data import Dataset
from blockid.data.dataset import Experiment
from blockid.data.folds import fold_plan, materialise
from blockid.errors import DataError


def _data(*lengths):
    exps = [Experiment(f"e{i}", np.arange(n, dtype=float), np.arange(n, dtype=float) * 2)
            for i, n in enumerate(lengths)]  # fmt: skip
    return Dataset(["u"], ["y"], None, exps, None)


def _covered(plan, data):
    """Every sample is held back by exactly one fold, and trained on by all the others."""
    for e, exp in enumerate(data.experiments):
        held = np.zeros(exp.n_samples, dtype=int)
        for fold in plan.folds:
            trained = np.zeros(exp.n_samples, dtype=bool)
            for s in fold.test:
                if s.experiment == e:
                    held[s.start : s.stop] += 1
            for s in fold.train:
                if s.experiment == e:
                    trained[s.start : s.stop] = True
            tested = np.zeros(exp.n_samples, dtype=bool)
            for s in fold.test:
                if s.experiment == e:
                    tested[s.start : s.stop] = True
            assert np.array_equal(trained, ~tested)
        assert np.all(held == 1)


@pytest.mark.parametrize("lengths", [(1000,), (400, 400), (700, 300), (100, 200, 300), (50,) * 10])
def test_folds_cover_every_sample_once(lengths):
    data = _data(*lengths)
    plan = fold_plan(data, 4)
    _covered(plan, data)
    assert 2 <= len(plan) <= max(4, len(lengths)) if len(lengths) < 3 else len(plan) <= 4


def test_two_records_are_cut_in_proportion_and_blocks_never_straddle_them():
    plan = fold_plan(_data(600, 200), 4)
    held = [(f.test[0].experiment, f.test[0].start, f.test[0].stop) for f in plan.folds]
    assert held == [(0, 0, 200), (0, 200, 400), (0, 400, 600), (1, 0, 200)]


def test_three_or_more_experiments_leave_one_group_out():
    plan = fold_plan(_data(100, 100, 100, 100, 100, 100), 3)
    assert len(plan) == 3
    assert [[s.experiment for s in f.test] for f in plan.folds] == [[0, 1], [2, 3], [4, 5]]
    assert "leave a group out" in plan.text
    assert "leave one experiment out" in fold_plan(_data(100, 100, 100), 4).text


def test_short_records_get_fewer_folds_and_too_short_ones_an_error():
    assert len(fold_plan(_data(100), 4, min_samples=30)) == 3
    assert len(fold_plan(_data(60), 4, min_samples=30)) == 2  # down to two, not further
    with pytest.raises(DataError, match="too short"):
        fold_plan(_data(40), 4, min_samples=30)
    with pytest.raises(DataError, match="at least 2"):
        fold_plan(_data(1000), 1)


def test_materialise_gives_views_and_the_limit_cuts_the_last_segment():
    data = _data(1000)
    plan = fold_plan(data, 4)
    train = materialise(data, plan.folds[1].train)
    assert [e.n_samples for e in train.experiments] == [250, 500]
    assert np.shares_memory(train.experiments[0].u, data.experiments[0].u)
    assert train.experiments[1].u[0, 0] == 500.0
    cut = materialise(data, plan.folds[1].train, limit=300)
    assert [e.n_samples for e in cut.experiments] == [250, 50]
    assert materialise(data, plan.folds[0].test).experiments[0].name == "e0[0:250]"
