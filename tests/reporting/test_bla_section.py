"""The report's best-linear-approximation section (reporting.bla_section)."""

from __future__ import annotations

import numpy as np

from blockid.data import Dataset
from blockid.data.dataset import Experiment
from blockid.design import multisine
from blockid.fitting import fit_model
from blockid.reporting.bla_section import bla_section
from blockid.reporting.entries import Entry
from reporting.page import Report


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


def _hammerstein_record() -> Dataset:
    """A static ``u + 0.3 u**3`` then ``z^-1 (0.5 + 0.3 z^-1) / (1 - 1.2 z^-1 + 0.5
    z^-2)``, 4 realisations of 3 periods of a random-phase multisine, a little noise."""
    from scipy.signal import lfilter

    x = multisine(256, f_max=0.4, periods=3, realisations=4, seed=0)
    rng = np.random.default_rng(0)
    experiments = []
    for m, u in enumerate(x.signals):
        y = lfilter([0, 0.5, 0.3], [1, -1.2, 0.5], u + 0.3 * u**3)
        experiments.append(Experiment(f"r{m}", u, y + 0.01 * rng.standard_normal(u.size)))
    return Dataset(("u",), ("y",), 1.0, experiments)


def test_each_model_s_linear_response_is_checked_against_the_bla():
    """The right dynamics lie within the BLA's bound (a Hammerstein model's scaled by a
    gain, an ARX of the right orders as it is); one pole too few does not."""
    data = _hammerstein_record()
    entries = [
        Entry(label, "", fit_model(data, structure, **orders), None, None)
        for label, structure, orders in [
            ("arx(2,2,1)", "arx", dict(na=2, nb=2, nk=1)),
            ("arx(1,1,1)", "arx", dict(na=1, nb=1, nk=1)),
            ("hammerstein", "hammerstein", dict(na=2, nb=2, nk=1, r1=3)),
        ]
    ]  # fmt: skip
    html = bla_section(data, "estimation data", entries)
    part = Report(f"<body>{html}</body>").sections["bla"][0]
    table = next(t for t in part.tables if t[0][0] == "model")
    rows = {r[0]: r[1:] for r in table[1:]}
    assert rows["arx(2,2,1)"][0] == "-" and float(rows["hammerstein"][0]) > 0
    within = {k: float(v[1].rstrip(" %")) for k, v in rows.items()}
    ratio = {k: float(v[2]) for k, v in rows.items()}
    assert within["arx(2,2,1)"] >= 95 and within["hammerstein"] >= 95
    assert within["arx(1,1,1)"] < 50 and ratio["arx(1,1,1)"] > 10 * ratio["arx(2,2,1)"]
    assert ratio["arx(2,2,1)"] < 3 and ratio["hammerstein"] < 3
    assert html.count("<figure>") == 2 and "scaled by the gain" in html
