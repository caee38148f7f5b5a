"""Subspace identification and the simulation-error fits of (polynomial) state-space
models, against plants whose matrices are known."""

import numpy as np
import pytest

from blockid.data import Dataset
from blockid.errors import OrderError, ParameterError
from blockid.fitting import fit_model
from blockid.fitting.state_space import (
    fit_polynomial_state_space,
    fit_state_space,
    order_from_singular_values,
    subspace,
)
from blockid.models.state_space import PolynomialStateSpace, StateSpace, monomial_exponents

from reference import STATE_SPACES, squared_state_record, state_space_record


def _markov(model, k):
    """``C A^k B`` (``D`` for k = -1) in the signals' own units."""
    scale = np.diag(model.output_scale) @ (
        model.D if k < 0 else model.C @ np.linalg.matrix_power(model.A, k) @ model.B
    )
    return scale @ np.diag(1.0 / model.input_scale)


@pytest.mark.parametrize("name", list(STATE_SPACES))
def test_subspace_recovers_known_systems_noise_free(name):
    plant = STATE_SPACES[name]
    feedthrough = bool(np.any(plant.D))
    fit = fit_model(state_space_record(plant, 3000), "state-space", method="subspace",
                    feedthrough=feedthrough)  # fmt: skip
    model = fit.model
    assert model.nx == plant.nx and fit.settings["order_from"].startswith("canonical")
    np.testing.assert_allclose(np.sort_complex(model.poles()), np.sort_complex(plant.poles()),
                               atol=1e-8)  # fmt: skip
    for k in range(-1, 12):
        np.testing.assert_allclose(_markov(model, k), _markov(plant, k), atol=1e-8)


def test_subspace_is_consistent_at_40_db_and_the_refinement_follows_the_free_run():
    plant = STATE_SPACES["2 in, 2 out, 3 states"]
    data = state_space_record(plant, 20000, snr_db=40.0)
    sub = fit_model(data, "state-space", method="subspace", nx=3).model
    refined = fit_model(data, "state-space", nx=3, max_nfev=30)
    for model in (sub, refined.model):
        np.testing.assert_allclose(np.sort(np.abs(model.poles())), np.sort(np.abs(plant.poles())),
                                   rtol=0.01)  # fmt: skip
    assert refined.method == "subspace+simulation-error"
    info = refined.settings["refinement"]
    assert info["final_normalised_mse"] <= info["initial_normalised_mse"]


def test_the_state_space_fit_equals_the_output_error_fit_where_they_coincide():
    """A single-input single-output model with two states and no direct term is an
    output-error model B/A with na = 2, nb = 2, nk = 1: both fits reach the same
    free-run error and the same transfer function."""
    plant = STATE_SPACES["siso, 2 states"]
    data = state_space_record(plant, 2000, snr_db=30.0)
    oe = fit_model(data, "output-error", na=2, nb=2, nk=1, tail_fraction=0.0, max_nfev=200)
    ss = fit_model(data, "state-space", nx=2, max_nfev=200)
    mse = [r.estimation_metrics["mse"]["y"] for r in (oe, ss)]
    assert mse[1] == pytest.approx(mse[0], rel=2e-3)
    num, den = ss.model.transfer_function()
    a = oe.model.a
    np.testing.assert_allclose(den[1:] / den[0], a, atol=2e-3)
    np.testing.assert_allclose(num[1:] / den[0], oe.model.b, atol=2e-3)


def test_the_order_rule_reads_the_largest_gap():
    assert order_from_singular_values(np.array([1.0, 0.99, 0.4, 0.38, 0.3]), 4) == 2
    assert order_from_singular_values(np.array([1.0, 0.5]), 5) == 1
    r = subspace(state_space_record(STATE_SPACES["siso, 2 states"], 1000, snr_db=40.0), max_order=1)
    assert r.nx == 1


def _cubic_plant():
    """Two states, the first fed back through -0.15 x1^3 (an odd nonlinearity: the
    operating point stays at zero, so the linear part is comparable)."""
    expo = monomial_exponents(2, 1, 3, "states")
    E = np.zeros((2, expo.shape[0]))
    E[0, 3] = -0.15  # x1^3
    return PolynomialStateSpace(["u"], ["y"], [[1.2, -0.35], [1.0, 0.0]], [[1.0], [0.0]],
                                [[1.0, 0.4]], [[0.0]], E, np.zeros((1, expo.shape[0])),
                                expo)  # fmt: skip


