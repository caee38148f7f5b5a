"""The linear block with a polynomial in feedback (Lur'e form): simulation against a
textbook twin, exact one-step prediction, Jacobian, files and refusals."""

import numpy as np
import pytest

import blockid.fitting.simulation_error as simulation_error
from blockid import errors
from blockid.blocks import Backlash, DeadZone, PiecewiseLinear, Polynomial, Saturation
from blockid.blocks.free_pwl import FreePiecewiseLinear
from blockid.blocks.linear import LinearBlock
from blockid.data import Dataset
from blockid.models import load_model, model_from_dict, save_model
from blockid.models.feedback import LinearFeedback

from reference import TanhSpring, _feedback


def duffing(**kwargs):
    kwargs.setdefault("feedback", Polynomial([0.0, 0.1, 1.0], constant=False))
    return LinearFeedback(
        "u", "y", linear=LinearBlock(2, 2, 1, a=[-1.5, 0.7], b=[0.2, 0.1]), **kwargs
    )


def simulate_reference(model, u, y_initial=None):
    """``A y = z^-nk B (u - N(y))`` around the offsets, one sample at a time."""
    a, b, nk = model.linear.a, model.linear.b, model.linear.nk
    c = model.feedback.coefficients
    s = np.asarray(u, float) - model.input_offset
    N = s.size
    y = np.zeros(N)
    n0 = 0
    if y_initial is not None:
        n0 = min(model.max_lag, N)
        k = min(n0, len(y_initial))
        y[:k] = np.asarray(y_initial, float)[:k] - model.output_offset

    def v(t):
        return 0.0 if t < 0 else s[t] - sum(cm * y[t] ** (m + 1) for m, cm in enumerate(c))

    for t in range(n0, N):
        y[t] = -sum(a[j] * (y[t - j - 1] if t - j - 1 >= 0 else 0.0) for j in range(len(a)))
        y[t] += sum(b[i] * v(t - nk - i) for i in range(len(b)))
    return y + model.output_offset


def _input(n=400, seed=0):
    return np.random.default_rng(seed).normal(0.0, 0.5, n)


@pytest.mark.parametrize("y_initial", [None, "measured", "short"])
def test_simulation_matches_the_textbook_recursion(y_initial):
    model = duffing(input_offset=0.3, output_offset=-1.2)
    u = _input() + 0.3
    y = model.simulate(u)[:, 0] + 0.01 * np.random.default_rng(1).standard_normal(u.size)
    y0 = {None: None, "measured": y[:5], "short": y[:1]}[y_initial]
    expected = simulate_reference(model, u, y0)
    assert np.all(np.isfinite(expected))
    np.testing.assert_allclose(model.simulate(u, y0)[:, 0], expected, rtol=0, atol=1e-12)
    if y0 is not None:
        assert model.simulate(u, y0)[0, 0] == y[0]


def test_one_step_prediction_is_exact_on_noise_free_data():
    model = duffing(input_offset=0.1, output_offset=2.0)
    u = _input() + 0.1
    y = model.simulate(u)
    pred = model.predict(u, y)
    assert pred.shape == y.shape
    np.testing.assert_allclose(pred, y, rtol=0, atol=1e-12)
    # on other outputs it is the textbook one-step formula from the measured outputs
    y_other = y[:, 0] + 0.05 * np.random.default_rng(2).standard_normal(u.size)
    pred = model.predict(u, y_other)[:, 0]
    yt, s = y_other - model.output_offset, u - model.input_offset
    v = s - sum(cm * yt ** (m + 1) for m, cm in enumerate(model.feedback.coefficients))
    t = np.arange(model.max_lag, u.size)
    one = -model.a[0] * yt[t - 1] - model.a[1] * yt[t - 2] + model.b[0] * v[t - 1]
    one += model.b[1] * v[t - 2]
    np.testing.assert_allclose(pred[t], one + model.output_offset, rtol=0, atol=1e-12)
    assert np.array_equal(pred[: model.max_lag], y_other[: model.max_lag])


