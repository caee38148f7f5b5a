"""Static blocks inside the loop of a block state-space model (multivariable Lur'e
systems, Wiener-Hammerstein paths): the exact Jacobian against finite differences, the
compiled loop against a plain one, known plants' blocks against the truth, the start
never bettered by a worse model, files, export and clear errors."""

import copy

import numpy as np
import pytest

import blockid.models.block_state_space as bss
from blockid import fit_model
from blockid.blocks import DeadZone, Polynomial, Saturation
from blockid.errors import ParameterError
from blockid.fitting.block_state_space import fit_block_state_space
from blockid.fitting.state_space import fit_state_space
from blockid.models import model_from_dict
from blockid.models.block_state_space import BlockStateSpace
from blockid.models.export import to_python_module

from reference import mimo_loop_plant, mimo_loop_record


def _fit_percent(model, u, y):
    ys = model.simulate(u, y[:20])
    return 100 * (1 - np.linalg.norm(ys - y, axis=0) / np.linalg.norm(y - y.mean(axis=0), axis=0))


@pytest.fixture(scope="module")
def lure():
    data, _, _ = mimo_loop_record("lure")
    return data, fit_block_state_space(data, nx=4, loop_block="saturation")


@pytest.fixture(scope="module")
def wiener_hammerstein():
    data, _, _ = mimo_loop_record("wiener-hammerstein")
    return data, fit_block_state_space(data, nx=4, loop_block="dead-zone")


def _true_units(fit_model_, kind, u):
    """Each fitted loop's argument against the plant's (the loop whose argument it
    follows), and the affine map from the one to the other."""
    plant = mimo_loop_plant(kind)
    p_fit = fit_model_._loop_run(fit_model_.block_inputs(fit_model_.normalised_input(u)), None)[1]
    p_true = plant._loop_run(plant.block_inputs(plant.normalised_input(u)), None)[1]
    out = []
    for l in range(p_fit.shape[1]):
        corr = [abs(np.corrcoef(p_fit[:, l], p_true[:, t])[0, 1]) for t in range(2)]
        t = int(np.argmax(corr))
        out.append((t, corr[t], np.polyfit(p_fit[:, l], p_true[:, t], 1)))
    return plant, out


def _knees(block):
    if block.kind == "saturation":
        return [block.lower / block.slope, block.upper / block.slope]
    return [block.lower, block.upper]


@pytest.mark.parametrize(
    ("kind", "block", "corr", "atol"),
    [("lure", "saturation", 0.9999, 0.01), ("wiener-hammerstein", "dead-zone", 0.999, 0.03)],
)
def test_each_loops_block_recovered_in_the_plants_units(
    kind, block, corr, atol, lure, wiener_hammerstein
):
    """The fitted loops' arguments follow the plant's (its outputs for the Lur'e plant,
    each path's middle signal for the Wiener-Hammerstein one; correlation above
    ``corr``), and mapped into the plant's units each block's knees (a saturation's) or
    edges (a dead zone's) lie within ``atol`` of the truth: -0.4/0.4 and -0.3/0.5,
    -0.3/0.2 and -0.2/0.4 (40 dB output noise)."""
    _, fit = lure if kind == "lure" else wiener_hammerstein
    u = np.random.default_rng(2).uniform(-1.5, 1.5, (1000, 2))
    plant, matched = _true_units(fit.model, kind, u)
    assert sorted(t for t, _, _ in matched) == [0, 1]
    for fitted, (t, r, to_true) in zip(fit.model.loop_blocks, matched, strict=True):
        assert fitted.kind == block and r > corr
        true = plant.loop_blocks[t]
        knees = sorted(np.polyval(to_true, _knees(fitted)))
        np.testing.assert_allclose(knees, [true.lower, true.upper], atol=atol)


@pytest.mark.parametrize("kind", ["lure", "wiener-hammerstein"])
def test_free_run_on_fresh_data_far_above_the_linear_state_space(kind, lure, wiener_hammerstein):
    data, fit = lure if kind == "lure" else wiener_hammerstein
    rng = np.random.default_rng(2)
    u = rng.uniform(-1.5, 1.5, (1000, 2))
    y = mimo_loop_plant(kind).simulate(u)
    ours = _fit_percent(fit.model, u, y)
    linear = _fit_percent(fit_state_space(data, nx=4).model, u, y)
    assert np.all(ours > 99.5), ours
    assert np.all(linear < 96), linear
    for name in ("y1", "y2"):  # never worse than its start, the linear model
        lin = fit.settings["linear_simulation_metrics"]["mse"][name]
        assert fit.estimation_metrics["mse"][name] <= lin


def _model(feedthrough=True):
    rng = np.random.default_rng(0)
    A = np.diag([0.7, 0.5, -0.3])
    A[0, 1] = 0.2
    return BlockStateSpace(
        ["a", "b"], ["y1", "y2"], A, rng.normal(size=(3, 2)), rng.normal(size=(2, 3)),
        np.zeros((2, 2)), input_blocks={"a": Polynomial([0.1, 1.0, 0.3])},
        loop_blocks=[Saturation(-0.5, 0.7), DeadZone(-0.2, 0.3, 0.8, 1.2)],
        Cp=rng.normal(size=(2, 3)), Dp=0.3 * rng.normal(size=(2, 2)) * feedthrough,
        Bq=0.3 * rng.normal(size=(3, 2)), Dq=0.2 * rng.normal(size=(2, 2)),
        output_blocks={"y2": Polynomial([0.0, 1.0, 0.2, 0.1], constant=False)},
        output_bias=[0.1, -0.2],
    )  # fmt: skip


