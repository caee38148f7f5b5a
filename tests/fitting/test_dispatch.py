"""fit_model: options resolved through the registry, the default centring decided by
the data, and what a failed uncentred fit says."""

import numpy as np
import pytest

from blockid.blocks import LinearBlock, Saturation
from blockid.data import Dataset
from blockid.errors import EstimationError
from blockid.fitting import fit_model
from blockid.fitting.dispatch import default_centring, takes_both_signs
from blockid.fitting.registry import STRUCTURES

from reference import _arx_data, _backlash_data, _dataset


def _saturated_record(mean: float, seed: int = 0) -> Dataset:
    """A second-order lag seen through a saturating sensor, around ``mean`` (a 2-10 V
    record for mean 6)."""
    rng = np.random.default_rng(seed)
    u = mean + 2.0 * rng.uniform(-1, 1, 2000)
    x = LinearBlock(2, 2, 1, a=[-1.2, 0.5], b=[0.2, 0.1]).simulate(u - mean)
    y = mean + np.clip(x, -0.3, 0.4) + 0.01 * rng.standard_normal(2000)
    return Dataset.from_arrays(u, y, ["u"], ["y"])


def test_a_saturation_on_a_positive_output_is_fitted_around_the_operating_point():
    """Issue 20: a hard output block was refused at default settings (fitted on the
    signal as recorded, its centre at 0 V, far from the 2-10 V data) although centring
    fixes it; the default now follows the data."""
    data = _saturated_record(6.0)
    fit = fit_model(data, "wiener", na=2, nb=2, nk=1, output_block="saturation")
    block = fit.model.output_block
    assert fit.settings["center"] is True
    assert block.lower == pytest.approx(-0.3, abs=0.03) and block.upper == pytest.approx(
        0.4, abs=0.03
    )
    # the same data shifted to take both signs keep the block at the signal's own zero
    both = _saturated_record(0.0)
    assert "center" not in fit_model(both, "wiener", na=2, nb=2, nk=1,
                                     output_block="saturation").settings  # fmt: skip


def test_a_refused_uncentred_fit_says_that_centring_may_help():
    data = _saturated_record(6.0)
    with pytest.raises(EstimationError, match=r"try center=True \(--center true\)"):
        fit_model(data, "wiener", na=2, nb=2, nk=1, output_block="saturation", center=False)


def test_default_centring_rules():
    wiener, hammerstein = STRUCTURES["wiener"], STRUCTURES["hammerstein"]
    positive, both = _saturated_record(6.0), _saturated_record(0.0)
    sat = {"output_block": Saturation.template()}
    assert default_centring(wiener, sat, positive) is True
    assert default_centring(wiener, sat, both) is False
    assert default_centring(wiener, {}, both) is True  # the structure's default
    assert default_centring(hammerstein, {}, positive) is False
    from blockid.blocks import PiecewiseLinear

    given = {"input_block": PiecewiseLinear([-1.0, 0.0, 1.0], [0.0, 0.0, 1.0])}
    assert default_centring(hammerstein, given, positive) is False  # never: given values
    assert takes_both_signs(np.r_[-np.ones(10), np.ones(90)])
    assert not takes_both_signs(np.r_[-np.ones(4), np.ones(96)])


def test_orders_the_data_cannot_hold_are_refused_before_any_work():
    """Issue 21: ``--na 99999999999`` asked for 745 GiB; ``--na 1000`` on 300 samples ran
    for half a minute and then blamed NaN in the data."""
    import time

    from blockid.errors import OrderError

    rng = np.random.default_rng(0)
    data = Dataset.from_arrays(rng.standard_normal(300), rng.standard_normal(300), ["u"], ["y"])
    for na in (99_999_999_999, 1000):
        t0 = time.perf_counter()
        with pytest.raises(OrderError, match=f"na={na}.*has only 300"):
            fit_model(data, "arx", na=na, nb=1, nk=1)
        assert time.perf_counter() - t0 < 1.0
    with pytest.raises(OrderError, match="nx=400"):
        fit_model(data, "state-space", nx=400)
    # every coefficient counts, na's and nb's: 150 + 149 on 300 samples of lag 150 leave
    # 150 regression rows for 299 parameters (mutation run 3: nb left out of the count)
    with pytest.raises(OrderError, match="has 299 parameters and needs at least 299"):
        fit_model(data, "arx", na=150, nb=149, nk=1)


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
def test_fit_model_fits_arx_through_the_registry():
    result = fit_model(_dataset(), "arx", na=1, nb=1, nk=1)
    np.testing.assert_allclose(
        result.model.simulate(np.ones(5))[:, 0], [0.0, 1.0, 1.5, 1.75, 1.875], atol=1e-10
    )


def test_explicit_center_false_overrides_the_wiener_default():
    u, y = _arx_data()
    data = Dataset.from_arrays(u + 3.0, y + 6.0, inputs=["u"], outputs=["y"])
    kwargs = dict(na=1, nb=1, nk=1, r2=1, max_nfev=5)
    centred = fit_model(data, "wiener", **kwargs)  # the Wiener default: centre
    plain = fit_model(data, "wiener", center=False, **kwargs)
    assert centred.model.input_offset == pytest.approx(np.mean(u + 3.0))
    assert plain.model.input_offset == 0.0 and plain.model.output_offset == 0.0


def test_refined_recursive_fit_keeps_the_recursion_trajectory():
    _, data = _backlash_data()
    opts = dict(method="aw-rls", na=1, nb=1, nk=1, record_history=True)
    plain = fit_model(data, "backlash", **opts)
    refined = fit_model(data, "backlash", refine=True, **opts)
    assert refined.method == "aw-rls+refine"
    for key in ("theta", "update"):
        np.testing.assert_array_equal(refined.history[key], plain.history[key])
    assert refined.history["names"] == plain.history["names"]
    assert plain.history["theta"].shape == (len(plain.history["update"]), 5)


@pytest.mark.parametrize(
    ("structure", "options"),
    [
        ("polynomial-state-space", {"nx": 2, "degree": 2}),
        ("output-error", {"na": 2, "nb": 2, "nk": 1, "tail_fraction": 0.0}),
    ],
)
def test_a_fit_that_stops_at_its_evaluation_limit_says_so(structure, options):
    """Stopped by ``max_nfev``, not converged: a warning naming the limit (the CLI prints
    the fit's warnings on stderr and keeps them in the model file); converged, none."""
    from reference import squared_state_record

    data = squared_state_record(800)
    cut = fit_model(data, structure, max_nfev=3, **options)
    assert "max_nfev" in cut.settings["stop_reason"]
    notes = [w for w in cut.settings.get("warnings", []) if "evaluation limit" in w]
    assert notes and "max_nfev = 3" in notes[0]
    full = fit_model(data, structure, max_nfev=2000, **options)
    assert "max_nfev" not in full.settings["stop_reason"]
    assert not [w for w in full.settings.get("warnings", []) if "evaluation limit" in w]
