"""``linearise`` (blockid.models.linearise) and ``to_control(model, operating_point=)``:
a nonlinear state-space model linearised at its equilibrium, against the truth — the
central differences of the model's own one-step map, the nonlinear model's response to
a small step, the state a long run settles in — and its refusals."""

import numpy as np
import pytest

from blockid.blocks import Polynomial, Saturation
from blockid.errors import EstimationError, ParameterError
from blockid.models import ARX, BlockStateSpace, PolynomialStateSpace, StateSpace
from blockid.models.export import linearise, state_space_matrices, to_control
from blockid.models.state_space import monomial_exponents

#: Each input's estimation range is its offset +- 2 scales.
RANGE = 4.0


def _polynomial(seed=3):
    """Two states, two inputs, two outputs, every monomial up to degree 3 and the
    constant (the default fits'), offsets and scales far from 0 and 1."""
    rng = np.random.default_rng(seed)
    expo = monomial_exponents(2, 2, 3, "full", constant=True)
    nm = expo.shape[0]
    return PolynomialStateSpace(
        ["flow", "heat"], ["level", "temp"], A=[[0.6, 0.1], [-0.2, 0.5]],
        B=[[1.0, 0.3], [0.2, 0.8]], C=[[1.0, 0.0], [0.4, 1.0]], D=[[0.1, 0.0], [0.0, 0.2]],
        E=0.05 * rng.standard_normal((2, nm)), F=0.05 * rng.standard_normal((2, nm)),
        exponents=expo, lower=-3.0, upper=3.0, input_offset=[2.0, -5.0],
        input_scale=[0.5, 4.0], output_offset=[10.0, 100.0], output_scale=[2.0, 30.0],
        sampling_time=0.1,
    )  # fmt: skip


def _blocks():
    """Input, loop and output blocks around a three-state core (smooth where it rests)."""
    rng = np.random.default_rng(0)
    A = np.diag([0.7, 0.5, -0.3])
    A[0, 1] = 0.2
    return BlockStateSpace(
        ["a", "b"], ["y1", "y2"], A, rng.normal(size=(3, 2)), rng.normal(size=(2, 3)),
        0.1 * rng.normal(size=(2, 2)), input_blocks={"a": Polynomial([0.1, 1.0, 0.3])},
        loop_blocks=[Saturation(-5.0, 5.0), Polynomial([0.0, 1.0, 0.2, -0.1])],
        Cp=0.3 * rng.normal(size=(2, 3)), Dp=0.3 * rng.normal(size=(2, 2)),
        Bq=0.3 * rng.normal(size=(3, 2)), Dq=0.2 * rng.normal(size=(2, 2)),
        output_blocks={"y2": Polynomial([0.0, 1.0, 0.2, 0.1], constant=False)},
        state_bias=[0.05, -0.02, 0.0], output_bias=[0.1, -0.2], input_offset=[1.0, -0.5],
        input_scale=[2.0, 0.5], output_offset=[3.0, 0.0], output_scale=[1.5, 2.0],
    )  # fmt: skip


def _physical_map(model, x, u):
    """The one-step map in physical input and output units: ``x(k+1)``, ``y(k)``."""
    x_next, yn = model.step(x, (u - model.input_offset) / model.input_scale)
    return x_next, model.output_offset + model.output_scale * yn


def _central_differences(model, x, u0, h=1e-6):
    """``∂[x+; y]/∂x`` and ``∂[x+; y]/∂u`` by central differences (step ``h`` in the
    normalised units each variable has)."""
    nx = x.size
    columns = []
    for i in range(nx + u0.size):
        e = np.zeros(nx + u0.size)
        e[i] = h if i < nx else h * model.input_scale[i - nx]
        up = np.r_[_physical_map(model, x + e[:nx], u0 + e[nx:])]
        down = np.r_[_physical_map(model, x - e[:nx], u0 - e[nx:])]
        columns.append((up - down) / (2 * e[i]))
    J = np.column_stack(columns)
    return J[:nx, :nx], J[:nx, nx:], J[nx:, :nx], J[nx:, nx:]


