"""The block state-space model: static blocks per channel around a MIMO linear core.

Against a slow reference written from the equations, its exact Jacobian against central
differences, walked in pieces, files and the exported module."""

import json

import numpy as np
import pytest

from blockid.blocks import DeadZone, PiecewiseLinear, Polynomial, Saturation
from blockid.errors import DataError, ModelFileError, OrderError
from blockid.models import model_from_dict
from blockid.models.block_state_space import BlockStateSpace
from blockid.models.export import to_python_module

from reference import assert_shaped_follows_the_names, tank_overflow_plant

A = [[0.7, 0.2, 0.0], [-0.2, 0.7, 0.0], [0.0, 0.0, 0.5]]
B = [[1.0, 0.0], [0.0, 0.5], [0.3, 1.0]]
C = [[1.0, 0.0, 0.5], [0.0, 1.0, 1.0]]
D = [[0.1, 0.0], [0.0, 0.2]]


def _model(**changes):
    kwargs = dict(
        input_blocks=[Polynomial([0.1, 1.0, 0.0, 0.3]), DeadZone(-0.2, 0.3, 1.0, 0.8)],
        output_blocks=[Polynomial([1.0, 0.2, -0.05], constant=False), None],
        state_bias=[0.05, -0.02, 0.0],
        output_bias=[0.1, -0.3],
        input_offset=[1.0, -0.5],
        input_scale=[2.0, 0.5],
        output_offset=[3.0, 0.0],
        output_scale=[1.5, 2.0],
    )
    kwargs.update(changes)
    return BlockStateSpace(["u1", "u2"], ["y1", "y2"], A, B, C, D, **kwargs)


def _reference(m, u, x0):
    """The model's equations, one sample at a time."""
    a, b, c, d = (np.asarray(v, dtype=float) for v in (A, B, C, D))
    x = np.array(x0, dtype=float)
    out = []
    for row in np.atleast_2d(u):
        un = (row - m.input_offset) / m.input_scale
        w = np.array(
            [f(v) if f is not None else v for f, v in zip(m.input_blocks, un, strict=True)]
        )
        w = np.array([float(np.asarray(v)) for v in w])
        z = c @ x + d @ w
        yn = np.array([g(np.array([v]))[0] if g is not None else v
                       for g, v in zip(m.output_blocks, z, strict=True)]) + m.output_bias  # fmt: skip
        out.append(m.output_offset + m.output_scale * yn)
        x = a @ x + b @ w + m.state_bias
    return np.array(out)


def _inputs(n=300, seed=0):
    rng = np.random.default_rng(seed)
    return np.column_stack(
        (1.0 + 2.0 * rng.standard_normal(n), -0.5 + 0.5 * rng.standard_normal(n))
    )


def test_simulation_follows_the_equations():
    m, u = _model(), _inputs()
    np.testing.assert_allclose(m.simulate(u), _reference(m, u, np.zeros(3)), rtol=1e-12, atol=1e-12)


def test_a_channel_without_a_block_passes_its_signal_through():
    m = _model(input_blocks={"u1": Polynomial([0.0, 1.0, 0.5])}, output_blocks=None)
    assert m.input_blocks[1] is None and m.output_blocks == (None, None)
    assert m.kind == "hammerstein"
    u = _inputs(50)
    np.testing.assert_allclose(m.simulate(u), _reference(m, u, np.zeros(3)), rtol=1e-12, atol=1e-12)


def test_jacobian_matches_central_differences_over_every_parameter_and_the_state():
    m, u = _model(), _inputs(120)
    un = m.normalised_input(u)
    x0 = np.array([0.3, -0.2, 0.1])
    y, J = m.jacobian_piece(un, *m._sensitivity_start(x0))
    theta = m.free_parameters()
    full = np.r_[theta, x0]
    p = theta.size

    def run(v):
        return m.with_free_parameters(v[:p]).run(un, v[p:])[0].reshape(-1)

    np.testing.assert_allclose(y.reshape(-1), run(full), rtol=1e-12, atol=1e-12)
    numeric = np.zeros_like(J)
    for k in range(full.size):
        h = 1e-6 * max(1.0, abs(full[k]))
        hi, lo = full.copy(), full.copy()
        hi[k] += h
        lo[k] -= h
        numeric[:, k] = (run(hi) - run(lo)) / (2 * h)
    # the dead zone's corners and the unused column are where differences and slopes part
    np.testing.assert_allclose(J, numeric, rtol=1e-5, atol=1e-6)
    assert np.abs(J[:, -3:]).max() > 0.1  # the state moves the output


