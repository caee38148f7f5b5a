"""The report's best-linear-approximation section (reporting.bla_section)."""

from __future__ import annotations

import numpy as np

from blockid.data import Dataset
from blockid.data.dataset import Experiment
from blockid.design import multisine
from blockid.reporting.bla_section import bla_section


def _wiener(cubic: float, realisations: int = 4, periods: int = 3, seed: int = 0) -> Dataset:
    """A first-order plant then ``x + cubic x**3``, excited by a random-phase multisine,
    with a little output noise."""
    from scipy.signal import lfilter

    x = multisine(512, f_max=0.2, periods=periods, realisations=realisations, seed=seed)
    rng = np.random.default_rng(seed)
    experiments = []
    for m, u in enumerate(x.signals):
        v = lfilter([0.3], [1.0, -0.7], u)
        y = v + cubic * v**3 + 1e-3 * rng.standard_normal(v.size)
        experiments.append(Experiment(f"r{m}", u, y))
    return Dataset(("u",), ("y",), 1.0, experiments)


def test_periodic_data_get_the_distortion_against_the_noise_and_the_figure():
    nonlinear = bla_section(_wiener(0.5), "estimation data")
    assert '<section id="bla">' in nonlinear and "robust method" in nonlinear
    assert "Verdict: " in nonlinear and "distortion dB" in nonlinear
    assert "a nonlinear model is worth trying" in nonlinear
    assert nonlinear.count("<figure>") == 1 and "data:image/png;base64," in nonlinear
    linear = bla_section(_wiener(0.0), "estimation data")
    assert "a nonlinear model is worth trying" not in linear
    assert "a linear model suffices" in linear


def test_a_record_that_is_no_whole_number_of_periods_gets_welch_and_says_why():
    data = _wiener(0.5, realisations=1, periods=3)
    e = data.experiments[0]
    cut = Dataset(("u",), ("y",), 1.0, [Experiment("r0", e.u[:1300], e.y[:1300])])
    html = bla_section(cut, "estimation range 0:1300")
    assert "Welch&#x27;s estimate, as the periodic one failed" in html
    assert "not a whole number of periods" in html and "Welch H1" in html


def test_several_inputs_or_outputs_are_not_measured_and_the_section_says_so():
    rng = np.random.default_rng(0)
    u, y = rng.standard_normal((400, 2)), rng.standard_normal((400, 1))
    two = Dataset(("u1", "u2"), ("y",), 1.0, [Experiment("e", u, y)])
    html = bla_section(two, "estimation data")
    assert "Not measured: the data have 2 input(s) and 1 output(s)" in html
    assert "<figure>" not in html
