"""Bounded memory on long records: the pieces give the whole-record answers.

Regressors (ARX, initial estimates) and simulation-error sensitivities are built in
pieces; a refinement whose Jacobian would be large sums ``J^T J`` piece by piece and
solves by Levenberg-Marquardt. Each piece-wise path is checked here against the
whole-record computation on small data, with the pieces made tiny.
"""

from __future__ import annotations

import numpy as np
import pytest

import blockid.fitting.simulation_error as se
from blockid.blocks import LinearBlock, Polynomial, TwoSegmentPolynomial
from blockid.blocks.integrator import Integrator
from blockid.config import config_context
from blockid.data import Dataset
from blockid.fitting.initial import initial_estimate
from blockid.models.block import (
    BacklashModel,
    ChainModel,
    Hammerstein,
    HammersteinWiener,
    Wiener,
    WienerHammerstein,
)

N1 = TwoSegmentPolynomial.from_segments(positive=[0.05, 1.0, 0.3], negative=[0.05, 0.6, -0.2])


def chains():
    return {
        "hammerstein": Hammerstein(
            "u", "y", input_block=N1, na=2, nb=2, nk=1, a=[-1.2, 0.35], b=[1.0, 0.4]
        ),
        "wiener": Wiener(
            "u",
            "y",
            output_block=Polynomial([1.0, 0.2, 0.05], constant=False),
            na=2,
            nb=3,
            nk=2,
            a=[-1.0, 0.3],
            b=[0.5, 0.2, 0.1],
        ),
        "hammerstein-wiener": HammersteinWiener(
            "u",
            "y",
            input_block=N1,
            output_block=Polynomial([1.0, 0.2, 0.05], constant=False),
            na=2,
            nb=2,
            nk=1,
            a=[-1.2, 0.35],
            b=[1.0, 0.4],
        ),
        "wiener-hammerstein": WienerHammerstein(
            "u",
            "y",
            first=LinearBlock(2, 1, 1, a=[-1.3, 0.5], b=[0.4]),
            static=Polynomial([0.05, 1.0, 0.2, -0.15]),
            second=LinearBlock(2, 2, 0, a=[-0.9, 0.3], b=[1.0, 0.5]),
        ),
        "hammerstein, double integrator": ChainModel(
            "u",
            "y",
            [N1, LinearBlock(1, 2, 1, a=[-0.5], b=[1.0, 0.3], unit_b0=True), Integrator(2)],
        ),
    }


@pytest.mark.parametrize("name", list(chains()))
@pytest.mark.parametrize("measured_start", [False, True])
@pytest.mark.parametrize("rows", [3, 7, 64])
def test_sensitivity_pieces_are_the_whole_record_walk(name, measured_start, rows, rng):
    """Every piece continues the linear blocks from the previous piece's last inputs and
    outputs: the stacked pieces equal the whole-record walk bit for bit, also with
    pieces shorter than a block's memory would allow (they are widened to it) and a
    short last piece; through an integrator, which restarts its cumulative sums from
    the last outputs' differences, to rounding."""
    model = chains()[name]
    u = rng.uniform(-1, 1, 250)
    y0 = model.simulate(u)[: model.max_lag, 0] + 0.01 if measured_start else None
    y, J = se.simulate_with_sensitivities(model, u, y0)
    pieces = list(se.sensitivity_chunks(model, u, y0, rows=rows))
    starts = [p[0] for p in pieces]
    assert starts[0] == 0 and len(set(np.diff(starts))) == 1  # equal pieces but the last
    if "integrator" in name:  # restarted from differences: equal to rounding
        np.testing.assert_allclose(np.concatenate([p[1] for p in pieces]), y, rtol=1e-13)
        np.testing.assert_allclose(np.vstack([p[2] for p in pieces]), J, rtol=1e-13, atol=1e-13)
        return
    np.testing.assert_array_equal(np.concatenate([p[1] for p in pieces]), y)
    np.testing.assert_array_equal(np.vstack([p[2] for p in pieces]), J)


def test_a_chain_with_a_dynamic_block_is_not_walked_in_pieces():
    from blockid.blocks import Backlash

    model = BacklashModel(
        "u", "y", input_block=Backlash(1.0, 0.1, 1.0, 0.1), na=1, nb=1, nk=1, a=[-0.5]
    )
    assert not se.chunkable(model) and se.chunkable(chains()["hammerstein"])
    with pytest.raises(Exception, match="static and linear blocks"):
        next(se.sensitivity_chunks(model, np.zeros(10)))


@pytest.mark.parametrize("structure", ["hammerstein", "hammerstein-wiener"])
def test_large_problem_solver_reaches_the_whole_jacobian_optimum(structure, rng):
    """Forced onto the normal-equation solver (every problem 'large', pieces of 500
    samples), the refinement reaches the optimum scipy's trust-region solver reaches
    with the whole Jacobian, and says which solver ran."""
    plant = chains()[structure]
    u = rng.uniform(-1, 1, 4000)
    y = plant.simulate(u)[:, 0] + 0.01 * rng.standard_normal(4000)
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    options = {"na": 2, "nb": 2, "nk": 1, "r1": 2, "r2": 3, "tail_fraction": 0.0}
    whole = se.fit_simulation_error(data, structure, **options)
    with config_context(jacobian_bytes=0, sensitivity_rows=500):
        pieces = se.fit_simulation_error(data, structure, **options)
    assert whole.settings["solver"] == se.SOLVERS[False]
    assert pieces.settings["solver"] == se.SOLVERS[True]
    assert "termination" in pieces.settings["stop_reason"]
    mse_whole = whole.settings["final_simulation_mse"]
    assert pieces.settings["final_simulation_mse"] == pytest.approx(mse_whole, rel=1e-6)
    np.testing.assert_allclose(
        pieces.model.free_parameters(), whole.model.free_parameters(), rtol=1e-3, atol=1e-4
    )
    np.testing.assert_allclose(  # and both are the plant, up to the noise
        pieces.model.free_parameters(), plant.free_parameters(), atol=0.02
    )


