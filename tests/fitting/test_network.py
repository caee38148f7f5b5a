"""fit_network on a small network with known truth: each subsystem fitted on its own
measured signals, the assembled network scored by free-run simulation (paper A's
procedure; see docs/networks.md)."""

import numpy as np
import pytest

from blockid.data import Dataset
from blockid.errors import ParameterError
from blockid.fitting import fit_model, fit_network, parse_subsystem, subset

N = 400
SPECS = [
    "S1: u1 -> v1 | arx na=1 nb=1 nk=1 method=batch",
    "S2: v1,u2 -> y | arx na=2 nb=1 nk=1 method=batch",
]


def _data():
    """S1: v1(t) = 0.6 v1(t-1) + 0.4 u1(t-1) + e1(t);
    S2: y(t) = 1.2 y(t-1) - 0.5 y(t-2) + 0.3 v1(t-1) + 0.8 u2(t-1) + e2(t),
    with small equation errors e (so least squares is consistent) and v1 measured."""
    rng = np.random.default_rng(7)
    u1, u2 = rng.standard_normal(N), rng.standard_normal(N)
    e1, e2 = 0.01 * rng.standard_normal(N), 0.01 * rng.standard_normal(N)
    v1, y = np.zeros(N), np.zeros(N)
    for t in range(2, N):
        v1[t] = 0.6 * v1[t - 1] + 0.4 * u1[t - 1] + e1[t]
        y[t] = 1.2 * y[t - 1] - 0.5 * y[t - 2] + 0.3 * v1[t - 1] + 0.8 * u2[t - 1] + e2[t]
    return Dataset.from_arrays(
        np.column_stack([u1, u2]),
        np.column_stack([v1, y]),
        inputs=["u1", "u2"],
        outputs=["v1", "y"],
        sampling_time=0.1,
    )


@pytest.fixture(scope="module")
def fitted():
    data = _data()
    return data, fit_network(data, [parse_subsystem(s) for s in SPECS])


def test_network_is_assembled_from_the_named_subsystems(fitted):
    data, fit = fitted
    net = fit.model
    assert [name for name, _ in net.subsystems] == ["S1", "S2"]
    assert net.inputs == ("u1", "u2") and net.outputs == ("v1", "y")
    assert net.sampling_time == 0.1
    assert (fit.method, fit.metrics_mode, fit.n_samples) == ("network", "simulation", N)
    assert net["S1"].inputs == ("u1",) and net["S1"].outputs == ("v1",)
    assert net["S2"].inputs == ("v1", "u2") and net["S2"].outputs == ("y",)


def test_subsystem_parameters_match_the_truth(fitted):
    _, fit = fitted
    s1, s2 = fit.model["S1"], fit.model["S2"]
    np.testing.assert_allclose(s1.a["v1"]["v1"], [-0.6], atol=0.01)
    np.testing.assert_allclose(s1.b["v1"]["u1"], [0.4], atol=0.01)
    np.testing.assert_allclose(s2.a["y"]["y"], [-1.2, 0.5], atol=0.01)
    np.testing.assert_allclose(s2.b["y"]["v1"], [0.3], atol=0.01)
    np.testing.assert_allclose(s2.b["y"]["u2"], [0.8], atol=0.01)


def test_each_subsystem_is_the_fit_on_its_own_signals_and_settings_say_so(fitted):
    data, fit = fitted
    expected = {}
    for name, ins, outs, orders in (
        ("S1", ["u1"], ["v1"], dict(na=1, nb=1, nk=1)),
        ("S2", ["v1", "u2"], ["y"], dict(na=2, nb=1, nk=1)),
    ):
        alone = fit_model(subset(data, ins, outs), "arx", method="batch", **orders)
        assert fit.model[name].to_dict() == alone.model.to_dict()
        expected[name] = {"structure": "arx", "method": alone.method, **alone.settings}
    assert fit.settings == {"subsystems": expected}
    assert fit.settings["subsystems"]["S2"]["method"] == "batch"


def test_estimation_metrics_are_of_the_free_run_from_the_external_inputs(fitted):
    data, fit = fitted
    net, exp = fit.model, data.experiments[0]
    skip = net.max_lag
    assert skip == 2
    # v1 feeds S2 as simulated by S1, not as measured: the network runs on u1, u2 alone
    v1 = net["S1"].simulate(exp.u[:, :1], exp.y[:skip, :1])[:, 0]
    y = net["S2"].simulate(np.column_stack([v1, exp.u[:, 1]]), exp.y[:skip, 1:])[:, 0]
    y_sim = np.column_stack([v1, y])[skip:]
    measured = exp.y[skip:]
    err = measured - y_sim
    rmse = np.sqrt(np.mean(err**2, axis=0))
    fit_pct = 100.0 * (
        1.0 - np.linalg.norm(err, axis=0) / np.linalg.norm(measured - measured.mean(0), axis=0)
    )
    metrics = fit.estimation_metrics
    assert set(metrics["rmse"]) == {"v1", "y"}
    for j, name in enumerate(("v1", "y")):
        assert metrics["rmse"][name] == pytest.approx(rmse[j], rel=1e-9)
        assert metrics["fit_percent"][name] == pytest.approx(fit_pct[j], rel=1e-9)
        assert metrics["max_abs_error"][name] == pytest.approx(np.max(np.abs(err[:, j])), rel=1e-9)
    # small equation errors: the free run follows the measurement closely
    assert metrics["fit_percent"]["v1"] > 97.0 and metrics["fit_percent"]["y"] > 95.0


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
def _network_data(n=200):
    rng = np.random.default_rng(7)
    u = rng.standard_normal(n)
    v = np.zeros(n)
    for t in range(1, n):
        v[t] = 0.6 * v[t - 1] + 0.4 * u[t - 1]
    return Dataset.from_arrays(u, v, ["u"], ["v"])


def test_network_fit_records_methods_and_scores_by_simulation():
    from blockid.fitting.network import SubsystemSpec, fit_network

    spec = SubsystemSpec("S1", ["u"], ["v"], "arx", "batch", {"na": 1, "nb": 1, "nk": 1})
    fit = fit_network(_network_data(), [spec])
    assert fit.metrics_mode == "simulation"
    assert fit.settings["subsystems"]["S1"]["method"] == "batch"
    assert fit.settings["subsystems"]["S1"]["structure"] == "arx"


def test_network_option_that_does_not_fit_is_named_with_the_subsystem_options():
    # method given among the options as well as the spec's method: fit_model's TypeError
    from blockid.fitting.network import SubsystemSpec, fit_network

    opts = {"na": 1, "nb": 1, "nk": 1, "method": "rls"}
    with pytest.raises(
        ParameterError,
        match=r"^subsystem S1: an option value does not fit \(na=1 nb=1 nk=1 method=rls\): ",
    ):
        fit_network(_network_data(), [SubsystemSpec("S1", ["u"], ["v"], "arx", None, opts)])


def test_a_block_per_channel_in_a_subsystem_string_keeps_its_channel():
    """``input-block=v2=polynomial`` splits at the first ``=`` (the option's name), so the
    value keeps its channel (mutation run 3: a split at the last gave the key
    ``input-block=v2``)."""
    s = parse_subsystem("S3: v1,v2 -> y1,y2 | block-state-space input-block=v2=polynomial:degree=3")
    assert s.options == {"input_block": "v2=polynomial:degree=3"}
