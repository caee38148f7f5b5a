"""``to_control`` and ``state_space_matrices`` (blockid.models.export): a state-space or
multivariable ARX model as one python-control ``StateSpace`` in physical deviations,
whose forced response plus the offsets is ``model.simulate``; the refusals."""

import numpy as np
import pytest

from blockid.blocks import LinearBlock, Polynomial
from blockid.data import Dataset
from blockid.errors import EstimationError, ParameterError
from blockid.models import ARX, BlockStateSpace, PolynomialStateSpace, StateSpace
from blockid.models.export import state_space_matrices, to_control

control = pytest.importorskip("control")


def _response(model, sys, u, x0=0.0):
    """``y_0 + forced_response(sys, u - u_0)``: the export's simulation in physical units."""
    ss = state_space_matrices(model)
    out = control.forced_response(sys, inputs=(u - ss["input_offset"]).T, initial_state=x0)
    return out.outputs.reshape(len(model.outputs), -1).T + ss["output_offset"]


@pytest.fixture(scope="module")
def fitted():
    """A 2x2 state space fitted by blockid on a simulated record (offsets and scales far
    from 0 and 1, so that the normalisation matters)."""
    from blockid.fitting import fit_model

    plant = StateSpace(
        ["flow", "heat"], ["level", "temp"], A=[[0.8, 0.2], [-0.2, 0.7]],
        B=[[1.0, 0.0], [0.5, 1.0]], C=[[1.0, 0.0], [0.3, 1.0]], D=[[0.0, 0.0], [0.0, 0.0]],
        input_offset=[3.0, -40.0], input_scale=[2.0, 10.0], output_offset=[12.0, 300.0],
        output_scale=[0.5, 25.0],
    )  # fmt: skip
    rng = np.random.default_rng(5)
    u = rng.normal([3.0, -40.0], [2.0, 10.0], size=(600, 2))
    y = plant.simulate(u) + [0.01, 0.5] * rng.standard_normal((600, 2))
    data = Dataset.from_arrays(u, y, ["flow", "heat"], ["level", "temp"], sampling_time=0.25)
    return fit_model(data, "state-space", nx=2).model, u, y


def test_a_fitted_two_by_two_state_space_is_one_control_state_space(fitted):
    model, u, y = fitted
    sys = to_control(model)
    assert isinstance(sys, control.StateSpace)
    assert sys.input_labels == ["flow", "heat"] and sys.output_labels == ["level", "temp"]
    assert sys.dt == 0.25 and sys.nstates == 2
    assert np.abs(model.input_offset).min() > 1 and model.output_scale[1] > 10  # scaled
    # from rest at the operating point
    np.testing.assert_allclose(_response(model, sys, u), model.simulate(u), rtol=0, atol=1e-9)
    # from the state the first measured outputs give: the same state basis
    x0 = model.initial_state(u, y[:20])
    expected = model.simulate(u, y[:20])
    got = _response(model, sys, u, x0)
    np.testing.assert_allclose(got[model.max_lag :], expected[model.max_lag :], rtol=0, atol=1e-9)


def test_the_matrices_carry_the_scales_and_the_offsets():
    model = StateSpace(
        ["u1", "u2"], ["y1", "y2"], A=[[0.5, 0.0], [0.1, 0.2]], B=[[1.0, 2.0], [0.0, 1.0]],
        C=[[1.0, 0.0], [0.0, 1.0]], D=[[0.0, 1.0], [0.0, 0.0]], input_offset=[1.0, 2.0],
        input_scale=[2.0, 4.0], output_offset=[10.0, 20.0], output_scale=[3.0, 5.0],
    )  # fmt: skip
    ss = state_space_matrices(model)
    np.testing.assert_array_equal(ss["B"], [[0.5, 0.5], [0.0, 0.25]])
    np.testing.assert_array_equal(ss["C"], [[3.0, 0.0], [0.0, 5.0]])
    np.testing.assert_array_equal(ss["D"], [[0.0, 0.75], [0.0, 0.0]])
    assert ss["input_offset"].tolist() == [1.0, 2.0] and ss["output_offset"].tolist() == [10, 20]
    assert ss["states"] == ["x1", "x2"]
    assert to_control(model).dt is True  # no sampling time: discrete, unspecified


def test_a_single_variable_state_space_is_a_state_space_and_its_pairs_stay_transfer_functions():
    model = StateSpace(["u"], ["y"], A=[[0.5]], B=[[1.0]], C=[[2.0]], D=[[0.0]],
                       input_offset=1.0, output_offset=-3.0, sampling_time=0.1)  # fmt: skip
    u = np.linspace(-1, 2, 30)
    sys = to_control(model)
    assert isinstance(sys, control.StateSpace)
    np.testing.assert_allclose(_response(model, sys, u), model.simulate(u), rtol=0, atol=1e-12)
    assert isinstance(to_control(model, index=0), control.TransferFunction)


