"""Initial estimates: exact on noise-free Hammerstein data, close elsewhere, always stable.

Inputs are uniform white noise on [-1, 1] (both signs, as the two-segment block B1
needs) unless a test says otherwise; the backlash gets a slow sinusoid.
"""

from __future__ import annotations

import numpy as np
import pytest

from blockid.blocks import (
    Backlash,
    DeadZone,
    PiecewiseLinear,
    Polynomial,
    Saturation,
    TwoSegmentPolynomial,
)
from blockid.data.dataset import Dataset
from blockid.errors import EstimationError, OrderError, ParameterError
from blockid.fitting import fit_model
from blockid.fitting.arx import fit_arx
from blockid.fitting.checks import linear_baseline, simulation_mse
from blockid.fitting.initial import (
    _stabilise,
    initial_estimate,
    resolve_structure,
    scaled_block,
)
from blockid.models.block import (
    BacklashModel,
    Hammerstein,
    HammersteinWiener,
    Wiener,
)

from reference import _arx_data, _backlash_data, _backlash_model

A2 = [-1.2, 0.5]  # poles 0.6 +- 0.37j
TWO_SEGMENT = TwoSegmentPolynomial([0.2, 1.0, 0.8, -0.6], [-0.3, -0.5, 1.2, 0.8])


def record(model, u, rng=None):
    y = model.simulate(u)[:, 0]
    if rng is not None:  # 40 dB output SNR
        y = y + 0.01 * np.std(y) * rng.standard_normal(y.size)
    return Dataset.from_arrays(u, y)


def uniform(seed, n=2000):
    return np.random.default_rng(seed).uniform(-1, 1, n)


@pytest.mark.parametrize(
    "block",
    [
        TWO_SEGMENT,
        Polynomial([0.3, 1.0, -0.5, 0.4]),  # with constant
        PiecewiseLinear([-1.0, -0.3, 0.4, 1.0], [-0.5, -0.2, 0.6, 0.8]),  # spans constants
    ],
    ids=["two-segment", "polynomial", "piecewise-linear"],
)
def test_hammerstein_estimate_is_exact_on_noise_free_data(block):
    """The over-parameterised regression is exact for a Hammerstein plant; the SVD
    factorisation recovers b and the block, including the constant that every lag
    shares."""
    true = Hammerstein("u1", "y1", input_block=block, na=2, nb=3, nk=1, a=A2, b=[1, 0.5, -0.2])
    data = record(true, uniform(0))
    template = type(block).from_dict(block.to_dict())
    est = initial_estimate(data, "hammerstein", na=2, nb=3, nk=1, input_block=template)
    np.testing.assert_allclose(est.free_parameters(), true.free_parameters(), atol=1e-9)
    assert est.b[0] == 1.0


def test_default_input_block_is_a_two_segment_polynomial_of_order_r1():
    true = Hammerstein("u1", "y1", input_block=TWO_SEGMENT, na=2, nb=2, nk=1, a=A2, b=[1, 0.5])
    est = initial_estimate(record(true, uniform(1)), "hammerstein", na=2, nb=2, nk=1)
    assert isinstance(est.input_block, TwoSegmentPolynomial)
    assert est.input_block.order == 3
    np.testing.assert_allclose(est.free_parameters(), true.free_parameters(), atol=1e-9)
    wider = initial_estimate(record(true, uniform(1)), "hammerstein", na=2, nb=2, nk=1, r1=5)
    assert wider.input_block.order == 5
    np.testing.assert_allclose(wider.input_block.f[4:], 0.0, atol=1e-8)  # truth is cubic


def test_wiener_estimate_is_close_on_noise_free_data():
    """ARX, then q by least squares from the simulated x, then a refit on N2^-1(y)."""
    true = Wiener(
        "u1",
        "y1",
        output_block=Polynomial([1.0, 0.3, 0.1], constant=False),
        na=3,
        nb=3,
        nk=2,
        a=[-1.1, 0.55, -0.125],
        b=[0.8, -0.3, 0.2],
    )
    est = initial_estimate(record(true, uniform(2)), "wiener", na=3, nb=3, nk=2)
    assert est.output_block.coefficients[0] == 1.0
    np.testing.assert_allclose(est.free_parameters(), true.free_parameters(), atol=1e-4)