@pytest.mark.parametrize("start_from_data", [False, True])
def test_sensitivities_equal_finite_differences(start_from_data):
    model = duffing(input_offset=0.2, output_offset=0.5)
    u = _input(300) + 0.2
    y0 = model.simulate(u)[: model.max_lag, 0] + 0.05 if start_from_data else None
    y_sim, S = model.simulate_with_sensitivities(u, y0)
    np.testing.assert_allclose(y_sim, model.simulate(u, y0)[:, 0], rtol=0, atol=1e-12)
    theta = model.free_parameters()
    assert S.shape == (u.size, theta.size)
    for i in range(theta.size):
        h = 1e-6 * max(1.0, abs(theta[i]))
        up, down = theta.copy(), theta.copy()
        up[i] += h
        down[i] -= h
        fd = (
            model.with_free_parameters(up).simulate(u, y0)[:, 0]
            - model.with_free_parameters(down).simulate(u, y0)[:, 0]
        ) / (2 * h)
        np.testing.assert_allclose(S[:, i], fd, rtol=1e-5, atol=1e-7)
    if start_from_data:
        assert np.all(S[: model.max_lag] == 0.0)


def test_parameters_names_orders_and_stability():
    model = duffing()
    assert model.free_parameter_names() == ["a_1", "a_2", "b_0", "b_1", "c_2", "c_3"]
    assert model.free_parameters().tolist() == [-1.5, 0.7, 0.2, 0.1, 0.1, 1.0]
    assert model.parameters == {"a": [-1.5, 0.7], "b": [0.2, 0.1], "c": [0.1, 1.0]}
    assert model.linear_orders() == (2, 2, 1) and model.max_lag == 2 and model.degree == 3
    lo, hi = model.parameter_bounds()
    assert np.all(np.isneginf(lo)) and np.all(np.isposinf(hi)) and lo.size == 6
    np.testing.assert_allclose(np.abs(model.poles()), np.sqrt(0.7))
    assert model.is_stable(1e-3)
    assert not model.with_free_parameters([-2.0, 1.1, 0.2, 0.1, 0.1, 1.0]).is_stable()
    again = model.with_free_parameters(model.free_parameters())
    assert again.parameters == model.parameters
    with pytest.raises(errors.OrderError, match="expected 6 free parameters"):
        model.with_free_parameters([1.0, 2.0])
    # the chain-facing members the fitting settings read
    assert model.linear_blocks == (model.linear,)
    assert model.input_block is None and model.output_block is None


def test_file_round_trip_is_bit_identical_with_offsets_and_ranges(tmp_path):
    model = duffing(sampling_time=0.01, input_offset=0.25, output_offset=-1.5)
    u = _input() + 0.25
    y = model.simulate(u)
    model = model.with_ranges([(u, y)])
    assert set(model.ranges) == {"u", "y"}
    assert model.ranges["y"] == [float(y.min() + 1.5), float(y.max() + 1.5)]
    again = load_model(save_model(model, tmp_path / "feedback.json"))
    assert type(again) is LinearFeedback
    assert again.ranges == model.ranges
    assert (again.input_offset, again.output_offset, again.sampling_time) == (0.25, -1.5, 0.01)
    assert np.array_equal(again.free_parameters(), model.free_parameters())
    assert np.array_equal(again.simulate(u, y[:2]), model.simulate(u, y[:2]))
    assert np.array_equal(again.predict(u, y), model.predict(u, y))
    assert again.to_dict() == model.to_dict()
    assert type(model_from_dict(model.to_dict())) is LinearFeedback


def test_replace_keeps_or_drops_ranges():
    u = _input()
    model = duffing().with_ranges([(u, duffing().simulate(u))])
    assert model.replace(sampling_time=0.5).ranges == model.ranges
    assert model.replace(output_offset=1.0).ranges == {}
    kept = model.replace(output_offset=1.0, ranges=model.ranges)
    assert kept.ranges == model.ranges
    with pytest.raises(TypeError, match="unknown"):
        model.replace(colour="red")