def test_a_linear_block_and_a_siso_arx_model_stay_transfer_functions():
    block = LinearBlock(2, 2, 1, a=[-1.2, 0.35], b=[1.0, 0.4])
    system = to_control(block)
    assert isinstance(system, control.TransferFunction) and system.dt is True
    arx = ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [-0.5]}}, b={"y": {"u": [1.0]}})
    assert isinstance(to_control(arx), control.TransferFunction)


def test_a_multivariable_arx_model_is_a_non_minimal_state_space():
    model = ARX(
        ["u1", "u2"], ["y1", "y2"], na=[[2, 1], [0, 1]], nb=[[1, 2], [2, 0]],
        nk=[[1, 0], [2, 1]],
        a={"y1": {"y1": [-0.9, 0.2], "y2": [0.1]}, "y2": {"y2": [-0.5]}},
        b={"y1": {"u1": [0.5], "u2": [0.3, -0.1]}, "y2": {"u1": [1.0, 0.2]}},
        input_offset=[0.1, -0.2], output_offset=[1.0, 2.0], sampling_time=2.0,
    )  # fmt: skip
    sys = to_control(model)
    assert sys.input_labels == ["u1", "u2"] and sys.output_labels == ["y1", "y2"]
    assert sys.dt == 2.0
    assert sys.state_labels[:2] == ["y1(k-1)", "y2(k-1)"] and "u1(k-2)" in sys.state_labels
    u = np.random.default_rng(1).normal(size=(80, 2))
    np.testing.assert_allclose(_response(model, sys, u), model.simulate(u), rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.sort_complex(sys.poles()[np.abs(sys.poles()) > 1e-9]),
                               np.sort_complex(model.poles()[np.abs(model.poles()) > 1e-9]))  # fmt: skip


def _polynomial(constant: float = 0.0, lower: float = -1.0) -> PolynomialStateSpace:
    return PolynomialStateSpace(
        ["u"], ["y"], A=[[0.6]], B=[[1.0]], C=[[1.0]], D=[[0.0]], E=[[constant, 0.1]],
        F=[[0.0, 0.05]], exponents=[[0, 0], [2, 0]], lower=[lower, -1.0], upper=[1.0, 1.0],
        input_offset=0.5, input_scale=2.0, output_offset=1.0, output_scale=3.0,
    )  # fmt: skip


def test_a_polynomial_state_space_is_exported_where_a_b_c_d_are_its_slope_at_rest():
    model = _polynomial()
    sys = to_control(model)
    # small deviations from the operating point: the linearisation, error of second order
    u = 0.5 + 1e-4 * np.sin(np.arange(50))
    assert np.abs(_response(model, sys, u) - model.simulate(u)).max() < 1e-7
    assert model.simulate(np.full(20, 0.5))[-1, 0] == 1.0  # at rest at (u_0, y_0)


def test_refusals_name_what_to_do():
    # a constant term and a block model are linearised (tests/models/test_linearise.py);
    # an equilibrium where the monomials are clipped is not
    with pytest.raises(EstimationError, match=r"clipped \(x1 = 0\.0025"):
        to_control(_polynomial(lower=0.1))
    blocks = BlockStateSpace(
        ["u1", "u2"], ["y1", "y2"], A=[[0.5]], B=[[1.0, 0.5]], C=[[1.0], [0.5]],
        D=[[0.0, 0.0], [0.0, 0.0]], input_blocks=Polynomial([1.0, 0.3], constant=False),
    )  # fmt: skip
    assert to_control(blocks).input_labels == ["u1", "u2"]
    # the escape hatch the messages name works
    assert to_control(_polynomial(lower=0.1).linear_part()).nstates == 1
    assert to_control(blocks.linear_part()).input_labels == ["w u1", "w u2"]
    with pytest.raises(ParameterError, match="has no state-space export"):
        state_space_matrices(LinearBlock(1, 1, 1, a=[-0.5], b=[1.0]))


def test_each_pair_of_the_state_space_is_the_transfer_function_index_gives(fitted):
    from blockid.models.export import transfer_functions

    model = fitted[0]
    sys = to_control(model)
    for k, tf in enumerate(transfer_functions(model)):
        i, j = model.outputs.index(tf["output"]), model.inputs.index(tf["input"])
        pair = to_control(model, index=k)
        for z in (1.0, 1j, np.exp(0.3j)):  # the same function of z
            np.testing.assert_allclose(pair(z), sys(z)[i, j], rtol=1e-9)


def test_the_example_in_docs_export_runs_as_printed(capsys):
    from pathlib import Path

    text = (Path(__file__).parents[2] / "docs" / "export.md").read_text(encoding="utf-8")
    blocks = [b.split("```")[0] for b in text.split("```python\n")[1:]]
    code = next(b for b in blocks if "state_space_matrices" in b)
    exec(code, {})
    printed = capsys.readouterr().out.splitlines()
    shown = [line[2:] for line in code.splitlines() if line.startswith("# ")]
    assert printed[:2] == shown[1:3]  # the names, dt and the offsets exactly
    assert float(printed[2]) < 1e-9 and float(printed[3]) < 1e-9
