"""blockid.fitting.state_space_refinement: the simulation-error refinement of the state
spaces, its normal equations and its early stopping on held-back tails."""

from __future__ import annotations

import numpy as np
import pytest

from blockid.config import config_context
from blockid.data import Dataset
from blockid.fitting import fit_model
from blockid.fitting.state_space import fit_polynomial_state_space, fit_state_space, subspace

from reference import STATE_SPACES, free_run_error, state_space_record


def test_the_refinement_rejects_a_start_that_explodes_and_says_so():
    """A start whose free run is finite but far off the data (here B scaled by 1e5: the
    squared residual is 1e10 times the output's variance) is the penalty, not a point to
    step from, and an exploding start is refused with the reason."""
    from blockid.errors import EstimationError
    from blockid.fitting.state_space import _normalised
    from blockid.fitting.state_space_refinement import _Problem, refine_state_space

    plant = next(iter(STATE_SPACES.values()))
    data = state_space_record(plant, 300)
    start = fit_state_space(data, nx=plant.nx, refine=False).model
    wild = start.replace(B=start.B * 1e5)
    problem = _Problem(wild, _normalised(data), feedthrough=False)
    theta = np.concatenate([wild.free_parameters()[problem.free], np.zeros(wild.nx)])
    r = problem.residuals(theta)
    assert r is problem.penalty
    with pytest.raises(EstimationError, match="unstable or its simulation explodes"):
        refine_state_space(wild, data, initial_states=[np.zeros(wild.nx)])


@pytest.mark.parametrize("threads", [1, 3])
def test_the_normal_equations_are_the_dense_jacobian_s_on_any_number_of_threads(
    threads,
):
    """``J^T J`` and ``-J^T r``, summed over pieces of two experiments, equal those of
    the whole Jacobian stacked at once; the number of threads that sum the tiles changes
    nothing, bit for bit (several pieces and tiles: ``state_space_rows`` and
    ``tile_columns`` made small)."""
    from blockid.fitting import state_space as ss
    from blockid.fitting import state_space_refinement as sr
    from blockid.fitting import threads as th

    plant = STATE_SPACES["2 in, 2 out, 3 states"]
    from blockid.data.dataset import Experiment

    rec = [state_space_record(plant, 700, seed=s).experiments[0] for s in (0, 1)]
    data = Dataset(list(plant.inputs), list(plant.outputs), None,
                   [Experiment(f"e{i}", r.u, r.y) for i, r in enumerate(rec)])  # fmt: skip
    start = fit_polynomial_state_space(data, nx=3, degree=2, max_nfev=2).model
    sig = ss._normalised(data)
    problem = sr._Problem(start, sig, feedthrough=True)
    x0s = [np.full(3, 0.1), np.full(3, -0.2)]
    theta = np.concatenate([start.free_parameters()[problem.free], *x0s])
    # three pieces per experiment, several tiles
    with config_context(state_space_rows=256, tile_columns=16):
        with th.fit_threads(threads):
            H, g = problem.normal_equations(theta)
        with th.fit_threads(1 if threads > 1 else 2):
            H2, g2 = problem.normal_equations(theta)
    assert np.array_equal(H, H2) and np.array_equal(g, g2)
    assert np.array_equal(H, H.T)
    # the reference: each experiment's whole Jacobian in one piece
    nm, nx = problem.n_model, 3
    kept = np.r_[np.flatnonzero(problem.free), problem.full.size + np.arange(nx)]
    J_all = np.zeros((0, nm + 2 * nx))
    r_all = np.zeros(0)
    for e, (u, y, x0) in enumerate(zip(sig.u, sig.y, x0s, strict=True)):
        out, J = start.jacobian_piece(u, *start._sensitivity_start(x0))
        block = np.zeros((J.shape[0], nm + 2 * nx))
        block[:, :nm] = J[:, kept[:nm]]
        block[:, nm + e * nx : nm + (e + 1) * nx] = J[:, kept[nm:]]
        J_all = np.vstack([J_all, block])
        r_all = np.r_[r_all, (y - out).reshape(-1)]
    assert np.allclose(H, J_all.T @ J_all, rtol=1e-10, atol=1e-9 * np.abs(H).max())
    assert np.allclose(g, -J_all.T @ r_all, rtol=1e-10, atol=1e-9 * np.abs(g).max())


def test_a_record_long_for_its_unknowns_holds_nothing_back():
    """2 000 samples for 9 unknowns (over 100 per unknown): the refinement is the one
    to convergence on everything, bit for bit, and says why."""
    plant = STATE_SPACES["siso, 2 states"]
    data = state_space_record(plant, 2000, seed=4, snr_db=40)
    default = fit_state_space(data, nx=2)
    whole = fit_state_space(data, nx=2, tail_fraction=0.0)
    assert default.settings["refinement"]["tail_fraction"] == 0.0
    assert "nothing held back" in default.settings["refinement"]["early_stopping_off"]
    np.testing.assert_array_equal(default.model.free_parameters(), whole.model.free_parameters())


