"""``refine_from``: a model fitted on part of a record, refined on all of it (identify's
warm starts). It must keep the model's form, end where a fit on all the data ends when
both start near the same optimum, and record what ``fit_model`` records (ranges, checks)
on the data it was refined on, not on the part the start saw."""

from __future__ import annotations

import numpy as np
import pytest

from blockid.blocks import DeadZone, Polynomial
from blockid.data import Dataset
from blockid.errors import ParameterError
from blockid.fitting import fit_model
from blockid.fitting.dispatch import refine_from
from blockid.models import Hammerstein
from blockid.models.block_state_space import BlockStateSpace

PLANT = Hammerstein("u", "y", input_block=DeadZone(-0.3, 0.3, 1.0, 1.0),
                    na=2, nb=2, nk=1, a=[-1.2, 0.5], b=[1.0, 0.4])  # fmt: skip


def _record(n=1200, seed=0, noise=0.0, scale=1.0):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-scale, scale, n // 4), 4)
    y = PLANT.simulate(u)[:, 0] + noise * rng.standard_normal(u.size)
    return Dataset.from_arrays(u, y, ["u"], ["y"])


def _part(data, stop):
    e = data.experiments[0]
    return Dataset.from_arrays(e.u[:stop, 0], e.y[:stop, 0], ["u"], ["y"])


OPTIONS = {"na": 2, "nb": 2, "nk": 1, "input_block": "dead-zone", "max_nfev": 100}


def test_a_chain_fitted_on_a_part_and_refined_on_all_recovers_the_plant():
    data = _record()
    start = fit_model(_part(data, 300), "hammerstein", max_nfev=3,
                      **{k: v for k, v in OPTIONS.items() if k != "max_nfev"})  # fmt: skip
    fit = refine_from(start.model, data, "hammerstein", **OPTIONS)
    assert type(fit.model) is Hammerstein and fit.model.na == 2 and fit.model.nk == 1
    assert fit.settings["initial"] == "given model"
    assert fit.model.parameters["a"] == pytest.approx([-1.2, 0.5], abs=1e-6)
    assert fit.estimation_metrics["rmse"]["y"] < 1e-6
    # the ranges are those of all the data, not of the part the start saw
    assert fit.model.ranges == fit.model.with_ranges([(e.u, e.y) for e in data.experiments]).ranges


def test_a_chain_started_near_the_optimum_ends_where_a_fit_on_all_data_ends():
    data = _record(noise=0.02, seed=3)
    direct = fit_model(data, "hammerstein", **OPTIONS)
    start = fit_model(_part(data, 600), "hammerstein", **OPTIONS)
    warm = refine_from(start.model, data, "hammerstein", **OPTIONS)
    u = data.experiments[0].u
    assert np.allclose(warm.model.simulate(u), direct.model.simulate(u), atol=1e-5)


def test_an_option_that_only_shaped_the_start_is_ignored_and_arx_is_refused():
    data = _record()
    start = fit_model(data, "hammerstein", **OPTIONS)
    fit = refine_from(start.model, data, "hammerstein", **OPTIONS, center=False)
    assert fit.model.input_block.kind == "dead-zone"
    with pytest.raises(ParameterError, match="arx is fitted by batch"):
        refine_from(start.model, data, "arx", na=2, nb=2, nk=1)


def test_a_state_space_model_refined_from_a_part_matches_the_fit_on_all_data():
    from blockid.models.state_space import StateSpace

    plant = StateSpace(["u"], ["y"], A=[[0.9, 0.2], [-0.2, 0.8]], B=[[1.0], [0.5]],
                       C=[[1.0, 0.0]], D=[[0.0]])  # fmt: skip
    rng = np.random.default_rng(1)
    u = rng.standard_normal(1500)
    y = plant.simulate(u)[:, 0] + 0.05 * rng.standard_normal(u.size)
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    direct = fit_model(data, "state-space", nx=2)
    start = fit_model(_part(data, 500), "state-space", nx=2)
    warm = refine_from(start.model, data, "state-space", nx=2)
    assert np.allclose(np.sort_complex(warm.model.poles()), np.sort_complex(direct.model.poles()),
                       atol=1e-5)  # fmt: skip
    assert warm.metrics_mode == "simulation" and warm.n_samples == 1500


