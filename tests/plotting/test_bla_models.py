"""Models against the measured BLA (plotting/bla_models.py): a linear model's response as
it is, a block-oriented one's scaled by the gain that fits it best, the share of lines
within the bound, and the models that have no one response."""

from types import SimpleNamespace

import numpy as np
import pytest

from blockid.blocks import Saturation
from blockid.models import ARX, Hammerstein
from blockid.plotting.bla_models import model_response, plot_bla_models

F = np.linspace(0.01, 0.4, 40)  # cycles per sample


def _h(f):
    """1 / (1 - 0.5 z^-1) z^-1, the linear block of both models."""
    z = np.exp(2j * np.pi * f)
    return z**-1 / (1 - 0.5 * z**-1)


def _bla(g, std=0.01, bound=0.05):
    return SimpleNamespace(frequencies=F, sampling_time=1.0, g=g, std=np.full(F.size, std),
                           bound=np.full(F.size, bound), confidence=0.95,
                           input_name="u", output_name="y")  # fmt: skip


ARX_MODEL = ARX(["u"], ["y"], na=1, nb=1, nk=1, a={"y": {"y": [-0.5]}}, b={"y": {"u": [1.0]}})
HAMMERSTEIN = Hammerstein("u", "y", input_block=Saturation(-1.0, 1.0), na=1, nb=1, nk=1,
                          a=[-0.5], b=[1.0])  # fmt: skip


def test_a_linear_model_is_drawn_unscaled_and_scored_against_the_bound():
    g = _h(F)
    g[:10] += 0.1  # ten lines outside the bound, by 10 standard deviations
    r = model_response("arx", ARX_MODEL, _bla(g))
    np.testing.assert_allclose(r.response, _h(F), rtol=1e-12)
    assert r.gain is None and r.within == pytest.approx(30 / 40)
    assert r.ratio == pytest.approx(10 * 100 / 40)


def test_a_block_model_is_scaled_by_its_best_real_gain():
    r = model_response("hammerstein", HAMMERSTEIN, _bla(0.4 * _h(F)))
    assert r.gain == pytest.approx(0.4, rel=1e-12)
    np.testing.assert_allclose(r.response, 0.4 * _h(F), rtol=1e-12)
    assert r.within == 1.0 and r.ratio == pytest.approx(0.0, abs=1e-20)


def test_models_without_one_response_are_named_with_the_reason():
    two = ARX(["u", "v"], ["y"], na=1, nb=1, nk=1)
    assert model_response("m", two, _bla(_h(F))) == "m: not one input to one output (u, v to y)"
    loop = SimpleNamespace(inputs=("u",), outputs=("y",), feedback=object())
    assert model_response("f", loop, _bla(_h(F))) == (
        "f: a feedback model; its forward path is not its response"
    )


def test_the_figure_draws_the_bla_its_bound_and_each_response_in_db():
    import matplotlib.pyplot as plt

    bla = _bla(_h(F))
    fig = plot_bla_models(bla, [model_response("arx", ARX_MODEL, bla)])
    try:
        top = fig.axes[0]
        measured, arx = top.get_lines()[:2]
        np.testing.assert_allclose(measured.get_ydata(), 20 * np.log10(np.abs(_h(F))))
        np.testing.assert_allclose(arx.get_ydata(), 20 * np.log10(np.abs(_h(F))), rtol=1e-12)
        assert "BLA's 95% bound" in [t.get_text() for t in top.get_legend().get_texts()]
    finally:
        plt.close(fig)
