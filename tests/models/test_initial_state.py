"""The initial state of a chain model: from ``max_lag`` measured outputs (unchanged) and
estimated from more of them (blockid.models.initial_state), and evaluate's
``initial_samples``."""

import numpy as np
import pytest
import scipy.optimize

from blockid.blocks import Backlash, Polynomial, Saturation, TwoSegmentPolynomial
from blockid.blocks.integrator import Integrator
from blockid.blocks.linear import LinearBlock
from blockid.data import Dataset
from blockid.errors import ParameterError
from blockid.evaluation import evaluate
from blockid.fitting.checks import simulation_mse
from blockid.fitting.simulation_error import fit_simulation_error, simulate_with_sensitivities
from blockid.models import (
    ARX,
    BacklashModel,
    ChainModel,
    Hammerstein,
    HammersteinWiener,
    Network,
    Wiener,
    WienerHammerstein,
)

SLOW = [-1.9, 0.9025]  # a double pole at 0.95: a start at rest is felt for ~100 samples


def _wiener_hammerstein():
    return WienerHammerstein(
        "u",
        "y",
        first=LinearBlock(2, 2, 0, a=SLOW, b=[0.04, 0.02]),
        static=Polynomial([1.0, 0.3, -0.2], constant=False),
        second=LinearBlock(2, 2, 1, a=[-1.2, 0.5], b=[1.0, 0.5]),
    )


def _wiener_not_monotone():
    # y = x - 0.5 x^2 turns at x = 1, inside the range x takes: no inverse, start at rest
    return Wiener(
        "u", "y", output_block=Polynomial([1.0, -0.5], constant=False), na=2, nb=2, nk=1,
        a=SLOW, b=[0.05, 0.03],
    )  # fmt: skip


def _hammerstein_wiener():
    return HammersteinWiener(
        "u", "y", input_block=TwoSegmentPolynomial([0.0, 1.0, 0.3], [0.0, 0.7, -0.2]),
        output_block=Polynomial([1.0, 0.001], constant=False), na=2, nb=2, nk=1, a=SLOW,
        b=[1.0, 0.3],
    )  # fmt: skip


def _integrating():
    return ChainModel("u", "y", [LinearBlock(2, 2, 1, a=SLOW, b=[0.05, 0.03]), Integrator()])


def _backlash():
    return BacklashModel(
        "u", "y", input_block=Backlash(0.9, 0.1, 1.1, 0.15), na=2, nb=1, nk=1, a=SLOW
    )


MODELS = {
    "wiener-hammerstein": _wiener_hammerstein,
    "wiener, not monotone": _wiener_not_monotone,
    "hammerstein-wiener": _hammerstein_wiener,
    "integrating": _integrating,
    "backlash": _backlash,
    "saturated output": lambda: ChainModel(
        "u",
        "y",
        [
            Polynomial([0.0, 1.0, 0.3]),
            LinearBlock(1, 1, 1, a=[-0.9], b=[1.0]),
            Integrator(),
            Saturation(-3.0, 3.0),
        ],
    ),  # fmt: skip
}


def _record(model, n=3000, cut=1000, seed=0):
    """The model with the ranges of a noise-free run from rest, and the run's input and
    output from sample ``cut`` on: a record that starts far from rest."""
    u = np.random.default_rng(seed).uniform(-1, 1, n)
    y = model.simulate(u)[:, 0]
    return model.with_ranges([(u, y)]), u[cut:], y[cut:]


def _old_simulate(model, u, y_initial=None):
    """ChainModel.simulate before the estimated start, copied: the last linear block from
    the first max_lag measured outputs, every other block at rest."""
    last = model.last_linear_index
    w = model._run(model._u(u), last)
    x = model.blocks[last].simulate(w, model.initial_state(y_initial))
    y = model._run_from(x, last + 1)
    return (y + model.output_offset)[:, None]


def _relative(a, b, scale):
    return np.max(np.abs(a - b)) / scale


# ----------------------------------------------------------------------------- estimated
def test_wiener_hammerstein_continues_exactly_from_fifty_measured_outputs():
    model, u, y = _record(_wiener_hammerstein())
    assert model.max_lag == 2
    scale = np.max(np.abs(y))
    old = model.simulate(u, y[: model.max_lag])[:, 0]  # what y[:50] gave before: cut to 2
    new = model.simulate(u, y[:50])[:, 0]
    old_error = _relative(old[50:150], y[50:150], scale)
    new_error = _relative(new[50:], y[50:], scale)
    assert old_error > 1e-3  # the first linear block started at rest: a transient
    assert new_error < 1e-8
    assert _relative(new[50:150], y[50:150], scale) * 100 < old_error