def test_a_record_walked_in_pieces_gives_the_whole_walk():
    m, u = _model(), _inputs(200)
    un = m.normalised_input(u)
    x0 = np.array([0.3, -0.2, 0.1])
    whole = m.jacobian_piece(un, *m._sensitivity_start(x0))[1]
    carried = m._sensitivity_start(x0)
    parts = [m.jacobian_piece(un[k : k + 64], *carried)[1] for k in range(0, 200, 64)]
    np.testing.assert_allclose(np.vstack(parts), whole, rtol=1e-12, atol=1e-13)


def test_the_initial_state_is_recovered_from_measured_outputs():
    m, u = _model(), _inputs(200)
    x0 = np.array([0.8, -0.4, 0.6])
    y = _reference(m, u, x0)
    np.testing.assert_allclose(m.initial_state(u, y[:20]), x0, atol=1e-8)
    sim = m.simulate(u, y[:20])
    np.testing.assert_allclose(sim[3:], y[3:], atol=1e-8)


def test_saved_and_loaded_it_simulates_identically():
    m, u = _model(), _inputs()
    back = model_from_dict(json.loads(json.dumps(m.to_dict())))
    assert isinstance(back, BlockStateSpace)
    y = _reference(m, u, np.zeros(3))
    np.testing.assert_array_equal(back.simulate(u), m.simulate(u))
    np.testing.assert_array_equal(back.simulate(u, y[:10]), m.simulate(u, y[:10]))


@pytest.mark.parametrize(
    "inputs, outputs",
    [
        ([Polynomial([0.1, 1.0, 0.0, 0.3]), PiecewiseLinear([-2.0, 0.0, 1.0], [-1.0, 0.0, 2.0])],
         [Polynomial([1.0, 0.2, -0.05], constant=False), Saturation(-2.0, 2.0)]),
        ([DeadZone(-0.2, 0.3, 1.0, 0.8), None], None),
    ],
)  # fmt: skip
def test_the_exported_module_simulates_as_the_model(inputs, outputs):
    m, u = _model(input_blocks=inputs, output_blocks=outputs), _inputs(400, seed=3)
    namespace: dict = {}
    exec(to_python_module(m), namespace)  # noqa: S102 - the module under test
    y = _reference(m, u, np.array([0.5, -0.3, 0.2]))
    np.testing.assert_allclose(namespace["simulate"](u), m.simulate(u), rtol=0, atol=1e-10)
    np.testing.assert_allclose(
        namespace["simulate"](u, y[:12]), m.simulate(u, y[:12]), rtol=0, atol=1e-10
    )


def test_blocks_named_for_channels_it_does_not_have_are_refused():
    with pytest.raises(OrderError, match=r"\['u3'\]"):
        _model(input_blocks={"u3": Polynomial([0.0, 1.0])})
    with pytest.raises(OrderError, match="2 input channel"):
        _model(input_blocks=[Polynomial([0.0, 1.0])])


def test_a_wrong_input_shape_names_the_inputs():
    with pytest.raises(DataError, match=r"2 input\(s\) \['u1', 'u2'\]"):
        _model().simulate(np.zeros((10, 3)))


def test_a_damaged_file_is_a_model_file_error():
    doc = _model().to_dict()
    doc["B"] = [[1.0]]
    with pytest.raises(ModelFileError, match="block state-space"):
        model_from_dict(doc)


def test_range_excursion_reports_the_inputs_and_each_output_blocks_argument():
    m = _model(input_range=[[-1.0, 1.0], [-1.0, 1.0]], output_range=[[-1.0, 1.0], [-1.0, 1.0]])
    u = np.column_stack((np.full(50, 1.0 + 2.0 * 2.0), np.full(50, -0.5)))  # u1_n = 2
    out = m.range_excursion(u)
    assert set(out) == {"u", "z y1"}  # y2 has no output block
    assert out["u"] == pytest.approx(0.5)