def _uniform(plant, n, amplitude=1.0, seed=0, snr_db=None):
    rng = np.random.default_rng(seed)
    u = rng.uniform(-amplitude, amplitude, n)
    y = plant.simulate(u)[:, 0]
    noise = 0.0 if snr_db is None else y.std() * 10 ** (-snr_db / 20)
    return Dataset.from_arrays(u, y + noise * rng.standard_normal(n), ["u"], ["y"]), noise


def _linearised_poles(model, u_physical=0.0):
    """Eigenvalues of the model's Jacobian at its equilibrium for a constant input: an
    invariant of every state basis, linear or not."""
    u0 = np.array([(u_physical - model.input_offset[0]) / model.input_scale[0]])
    x = np.zeros(model.nx)
    for _ in range(2000):  # the equilibrium, by the (contracting) iteration itself
        z = np.concatenate([x, u0])
        zeta = np.prod(np.clip(z, model.lower, model.upper) ** model.exponents, axis=1)
        x = model.A @ x + model.B @ u0 + model.E @ zeta
    z = np.concatenate([x, u0])
    slopes = np.zeros((model.n_monomials, model.nx))
    for j, row in enumerate(model.exponents):
        for i in range(model.nx):
            if row[i]:
                d = row.copy()
                d[i] -= 1
                slopes[j, i] = row[i] * np.prod(z**d)
    return np.sort(np.abs(np.linalg.eigvals(model.A + model.E @ slopes)))


def test_pnlss_noise_free_recovers_the_plant_up_to_its_state_basis():
    """Noise-free, the fit reaches the plant to rounding: the same outputs on a new
    record to 1e-6 of their spread, and the same poles of the dynamics linearised at
    the equilibrium (invariant of the state basis, which a polynomial model may even
    change nonlinearly) to 1e-6."""
    plant = _cubic_plant()
    data, _ = _uniform(plant, 3000)
    fit = fit_polynomial_state_space(data, nx=2, degree=3, monomials="states", max_nfev=300)
    model = fit.model
    assert fit.settings["refinement"]["final_normalised_mse"] < 1e-16
    np.testing.assert_allclose(_linearised_poles(model), [0.5, 0.7], atol=1e-6)
    fresh, _ = _uniform(plant, 1000, amplitude=0.9, seed=5)
    f = fresh.experiments[0]
    np.testing.assert_allclose(model.simulate(f.u, f.y[:20]), f.y, atol=1e-6 * f.y.std())


def test_pnlss_at_40_db_reaches_the_noise_floor_and_its_linear_part_the_poles():
    plant = _cubic_plant()
    data, noise = _uniform(plant, 4000, snr_db=40.0)
    fit = fit_polynomial_state_space(data, nx=2, degree=3, monomials="states", max_nfev=200)
    linear = fit_state_space(data, nx=2)
    rmse = fit.estimation_metrics["rmse"]["y"]
    assert rmse < 1.1 * noise < 0.2 * linear.estimation_metrics["rmse"]["y"]
    np.testing.assert_allclose(_linearised_poles(fit.model), [0.5, 0.7], rtol=0.01)
    # beyond the estimation range (input 20 % larger): bounded, and still close
    fresh, _ = _uniform(plant, 2000, amplitude=1.2, seed=7)
    f = fresh.experiments[0]
    y = fit.model.simulate(f.u, f.y[:20])
    assert np.all(np.isfinite(y)) and np.abs(y).max() < 2 * np.abs(f.y).max()


def test_a_linear_degree_gives_the_linear_model_and_bad_options_are_named():
    data, _ = _uniform(_cubic_plant(), 500)
    fit = fit_polynomial_state_space(data, nx=2, degree=1)
    assert type(fit.model) is StateSpace
    from blockid.errors import ParameterError

    with pytest.raises(ParameterError, match="degree"):
        fit_polynomial_state_space(data, nx=2, degree=7)
    with pytest.raises(ParameterError, match="weighting"):
        subspace(data, weighting="pca")