def test_hammerstein_wiener_estimate_is_a_good_start_at_40_db():
    true = HammersteinWiener(
        "u1",
        "y1",
        input_block=TWO_SEGMENT,
        output_block=Polynomial([1.0, 0.2, 0.05], constant=False),
        na=3,
        nb=3,
        nk=2,
        a=[-1.1, 0.55, -0.125],
        b=[1, -0.3, 0.2],
    )
    rng = np.random.default_rng(3)
    data = record(true, rng.uniform(-1, 1, 3000), rng)
    est = initial_estimate(data, "hammerstein-wiener", na=3, nb=3, nk=2)
    assert est.is_stable() and est.b[0] == 1.0 and est.output_block.coefficients[0] == 1.0
    base = simulation_mse(linear_baseline(data, 3, 3, 2), data)
    assert simulation_mse(est, data) < 0.05 * base  # measured 0.5 %
    identity_q = initial_estimate(data, "hammerstein", na=3, nb=3, nk=2)
    assert simulation_mse(est, data) < simulation_mse(identity_q, data)
    # the plain ARX fit is one of the candidates, so the start is never worse than it
    plain = fit_arx(data, 3, 3, 2).model
    assert simulation_mse(est, data) <= simulation_mse(plain, data)


def test_backlash_estimate_from_the_grid_search():
    """Paper A's S2 on a slow sinusoid: c on the grid next to the truth, equal slopes."""
    true = BacklashModel(
        "u1", "y1", input_block=Backlash(0.9, 0.8, 0.9, 0.85), na=2, nb=1, nk=1, a=[-1.0, 0.17]
    )
    u = 10 * np.sin(2 * np.pi * np.arange(2000) / 400)
    data = record(true, u)
    est = initial_estimate(data, "backlash", na=2, nb=1, nk=1)
    block = est.input_block
    assert block.c_left == block.c_right == pytest.approx(0.825, abs=0.1)
    assert block.m_left == block.m_right > 0
    assert est.is_stable() and est.b[0] == 1.0
    base = simulation_mse(linear_baseline(data, 2, 1, 1), data)
    assert simulation_mse(est, data) < 0.1 * base


@pytest.mark.parametrize(
    "true_block, template",
    [
        (DeadZone(-0.3, 0.2, 1.5, 0.8), DeadZone(0.0, 0.0)),
        (Saturation(-0.6, 0.5, 1.5), Saturation(-1.0, 1.0)),
    ],
    ids=["dead-zone", "saturation"],
)
def test_hard_nonlinearity_estimates_beat_a_linear_model(true_block, template):
    true = Hammerstein("u1", "y1", input_block=true_block, na=2, nb=2, nk=1, a=A2, b=[1, 0.5])
    rng = np.random.default_rng(4)
    data = record(true, rng.uniform(-1, 1, 3000), rng)
    est = initial_estimate(data, "hammerstein", na=2, nb=2, nk=1, input_block=template)
    assert type(est.input_block) is type(true_block)
    assert est.is_stable() and est.b[0] == 1.0
    base = simulation_mse(linear_baseline(data, 2, 2, 1), data)
    assert simulation_mse(est, data) < 0.25 * base  # measured 0.1 % and 15 %


def test_scaled_block_is_the_block_times_the_gain():
    u = np.linspace(-2, 2, 101)
    for block in (TWO_SEGMENT, DeadZone(-0.3, 0.2, 1.5, 0.8), Saturation(-0.6, 0.5, 1.5)):
        np.testing.assert_allclose(scaled_block(block, 2.5)(u), 2.5 * block(u), atol=1e-14)
    b = Backlash(0.9, 0.4, 1.1, 0.3)
    u = 2 * np.sin(np.arange(200) / 9)
    np.testing.assert_allclose(scaled_block(b, 2.5).simulate(u), 2.5 * b.simulate(u), atol=1e-13)
    with pytest.raises(EstimationError, match="keep the sign in the linear block"):
        scaled_block(DeadZone(0, 0), -1.0)


def test_unstable_poles_are_reflected_inside():
    a = np.real(np.poly([1.25, 0.5]))[1:]
    fixed = _stabilise(a)
    poles = np.sort(np.abs(np.roots(np.concatenate(([1.0], fixed)))))
    np.testing.assert_allclose(poles, [0.5, 0.99 / 1.25])
    stable = np.array([-1.2, 0.5])
    assert _stabilise(stable) is stable


def test_resolve_structure():
    assert resolve_structure("hammerstein-wiener") is HammersteinWiener
    assert resolve_structure(Wiener) is Wiener
    with pytest.raises(ParameterError, match="choose one of"):
        resolve_structure("narx")