def test_extrapolation_of_the_feedback_polynomial_is_flagged():
    model = duffing()
    u = _input()
    model = model.with_ranges([(u, model.simulate(u))])
    assert model.extrapolation(u) == []
    notes = model.extrapolation(1.5 * u)
    assert len(notes) == 1 and "feedback polynomial" in notes[0] and "'y'" in notes[0]
    # the recorded range of y covers the model's own free run too: never a warning on
    # the estimation data, even for a model that swings wider than the measurement
    softer = duffing(feedback=None)  # the zero cubic: larger swings than the plant
    y = duffing().simulate(u)
    softer = softer.with_ranges([(u, y)])
    assert softer.ranges["y"][1] > float(y.max())
    assert softer.extrapolation(u) == []


def test_models_that_make_no_sense_are_refused():
    lin = LinearBlock(2, 1, 1, a=[-1.5, 0.7], b=[0.5])
    with pytest.raises(errors.OrderError, match="nk >= 1"):
        LinearFeedback("u", "y", linear=LinearBlock(2, 1, 0, a=[-1.5, 0.7], b=[0.5]))
    with pytest.raises(errors.OrderError, match="must be a static block.*backlash"):
        LinearFeedback("u", "y", linear=lin, feedback=Backlash(1.0, 0.1, 1.0, 0.1))
    with pytest.raises(errors.OrderError, match="must be a static block.*linear"):
        LinearFeedback("u", "y", linear=lin, feedback=LinearBlock(1, 1, 1, a=[0.5], b=[1.0]))
    with pytest.raises(errors.OrderError, match="no constant and no linear term"):
        LinearFeedback("u", "y", linear=lin, feedback=Polynomial([0.3, 0.0, 1.0], constant=False))
    with pytest.raises(errors.OrderError, match="no constant and no linear term"):
        LinearFeedback("u", "y", linear=lin, feedback=Polynomial([0.0, 0.0, 1.0]))
    with pytest.raises(errors.OrderError, match="one input"):
        LinearFeedback(["u1", "u2"], "y", linear=lin)
    with pytest.raises(errors.OrderError, match="LinearBlock"):
        LinearFeedback("u", "y", linear=Polynomial([1.0]))
    with pytest.raises(errors.ModelFileError, match="blocks do not fit"):
        data = duffing().to_dict()
        data["linear"]["nk"] = 0
        model_from_dict(data)


def test_refine_recovers_the_plant_from_a_perturbed_start():
    truth = duffing(input_offset=0.2, output_offset=0.4)
    u = _input(3000, seed=5) + 0.2
    data = Dataset.from_arrays(u, truth.simulate(u), ["u"], ["y"])
    rng = np.random.default_rng(6)
    theta = truth.free_parameters()
    start = truth.with_free_parameters(theta * (1 + 0.05 * rng.standard_normal(theta.size)))
    fit = simulation_error.refine(start, data, tail_fraction=0.0)
    np.testing.assert_allclose(fit.model.free_parameters(), theta, atol=1e-7)
    assert fit.model.output_offset == 0.4 and set(fit.model.ranges) == {"u", "y"}
    assert fit.settings["na"] == 2 and fit.settings["output_block"] is None
    assert fit.metrics_mode == "simulation"


# ----------------------------------------------------- other static blocks in feedback
def _fed_back(block, **kwargs):
    return LinearFeedback(
        "u", "y", linear=LinearBlock(2, 2, 1, a=[-1.5, 0.7], b=[0.5, 0.2]), feedback=block,
        **kwargs,
    )  # fmt: skip


OTHER_BLOCKS = {
    "dead-zone": DeadZone(-0.3, 0.4, 0.8, 0.6),
    "saturation": Saturation(-0.5, 0.4, 0.7),
    "piecewise-linear": PiecewiseLinear([-1.0, 0.0, 0.5, 1.0], [-0.6, 0.0, 0.1, 0.6]),
    "piecewise-linear-free": FreePiecewiseLinear([-1.0, 0.0, 0.5, 1.0], [-0.6, 0.0, 0.1, 0.6]),
    "user block (Python loop)": TanhSpring(0.4),
}