def test_a_fitted_model_measures_extrapolation_against_the_range_it_covered():
    """The monomials' clipping range comes from the linear start; the refinement moves
    the states, which may then cover another range. Measured against the clipping
    range, a model was "extrapolating" by 50 % on its own estimation input, and
    identify's trust check rejected the right model; the fit now records the range its
    states cover, and a free run on that input stays within it."""
    data = squared_state_record()
    u = data.experiments[0].u[:, 0]
    model = fit_model(data, "polynomial-state-space", nx=2, degree=2, max_nfev=15).model
    assert max(model.range_excursion(u).values()) < 0.05
    assert max(model.range_excursion(1.3 * u).values()) > 0.05
    again = type(model).from_dict(model.to_dict())
    np.testing.assert_array_equal(again.observed_lower, model.observed_lower)


@pytest.mark.parametrize("structure", ["state-space", "polynomial-state-space"])
def test_collinear_inputs_are_refused_naming_them(structure):
    """Two inputs that move together (u2 = 3 u1) leave B's columns unidentifiable; the
    subspace fit used to split their effect without a word (issue 18, data)."""
    from blockid.errors import DataError

    rng = np.random.default_rng(0)
    u1, u3 = rng.standard_normal(400), rng.standard_normal(400)
    y = np.convolve(u1 + 0.5 * u3, [0.0, 0.5, 0.2], "full")[:400]
    u = np.c_[u1, 3.0 * u1 + 1.0, u3]
    data = Dataset.from_arrays(u, y, ["u1", "u2", "u3"], ["y"])
    with pytest.raises(DataError, match=r"inputs 'u1', 'u2' are \(nearly\) linear") as err:
        fit_model(data, structure, nx=2)
    assert "'u3'" not in str(err.value)
    # the same inputs moving independently fit
    free = Dataset.from_arrays(np.c_[u1, rng.standard_normal(400), u3], y,
                               ["u1", "u2", "u3"], ["y"])  # fmt: skip
    assert list(fit_model(free, "state-space", nx=2).model.inputs) == ["u1", "u2", "u3"]