def test_hammerstein_start_is_the_exact_one():
    # the output is the linear block's: y[:max_lag] is its exact state, and the
    # estimate, started there, stays there
    model, u, y = _record(
        Hammerstein(
            "u", "y", input_block=TwoSegmentPolynomial([0.0, 1.0, 0.3], [0.0, 0.7, -0.2]),
            na=2, nb=2, nk=1, a=SLOW, b=[1.0, 0.3],
        )
    )  # fmt: skip
    exact = model.simulate(u, y[: model.max_lag])[:, 0]
    new = model.simulate(u, y[:40])[:, 0]
    scale = np.max(np.abs(y))
    assert _relative(new, exact, scale) < 1e-9
    assert _relative(new[40:], y[40:], scale) < 1e-9


def test_hammerstein_wiener_start_from_the_inverse_is_kept():
    model, u, y = _record(_hammerstein_wiener())
    assert model.initial_state(y[:2]) is not None  # the output block inverts
    new = model.simulate(u, y[:30])[:, 0]
    np.testing.assert_allclose(new, model.simulate(u, y[:2])[:, 0], rtol=0, atol=1e-9)


def test_wiener_output_that_cannot_be_inverted_is_estimated_much_better_than_rest():
    model, u, y = _record(_wiener_not_monotone())
    assert model.initial_state(y[:2]) is None  # today: from rest
    scale = np.max(np.abs(y))
    rest = model.simulate(u, y[:2])[:, 0]
    np.testing.assert_array_equal(rest, model.simulate(u)[:, 0])
    new = model.simulate(u, y[:50])[:, 0]
    rest_error = _relative(rest[50:150], y[50:150], scale)
    assert rest_error > 1e-3
    assert _relative(new[50:], y[50:], scale) < 1e-6 * rest_error


def test_an_integrating_chain_estimates_the_integrators_level_only():
    """The start of a block before an integrator, fitted to the window, is summed by the
    integrator into a lasting offset: with any model error it drifts (an EMPS
    Wiener-Hammerstein model with an integrator, simulated on the test record from 20
    measured samples: 207 mm RMSE on a 0.25 m stroke, against 4.4 mm from one). Such a
    chain estimates the integrator's start (the measured level, over the whole window)
    and starts the blocks before it at rest."""
    from blockid.models.initial_state import _layout

    model, u, y = _record(_integrating(), cut=0)  # a record from rest
    assert [i for i, _, _ in _layout(model, 50)] == [1]  # the integrator only
    new = model.simulate(u, y[:50])[:, 0]
    assert _relative(new, y, np.max(np.abs(y))) < 1e-8
    shifted = model.simulate(u, y[:50] + 0.1)[:, 0]  # a level the window shows: followed
    np.testing.assert_allclose(shifted[50:] - new[50:], 0.1, atol=1e-9)


def test_backlash_starts_at_rest_but_the_linear_block_is_estimated():
    model, u, y = _record(_backlash(), cut=0)  # from rest: the backlash's rest is right
    new = model.simulate(u, y[:20])[:, 0]
    np.testing.assert_allclose(new, y, rtol=0, atol=1e-9 * np.max(np.abs(y)))


def test_the_estimate_reads_the_first_n_samples_only():
    model, u, y = _record(_wiener_hammerstein())
    short = model.simulate(u[:200], y[:50])[:, 0]
    np.testing.assert_array_equal(short, model.simulate(u, y[:50])[:200, 0])


def test_a_failing_estimate_falls_back_to_the_start_from_max_lag(monkeypatch):
    model, u, y = _record(_wiener_hammerstein())

    def fails(*args, **kwargs):
        raise ValueError("no")

    monkeypatch.setattr(scipy.optimize, "least_squares", fails)  # imported when used
    np.testing.assert_array_equal(model.simulate(u, y[:50]), _old_simulate(model, u, y[:50]))


def test_a_non_finite_measurement_falls_back_to_the_start_from_max_lag():
    model, u, y = _record(_wiener_hammerstein())
    y = y.copy()
    y[10] = np.nan
    got = model.simulate(u, y[:50])
    assert np.all(np.isfinite(got))
    np.testing.assert_array_equal(got, _old_simulate(model, u, y[:50]))


# ----------------------------------------------------------------------------- unchanged
@pytest.mark.parametrize("name", list(MODELS))
def test_at_most_max_lag_outputs_start_as_before_bit_for_bit(name):
    model, u, y = _record(MODELS[name]())
    for y0 in (None, y[:1], y[: model.max_lag], y[: model.max_lag, None]):
        np.testing.assert_array_equal(model.simulate(u, y0), _old_simulate(model, u, y0))


@pytest.mark.parametrize("name", ["wiener-hammerstein", "hammerstein-wiener", "integrating"])
def test_the_optimisers_sensitivities_follow_the_max_lag_start(name):
    model, u, y = _record(MODELS[name]())
    y_sim, _ = simulate_with_sensitivities(model, u, y[: model.max_lag])
    np.testing.assert_allclose(y_sim, model.simulate(u, y[: model.max_lag])[:, 0], atol=1e-9)


