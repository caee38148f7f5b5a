"""Tests of blockid.plotting.linear: transfer functions of every model kind, their poles,
zeros, step and frequency responses, and the figure (Agg backend, see conftest)."""

import numpy as np
import pytest
from matplotlib.figure import Figure

from blockid.blocks import LinearBlock, Polynomial
from blockid.blocks.static import DeadZone
from blockid.models import ARX, Hammerstein
from blockid.models.block import WienerHammerstein
from blockid.models.feedback import LinearFeedback
from blockid.models.state_space import StateSpace
from blockid.plotting.linear import (
    PZ_REACH,
    LinearDynamics,
    describe_dynamics,
    linear_dynamics,
    linear_figure,
    oscillation,
    pole_rows,
)

BLOCK = LinearBlock(2, 2, 3, a=[-1.5, 0.7], b=[1.0, 0.5])


def _one(model):
    (g,) = linear_dynamics(model)
    return g


def _nonzero(roots):
    roots = np.asarray(roots)
    return np.sort_complex(roots[np.abs(roots) > 1e-9])


def test_a_linear_block_keeps_its_poles_zeros_gain_and_delay():
    g = _one(BLOCK)
    np.testing.assert_allclose(_nonzero(g.poles()), np.sort_complex(BLOCK.poles()))
    np.testing.assert_allclose(_nonzero(g.zeros()), np.sort_complex(BLOCK.zeros()))
    assert g.static_gain() == pytest.approx(BLOCK.static_gain())
    assert g.delay() == BLOCK.nk
    assert g.frequency_response(0.0) == pytest.approx(BLOCK.static_gain())
    # the step response is the block's own simulation of a unit step from rest
    np.testing.assert_allclose(g.step(60), BLOCK.simulate(np.ones(60)), atol=1e-12)
    assert g.step(g.step_length())[-1] == pytest.approx(BLOCK.static_gain(), rel=1e-2)


def test_every_model_kind_gives_its_linear_parts():
    static = Polynomial([0.0, 1.0, 0.3])
    hammerstein = Hammerstein("u", "y", input_block=static, na=2, nb=2, nk=3, a=[-1.5, 0.7],
                              b=[1.0, 0.5], sampling_time=0.1)  # fmt: skip
    assert _one(hammerstein).name == "linear block"
    assert _one(hammerstein).dt == 0.1
    chain = WienerHammerstein(
        "u", "y", first=LinearBlock(1, 1, 0, a=[-0.5], b=[0.5]),
        static=Polynomial([1.0, 0.0, -0.1], constant=False),
        second=LinearBlock(1, 1, 1, a=[-0.2], b=[1.0]),
    )  # fmt: skip
    names = [g.name for g in linear_dynamics(chain)]
    assert names == ["linear block 1 of 2 (input side)", "linear block 2 of 2 (output side)"]
    feedback = LinearFeedback("u", "y", linear=BLOCK, feedback=DeadZone(-0.3, 0.4, 0.8, 0.6))
    assert _one(feedback).name.startswith("forward path B/A")
    assert _one(feedback).static_gain() == pytest.approx(BLOCK.static_gain())
    arx = ARX(["u"], ["y"], na=2, nb=2, nk=1, a={"y": {"y": [-1.2, 0.35]}},
              b={"y": {"u": [1.0, 0.4]}})  # fmt: skip
    assert _one(arx).name == "y / u"
    assert _one(arx).static_gain() == pytest.approx(1.4 / (1 - 1.2 + 0.35))
    ss = StateSpace(["u1", "u2"], ["y"], A=[[0.5, 0.1], [0.0, 0.3]], B=[[1.0, 0.0], [0.0, 1.0]],
                    C=[[1.0, 1.0]], D=[[0.0, 0.0]])  # fmt: skip
    parts = linear_dynamics(ss)
    assert [g.name for g in parts] == ["linear part: y / u1", "linear part: y / u2"]
    # C (I - A)^-1 B: the static gain of each pair
    gains = np.array([[1.0, 1.0]]) @ np.linalg.inv(np.eye(2) - [[0.5, 0.1], [0.0, 0.3]])
    np.testing.assert_allclose([g.static_gain() for g in parts], gains[0])
    mimo = ARX(["u"], ["y1", "y2"], na=1, nb=1, nk=1)
    assert linear_dynamics(mimo) == []


def test_pole_rows_list_a_conjugate_pair_once_and_count_the_delay():
    g = LinearDynamics("g", np.array([1.0]), np.poly([0.6 + 0.3j, 0.6 - 0.3j, 0.0, 0.0]), 0.5)
    rows = pole_rows(g)
    assert [r[0] for r in rows] == ["pole", "2 poles"]
    pair = rows[0]
    assert pair[1] == "0.6 ± 0.3j"
    r = abs(0.6 + 0.3j)
    assert pair[2] == pytest.approx(r)
    assert pair[3] == f"{-0.5 / np.log(r):.4g} s"
    assert pair[4] == f"{np.angle(0.6 + 0.3j) / (2 * np.pi) / 0.5:.4g} Hz"
    untimed = pole_rows(LinearDynamics("g", g.num, g.den, None))
    assert untimed[0][3].endswith("samples") and untimed[0][4].endswith("cycles/sample")


