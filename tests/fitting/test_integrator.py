"""The ``integrator`` option: integrating plants fitted with an explicit integrator, the
warning for a fitted pole on the stability margin, and the search's integrator variants."""

import numpy as np
import pytest

from blockid.blocks import Integrator, LinearBlock, Polynomial, TwoSegmentPolynomial
from blockid.data import Dataset
from blockid.errors import ParameterError
from blockid.fitting import fit_model
from blockid.fitting.checks import STABILITY_MARGIN, margin_for, margin_notes
from blockid.models import ARX, ChainModel

LINEAR = LinearBlock(2, 2, 1, [-1.2, 0.35], [1.0, 0.4])  # poles 0.7 and 0.5


def _record(blocks, n=300, mean=0.2, noise=0.0, seed=0):
    rng = np.random.default_rng(seed)
    u = mean + rng.uniform(-1, 1, n)
    y = ChainModel("u", "y", blocks).simulate(u)[:, 0]
    y = y + noise * rng.standard_normal(n)
    return Dataset.from_arrays(u, y, ["u"], ["y"], sampling_time=0.01)


def _integrators(model):
    return [b.order for b in model.blocks if b.kind == "integrator"]


@pytest.mark.parametrize("center", [False, True])
def test_output_error_with_an_integrator_recovers_a_drifting_plant(center):
    # the input's mean 0.2 makes the position drift: the offset lives in an affine
    # input block, so it survives fit_model's centring and is refined with the rest
    data = _record([LINEAR, Integrator(1)])
    fit = fit_model(data, "output-error", na=2, nb=2, nk=1, integrator=1, center=center)
    model = fit.model
    assert _integrators(model) == [1] and fit.settings["integrator"] == 1
    assert fit.settings["initial"].startswith("hammerstein fit to the output differenced 1")
    a, b = model.linear_blocks[0].a, model.linear_blocks[0].b
    gain = model.blocks[0].coefficients[1]
    np.testing.assert_allclose(a, LINEAR.a, atol=1e-8)
    np.testing.assert_allclose(gain * b, LINEAR.b, atol=1e-8)
    e = data.experiments[0]
    np.testing.assert_allclose(model.simulate(e.u, e.y[:1])[:, 0], e.y[:, 0], atol=1e-6)
    # the affine input block is an offset by choice: no "linear in disguise" note
    assert not fit.settings.get("warnings")


def test_hammerstein_and_double_integrator_recover_the_plant():
    plant = [TwoSegmentPolynomial.from_segments([0, 0.8, 0.3], [0, 0.5, -0.2]), LINEAR]
    data = _record([*plant, Integrator(1)], mean=0.0)
    fit = fit_model(data, "hammerstein", na=2, nb=2, nk=1, r1=2, integrator=1)
    truth = ChainModel("u", "y", [*plant, Integrator(1)]).free_parameters()
    np.testing.assert_allclose(fit.model.free_parameters(), truth, atol=1e-8)

    data2 = _record([LINEAR, Integrator(2)], n=400, mean=0.0)
    fit2 = fit_model(data2, "output-error", na=2, nb=2, nk=1, integrator=2, center=False)
    assert _integrators(fit2.model) == [2]
    e = data2.experiments[0]
    sim = fit2.model.simulate(e.u, e.y[:2])[:, 0]
    assert np.max(np.abs(sim - e.y[:, 0])) < 1e-6 * np.ptp(e.y)


def test_a_plain_fit_pins_a_pole_at_the_margin_and_says_so():
    data = _record([LINEAR, Integrator(1)], mean=0.0, noise=0.05)
    plain = fit_model(data, "output-error", na=3, nb=2, nk=1, center=False)
    poles = np.abs(plain.model.poles())
    assert poles.max() >= 1 - 2 * STABILITY_MARGIN
    (note,) = [w for w in plain.settings["warnings"] if "stability margin" in w]
    assert "integrates" in note and "integrator=1 (--integrator 1)" in note
    with_it = fit_model(data, "output-error", na=2, nb=2, nk=1, integrator=1)
    assert not any("stability margin" in w for w in with_it.settings.get("warnings", []))
    sim = [r.estimation_metrics["mse"]["y"] for r in (plain, with_it)]
    assert sim[1] < 0.5 * sim[0], sim


