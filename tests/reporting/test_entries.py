"""The models a report shows (reporting/entries.py): an entry's model and heading, and
when a one-step prediction is the free run itself."""

from types import SimpleNamespace

import numpy as np

from blockid.data import Dataset
from blockid.evaluation import evaluate
from blockid.models import ARX
from blockid.models.state_space import StateSpace
from blockid.reporting.entries import Entry, heading, predicts_by_free_run


def test_an_entry_s_model_is_its_fit_s_and_its_heading_is_escaped():
    entry = Entry("ARX <na=2> & co", "batch", SimpleNamespace(model="m"), None, None)
    assert entry.model == "m"
    assert heading(entry) == "<h3>ARX &lt;na=2&gt; &amp; co</h3>"
    assert Entry("failed", "batch", None, None, None, error="diverged").model is None


def _data(n=200):
    u = np.random.default_rng(0).standard_normal(n)
    return Dataset.from_arrays(u, np.cumsum(u) * 0.1, ["u"], ["y"])


def test_a_state_space_without_a_predictor_gain_predicts_by_its_free_run():
    data = _data()
    model = StateSpace(["u"], ["y"], [[0.5]], [[1.0]], [[1.0]], [[0.0]])
    assert predicts_by_free_run(
        evaluate(model, data, "simulation"), evaluate(model, data, "one-step")
    )
    with_k = model.replace(K=np.array([[0.3]]))
    assert not predicts_by_free_run(
        evaluate(with_k, data, "simulation"), evaluate(with_k, data, "one-step")
    )


def test_an_arx_one_step_prediction_is_not_its_free_run_and_a_missing_one_is_neither():
    data = _data()
    arx = ARX(["u"], ["y"], na=1, nb=1, nk=1, a={"y": {"y": [-0.9]}}, b={"y": {"u": [0.1]}})
    simulation = evaluate(arx, data, "simulation")
    assert not predicts_by_free_run(simulation, evaluate(arx, data, "one-step"))
    assert not predicts_by_free_run(simulation, None)
    assert not predicts_by_free_run(None, simulation)