def test_a_block_state_space_model_records_the_ranges_of_all_the_data():
    """The start saw inputs within +-0.5, the whole record spans +-1: the refined model's
    recorded input range (normalised) and loop range are those of the whole record."""
    rng = np.random.default_rng(2)
    u = np.concatenate([rng.uniform(-0.5, 0.5, 600), rng.uniform(-1, 1, 900)])
    u = np.repeat(u, 2)[: u.size]
    plant = BlockStateSpace(["u"], ["y"], A=[[0.8]], B=[[1.0]], C=[[1.0]], D=[[0.0]],
                            input_blocks=[Polynomial([0.0, 1.0, 0.0, 0.5])])  # fmt: skip
    y = plant.simulate(u)[:, 0] + 0.01 * rng.standard_normal(u.size)
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    options = {"nx": 1, "input_block": "polynomial:degree=3", "max_nfev": 50}
    start = fit_model(_part(data, 600), "block-state-space", **options)
    warm = refine_from(start.model, data, "block-state-space", **options)
    seen = warm.model.normalised_input(data.experiments[0].u)
    assert warm.model.input_range[0] == pytest.approx([seen.min(), seen.max()])
    assert start.model.input_range[0][1] < 0.6 * warm.model.input_range[0][1]
    assert warm.estimation_metrics["fit_percent"]["y"] > 95


def test_an_integrating_chain_keeps_its_integrator():
    from scipy.signal import lfilter

    rng = np.random.default_rng(0)
    u = np.repeat(rng.normal(size=40), 20) + 0.1 * rng.normal(size=800)
    u -= u.mean()
    y = lfilter([0, 0.05], [1, -1.7, 0.7], u)
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    options = {"na": 1, "nb": 1, "nk": 1, "integrator": 1, "max_nfev": 50}
    start = fit_model(_part(data, 400), "output-error", **options)
    warm = refine_from(start.model, data, "output-error", **options)
    assert [b.kind for b in warm.model.blocks][-1] == "integrator"
    assert warm.estimation_metrics["fit_percent"]["y"] > 99


def test_a_model_fitted_degree_by_degree_is_refined_with_its_top_degree_s_limit():
    """identify's warm starts of a climbed polynomial model refine all of its (many)
    parameters: with the climbed degree's limit (``rung_nfev``), not the lower one's."""
    from reference import cubic_state_record

    data = cubic_state_record(600)
    options = dict(nx=2, degree=3, start_degree=2, max_nfev=30, rung_nfev=4)
    start = fit_model(data, "polynomial-state-space", **options).model
    fit = refine_from(start, data, "polynomial-state-space", **options)
    assert fit.settings["max_nfev"] == 4
    assert fit.settings["refinement"]["function_evaluations"] <= 4 + 1


def test_the_direct_term_is_refined_when_feedthrough_is_asked_and_kept_when_not():
    """A linear state space whose direct term D was set wrong (zero) on a plant with one
    (D = 0.5): refined with ``feedthrough=True`` it reaches the noise; without, D stays
    zero and the free-run error stays tens of times the noise."""
    from blockid.models import StateSpace

    plant = StateSpace(["u"], ["y"], [[0.7, 0.2], [-0.2, 0.6]], [[1.0], [0.5]],
                       [[1.0, 0.0]], [[0.5]])  # fmt: skip
    rng = np.random.default_rng(0)
    u = rng.standard_normal(1000)
    y = plant.simulate(u)[:, 0] + 0.01 * rng.standard_normal(u.size)
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    document = fit_model(data, "state-space", nx=2, feedthrough=True).model.to_dict()
    document["D"] = [[0.0]]
    start = StateSpace.from_dict(document)
    on = refine_from(start, data, "state-space", nx=2, feedthrough=True)
    off = refine_from(start, data, "state-space", nx=2, feedthrough=False)
    assert on.estimation_metrics["rmse"]["y"] < 0.012
    assert np.asarray(off.model.D).item() == 0.0
    assert off.estimation_metrics["rmse"]["y"] > 20 * on.estimation_metrics["rmse"]["y"]