def test_the_jacobian_is_the_finite_difference_of_the_simulation_across_pieces():
    """Every parameter (core, loop maps, input, loop and output blocks, h) and x(0):
    the compiled walk, carried over two pieces, against central differences."""
    m = _model()
    rng = np.random.default_rng(1)
    un = m.normalised_input(rng.normal(size=(300, 2)))
    x0 = rng.normal(size=3)
    carried = m._sensitivity_start(x0)
    first, J1 = m.jacobian_piece(un[:150], *carried)
    second, J2 = m.jacobian_piece(un[150:], *carried)
    J = np.vstack((J1, J2))
    np.testing.assert_array_equal(np.vstack((first, second)), m.run(un, x0)[0])
    theta, h = m.free_parameters(), 1e-6

    def run(t, x):
        return m.with_free_parameters(t).run(un, x)[0].reshape(-1)

    fd = np.zeros_like(J)
    for i in range(theta.size + 3):
        step = np.zeros(theta.size + 3)
        step[i] = h
        plus = run(theta + step[: theta.size], x0 + step[theta.size :])
        minus = run(theta - step[: theta.size], x0 - step[theta.size :])
        fd[:, i] = (plus - minus) / (2 * h)
    np.testing.assert_allclose(J, fd, rtol=0, atol=1e-6)
    assert np.abs(J).max(axis=0)[: theta.size][m.parameter_mask(True)].min() > 0


def _evaluated_in_python(model):
    """``model`` with each loop block replaced by the same block of a family the compiled
    loop does not know (a subclass whose ``compiled_form`` is None, as a block family of
    one's own may be): the model then runs its loop sample by sample in Python."""

    def uncompiled(block):
        family = type(f"Uncompiled{type(block).__name__}", (type(block),),
                      {"compiled_form": lambda self: None})  # fmt: skip
        twin = copy.copy(block)
        twin.__class__ = family
        return twin

    return model.replace(loop_blocks=[uncompiled(b) for b in model.loop_blocks])


def test_the_compiled_loop_equals_the_plain_python_loop():
    """Inside and outside a polynomial loop block's recorded range (where it continues
    along its tangent), with a two-segment polynomial and the piecewise-linear kinds."""
    from blockid.blocks.polynomial import TwoSegmentPolynomial

    m = _model().replace(
        loop_blocks=[Polynomial([0.0, 1.0, 0.0, -0.2]), TwoSegmentPolynomial([0, 1, 0.3], [0, 0.5, 0])],
        loop_range=[[-0.5, 0.5], [-1.0, 1.0]],
    )  # fmt: skip
    un = np.random.default_rng(3).normal(size=(400, 2))
    assert np.abs(m._loop_run(m.block_inputs(un), None)[1]).max() > 1.0  # beyond the ranges
    for model in (m, _model()):  # polynomial kinds, then the piecewise-linear ones
        python = _evaluated_in_python(model)
        assert bss._pack(model.loop_blocks) is not None and bss._pack(python.loop_blocks) is None
        np.testing.assert_allclose(python.run(un)[0], model.run(un)[0], rtol=0, atol=1e-12)


def test_a_fitted_loop_model_saved_loaded_and_exported_simulates_identically(lure):
    data, fit = lure
    m = fit.model
    back = model_from_dict(m.to_dict())
    namespace: dict = {}
    exec(to_python_module(back), namespace)  # noqa: S102 - the module under test
    u, y0 = data.experiments[0].u, data.experiments[0].y[:20]
    for start in (None, y0):
        ours = m.simulate(u, start)
        np.testing.assert_array_equal(back.simulate(u, start), ours)
        np.testing.assert_allclose(namespace["simulate"](u, start), ours, rtol=0, atol=1e-10)


def test_loops_have_their_curves_ranges_and_names(lure):
    data, fit = lure
    m = fit.model
    assert m.kind == "loop" and m.loops == ("p1", "p2")
    assert set(m.range_excursion(data.experiments[0].u)) == {"p p1", "p p2"}
    assert m.range_excursion(data.experiments[0].u)["p p1"] < 0.2  # the estimation data
    titles = [c["title"] for c in m.static_curves(data.experiments[0].u)]
    assert titles == ["loop block p1 (saturation)", "loop block p2 (saturation)"]
    names = m.free_parameter_names()
    assert "Bq[0,1]" in names and "Cp[1,3]" in names and "loop p2: upper" in names
    assert set(m.shaped(np.zeros(len(names)))) >= {"Bq", "Dq", "Cp", "Dp", "loop block p2"}


def test_a_loop_named_by_its_output_and_an_unknown_output_named():
    data, _, _ = mimo_loop_record("lure", n=600)
    fit = fit_model(data, "block-state-space", nx=4, loop_block="y2=saturation", max_nfev=5)
    assert len(fit.model.loop_blocks) == 1 and fit.settings["loop_blocks"] == ["saturation"]
    with pytest.raises(ParameterError, match=r"\['y7'\]"):
        fit_model(data, "block-state-space", loop_block="y7=saturation")