@pytest.mark.parametrize("make, u0", [(_polynomial, [2.3, -3.0]), (_blocks, [1.8, -0.2])])
def test_the_linearisation_is_the_central_difference_of_the_one_step_map(make, u0):
    model, u0 = make(), np.array(u0)
    op = linearise(model, u0)
    x = op["equilibrium_state"]
    x_next, y = _physical_map(model, x, u0)
    assert np.abs(x_next - x).max() < 1e-11 and np.abs(x).max() > 0.05  # a real equilibrium
    np.testing.assert_allclose(y, op["output_offset"], rtol=1e-14)
    assert op["input_offset"].tolist() == u0.tolist()
    for got, want in zip((op["A"], op["B"], op["C"], op["D"]), _central_differences(model, x, u0),
                         strict=True):  # fmt: skip
        np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-6 * np.abs(want).max())


@pytest.mark.parametrize("make, u0", [(_polynomial, [2.3, -3.0]), (_blocks, [1.8, -0.2])])
def test_a_small_step_of_the_nonlinear_model_is_the_forced_response_of_the_export(make, u0):
    control = pytest.importorskip("control")
    model, u0 = make(), np.array(u0)
    sys = to_control(model, operating_point=u0)
    op = state_space_matrices(model, operating_point=u0)
    assert sys.input_labels == list(model.inputs) and sys.output_labels == list(model.outputs)
    assert sys.dt == (model.sampling_time or True)
    step = 1e-4 * RANGE * model.input_scale  # 1e-4 of each input's range
    u = np.tile(u0, (300, 1))
    u[20:, 0] += step[0]
    u[120:, 1] -= step[1]
    yn = model.run(model.normalised_input(u), op["equilibrium_state"])[0]
    deviation = model.output_offset + model.output_scale * yn - op["output_offset"]
    linear = control.forced_response(sys, inputs=(u - u0).T).outputs.reshape(2, -1).T
    error = np.abs(deviation - linear).max(axis=0) / np.abs(deviation).max(axis=0)
    assert error.max() < 1e-3, error


def test_a_model_with_a_constant_term_rests_where_a_long_run_settles():
    model = _polynomial()
    assert not model.exponents[0].any()  # the monomial 1
    op = linearise(model)  # default: the input offset
    assert op["input_offset"].tolist() == model.input_offset.tolist()
    assert np.abs(op["equilibrium_state"]).max() > 0.01  # x = 0 is not at rest
    settled = model.simulate(np.tile(model.input_offset, (400, 1)))[-1]
    np.testing.assert_allclose(op["output_offset"], settled, rtol=1e-12)
    assert op["spectral_radius"] == np.abs(np.linalg.eigvals(op["A"])).max() < 1
    pytest.importorskip("control")
    sys = to_control(model)
    np.testing.assert_array_equal(sys.A, op["A"])
    np.testing.assert_array_equal(sys.D, op["D"])


def test_without_monomials_beyond_degree_one_at_rest_it_is_the_old_export():
    """No constant and a range around 0: ``x = 0`` at the input offset is the
    equilibrium, and the linearisation is ``A, B, C, D`` scaled as for a linear model."""
    model = PolynomialStateSpace(
        ["u"], ["y"], A=[[0.6]], B=[[1.0]], C=[[1.0]], D=[[0.0]], E=[[0.1]], F=[[0.05]],
        exponents=[[2, 0]], lower=[-1.0, -1.0], upper=[1.0, 1.0], input_offset=0.5,
        input_scale=2.0, output_offset=1.0, output_scale=3.0,
    )  # fmt: skip
    op = state_space_matrices(model)
    old = state_space_matrices(model.linear_part())
    for key in ("A", "B", "C", "D", "input_offset", "output_offset", "equilibrium_state"):
        np.testing.assert_array_equal(op[key], old[key])