def test_large_problem_solver_keeps_early_stopping_and_bounds(rng):
    """The normal-equation solver reports to the same early-stopping monitor (tail held
    out) and never leaves the parameter bounds."""
    plant = chains()["hammerstein"]
    u = rng.uniform(-1, 1, 3000)
    y = plant.simulate(u)[:, 0] + 0.01 * rng.standard_normal(3000)
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    with config_context(jacobian_bytes=0):
        result = se.fit_simulation_error(data, "hammerstein", na=2, nb=2, nk=1, r1=2)
    assert result.settings["tail_mse"] <= result.settings["initial_tail_mse"]
    assert len(result.history["tail_mse"]) == result.settings["iterations"] + 1
    lower, upper = result.model.parameter_bounds()
    theta = result.model.free_parameters()
    assert np.all(theta >= lower) and np.all(theta <= upper)


def test_initial_estimate_from_pieces_is_the_whole_record_estimate(rng):
    """The initial estimate's regressions run on pieces of rows: pieces of 5 rows give
    the estimate of one piece per experiment (least squares to rounding)."""
    plant = chains()["hammerstein-wiener"]
    u = rng.uniform(-1, 1, 1500)
    y = plant.simulate(u)[:, 0] + 0.005 * rng.standard_normal(1500)
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    whole = initial_estimate(data, HammersteinWiener, na=2, nb=2, nk=1, r1=2, r2=3)
    with config_context(regressor_rows=5):
        pieces = initial_estimate(data, HammersteinWiener, na=2, nb=2, nk=1, r1=2, r2=3)
    np.testing.assert_allclose(
        pieces.free_parameters(), whole.free_parameters(), rtol=1e-8, atol=1e-10
    )


def test_linearity_note_uses_the_closed_form_affine_fit(rng):
    """The 'linear in disguise' check fits a line in closed form (no design matrix on
    a long record): the same deviation as least squares, and the note fires for a
    fitted polynomial that is a line and not for a curved one."""
    from blockid.fitting.checks import _affine_deviation, linear_block_notes

    s = rng.uniform(-1, 1, 500)
    out = 0.3 + 2.0 * s + 0.05 * s**2
    design = np.column_stack([np.ones_like(s), s])
    coef = np.linalg.lstsq(design, out, rcond=None)[0]
    expected = float(np.max(np.abs(out - design @ coef)))
    assert _affine_deviation(s, out) == pytest.approx(expected, rel=1e-10)
    assert _affine_deviation(s, 1.0 - 3.0 * s) < 1e-14
    assert _affine_deviation(np.ones(5), np.ones(5)) == 0.0
    u = rng.uniform(-1, 1, 400)
    data = Dataset.from_arrays(u, np.zeros(400), ["u"], ["y"])
    linear = Hammerstein(
        "u", "y", input_block=Polynomial([0.0, 1.0, 1e-12]), na=1, nb=1, nk=1, a=[-0.5]
    )
    curved = Hammerstein(
        "u", "y", input_block=Polynomial([0.0, 1.0, 0.5]), na=1, nb=1, nk=1, a=[-0.5]
    )
    assert any("is linear over the estimation data" in n for n in linear_block_notes(linear, data))
    assert not any("is linear" in n for n in linear_block_notes(curved, data))


@pytest.mark.slow  # traced allocations make the fit several times slower (about 6 s)
def test_default_fit_memory_stays_a_small_multiple_of_the_data(rng):
    """With pieces scaled down to the record (the defaults are 65,536 rows and 64 MB of
    Jacobian, sized for millions of samples), the default Hammerstein fit's peak of
    traced allocations stays under 8 times the two signals; holding the regressors
    and the Jacobian made it about 55 times."""
    import tracemalloc

    from blockid.fitting import fit_model

    n = 60_000
    plant = chains()["hammerstein"]
    u = rng.uniform(-1, 1, n)
    y = plant.simulate(u)[:, 0] + 0.01 * rng.standard_normal(n)
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    small = Dataset.from_arrays(u[:2000], y[:2000], ["u"], ["y"])
    with config_context(regressor_rows=2048, sensitivity_rows=2048, jacobian_bytes=0):
        fit_model(small, "hammerstein", na=2, nb=2, nk=1)  # imports and compiled kernels
        tracemalloc.start()
        try:
            result = fit_model(data, "hammerstein", na=2, nb=2, nk=1)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
    assert result.settings["solver"] == se.SOLVERS[True]
    assert peak < 8 * (u.nbytes + y.nbytes), f"peak {peak / 1e6:.1f} MB"
