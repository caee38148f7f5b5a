"""The contract every online learner keeps (fitting/online_base.py): update returns the
prediction before learning, hold, revert and rewind, the saved state, the options a
stream cannot honour and orders against a starting model."""

import json

import numpy as np
import pytest

from blockid.errors import DataError, ParameterError
from blockid.fitting.online import online_estimator
from blockid.models import ARX
from fitting.online_cases import ARX_ORDERS, LEARNERS, PLANTS, TITO, _record, _vector


# ---------------------------------------------------------------------- predictions
def test_update_returns_the_prediction_of_the_model_before_the_update():
    u, y = _record(TITO, 300, noise=0.05)
    online = online_estimator(
        "arx", "rls", {**ARX_ORDERS, "forgetting": 0.99}, *[list(TITO.inputs), list(TITO.outputs)]
    )
    lag = TITO.max_lag
    for k in range(len(u)):
        before = online.model()
        prediction = online.update(u[k], y[k])
        assert prediction.shape == (2,)
        if k < lag:
            assert np.all(np.isnan(prediction))  # no regressor yet
        elif k % 7 == 0:
            expected = before.predict(u[: k + 1], y[: k + 1])[-1]
            np.testing.assert_allclose(prediction, expected, rtol=1e-12, atol=1e-12)
    # a chunk keeps the same predictions
    chunked = online_estimator(
        "arx", "rls", {**ARX_ORDERS, "forgetting": 0.99}, *[list(TITO.inputs), list(TITO.outputs)]
    )
    chunked.partial_fit(u[:100], y[:100])
    before = chunked.model()
    chunked.partial_fit(u[100:101], y[100:101])
    np.testing.assert_allclose(
        chunked.predictions_[0], before.predict(u[:101], y[:101])[-1], rtol=1e-12
    )


@pytest.mark.parametrize("name", list(LEARNERS))
def test_hold_revert_and_rewind_leave_the_estimate_and_move_the_memory(name):
    """Every learner: a held sample leaves theta and P as they were and is counted;
    revert takes back the last update exactly; rewind puts back a snapshot's estimate
    while the memory stays current (the next predictions are those of that estimate
    on the true lags)."""
    structure, method, options, plant = LEARNERS[name]
    names = [list(plant.inputs), list(plant.outputs)]
    u, y = _record(plant, 300, noise=0.01)
    online = online_estimator(structure, method, options, *names)
    twin = online_estimator(structure, method, options, *names)  # learns every sample
    for k in range(200):
        online.update(u[k], y[k])
        twin.update(u[k], y[k])
    snapshot, estimate = online.snapshot(), _vector(online)
    online.update(u[200], y[200], learn=False)
    np.testing.assert_array_equal(_vector(online), estimate)
    assert online.n_samples == 201
    online.update(u[201], y[201])
    online.revert()
    np.testing.assert_array_equal(_vector(online), estimate)
    for k in range(202, 250):
        online.update(u[k], y[k])
    assert not np.array_equal(_vector(online), estimate)
    online.rewind(snapshot)
    np.testing.assert_array_equal(_vector(online), estimate)
    assert online.n_samples == 250
    if structure == "arx":  # the prediction of the rewound estimate on the true lags
        model = online.model()
        np.testing.assert_allclose(
            online.update(u[250], y[250]), model.predict(u[:251], y[:251])[-1], rtol=1e-12
        )
    json.dumps(snapshot)  # JSON-ready (a stream's checkpoint holds it)


# ---------------------------------------------------------------------- options
@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"passes": 3}, "one pass"),
        ({"normalize": True}, "input_scale and output_scale"),
        ({"center": True}, "center=True"),
        ({"input_scale": 2.0}, "both input_scale and output_scale"),
        ({"eps1": 1.0}, "eps1 not used by hammerstein-wiener"),
        ({"initial": PLANTS["hammerstein"]}, "must be a HammersteinWiener"),
        ({"initial": PLANTS["hammerstein-wiener"], "initial_parameters": 0.1}, "not both"),
    ],
)
def test_options_a_stream_cannot_honour_are_refused(options, message):
    with pytest.raises(ParameterError, match=message):
        online_estimator("hammerstein-wiener", "key-term-rls", options, "u", "y")


@pytest.mark.parametrize(
    ("structure", "method", "start", "given"),
    [
        ("arx", "rls", ARX(["u"], ["y"], 2, 2, 1, a={"y": {"y": [-1.2, 0.35]}},
                           b={"y": {"u": [1.0, 0.4]}}), {"na": 3, "nb": 1}),
        ("arx", "rls", ARX(["u"], ["y"], 2, 2, 1), {"na": 1}),
        ("arx", "rls", ARX(["u"], ["y"], 2, 2, 1), {"nb": 1}),
        ("arx", "rls", ARX(["u"], ["y"], 2, 2, 1), {"nk": 2}),
        ("hammerstein-wiener", "key-term-rls", PLANTS["hammerstein-wiener"], {"nk": 2}),
        ("hammerstein-wiener", "key-term-rls", PLANTS["hammerstein-wiener"], {"r2": 2}),
    ],
)  # fmt: skip
def test_orders_given_beside_a_starting_model_must_be_its_own(structure, method, start, given):
    """The starting model's parameters were laid out by the orders given instead of its
    own: taken silently (ARX na=3, nb=1 read the 2+2 numbers as 3+1) or failing deep in
    NumPy ("operands could not be broadcast")."""
    with pytest.raises(ParameterError, match="differs from the starting model's"):
        online_estimator(structure, method, {**given, "initial": start}, ["u"], ["y"])
    own = {k: getattr(start, k) for k in ("na", "nb", "nk")}
    online_estimator(structure, method, {**own, "initial": start}, ["u"], ["y"])  # its own: fine
    # none given: every order is the starting model's own (mutation run 3: nb, nk fell
    # back to the defaults, which then differed from the model's)
    online_estimator(structure, method, {"initial": start}, ["u"], ["y"])
    if structure == "arx":  # a delay that is not the default's
        delayed = ARX(["u"], ["y"], 2, 2, 3)
        est = online_estimator(structure, method, {"initial": delayed}, ["u"], ["y"])
        assert np.all(np.asarray(est.template.nk) == 3)


def test_online_update_refuses_a_missing_output_sample():
    from blockid.fitting.online import online_estimator

    est = online_estimator("arx", "rls", {}, ["u"], ["y"])
    with pytest.raises(DataError, match="^the chunk contains NaN or inf"):
        est.update(1.0, np.nan)
    assert est.n_samples == 0