def test_a_network_gives_each_subsystem_its_own_max_lag_as_before():
    chain = Wiener(
        "u", "v", output_block=Polynomial([1.0, 0.1], constant=False), na=1, nb=1, nk=1,
        a=[-0.9], b=[1.0],
    )  # fmt: skip
    arx = ARX(["v"], ["y"], 3, 1, 1, a={"y": {"y": [-0.5, 0.1, 0.05]}}, b={"y": {"v": [1.0]}})
    net = Network([("S1", chain), ("S2", arx)])
    u = np.random.default_rng(3).uniform(-1, 1, 300)
    y = net.simulate(u) + 0.1
    assert net.max_lag == 3 > chain.max_lag
    v = chain.simulate(u, y[:1, :1])  # the chain given its own max_lag only
    expected = np.column_stack([v[:, 0], arx.simulate(v, y[:3, 1:])[:, 0]])
    np.testing.assert_array_equal(net.simulate(u, y[:3]), expected)


# ----------------------------------------------------------------------------- evaluate
def _data(u, y):
    return Dataset.from_arrays(u, y, ["u"], ["y"])


def test_evaluate_starts_from_n_measured_outputs_and_scores_from_n():
    model, u, y = _record(_wiener_hammerstein())
    data = _data(u, y)
    out = evaluate(model, data, initial_samples=50)
    np.testing.assert_array_equal(out.outputs[0], model.simulate(u, y[:50]))
    assert out.skip == 50
    err = y[50:] - out.outputs[0][50:, 0]
    assert out.metrics["mse"]["y"] == pytest.approx(np.mean(err**2), rel=1e-12)
    doc = out.to_dict()
    assert doc["initial_samples"] == 50 and doc["initial_samples_per_experiment"] == 50
    default = evaluate(model, data)
    assert "initial_samples" not in default.to_dict() and default.skip == model.max_lag
    assert out.metrics["mse"]["y"] < 1e-6 * default.metrics["mse"]["y"]


def test_evaluate_with_fewer_initial_samples_than_max_lag_scores_from_max_lag():
    model, u, y = _record(_wiener_hammerstein())
    out = evaluate(model, _data(u, y), initial_samples=1)
    assert out.skip == model.max_lag == 2
    np.testing.assert_array_equal(out.outputs[0], model.simulate(u, y[:1]))


@pytest.mark.parametrize("bad", [0, -3, 2.5, True, "5", 2000])
def test_evaluate_refuses_a_bad_number_of_initial_samples(bad):
    model, u, y = _record(_wiener_hammerstein())
    with pytest.raises(ParameterError, match="initial_samples") as info:
        evaluate(model, _data(u, y), initial_samples=bad)
    assert info.value.parameter == "initial_samples"


def test_evaluate_refuses_initial_samples_for_one_step_prediction():
    model, u, y = _record(_hammerstein_wiener())
    with pytest.raises(ParameterError, match="free-run simulation only") as info:
        evaluate(model, _data(u, y), "one-step", initial_samples=10)
    assert info.value.parameter == "initial_samples"


# ----------------------------------------------------------------------------- fitting
def _hammerstein_wiener_fit():
    """An H-W fit whose quadratic output block turns inside the range of x."""
    plant = HammersteinWiener(
        "u", "y", input_block=TwoSegmentPolynomial([0.0, 1.0, 0.2], [0.0, 0.8, -0.1]),
        output_block=Polynomial([1.0, -0.6], constant=False), na=2, nb=2, nk=1,
        a=[-1.3, 0.45], b=[1.0, 0.3],
    )  # fmt: skip
    rng = np.random.default_rng(4)
    u = rng.uniform(-1, 1, 600)
    y = plant.simulate(u)[:, 0] + 0.01 * rng.standard_normal(600)
    data = _data(u, y)
    result = fit_simulation_error(
        data, "hammerstein-wiener", na=2, nb=2, nk=1, r1=2, r2=2, tail_fraction=0.0
    )
    assert result.model.initial_state(y[:2]) is None  # not invertible over the data
    return result, data


@pytest.fixture(scope="module")
def hammerstein_wiener_fit():
    return _hammerstein_wiener_fit()


def test_the_reported_simulation_error_is_the_delivered_models(hammerstein_wiener_fit):
    result, data = hammerstein_wiener_fit
    delivered = simulation_mse(result.model, data)
    assert result.settings["final_simulation_mse"] == pytest.approx(delivered, rel=1e-12)
    assert evaluate(result.model, data).metrics["mse"]["y"] == pytest.approx(delivered, rel=1e-12)


def test_the_optimisers_criterion_is_the_delivered_models(hammerstein_wiener_fit):
    result, data = hammerstein_wiener_fit
    optimised = result.history["fit_mse"][-1]  # the solver's cost at the returned model
    assert optimised == pytest.approx(simulation_mse(result.model, data), rel=1e-12)
