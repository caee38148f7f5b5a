"""The integrator block against slow reference twins: a plain loop for its recursion,
finite differences for the sensitivities it passes on, and its files."""

import numpy as np
import pytest

from blockid.blocks import Integrator, LinearBlock, Polynomial, block_from_dict, block_template
from blockid.errors import ParameterError
from blockid.fitting.simulation_error import simulate_with_sensitivities
from blockid.models import ChainModel, load_model, save_model


def _loop(w, order, x_init=()):
    """x(k) = sum_j c_j x(k-j) + w(k-1), (1 - z^-1)^order = 1 - sum_j c_j z^-j, at rest
    before k = 0; the first len(x_init) outputs given."""
    c = -np.poly(np.ones(order))[1:]
    x = [0.0] * len(w)
    for k in range(len(w)):
        if k < len(x_init):
            x[k] = float(x_init[k])
            continue
        past = sum(c[j - 1] * (x[k - j] if k - j >= 0 else 0.0) for j in range(1, order + 1))
        x[k] = past + (w[k - 1] if k >= 1 else 0.0)
    return np.array(x)


@pytest.mark.parametrize("order", [1, 2, 3])
@pytest.mark.parametrize("x_init", [None, [0.7], [0.7, -0.2]])
def test_simulate_is_the_recursion(order, x_init):
    w = np.random.default_rng(order).standard_normal(50)
    block = Integrator(order)
    # as LinearBlock.simulate: the first `order` outputs given, missing ones zero
    given = () if x_init is None else (list(x_init) + [0.0] * order)[:order]
    np.testing.assert_allclose(block.simulate(w, x_init), _loop(w, order, given), atol=1e-12)


def test_it_is_the_linear_block_of_its_coefficients():
    w = np.random.default_rng(1).standard_normal(40)
    for order, a in ((1, [-1.0]), (2, [-2.0, 1.0])):
        block = Integrator(order)
        twin = LinearBlock(order, 1, 1, a, [1.0])
        assert block.a.tolist() == a and block.b.tolist() == [1.0] and block.nk == 1
        np.testing.assert_allclose(block.simulate(w), twin.simulate(w), atol=1e-12)
        np.testing.assert_allclose(block.simulate(w, [2.0, 3.0]), twin.simulate(w, [2.0, 3.0]))
        y = block.simulate(w, [2.0, 3.0])
        np.testing.assert_allclose(block.predict(w, y), twin.predict(w, y), atol=1e-12)
        np.testing.assert_allclose(block.poles(), np.ones(order))


@pytest.mark.parametrize("order", [1, 2])
def test_forward_integrates_the_incoming_sensitivities(order):
    rng = np.random.default_rng(2)
    w, S_in = rng.standard_normal(30), rng.standard_normal((30, 3))
    x0, S0 = np.array([1.0, 2.0]), rng.standard_normal((2, 3))
    block = Integrator(order)
    own = np.full(order + 1, -1)
    for init in (None, (x0, S0)):
        x, S = block.forward(w, S_in, own, init)
        given = () if init is None else x0[:order]
        np.testing.assert_allclose(x, _loop(w, order, given), atol=1e-12)
        for j in range(3):
            start = () if init is None else S0[:order, j]
            np.testing.assert_allclose(S[:, j], _loop(S_in[:, j], order, start), atol=1e-12)


@pytest.mark.parametrize("order", [1, 2])
def test_chain_sensitivities_through_the_integrator_match_differences(order):
    chain = ChainModel(
        "u",
        "y",
        [
            Polynomial([0.1, 1.0, 0.3]),
            LinearBlock(2, 2, 1, [-1.2, 0.35], [1.0, 0.4]),
            Integrator(order),
        ],
    )
    rng = np.random.default_rng(3)
    u, y0 = rng.uniform(-1, 1, 80), np.array([0.5, 0.8])
    y, dy = simulate_with_sensitivities(chain, u, y0)
    np.testing.assert_allclose(y, chain.simulate(u, y0[: chain.max_lag])[:, 0], atol=1e-9)
    theta = chain.free_parameters()
    assert dy.shape == (80, theta.size) and theta.size == 6  # the integrator adds none
    for i in range(theta.size):
        h = 1e-6 * max(1.0, abs(theta[i]))
        up, down = theta.copy(), theta.copy()
        up[i] += h
        down[i] -= h
        diff = (
            chain.with_free_parameters(up).simulate(u, y0)[:, 0]
            - chain.with_free_parameters(down).simulate(u, y0)[:, 0]
        ) / (2 * h)
        np.testing.assert_allclose(dy[:, i], diff, rtol=1e-5, atol=1e-5 * np.abs(diff).max())


def test_differenced_recovers_the_input():
    rng = np.random.default_rng(4)
    u, w = rng.standard_normal(60), rng.standard_normal(60)
    for order in (1, 2):
        x = Integrator(order).simulate(w, [0.3, -0.1])
        u_k, w_k = Integrator(order).differenced(u, x)
        np.testing.assert_allclose(w_k, w[order - 1 : 59], atol=1e-11)
        np.testing.assert_array_equal(u_k, u[order - 1 : 59])
    with pytest.raises(ParameterError, match="longer record"):
        Integrator(2).differenced(u[:2], w[:2])


def test_nothing_to_fit_and_never_unstable():
    block = Integrator(2)
    assert block.parameters == {"order": 2} and block.integrates == 2
    assert not block.free_mask(True).any() and not block.free_mask(False).any()
    assert block.is_stable() and block.is_stable(0.5)
    assert block.with_vector(block.to_vector()) is block
    with pytest.raises(ParameterError, match="no free parameters"):
        block.with_vector([-2.0, 1.0, 2.0])
    assert block.rest_state(3.0) == 0.0
    for bad in (0, -1, 1.5, True, "1"):
        with pytest.raises(ParameterError, match="whole number"):
            Integrator(bad)


def test_files_and_templates_round_trip(tmp_path):
    for order in (1, 2):
        block = Integrator(order)
        assert block.to_dict() == {"kind": "integrator", "order": order}
        again = block_from_dict(block.to_dict())
        assert type(again) is Integrator and again.order == order
    assert block_template("integrator").order == 1
    assert block_template("integrator:order=2").order == 2
    chain = ChainModel(
        "u",
        "y",
        [LinearBlock(1, 1, 0, [-0.5], [0.2]), Integrator(2)],
        input_offset=0.1,
        output_offset=2.0,
    )
    path = tmp_path / "m.json"
    save_model(chain, path)
    loaded = load_model(path)
    u = np.random.default_rng(5).standard_normal(50)
    assert [b.kind for b in loaded.blocks] == ["linear", "integrator"]
    np.testing.assert_array_equal(loaded.simulate(u, [1.0, 1.5]), chain.simulate(u, [1.0, 1.5]))


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
def test_integrator_refuses_a_complex_initial_output():
    # read as floats: a complex start is an error, not cut to its real part
    np.testing.assert_array_equal(Integrator().simulate(np.ones(3), x_init=[2]), [2.0, 3.0, 4.0])
    with pytest.raises(TypeError):
        Integrator().simulate(np.ones(3), x_init=[2.0 + 1.0j])