def test_where_the_tails_get_worse_the_head_fit_s_best_iterate_is_returned():
    """Six states for a two-state plant on 400 samples at 6 dB. The refinement with a
    held-back tail is the refinement of the head alone (the same iterates, bit for
    bit); where the tail error rose again it returns the iterate
    whose free run simulated the tail best: one of the head fit's iterates (each the
    result of a head fit stopped at that many simulations), the best of them all."""
    from blockid.data.folds import Segment, materialise
    from blockid.fitting.state_space import refine_state_space

    plant = STATE_SPACES["siso, 2 states"]
    data = state_space_record(plant, 400, seed=5, snr_db=6)
    start = subspace(data, nx=6).model
    start = start.replace(B=0.7 * start.B)  # a start the refinement first improves
    e = data.experiments[0]
    x0 = [start.initial_state(e.u, e.y[:24])]
    tailed, info = refine_state_space(
        start, data, initial_states=x0, tail_fraction=0.25, patience=None, feedthrough=False
    )
    assert info["tail_mse"] < info["initial_tail_mse"]
    head = materialise(data, [Segment(0, 0, 300)])
    iterates = [
        refine_state_space(
            start, head, initial_states=x0, feedthrough=False, max_nfev=k, tail_fraction=0.0
        )[0]
        for k in range(1, info["function_evaluations"] + 1)
    ]

    def tail_error(model):
        return float(np.mean((model.simulate(e.u, e.y[:24])[300:] - e.y[300:]) ** 2))

    same = [m for m in iterates if np.array_equal(m.free_parameters(), tailed.free_parameters())]
    assert same, "the tailed refinement returned no iterate of the head's refinement"
    assert tail_error(tailed) < tail_error(iterates[-1])


def test_early_stopping_keeps_an_over_sized_model_from_fitting_the_noise():
    """Eight states for a two-state plant on 400 samples at 6 dB: refined to
    convergence it simulates the noise-free plant worse than the early-stopped fit."""
    plant = STATE_SPACES["siso, 2 states"]
    data = state_space_record(plant, 400, seed=5, snr_db=6)
    full = fit_state_space(data, nx=8, tail_fraction=0.0)
    stopped = fit_state_space(data, nx=8, tail_fraction=0.25)
    assert stopped.settings["refinement"]["tail_fraction"] == 0.25
    assert free_run_error(stopped.model, plant) < 0.8 * free_run_error(full.model, plant)


def test_a_refinement_that_helps_no_tail_returns_its_start_and_says_so():
    plant = STATE_SPACES["siso, 2 states"]
    data = state_space_record(plant, 400, seed=5, snr_db=6)
    fit = fit_state_space(data, nx=8, tail_fraction=0.25, patience=1)
    sub = fit_state_space(data, nx=8, refine=False)
    assert fit.settings["refinement"]["early_stopping"]
    assert fit.settings["stop_reason"].startswith("early stopping: no better tail error in 1")
    assert any("kept the start" in w for w in fit.settings["warnings"])
    np.testing.assert_allclose(fit.model.A, sub.model.A)


def test_experiments_too_short_for_a_head_hold_nothing_back():
    plant = STATE_SPACES["siso, 2 states"]
    data = state_space_record(plant, 110, seed=6, snr_db=30)
    fit = fit_state_space(data, nx=2, tail_fraction=0.2)
    assert "tail_fraction" not in fit.settings["refinement"]
    np.testing.assert_array_equal(
        fit.model.free_parameters(),
        fit_state_space(data, nx=2, tail_fraction=0.0).model.free_parameters(),
    )


def test_an_early_stopped_fit_says_so_once_per_refinement_and_not_to_raise_max_nfev():
    """A linear plant, 400 noisy samples, degree-2 monomials stopped at 30 simulations:
    the nonlinear refinement returns an earlier iterate (its tail got worse after it),
    so the evaluation limit's advice to raise --max-nfev would mislead; the linear
    start's note, if any, is marked as the linear start's."""
    plant = STATE_SPACES["siso, 2 states"]
    data = state_space_record(plant, 400, seed=5, snr_db=6)
    fit = fit_model(data, "polynomial-state-space", nx=2, degree=2, max_nfev=30)
    notes = fit.settings.get("warnings", [])
    assert fit.settings["best_tail_earlier"] and fit.settings["stop_reason"] == "max_nfev reached"
    assert not any("evaluation limit" in n for n in notes), notes
    assert len(set(notes)) == len(notes)
    assert all(n.startswith("the linear start: ") for n in notes[:-1] if "kept the start" in n)