def test_margin_notes_only_for_fitted_poles_near_the_circle():
    near = LinearBlock(1, 1, 1, [-(1 - 1.5 * STABILITY_MARGIN)], [1.0])
    inside = LinearBlock(1, 1, 1, [-0.99], [1.0])
    ringing = LinearBlock(1, 1, 1, [1 - 1.5 * STABILITY_MARGIN], [1.0])  # pole near -1
    m = STABILITY_MARGIN
    assert margin_notes(ChainModel("u", "y", [inside, Integrator(1)]), m) == []
    (note,) = margin_notes(ChainModel("u", "y", [near, Integrator(1)]), m)
    assert "integrator=2" in note  # one integrator already: suggest the second
    assert note.endswith("with a structure that takes one")  # none named by the caller
    (named,) = margin_notes(ChainModel("u", "y", [near, Integrator(1)]), m, ["output-error"])
    assert named.endswith("with output-error")
    (note,) = margin_notes(ChainModel("u", "y", [ringing]), m)
    assert "integrates" not in note and "nearly undamped" in note
    arx = ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [-0.9995]}}, b={"y": {"u": [1.0]}})
    assert margin_notes(arx, m) == []
    # on a record of 25 000 samples the margin is 4e-5: 1 - 1.5e-3 is well inside it,
    # and a pole at 1 - 6e-5 is the one on the margin
    long = margin_for(25_000)
    assert margin_notes(ChainModel("u", "y", [near, Integrator(1)]), long) == []
    edge = LinearBlock(1, 1, 1, [-(1 - 1.5 * long)], [1.0])
    (note,) = margin_notes(ChainModel("u", "y", [edge]), long)
    assert "integrator=1" in note and "0.99996" in note


def test_the_option_is_checked_and_offered_where_it_applies():
    data = _record([LINEAR, Integrator(1)], n=100)
    with pytest.raises(ParameterError, match="from 0 to 2") as info:
        fit_model(data, "output-error", na=2, nb=2, nk=1, integrator=3)
    assert info.value.parameter == "integrator"
    with pytest.raises(ParameterError, match="integrator not used by wiener"):
        fit_model(data, "wiener", na=2, nb=2, nk=1, integrator=1)
    zero = fit_model(data, "output-error", na=2, nb=2, nk=1, integrator="0", max_nfev=3)
    assert _integrators(zero.model) == [] and "integrator" not in zero.settings


def test_polynomial_template_is_unaffected():
    # the affine-by-form exemption does not hide a fitted polynomial that stayed linear
    from blockid.fitting.checks import linear_block_notes

    chain = ChainModel("u", "y", [Polynomial([0.0, 1.0, 0.0, 0.0]), LINEAR])
    notes = linear_block_notes(chain, _record([LINEAR], n=50))
    assert any("is linear over the estimation data" in n for n in notes)


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
def test_integrator_fit_passes_refine_options_and_times_the_start():
    from blockid.blocks import Integrator, LinearBlock
    from blockid.data import Dataset
    from blockid.fitting import fit_model
    from blockid.models import ChainModel

    rng = np.random.default_rng(0)
    u = 0.2 + rng.uniform(-1, 1, 200)
    plant = [LinearBlock(2, 2, 1, [-1.2, 0.35], [1.0, 0.4]), Integrator(1)]
    y = ChainModel("u", "y", plant).simulate(u)[:, 0] + 0.01 * rng.standard_normal(200)
    data = Dataset.from_arrays(u, y, ["u"], ["y"], sampling_time=0.01)
    fit = fit_model(data, "output-error", na=2, nb=2, nk=1, integrator=1, max_nfev=1)
    assert fit.settings["max_nfev"] == 1
    assert fit.settings["stop_reason"] == "max_nfev reached"
    assert fit.settings["integrator"] == 1
    assert fit.model.sampling_time == 0.01
    assert set(fit.history) == {"fit_mse", "tail_mse", "seconds", "initial_seconds"}
    assert isinstance(fit.history["initial_seconds"], float)
    assert 0.0 < fit.history["initial_seconds"] < 60.0