def test_bad_requests_name_the_fix():
    true = Hammerstein("u1", "y1", input_block=TWO_SEGMENT, na=2, nb=2, nk=1, a=A2, b=[1, 0.5])
    data = record(true, uniform(5, 300))
    with pytest.raises(ParameterError, match="no input block"):
        initial_estimate(data, "wiener", na=2, nb=2, nk=1, input_block=TWO_SEGMENT)
    with pytest.raises(ParameterError, match="static input block"):
        initial_estimate(data, "hammerstein", na=2, nb=2, nk=1, input_block=Backlash(1, 0, 1, 0))
    with pytest.raises(OrderError, match="nb must be"):
        initial_estimate(data, "hammerstein", na=2, nb=0, nk=1)
    with pytest.raises(OrderError, match="r2 must be"):
        initial_estimate(data, "wiener", na=2, nb=2, nk=1, r2=0)
    with pytest.raises(OrderError, match="lower the orders"):
        initial_estimate(data.select(0, 10), "hammerstein", na=2, nb=2, nk=1)
    positive = Dataset.from_arrays(np.abs(data.experiments[0].u), data.experiments[0].y)
    with pytest.raises(EstimationError, match="never changes sign"):
        initial_estimate(positive, "hammerstein", na=2, nb=2, nk=1)


def test_a_backlash_plant_with_negative_gain_keeps_its_sign_in_the_linear_block():
    """A backlash's slopes stay positive: the plant's negative gain is b_0 = -1 of the
    linear block (the sign once sent the user to negate the input, in a circle)."""
    true = BacklashModel(
        "u1", "y1", input_block=Backlash(0.9, 0.3, 0.9, 0.3), na=1, nb=1, nk=1, a=[-0.5]
    )
    u = 3 * np.sin(2 * np.pi * np.arange(600) / 200)
    flipped = Dataset.from_arrays(u, -true.simulate(u)[:, 0])
    est = initial_estimate(flipped, "backlash", na=1, nb=1, nk=1)
    assert est.b[0] == -1.0 and est.input_block.m_left > 0 and est.input_block.m_right > 0
    np.testing.assert_allclose(est.simulate(u)[:, 0], flipped.experiments[0].y[:, 0],
                               atol=0.05 * np.abs(flipped.experiments[0].y).max())  # fmt: skip


def test_a_gain_moves_into_a_block_as_far_as_its_family_allows():
    """A positive-slope family takes ``|gain|`` and leaves the sign; a family linear in
    its parameters takes the gain whole."""
    from blockid.fitting.initial import absorbed_gain

    u = np.linspace(-2, 2, 101)
    sat = Saturation(-0.6, 0.5, 1.5)
    block, sign = absorbed_gain(sat, -2.0)
    assert sign == -1.0
    np.testing.assert_allclose(sign * block(u), -2.0 * sat(u), atol=1e-14)
    poly = Polynomial([0.0, 1.0, 0.3])
    block, sign = absorbed_gain(poly, -2.0)
    assert sign == 1.0
    np.testing.assert_allclose(block(u), -2.0 * poly(u), atol=1e-14)


@pytest.mark.parametrize(
    "block", [Saturation(-0.8, 0.6, 1.0), DeadZone(-0.2, 0.3, 1.0, 1.0)], ids=lambda b: b.kind
)
def test_a_hard_output_block_is_shaped_before_the_refinement(block):
    """Output blocks not linear in their parameters start from the best shape of their
    grid fitted to the linear start's x (a saturation left at its template (-1, 1)
    refined into a local minimum 25 times the noise floor)."""
    plant = Wiener("u", "y", output_block=block, na=2, nb=2, nk=1, a=[-1.2, 0.35], b=[1.0, 0.4])
    rng = np.random.default_rng(0)
    u = rng.normal(0.0, 0.08, 3000)
    y = plant.simulate(u)[:, 0]
    y = y + 0.01 * np.std(y) * rng.standard_normal(y.size)
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    fit = fit_model(data, "wiener", na=2, nb=2, nk=1, output_block=block.kind)
    gain = plant.b[0] / fit.model.b[0]  # the gain between the blocks is not identifiable
    got = fit.model.output_block.parameters
    assert simulation_mse(fit.model, data) < 1.05 * simulation_mse(plant, data)
    if block.kind == "saturation":
        assert got["lower"] == pytest.approx(-0.8, rel=0.02)
        assert got["upper"] == pytest.approx(0.6, rel=0.02)
        assert got["slope"] / gain == pytest.approx(1.0, rel=0.02)
    else:
        assert got["lower"] * gain == pytest.approx(-0.2, rel=0.03)
        assert got["upper"] * gain == pytest.approx(0.3, rel=0.03)


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
def test_initial_backlash_estimate_of_a_plant_with_a_tiny_gain_is_the_scaled_one():
    # measured in units where the gain is 1e-13: every grid shape's b_0 is about 1e-13,
    # below 1e-12 in absolute terms but far from zero relative to b itself
    from blockid.fitting import initial_estimate

    truth, data = _backlash_data()
    _, tiny = _backlash_data(scale=1e-13)
    plain = initial_estimate(data, "backlash", na=1, nb=1, nk=1).parameters
    small = initial_estimate(tiny, "backlash", na=1, nb=1, nk=1).parameters
    assert plain["c_left"] == pytest.approx(0.3, abs=0.02)
    assert plain["m_left"] == pytest.approx(1.0, abs=0.03)
    for key in ("c_left", "c_right", "a"):
        np.testing.assert_allclose(small[key], plain[key], rtol=1e-9)
    for key in ("m_left", "m_right"):
        assert small[key] == pytest.approx(1e-13 * plain[key], rel=1e-9)