def block_reference(model, u, y_initial=None):
    """``A y = z^-nk B (u - N(y))`` with the block itself called on every sample."""
    a, b, nk, block = model.linear.a, model.linear.b, model.linear.nk, model.feedback
    s = np.asarray(u, float) - model.input_offset
    y, v = np.zeros(s.size), np.zeros(s.size)
    n0 = 0
    if y_initial is not None:
        n0 = model.max_lag
        y[:n0] = np.asarray(y_initial, float)[:n0] - model.output_offset
    for t in range(s.size):
        if t >= n0:
            y[t] = -sum(a[j] * y[t - j - 1] for j in range(len(a)) if t - j - 1 >= 0)
            y[t] += sum(b[i] * v[t - nk - i] for i in range(len(b)) if t - nk - i >= 0)
        v[t] = s[t] - float(block(np.array([y[t]]))[0])
    return y + model.output_offset


@pytest.mark.parametrize("name", list(OTHER_BLOCKS))
@pytest.mark.parametrize("start", [None, "measured"])
def test_other_blocks_in_feedback_simulate_as_the_recursion(name, start):
    model = _fed_back(OTHER_BLOCKS[name], input_offset=0.2, output_offset=-0.5)
    u = 0.2 + 2.0 * _input(300, seed=4)
    y0 = None if start is None else [-0.3, -0.6]
    got = model.simulate(u, y0)[:, 0]
    np.testing.assert_allclose(got, block_reference(model, u, y0), rtol=0, atol=1e-12)
    assert np.ptp(got) > 0.5  # the input drives the loop through the block's kinks


@pytest.mark.parametrize("name", list(OTHER_BLOCKS))
def test_sensitivities_of_other_blocks_match_finite_differences(name):
    model = _fed_back(OTHER_BLOCKS[name])
    u = 2.0 * _input(300, seed=5)
    y0 = [0.1, -0.2]
    y, dy = model.simulate_with_sensitivities(u, y0)
    np.testing.assert_array_equal(y, model.simulate(u, y0)[:, 0])
    theta = model.free_parameters()
    assert dy.shape == (u.size, theta.size)
    for i in range(theta.size):
        h = 1e-6 * max(1.0, abs(theta[i]))
        up, down = theta.copy(), theta.copy()
        up[i] += h
        down[i] -= h
        fd = (
            model.with_free_parameters(up).simulate(u, y0)[:, 0]
            - model.with_free_parameters(down).simulate(u, y0)[:, 0]
        ) / (2 * h)
        np.testing.assert_allclose(dy[:, i], fd, rtol=0, atol=1e-5 * np.max(np.abs(dy)))


def test_free_entries_and_names_of_other_blocks():
    dz = _fed_back(OTHER_BLOCKS["dead-zone"])
    assert dz.free_parameter_names() == [
        "a_1", "a_2", "b_0", "b_1", "N.lower", "N.upper", "N.slope_left", "N.slope_right"
    ]  # fmt: skip
    lo, hi = dz.parameter_bounds()
    assert np.all(lo[:4] == -np.inf) and lo[6] > 0 and lo[7] > 0 and np.all(hi == np.inf)
    free = _fed_back(OTHER_BLOCKS["piecewise-linear-free"])
    names = free.free_parameter_names()
    assert "N.breakpoints_0" not in names and "N.breakpoints_3" not in names  # ends fixed
    assert "N.breakpoints_1" in names and "N.values_0" in names
    moved = free.with_free_parameters(free.free_parameters() + 0.01)
    assert moved.feedback.breakpoints[0] == -1.0 and moved.feedback.breakpoints[-1] == 1.0
    assert dz.parameters == {
        "a": [-1.5, 0.7], "b": [0.5, 0.2], "N.lower": -0.3, "N.upper": 0.4,
        "N.slope_left": 0.8, "N.slope_right": 0.6,
    }  # fmt: skip
    assert duffing().parameters.keys() == {"a", "b", "c"}


def test_poles_are_those_of_the_loop_linearised_at_rest():
    """A saturation has slope m at rest: the small-signal loop is A + m z^-1 B."""
    sat = _fed_back(Saturation(-0.5, 0.4, 0.7))
    expected = np.roots([1.0, -1.5 + 0.7 * 0.5, 0.7 + 0.7 * 0.2])
    np.testing.assert_allclose(np.sort_complex(sat.poles()), np.sort_complex(expected))
    # a dead zone around 0 has no slope there: the poles of A
    dz = _fed_back(DeadZone(-0.3, 0.4))
    np.testing.assert_allclose(np.sort_complex(dz.poles()), np.sort_complex(dz.linear.poles()))
    # A stable, but a negative feedback slope of -1.2 makes the loop at rest unstable
    unstable = _fed_back(PiecewiseLinear([-1.0, 1.0], [1.2, -1.2]))
    assert unstable.linear.is_stable() and not unstable.is_stable()
    assert np.max(np.abs(unstable.poles())) > 1.0