def test_a_linear_model_at_an_operating_point_rests_at_its_static_gain():
    model = StateSpace(["u"], ["y"], A=[[0.5]], B=[[1.0]], C=[[2.0]], D=[[0.1]],
                       input_offset=1.0, input_scale=2.0, output_offset=-3.0, output_scale=4.0)  # fmt: skip
    op = state_space_matrices(model, operating_point=5.0)
    old = state_space_matrices(model)
    for key in "ABCD":
        np.testing.assert_allclose(op[key], old[key], rtol=1e-15)
    gain = (old["C"] @ np.linalg.solve(np.eye(1) - old["A"], old["B"]) + old["D"])[0, 0]
    assert op["output_offset"][0] == pytest.approx(-3.0 + gain * (5.0 - 1.0), rel=1e-12)


def test_an_unstable_equilibrium_is_refused():
    model = PolynomialStateSpace(["u"], ["y"], A=[[1.1]], B=[[1.0]], C=[[1.0]], D=[[0.0]],
                                 E=[[0.1]], F=[[0.0]], exponents=[[2, 0]])  # fmt: skip
    with pytest.raises(EstimationError, match=r"unstable .*magnitude 1\.1 >= 1"):
        linearise(model)


def test_a_model_without_an_equilibrium_is_refused():
    # x+ = x + 0.5 + 0.1 x^2 > x for every x: no state is at rest
    model = PolynomialStateSpace(["u"], ["y"], A=[[1.0]], B=[[1.0]], C=[[1.0]], D=[[0.0]],
                                 E=[[0.5, 0.1]], F=[[0.0, 0.0]], exponents=[[0, 0], [2, 0]])  # fmt: skip
    with pytest.raises(EstimationError, match="no equilibrium at u0 = 0"):
        linearise(model)


def test_an_equilibrium_where_the_monomials_are_clipped_is_refused():
    model = PolynomialStateSpace(
        ["u"], ["y"], A=[[0.6]], B=[[1.0]], C=[[1.0]], D=[[0.0]], E=[[0.0, 0.1]],
        F=[[0.0, 0.05]], exponents=[[0, 0], [2, 0]], lower=[0.1, -1.0], upper=[1.0, 1.0],
    )  # fmt: skip
    with pytest.raises(EstimationError, match=r"clipped \(x1 = 0\.0025 \(range 0\.1 \.\. 1\)\)"):
        linearise(model)
    inputs = model.replace(B=[[0.01]], E=[[0.0, 0.1, 0.01]], F=[[0.0, 0.0, 0.0]],
                           exponents=[[0, 0], [2, 0], [0, 2]], lower=[-1.0, -1.0])  # fmt: skip
    with pytest.raises(EstimationError, match=r"clipped \(input u = 3 \(range -1 \.\. 1\)\)"):
        linearise(inputs, u0=3.0)


def test_a_wrong_operating_point_and_one_where_none_applies_are_parameter_errors():
    model = _polynomial()
    with pytest.raises(
        ParameterError, match=r"one per input \(2: flow, heat\), got \[1.0, 2.0, 3.0\]"
    ):
        linearise(model, [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(linearise(model, 2.0)["input_offset"], [2.0, 2.0])
    arx = ARX(["u1", "u2"], ["y"], [[1]], [[1, 1]], [[1, 1]])
    with pytest.raises(ParameterError, match="do not depend on an operating point") as info:
        state_space_matrices(arx, operating_point=1.0)
    assert info.value.parameter == "operating_point"
    with pytest.raises(ParameterError, match="no one-step state map"):
        linearise(arx)
    pytest.importorskip("control")
    with pytest.raises(ParameterError, match="leave operating_point out"):
        to_control(model, index=0, operating_point=1.0)


def test_the_example_in_docs_export_runs_as_printed(capsys):
    pytest.importorskip("control")
    from pathlib import Path

    text = (Path(__file__).parents[2] / "docs" / "export.md").read_text(encoding="utf-8")
    blocks = [b.split("```")[0] for b in text.split("```python\n")[1:]]
    code = next(b for b in blocks if "linearise(" in b)
    exec(code, {})
    printed = capsys.readouterr().out.splitlines()
    lines = code.splitlines()
    shown = [
        after[2:]
        for line, after in zip(lines[:-1], lines[1:], strict=True)
        if line.startswith("print(")
    ]
    assert printed[:2] == shown[:2]  # the equilibrium, y*, the pole and the gain exactly
    assert float(printed[2]) < 1e-3  # the small-signal check
