"""One report of the built-in example, made once through the command line and shared."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from blockid.evaluation import evaluate
from blockid.workflows.identify import Candidate, IdentifyResult, Score


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


# ------------------------------------------------------------------ identify
LONG_REASON = (
    "its free run from rest strays 22.2 times further from the measured output than its "
    "start and the output's range explain (limit 5) " * 6
).strip()


@pytest.fixture(scope="module")
def identified(compared):
    """An identify result around the example's Hammerstein fit, with an ARX candidate
    in its search and a rejected one whose reason is long."""
    fit = compared.result.models[1].fit
    chosen = Score(Candidate("hammerstein", {"na": 3, "nb": 3, "nk": 8}), stage="finalists",
                   rmse=0.02, fit_percent=75.0, n_parameters=13)  # fmt: skip
    arx = Score(Candidate("arx", {"na": 3, "nb": 3, "nk": 8, "center": True}), stage="linear orders",
                rmse=0.05, fit_percent=40.0, n_parameters=6)  # fmt: skip
    other = Score(Candidate("wiener", {"na": 2, "nb": 2, "nk": 8}), stage="structures",
                  rmse=0.03, fit_percent=60.0, n_parameters=8)  # fmt: skip
    long_label = Candidate("hammerstein-wiener", {"na": 2, "nb": 2, "nk": 10,
                           "input_block": "two-segment-polynomial:degree=3",
                           "output_block": "polynomial:degree=3", "center": False})  # fmt: skip
    rejected = [Score(long_label, stage="nonlinearity", reason=LONG_REASON)]
    return IdentifyResult(
        selected=chosen, fit=fit, ranked=[chosen, other, arx], rejected=rejected,
        simulation=evaluate(fit.model, compared.val, "simulation"),
        one_step=evaluate(fit.model, compared.val, "one-step"), one_step_error=None,
        on="validation", seconds=1.5, holdout="3 contiguous folds (blocked cross-validation)",
        search={"effort": "quick"},
    )  # fmt: skip