@pytest.mark.parametrize("name", ["dead-zone", "saturation", "piecewise-linear-free"])
def test_other_blocks_in_feedback_save_and_load(name, tmp_path):
    model = _fed_back(OTHER_BLOCKS[name], input_offset=0.1, output_offset=0.2)
    u = _input(200, seed=6)
    model = model.with_ranges([(u, model.simulate(u))])
    save_model(model, tmp_path / "m.json")
    loaded = load_model(tmp_path / "m.json")
    assert loaded.feedback.kind == model.feedback.kind
    np.testing.assert_array_equal(loaded.simulate(u), model.simulate(u))
    np.testing.assert_array_equal(loaded.free_parameters(), model.free_parameters())


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
U = np.array([0.0, 1.0, -2.0, 0.5, 3.0, -1.0])


def test_feedback_block_without_kind_is_refused_by_name():
    from blockid.blocks.linear import LinearBlock
    from blockid.errors import OrderError
    from blockid.models.feedback import LinearFeedback

    with pytest.raises(OrderError) as info:
        LinearFeedback("u", "y", linear=LinearBlock(1, 1, 1, a=[-0.5], b=[1.0]), feedback=object())
    assert str(info.value) == (
        "the feedback block must be a static block (polynomial, dead-zone, saturation, "
        "piecewise-linear, ...), got object; a dynamic or linear block cannot be fed back"
    )


def test_feedback_template_refuses_a_degree_below_one():
    from blockid.errors import OrderError
    from blockid.models.feedback import LinearFeedback

    with pytest.raises(OrderError) as info:
        LinearFeedback.template("u", "y", na=1, nb=1, nk=1, r=0)
    assert str(info.value) == "the feedback degree r must be a whole number >= 1, got 0"


def test_feedback_ranges_of_a_diverging_free_run_keep_the_measured_outputs():
    # N(y) = y^2: y(t) = 0.5 y(t-1) + u(t-1) - y(t-1)^2 runs to -inf, then NaN
    model = _feedback([0.0, 1.0])
    u = np.array([0.0] + [3.0] * 15)
    y = np.array([0.0, 0.5, 1.0, -1.0, 2.0] + [0.0] * 11)
    assert not np.isfinite(model.simulate(u)).all()
    assert model.estimation_ranges([(u, y)]) == {"u": [0.0, 3.0], "y": [-1.0, 2.0]}


def test_feedback_extrapolation_tolerates_two_percent_of_the_range():
    from blockid.blocks.linear import LinearBlock

    # N = 0 and y(t) = u(t-1); range [-1, 49]: 2 % is 1, so y = -2 and 50 are still inside
    model = _feedback(
        [0.0, 0.0], linear=LinearBlock(0, 1, 1, b=[1.0]), ranges={"u": [-2, 50], "y": [-1, 49]}
    )
    assert model.extrapolation(np.array([-2.0, 50.0, 0.0])) == []
    assert model.extrapolation(np.array([-2.0, -2.5, 0.0])) == [
        "the output 'y' (input of the feedback polynomial) leaves the range seen in "
        "estimation [-1, 49] in 1 of 3 samples (by up to 3 % of that range): the model "
        "extrapolates there"
    ]


def test_feedback_from_dict_without_offsets_has_zero_offsets():
    model = _feedback([0.0, 0.1], input_offset=0.5, output_offset=1.0)
    data = model.to_dict()
    data.pop("offsets")
    loaded = model_from_dict(data)
    assert (loaded.input_offset, loaded.output_offset) == (0.0, 0.0)
    np.testing.assert_array_equal(loaded.simulate(U), _feedback([0.0, 0.1]).simulate(U))