def test_the_states_of_a_free_run_are_those_of_a_walk_sample_by_sample():
    """``states`` (one run whose output is the state) against the state map applied one
    sample at a time, from rest and from a given state."""
    plant = STATE_SPACES["siso, 2 states"]
    data = state_space_record(plant, 500)
    model = fit_polynomial_state_space(data, nx=2, degree=3, max_nfev=3).model
    u = data.experiments[0].u
    un = model.normalised_input(u)
    A, B, _, _, E, _, expo, lo, hi = model._arrays()
    from blockid._kernels.state_space import monomials

    for x0 in (None, np.array([0.3, -0.1])):
        x = np.zeros(2) if x0 is None else x0.copy()
        expected = np.empty((u.shape[0], 2))
        zeta = np.empty(expo.shape[0])
        for k in range(u.shape[0]):
            expected[k] = x
            monomials(np.r_[x, un[k]], expo, lo, hi, zeta)
            x = A @ x + B @ un[k] + E @ zeta
        assert np.allclose(model.states(u, x0), expected, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("record", ["lure", "wiener-hammerstein"])
def test_multivariable_feedback_and_wiener_hammerstein_plants_are_polynomial_state_spaces(
    record,
):
    """A static block fed back around a linear core, or between two linear blocks, makes
    the state update polynomial in the state: the polynomial state space holds these
    block models of several channels (with more parameters than the structure needs)."""
    from reference import mimo_lure_record, mimo_wiener_hammerstein_record

    make, nx = {"lure": (mimo_lure_record, 2),
                "wiener-hammerstein": (mimo_wiener_hammerstein_record, 4)}[record]  # fmt: skip
    data, fresh = make()
    from blockid.evaluation.validate import evaluate

    def fit_percent(structure, **options):
        model = fit_model(data, structure, nx=nx, **options).model
        return min(evaluate(model, fresh, "simulation").metrics["fit_percent"].values())

    assert fit_percent("polynomial-state-space", degree=3, monomials="states") > 99.5
    assert fit_percent("state-space") < 90.0


# ------------------------------------------------------------ the polynomial model's order
def _three_state_cubic():
    """Three states (a resonance and a slower mode), the first fed back through a cube."""
    expo = monomial_exponents(3, 1, 3, "states")
    E = np.zeros((3, expo.shape[0]))
    E[0, list(map(tuple, expo)).index((3, 0, 0, 0))] = -0.1
    A = [[1.2, -0.5, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.8]]
    return PolynomialStateSpace(["u"], ["y"], A, [[1.0], [0.0], [0.6]], [[1.0, 0.4, 1.0]],
                                [[0.0]], E, np.zeros((1, expo.shape[0])), expo)  # fmt: skip


def test_the_polynomial_model_s_order_is_chosen_on_held_back_halves():
    """Without ``nx``: the plant's three states from linear models scored on the half of
    the record each never saw; the scan stops two orders past the best, every order's
    score recorded; a given ``nx`` is taken as it is."""
    from blockid.fitting.state_space import ORDER_TIE, order_by_validation

    data, _ = _uniform(_three_state_cubic(), 4000, amplitude=0.8, snr_db=40.0)
    nx, scores = order_by_validation(data, 10)
    errors = {s["nx"]: s["error"] for s in scores}
    assert nx == 3
    assert list(errors) == [1, 2, 3, 4, 5]  # stopped two past the last clear gain
    assert errors[2] > 1.2 * errors[3]  # the third state matters
    assert errors[3] <= (1 + ORDER_TIE) * min(errors.values())
    fit = fit_polynomial_state_space(data, degree=2, max_nfev=5)
    assert fit.settings["nx"] == 3 and fit.settings["order_from"].startswith("cross-validated")
    assert [s["nx"] for s in fit.settings["order_scores"]] == [1, 2, 3, 4, 5]
    given = fit_polynomial_state_space(data, nx=2, degree=2, max_nfev=5)
    assert given.settings["nx"] == 2 and given.settings["order_from"] == "given"


def test_a_record_too_short_for_two_folds_falls_back_to_the_canonical_correlations():
    from blockid.fitting.state_space import order_by_validation

    data, _ = _uniform(_cubic_plant(), 100)
    assert order_by_validation(data, 10) == (None, [])
    fit = fit_polynomial_state_space(data, degree=2, max_nfev=3)
    assert fit.settings["order_from"].startswith("canonical correlations")


def test_a_model_over_more_monomials_simulates_as_before():
    fit = fit_polynomial_state_space(_uniform(_cubic_plant(), 800)[0], nx=2, degree=2,
                                     max_nfev=20)  # fmt: skip
    model = fit.model
    grown = model.with_monomials(monomial_exponents(2, 1, 3, "full", constant=True))
    assert grown.n_monomials > model.n_monomials
    u = np.random.default_rng(3).uniform(-1, 1, 300)
    np.testing.assert_array_equal(grown.simulate(u), model.simulate(u))
    with pytest.raises(OrderError, match="keeps every monomial"):
        model.with_monomials(monomial_exponents(2, 1, 3, "states"))


def test_degree_by_degree_climbs_to_the_plant_and_records_each_rung():
    """Noise-free cubic plant: the fit of degree 2 first, then 3 from it, reaches the
    plant as the one-rung fit does (the poles of the linearisation to 1e-5), and says what
    each rung did."""
    plant = _cubic_plant()
    data, _ = _uniform(plant, 3000)
    fit = fit_polynomial_state_space(data, nx=2, degree=3, monomials="states",
                                     start_degree=2, max_nfev=300)  # fmt: skip
    assert [r["degree"] for r in fit.settings["rungs"]] == [2, 3]
    assert fit.settings["start_degree"] == 2 and fit.model.degree == 3
    assert fit.settings["refinement"]["final_normalised_mse"] < 1e-10
    np.testing.assert_allclose(_linearised_poles(fit.model), [0.5, 0.7], atol=1e-5)
    with pytest.raises(ParameterError, match="start_degree <= degree"):
        fit_polynomial_state_space(data, nx=2, degree=2, start_degree=3)


def test_the_subspace_estimate_keeps_the_stability_margin():
    """A plant whose pole lies between the margin and the unit circle (0.99975 on 2 000
    samples, margin 0.0005) gets a subspace pole reflected inside ``1 - margin`` (the
    margin every fit keeps), not merely inside the unit circle."""
    from scipy.signal import lfilter

    from blockid.fitting.checks import stability_margin

    rng = np.random.default_rng(3)
    u = rng.standard_normal(2000)
    y = lfilter([0.0, 0.05], [1.0, -0.99975], u)
    data = Dataset.from_arrays(u, y + 1e-4 * rng.standard_normal(u.size), ["u"], ["y"])
    margin = stability_margin(data)
    assert margin == 0.0005
    (pole,) = np.linalg.eigvals(subspace(data, nx=1).model.A)
    assert 1.0 - 3 * margin < abs(pole) < 1.0 - margin  # reflected: inside the margin