def test_beyond_its_recorded_range_a_polynomial_block_follows_its_tangent():
    """A cubic run on inputs beyond the range it was estimated on runs away; like the
    chains' polynomial blocks, it continues along its tangent there, and the exported
    module does the same."""
    m = _model(input_range=[[-1.0, 1.0], [-1.0, 1.0]], output_range=[[-2.0, 2.0], [-2.0, 2.0]])
    un = np.linspace(-4.0, 4.0, 801)
    w = m.block_inputs(np.column_stack((un, un)))[:, 0]
    cubic = m.input_blocks[0]
    inside = np.abs(un) <= 1.0
    np.testing.assert_allclose(w[inside], cubic(un[inside]), rtol=0, atol=1e-15)
    right = un > 1.0
    slope = cubic.derivative(np.array([1.0]))[0]
    np.testing.assert_allclose(w[right], cubic(np.array([1.0]))[0] + slope * (un[right] - 1.0))
    assert np.abs(w).max() < 0.5 * np.abs(cubic(un)).max()  # the cubic itself runs away
    u = 1.0 + 2.0 * np.column_stack((np.linspace(-3, 3, 300), np.linspace(2, -2, 300)))
    namespace: dict = {}
    exec(to_python_module(m), namespace)  # noqa: S102 - the module under test
    y = _reference(_model(), u, np.zeros(3))
    for start in (None, y[:10]):
        np.testing.assert_allclose(namespace["simulate"](u, start), m.simulate(u, start),
                                   rtol=0, atol=1e-10)  # fmt: skip


def test_only_a_fit_with_feedthrough_moves_d_and_the_state_bias_is_held():
    m = _model()
    names = m.free_parameter_names()
    for feedthrough in (False, True):
        mask = m.parameter_mask(feedthrough)
        assert mask.dtype == bool and mask.size == len(names)
        d = [k for k, n in enumerate(names) if n.startswith("D[")]
        assert d and all(mask[k] == feedthrough for k in d)
        assert not any(mask[k] for k, n in enumerate(names) if n.startswith("e["))
        assert all(mask[k] for k, n in enumerate(names) if n.startswith(("A[", "B[", "h[")))


def test_a_panel_for_every_block_even_after_a_channel_without_one():
    m = _model(input_blocks={"u2": DeadZone(-0.2, 0.3, 1.0, 0.8)}, output_blocks=None)
    curves = m.static_curves(_inputs(100))
    assert [c["title"] for c in curves] == ["input block on u2 (dead-zone)"]


def test_each_panel_says_which_block_it_draws_and_draws_that_block():
    """``side`` and ``index`` name the block of each panel (the report and the plots
    read them), and the panel's curve is that block's own on the panel's grid."""
    m = _model()
    curves = m.static_curves(_inputs(100))
    assert [(c["side"], c["index"]) for c in curves] == [("input", 0), ("input", 1), ("output", 0)]
    for c in curves:
        np.testing.assert_array_equal(c["y"], m.block_curve(c["side"], c["index"], c["grid"]))


def test_measured_outputs_of_the_wrong_shape_are_named():
    with pytest.raises(DataError, match=r"2 output\(s\) \['y1', 'y2'\]"):
        _model().initial_state(_inputs(20), np.zeros((20, 3)))


@pytest.mark.parametrize("model", [_model(), tank_overflow_plant()], ids=["blocks", "loop"])
def test_standard_errors_land_on_the_parameters_they_belong_to(model):
    """``shaped`` (the standard errors' table) puts every free parameter under its own
    name, the loop's rows and columns (Bq, Dq, Cp, Dp) and its block included, and
    leaves out only the unused column (``F``)."""
    seen = assert_shaped_follows_the_names(model)
    names = model.free_parameter_names()
    assert sorted(seen) == [k for k, n in enumerate(names) if not n.startswith("F[")]
