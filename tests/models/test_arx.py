import json

import numpy as np
import pytest
from scipy.signal import lfilter

from blockid import errors
from blockid.models import ARX, model_from_dict

import reference


def tito(**kw):
    """A stable two-input two-output ARX like paper A's flow field (na=2, nb=2, nk=1)."""
    return reference.tito_arx(**kw)


def simulate_reference(model, u, y0):
    """Plain-Python free run of the ARX difference equation."""
    N = len(u)
    y = np.zeros((N, len(model.outputs)))
    y[: model.max_lag] = y0[: model.max_lag]
    for t in range(model.max_lag, N):
        for i, yi in enumerate(model.outputs):
            acc = 0.0
            for j, yj in enumerate(model.outputs):
                for k, a in enumerate(model.a[yi][yj], start=1):
                    acc -= a * y[t - k, j]
            for m, um in enumerate(model.inputs):
                for lag, b in enumerate(model.b[yi][um]):
                    acc += b * u[t - model.nk[i, m] - lag, m]
            y[t, i] = acc
    return y


def test_simulate_matches_reference_and_lfilter(rng):
    model = tito()
    u = rng.standard_normal((300, 2))
    y0 = rng.standard_normal((5, 2))
    np.testing.assert_allclose(model.simulate(u, y0), simulate_reference(model, u, y0), atol=1e-12)
    siso = ARX(
        ["u"], ["y"], na=2, nb=2, nk=3, a={"y": {"y": [-1.5, 0.7]}}, b={"y": {"u": [1.0, 0.5]}}
    )
    uu = rng.standard_normal(200)
    ref = lfilter([0, 0, 0, 1.0, 0.5], [1, -1.5, 0.7], uu)
    np.testing.assert_allclose(siso.simulate(uu)[:, 0], ref, atol=1e-10)


def test_predict_is_one_step_and_regressors_reproduce_it(rng):
    model = tito()
    u = rng.standard_normal((200, 2))
    y = model.simulate(u) + 0.01 * rng.standard_normal((200, 2))
    pred = model.predict(u, y)
    for i in range(2):
        Phi, target = model.regressors(u, y, i)
        np.testing.assert_allclose(pred[model.max_lag :, i], Phi @ model.parameter_vector(i))
        assert target.shape == (200 - model.max_lag,)
    # one-step prediction of noise-free data is exact
    y_clean = model.simulate(u)
    np.testing.assert_allclose(model.predict(u, y_clean), y_clean, atol=1e-12)


def test_offsets_shift_the_operating_point(rng):
    base = tito()
    shifted = tito(input_offset=[410.0, 350.0], output_offset=[110.0, 0.578])
    u = rng.standard_normal((100, 2))
    np.testing.assert_allclose(
        shifted.simulate(u + [410.0, 350.0]), base.simulate(u) + [110.0, 0.578], atol=1e-9
    )


def test_parameter_vector_round_trip_and_names():
    model = tito()
    theta = model.parameter_vector(0)
    assert model.parameter_names(0)[:3] == ["a[y1][y1][1]", "a[y1][y1][2]", "a[y1][y2][1]"]
    model.set_parameter_vector(0, theta * 2)
    np.testing.assert_allclose(model.parameter_vector(0), theta * 2)
    assert model.hierarchical_groups(0) == [[0, 1, 2, 3], [4, 5, 6, 7]]


def test_poles_and_stability():
    siso = ARX(["u"], ["y"], na=2, a={"y": {"y": [-1.5, 0.7]}})
    np.testing.assert_allclose(np.sort(np.abs(siso.poles())), [np.sqrt(0.7)] * 2)
    assert siso.is_stable()
    # paper A's printed S2 signs give a pole near -1.15 (SPEC)
    printed = ARX(["x"], ["v2"], na=2, a={"v2": {"v2": [1.0, -0.17]}})
    assert not printed.is_stable()
    assert np.isclose(np.min(printed.poles().real), -1.1481, atol=1e-3)


def test_dict_round_trip_gives_identical_simulation(rng):
    model = tito(sampling_time=0.05, input_offset=[1.0, 2.0], output_offset=[3.0, 4.0])
    again = model_from_dict(json.loads(json.dumps(model.to_dict())))
    u = rng.standard_normal((100, 2))
    assert np.array_equal(model.simulate(u), again.simulate(u))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"na": -1}, "na must hold whole numbers >= 0"),
        ({"nb": [[1, 2, 3]]}, "nb must be a whole number or a 1x1 matrix"),
        ({"nk": 1.5}, "nk must hold whole numbers"),
        (
            {"a": {"y": {"y": [1.0, 2.0]}}},
            r"a\['y'\]\['y'\] has 2 coefficients but the orders call for 1",
        ),
        ({"b": {"y": {"w": [1.0]}}}, "names a signal the model does not have"),
    ],
)
def test_bad_orders_are_named(kwargs, match):
    with pytest.raises(errors.OrderError, match=match):
        ARX(["u"], ["y"], **kwargs)


def test_wrong_signal_shape_is_named(rng):
    with pytest.raises(errors.DataError, match=r"2 input\(s\) \['v1', 'v2'\].*shape \(10, 3\)"):
        tito().simulate(np.ones((10, 3)))


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
U = np.array([0.0, 1.0, -2.0, 0.5, 3.0, -1.0])


def test_arx_from_dict_without_offsets_has_zero_offsets():
    m = ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [-0.5]}}, b={"y": {"u": [1.0]}})
    data = m.to_dict()
    data.pop("offsets", None)
    loaded = model_from_dict(data)
    np.testing.assert_array_equal(loaded.simulate(U), m.simulate(U))
    assert list(np.ravel(loaded.input_offset)) == [0.0]


def test_a_single_output_model_takes_its_coefficients_as_plain_lists():
    as_lists = ARX(["u"], ["y"], na=1, nb=2, nk=1, a=[-0.9], b=[0.1, 0.05])
    as_dicts = ARX(["u"], ["y"], na=1, nb=2, nk=1,
                   a={"y": {"y": [-0.9]}}, b={"y": {"u": [0.1, 0.05]}})  # fmt: skip
    u = np.sin(np.arange(20) / 3)
    np.testing.assert_array_equal(as_lists.simulate(u), as_dicts.simulate(u))
    assert as_lists.simulate(np.ones(3))[:, 0].tolist() == pytest.approx([0.0, 0.1, 0.24])


def test_a_plain_list_for_several_inputs_is_refused_with_the_dict_form():
    with pytest.raises(errors.OrderError, match=r"b must be a dict b\[output\]\[input\]"):
        ARX(["u1", "u2"], ["y"], a=[-0.9], b=[0.1])