def test_start_score_runs_from_the_measured_initial_outputs():
    from blockid.fitting.initial import _sse

    truth, data = _backlash_data()
    u = data.experiments[0].u[:, 0]
    z = truth.simulate(u, [2.0])[:, 0]  # started away from rest: x(0) = 2
    assert _sse(truth, [u], [z]) == 0.0
    other = _backlash_model(a=-0.4)
    expected = np.sum((z[1:] - other.simulate(u, [2.0])[1:, 0]) ** 2)
    assert _sse(other, [u], [z]) == pytest.approx(expected, rel=1e-12)
    assert _sse(None, [u], [z]) == np.inf


def test_hammerstein_wiener_first_candidate_is_the_linear_fit():
    from blockid.fitting.initial import _linear_start, _signals, _template, _with_output_block
    from blockid.models import HammersteinWiener

    u, y = _arx_data()
    data = Dataset.from_arrays(u, y + 0.1 * y**3, ["u"], ["y"])
    template = _template(HammersteinWiener, data, 1, 2, 1, 3, 3, None, None)
    start = _linear_start(*_signals(data), template)
    first = _with_output_block(data, template)[0]
    np.testing.assert_array_equal(first.linear.a, start[1])
    np.testing.assert_array_equal(first.linear.b, start[2])


def _negative_gain_record(block, seed=0, n=2000):
    """``u -> block -> linear block of negative static gain`` at 40 dB (the issue's
    plant): the structure the fit takes, and the data."""
    cls, structure = (BacklashModel, "backlash") if block.kind == "backlash" else (
        Hammerstein, "hammerstein")  # fmt: skip
    plant = cls("u", "y", input_block=block, na=2, nb=2, nk=1, a=[-1.2, 0.5], b=[-1.0, -0.4])
    rng = np.random.default_rng(seed)
    u = rng.uniform(-2, 2, n)
    y = plant.simulate(u)[:, 0]
    y = y + y.std() * 0.01 * rng.standard_normal(n)
    return structure, Dataset.from_arrays(u, y, ["u"], ["y"])


@pytest.mark.parametrize(
    ("block", "edges"),
    [
        (Saturation(-0.8, 1.0, 1.0), ("lower", "upper")),
        (DeadZone(-0.5, 0.4, 1.0, 1.0), ("lower", "upper")),
        (Backlash(1.0, 0.3, 1.0, 0.3), ("c_left", "c_right")),
    ],
    ids=lambda b: getattr(b, "kind", ""),
)
def test_a_plant_of_negative_gain_is_fitted_with_its_block(block, edges):
    """Saturation, dead zone and backlash before a linear block of static gain -1/0.3:
    the default fit recovers the knees and edges within 2 % at 40 dB, the linear block
    its poles, the sign kept in b_0 = -1 (the fit once refused and said to negate the
    input)."""
    structure, data = _negative_gain_record(block)
    options = {} if structure == "backlash" else {"input_block": block.kind}
    fit = fit_model(data, structure, na=2, nb=2, nk=1, **options)
    got = fit.model.input_block
    for name in edges:
        assert getattr(got, name) == pytest.approx(getattr(block, name), rel=0.02)
    assert fit.model.b[0] == -1.0
    np.testing.assert_allclose(fit.model.a, [-1.2, 0.5], atol=0.01)
    np.testing.assert_allclose(fit.model.b[1], -0.4, atol=0.02)
