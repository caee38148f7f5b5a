"""The uncertainty a figure draws (plotting/uncertainty.py): standard errors matched to
the free parameters in every stored form, models drawn inside their bounds, and the
band of a quantity over the draws."""

from __future__ import annotations

import numpy as np

from reference import _with_errors


def test_standard_errors_in_the_shape_of_the_parameters_are_matched(hammerstein):
    from blockid.plotting.uncertainty import free_standard_errors

    fit = hammerstein[3].models[0].fit
    model = fit.model
    shaped = {
        k: (np.full(len(v), 0.5).tolist() if isinstance(v, list) else 0.5)
        for k, v in model.parameters.items()
    }
    shaped["a"] = [0.1, 0.2, 0.3]
    se = free_standard_errors(_with_errors(hammerstein[3], shaped).models[0].fit)
    names = model.free_parameter_names()
    assert se is not None and se.size == len(names)
    assert [se[names.index(f"a_{j}")] for j in (1, 2, 3)] == [0.1, 0.2, 0.3]
    by_name = {n: 0.25 for n in names}
    assert np.all(free_standard_errors(_with_errors(hammerstein[3], by_name).models[0].fit) == 0.25)
    assert free_standard_errors(_with_errors(hammerstein[3], [1.0, 2.0]).models[0].fit) is None
    assert free_standard_errors(fit) is None
    # a parameter the data did not determine (null, as a fit's JSON stores it): no draws,
    # and no TypeError (blockid identify --report on a Hammerstein-Wiener chain ended so)
    shaped["a"] = [0.1, None, 0.3]
    assert free_standard_errors(_with_errors(hammerstein[3], shaped).models[0].fit) is None


def test_draws_stay_inside_the_parameter_bounds_and_follow_the_covariance():
    from blockid.blocks import Saturation
    from blockid.models import Hammerstein
    from blockid.plotting.uncertainty import sampled_models

    model = Hammerstein("u", "y", input_block=Saturation(-1.0, 1.0), na=1, nb=1, nk=1,
                        a=[-0.5], b=[1.0])  # fmt: skip
    theta = model.free_parameters()
    cov = np.diag(np.full(theta.size, 1e-4))
    draws = np.array([m.free_parameters() for m in sampled_models(model, n=400, covariance=cov)])
    assert len(draws) == 400
    np.testing.assert_allclose(draws.mean(0), theta, atol=3e-3)
    np.testing.assert_allclose(draws.std(0), 1e-2, rtol=0.15)
    low, high = model.parameter_bounds()
    wide = [m.free_parameters() for m in sampled_models(model, se=np.full(theta.size, 50.0), n=50)]
    assert np.all(np.asarray(wide) >= low) and np.all(np.asarray(wide) <= high)


def test_the_band_is_the_middle_95_percent_of_the_finite_draws():
    from blockid.plotting.uncertainty import sampled_band

    draws = [float(k) for k in range(101)] + [float("nan")]
    lo, hi = sampled_band(draws, lambda d: np.array([d, 2 * d]))
    np.testing.assert_allclose(lo, [2.5, 5.0])
    np.testing.assert_allclose(hi, [97.5, 195.0])
    assert sampled_band(list(range(9)), lambda d: np.array([d])) is None  # fewer than 10
