import numpy as np
import pytest

from blockid import errors
from blockid.blocks import Backlash
from blockid.data import Dataset
from blockid.errors import OrderError
from blockid.fitting import parse_subsystem, subset
from blockid.models import ARX, BacklashModel, Network, load_model, save_model
from blockid.models.network import check_wiring


def paper_a_network():
    s1 = ARX(["u1"], ["v1"], 1, 1, 1, a={"v1": {"v1": [-0.62]}}, b={"v1": {"u1": [0.39]}})
    s2 = BacklashModel(
        "u2", "v2", input_block=Backlash(0.9, 0.8, 0.9, 0.85), na=2, nb=1, nk=1, a=[-1.0, 0.17]
    )
    s3 = ARX(
        ["v1", "v2"],
        ["y1", "y2"],
        na=2,
        nb=2,
        nk=1,
        a={
            "y1": {"y1": [-1.2, 0.4], "y2": [0.1, 0.0]},
            "y2": {"y1": [0.05, 0.02], "y2": [-0.9, 0.2]},
        },
        b={
            "y1": {"v1": [0.05, 0.02], "v2": [0.01, -0.005]},
            "y2": {"v1": [0.0, 0.003], "v2": [0.04, 0.01]},
        },
    )
    return Network([("S1", s1), ("S2", s2), ("S3", s3)], sampling_time=0.05)


def test_signals_and_free_run_equal_the_chained_subsystems(rng):
    net = paper_a_network()
    assert net.inputs == ("u1", "u2") and net.outputs == ("v1", "v2", "y1", "y2")
    u = np.column_stack([rng.uniform(-5, 5, 300), rng.uniform(-5, 5, 300)])
    out = net.simulate(u)
    v1 = net["S1"].simulate(u[:, :1])
    v2 = net["S2"].simulate(u[:, 1:])
    y = net["S3"].simulate(np.column_stack([v1, v2]))
    np.testing.assert_allclose(out, np.column_stack([v1, v2, y]), atol=1e-12)
    # one-step prediction on noise-free data is exact
    np.testing.assert_allclose(net.predict(u, out)[net.max_lag :], out[net.max_lag :], atol=1e-9)


def test_network_file_round_trip(tmp_path, rng):
    net = paper_a_network()
    again = load_model(save_model(net, tmp_path / "net.json"))
    u = rng.uniform(-5, 5, (200, 2))
    assert np.array_equal(again.simulate(u), net.simulate(u))


def test_wiring_errors():
    s1 = ARX(["u"], ["v"], 1, 1, 1)
    with pytest.raises(errors.OrderError, match="made by subsystem .B. and by .C."):
        Network([("A", ARX(["v"], ["y"], 1, 1, 1)), ("B", s1), ("C", ARX(["u2"], ["v"], 1, 1, 1))])


def test_parse_subsystem_and_subset(rng):
    spec = parse_subsystem("S2: u2 -> v2 | backlash na=2 nb=1 nk=1 method=aw-rls eps1=1.5")
    assert (spec.structure, spec.method, spec.options) == (
        "backlash",
        "aw-rls",
        {"na": "2", "nb": "1", "nk": "1", "eps1": "1.5"},  # text: fit_model converts
    )
    with pytest.raises(errors.ParameterError, match="expected 'NAME: IN"):
        parse_subsystem("S1 u1 v1")
    data = Dataset.from_arrays(
        rng.standard_normal((10, 2)),
        rng.standard_normal((10, 2)),
        inputs=["u1", "u2"],
        outputs=["v1", "y1"],
    )
    sub = subset(data, ["v1"], ["y1"])
    np.testing.assert_array_equal(sub.experiments[0].u[:, 0], data.experiments[0].y[:, 0])
    with pytest.raises(errors.DataError, match=r"\['nope'\] are not in the data"):
        subset(data, ["nope"], ["y1"])


def test_bad_option_values_are_reported_per_subsystem(rng):
    from blockid.fitting import fit_network

    data = Dataset.from_arrays(
        rng.standard_normal(200), rng.standard_normal(200), inputs=["u1"], outputs=["v1"]
    )
    spec = parse_subsystem("S1: u1 -> v1 | arx na=1 nb=1 nk=1 method=rls passes=abc")
    with pytest.raises(errors.ParameterError, match="subsystem S1"):
        fit_network(data, [spec])
    spec = parse_subsystem("S1: u1 -> v1 | arx method=rls forgetting=none")
    assert spec.options == {"forgetting": "none"}
    fit = fit_network(data, [spec])  # "none": the method's default forgetting (1)
    assert fit.settings["subsystems"]["S1"]["forgetting"] == "1.0"


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
def test_check_wiring_messages_name_the_signal_and_the_whole_cycle():
    from blockid.errors import OrderError
    from blockid.models.network import check_wiring

    with pytest.raises(OrderError) as info:
        check_wiring([("S1", ["u"], ["v"]), ("S2", ["u"], ["v"])])
    assert str(info.value) == (
        "signal 'v' is made by subsystem 'S1' and by 'S2'; each signal must come from one subsystem"
    )
    tail = (
        "; every signal in it is made inside the network, so the loop has no external input "
        "to start from. Feed one of them from outside (a measured input), or model the loop "
        "inside one subsystem"
    )
    loop3 = [("S1", ["v3"], ["v1"]), ("S2", ["v1"], ["v2"]), ("S3", ["v2"], ["v3"])]
    with pytest.raises(OrderError) as info:
        check_wiring(loop3)
    assert str(info.value) == (
        "the subsystems form a cycle: 'S1' -> v1 -> 'S2' -> v2 -> 'S3' -> v3 -> 'S1'" + tail
    )
    with pytest.raises(OrderError) as info:
        check_wiring([("S1", ["u", "v1"], ["v1"])])
    assert str(info.value) == "the subsystems form a cycle: 'S1' -> v1 -> 'S1'" + tail


def test_network_to_dict_lists_its_external_inputs_and_all_outputs():
    s1 = ARX(["u"], ["v"], 1, 1, 1, a={"v": {"v": [-0.5]}}, b={"v": {"u": [1.0]}})
    s2 = ARX(["v"], ["y"], 1, 1, 1, a={"y": {"y": [-0.25]}}, b={"y": {"v": [2.0]}})
    from blockid.models.network import Network

    data = Network([("S1", s1), ("S2", s2)], sampling_time=0.1).to_dict()
    assert data["structure"] == "network"
    assert data["inputs"] == ["u"]
    assert data["outputs"] == ["v", "y"]
    assert [s["name"] for s in data["subsystems"]] == ["S1", "S2"]


def test_cyclic_network_is_named():
    s1 = ARX(["v2"], ["v1"], 1, 1, 1)
    s2 = ARX(["v1"], ["v2"], 1, 1, 1)
    with pytest.raises(OrderError, match=r"cycle: 'S1' -> v1 -> 'S2' -> v2 -> 'S1'"):
        Network([("S1", s1), ("S2", s2)])
    with pytest.raises(OrderError, match=r"'S' -> y -> 'S'"):
        check_wiring([("S", ["y"], ["y"])])