@pytest.mark.parametrize("dt", [0.05, None])
def test_the_figure_draws_the_z_plane_the_step_and_the_bode_plot(dt):
    g = LinearDynamics("linear block", *(lambda tf: (tf.num, tf.den))(_one(BLOCK)), dt)
    fig = linear_figure([g])
    assert isinstance(fig, Figure)
    pz, step, mag, phase = fig.axes
    # z-plane: the unit circle and the poles where they are
    circle = pz.lines[0]
    np.testing.assert_allclose(np.hypot(*circle.get_data()), 1.0)
    poles = next(line for line in pz.lines if line.get_label() == "poles")
    np.testing.assert_allclose(
        np.sort_complex(_nonzero(poles.get_xdata() + 1j * poles.get_ydata())),
        np.sort_complex(BLOCK.poles()),
    )
    # the step settles at the static gain, drawn dashed
    gain = BLOCK.static_gain()
    assert step.lines[0].get_ydata()[-1] == pytest.approx(gain, rel=1e-2)
    assert step.lines[1].get_ydata()[0] == pytest.approx(gain)
    # Bode: magnitude at the lowest frequency = the static gain, in dB; the gain line
    magnitude = mag.lines[0].get_ydata()
    assert magnitude[0] == pytest.approx(20 * np.log10(gain), abs=0.05)
    assert mag.lines[1].get_ydata()[0] == pytest.approx(20 * np.log10(gain))
    freq = mag.lines[0].get_xdata()
    if dt:
        assert freq[-1] == pytest.approx(0.5 / dt)  # up to the Nyquist frequency
        assert phase.get_xlabel() == "frequency [Hz]" and step.get_xlabel() == "time [s]"
    else:
        assert freq[-1] == pytest.approx(np.pi)
        assert phase.get_xlabel() == "frequency [rad/sample]" and step.get_xlabel() == "sample"
    # one legend, under the panels, none on the data
    assert all(ax.get_legend() is None for ax in fig.axes)
    assert len(fig.subfigs[0].legends) == 1


def test_an_integrating_block_has_an_infinite_gain_and_no_gain_line():
    g = _one(LinearBlock(1, 1, 1, a=[-1.0], b=[0.1]))
    assert g.static_gain() == np.inf and not g.stable()
    fig = linear_figure([g])
    step = fig.axes[1]
    assert len(step.lines) == 1
    np.testing.assert_allclose(step.lines[0].get_ydata()[:4], [0.0, 0.1, 0.2, 0.3])


def test_a_negative_real_pole_is_a_mode_at_the_nyquist_frequency():
    """Its envelope decays with -T/ln|p|; it turns at the Nyquist frequency (period 2
    samples), which the table and the sentence say (once an empty cell and 'slowest
    pole |p| = 0.999')."""
    g = LinearDynamics("g", np.array([1.0]), np.poly([-0.999, 0.5]), 0.02)
    (nyquist, real) = [r for r in pole_rows(g) if r[0] == "pole"]
    assert nyquist[1] == "-0.999"
    assert nyquist[3] == f"{-0.02 / np.log(0.999):.4g} s"
    assert nyquist[4] == "25 Hz: the Nyquist frequency, period 2 samples"
    assert real[4] == "none"
    text = describe_dynamics(g)
    assert "its least damped pole p = -0.999 is a mode at the Nyquist frequency" in text
    assert "slowest pole" not in text
    high = abs(g.frequency_response(np.pi))
    assert f"|G(-1)| = {high:.4g}" in text
    near = LinearDynamics("g", np.array([1.0]), np.poly([-0.95 + 0.1j, -0.95 - 0.1j]), None)
    (pair,) = [r for r in pole_rows(near) if r[0] == "pole"]
    assert "near the Nyquist frequency, period 2.07 samples" in pair[4]
    assert "least damped poles -0.95 ± 0.1j" in describe_dynamics(near)
    assert (
        oscillation(0.8 + 0.1j, None) == f"{np.angle(0.8 + 0.1j) / (2 * np.pi):.4g} cycles/sample"
    )


def test_a_far_zero_leaves_the_unit_circle_readable():
    """A zero at -7.8 once stretched the axes to +-8.6 (the unit circle a dot): the
    z-plane stays within +-1.5 and an arrow at the border names the zero."""
    g = LinearDynamics("g", 0.1 * np.poly([-7.8, 0.5]), np.poly([0.9, 0.8, -0.3]), None)
    pz = linear_figure([g]).axes[0]
    assert pz.get_xlim() == (-PZ_REACH, PZ_REACH) and pz.get_ylim() == (-PZ_REACH, PZ_REACH)
    marks = [a for a in pz.texts if "-7.8" in a.get_text()]
    assert [m.get_text() for m in marks] == ["zero -7.8"]
    (arrow,) = [a for a in pz.texts if a.arrow_patch is not None and not a.get_text()]
    x, y = arrow.xy
    assert x == pytest.approx(-0.92 * PZ_REACH) and y == pytest.approx(0.0)
    near = LinearDynamics("g", np.array([1.0]), np.poly([0.5, 0.2]), None)
    pz = linear_figure([near]).axes[0]
    assert pz.get_xlim() == pytest.approx((-1.1, 1.1))  # all inside: around the circle
    assert not pz.texts
