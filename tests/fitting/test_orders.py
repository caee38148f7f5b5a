"""Order selection by false nearest neighbours (fitting/orders.py)."""

import json

import numpy as np
import pytest
from scipy.signal import lfilter

from blockid.data import Dataset, Experiment
from blockid.errors import DataError, OrderError, ParameterError
from blockid.fitting.orders import OrderEvidence, false_nearest_neighbours

from reference import _dataset


def arx(u, a, b, nk, f=None, g=None):
    """y = g(x), A(z) x = z^-nk B(z) f(u): MATLAB convention, a = [a_1..], b = [b_0..]."""
    w = u if f is None else f(u)
    x = lfilter(np.r_[np.zeros(nk), b], np.r_[1.0, a], w)
    return x if g is None else g(x)


def with_noise(y, snr_db, rng):
    return y + rng.standard_normal(len(y)) * y.std() * 10 ** (-snr_db / 20)


# Three plants of known orders. The Wiener plant's NARX orders equal its linear
# block's, because tanh is invertible: y(k) = g(-a1 g^-1(y(k-1)) - ... + b u(...)).
PLANTS = {
    "arx(2,2,1)": (dict(a=[-1.2, 0.5], b=[1.0, 0.5], nk=1), (2, 2, 1)),
    "hammerstein(3,2,2)": (
        dict(a=[-0.7, 0.2, 0.3], b=[1.0, -0.6], nk=2, f=lambda v: v + 0.5 * v**3),
        (3, 2, 2),
    ),
    "wiener(2,2,1)": (
        dict(a=[-1.2, 0.5], b=[1.0, 0.5], nk=1, g=lambda x: np.tanh(0.3 * x)),
        (2, 2, 1),
    ),
}


def plant_data(name, n=2000, snr_db=None, seed=1, scale=1.0):
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, n)
    kwargs, truth = PLANTS[name]
    y = arx(u, **kwargs)
    if snr_db is not None:
        y = with_noise(y, snr_db, rng)
    return Dataset.from_arrays(scale * u, scale * y), truth


@pytest.mark.parametrize("snr_db", [None, 40], ids=["noise-free", "40dB"])
@pytest.mark.parametrize("name", list(PLANTS))
def test_recommends_the_true_orders_and_delay(name, snr_db):
    data, truth = plant_data(name, snr_db=snr_db)
    ev = false_nearest_neighbours(data, max_na=4, max_nb=4, max_nk=3)
    assert ev.recommended == truth
    assert ev.passed
    na, nb, nk = truth
    # the delay: the true one is the best at the true orders, by a clear margin
    scan = ev.delay_scan()
    assert min(scan, key=scan.get) == nk
    assert all(v > 5.0 for k, v in scan.items() if k > nk)
    # one lag less in either direction fails
    assert ev.share(na - 1, nb, nk) > 5.0 and ev.share(na, nb - 1, nk) > 2.0
    if snr_db is None:
        assert ev.share(*truth) <= 0.2


@pytest.mark.parametrize("name", list(PLANTS))
def test_share_falls_as_orders_grow(name):
    data, truth = plant_data(name)  # the classic test (no noise allowance) on clean data
    ev = false_nearest_neighbours(data, max_na=4, max_nb=4, max_nk=3, noise=0.0)
    best = ev.best_over_delay()
    assert best[0, 0] > 90.0  # no output lag, one input lag: almost every neighbour false
    assert np.all(np.diff(best, axis=0) <= 0.5)  # more output lags: fewer false
    assert np.all(np.diff(best, axis=1) <= 0.5)  # more input lags: fewer false
    assert best[-1, -1] <= 0.2


def test_units_do_not_matter():
    data, _ = plant_data("hammerstein(3,2,2)", snr_db=40)
    scaled, _ = plant_data("hammerstein(3,2,2)", snr_db=40, scale=1000.0)
    a = false_nearest_neighbours(data)
    b = false_nearest_neighbours(scaled)
    assert a.recommended == b.recommended
    np.testing.assert_allclose(a.percent, b.percent, atol=0.11)  # a tie or two may flip


def test_subsampled_queries_give_the_full_answer():
    data, truth = plant_data("arx(2,2,1)", n=5000, snr_db=40, seed=5)
    full = false_nearest_neighbours(data, max_points=None)
    sub = false_nearest_neighbours(data, max_points=1000, seed=3)
    assert full.settings["n_scored"] == full.settings["n_reference"] > 4900
    assert sub.settings["n_scored"] == 1000
    assert full.recommended == sub.recommended == truth
    assert np.abs(full.percent - sub.percent).max() < 6.0  # sampling error of 1000 points


def test_experiments_are_never_straddled_and_agree_with_one_record():
    rng = np.random.default_rng(7)
    exps = []
    for i in range(3):
        u = rng.uniform(-1, 1, 800)
        y = arx(u, a=[-1.2, 0.5], b=[1.0, 0.5], nk=1)  # each record starts from rest
        exps.append(Experiment(f"run{i}", u, y))
    data = Dataset(("u1",), ("y1",), None, exps)
    ev = false_nearest_neighbours(data, max_na=3, max_nb=3, max_nk=2)
    lag = max(3, 2 + 3 - 1)
    assert ev.settings["n_reference"] == 3 * (800 - lag)
    assert ev.recommended == (2, 2, 1)


def test_two_inputs_share_nb_and_nk():
    rng = np.random.default_rng(3)
    u = rng.uniform(-1, 1, (3000, 2))
    y = arx(u[:, 0], a=[-1.2, 0.5], b=[1.0, 0.5], nk=1)
    y = y + lfilter([0.0, 0.8, -0.4], [1.0, -1.2, 0.5], u[:, 1])
    data = Dataset.from_arrays(u, y)
    ev = false_nearest_neighbours(data, max_na=3, max_nb=3, max_nk=2)
    assert ev.inputs == ("u1", "u2")
    assert ev.recommended == (2, 2, 1)


def test_result_table_frame_json_and_search_grid():
    data, _ = plant_data("arx(2,2,1)")
    ev = false_nearest_neighbours(data, max_na=2, max_nb=3, max_nk=1)
    assert isinstance(ev, OrderEvidence)
    assert ev.percent.shape == (3, 3, 2)
    frame = ev.to_frame()
    assert list(frame.columns) == ["na", "nb", "nk", "false_percent"] and len(frame) == 18
    row = frame[(frame.na == 1) & (frame.nb == 2) & (frame.nk == 1)]
    assert row.false_percent.item() == ev.share(1, 2, 1)
    doc = json.loads(json.dumps(ev.to_dict(), allow_nan=False))
    assert doc["recommended"] == {"na": 2, "nb": 2, "nk": 1}
    assert doc["evidence"]["one_lag_less"]["na - 1"] == ev.share(1, 2, 1)
    assert set(doc["evidence"]["delay_scan"]) == {"0", "1"}
    assert len(doc["table"]) == 18
    assert doc["evidence"]["notes"] == [
        "na = 2 is the largest tried: try a larger max_na",
        "nk = 1 is the largest tried: try a larger max_nk",
    ]
    assert ev.search_grid() == {"na": [1, 2, 3], "nb": [1, 2, 3], "nk": [0, 1, 2]}
    with pytest.raises(OrderError, match="not in the grid"):
        ev.share(5, 1, 1)


def test_orders_at_the_edge_of_the_grid_are_flagged():
    data, _ = plant_data("hammerstein(3,2,2)")
    ev = false_nearest_neighbours(data, max_na=2, max_nb=2, max_nk=1)
    notes = " ".join(ev.evidence()["notes"])
    assert "largest tried" in notes


def test_noisy_data_without_a_pass_fall_back_to_the_knee():
    data, _ = plant_data("arx(2,2,1)", n=2000, snr_db=10, seed=2)
    # without a noise allowance no order passes at 10 dB (seeds 1-5 checked)
    ev = false_nearest_neighbours(data, max_na=3, max_nb=3, max_nk=2, threshold=0.1, noise=0.0)
    assert not ev.passed
    assert ev.pass_mark == pytest.approx(ev.percent.min() + 0.1)
    assert "knee" in ev.evidence()["notes"][0]
    # the noise allowance of Rhodes & Morari lowers the shares
    loose = false_nearest_neighbours(data, max_na=3, max_nb=3, max_nk=2, noise=0.3)
    assert loose.percent.sum() < ev.percent.sum()
    # ...and the estimated allowance (the default) finds a passing order
    assert false_nearest_neighbours(data, max_na=3, max_nb=3, max_nk=2, threshold=0.1).passed
    # a pass mark of exactly 0 is allowed (only an order with no false neighbour passes)
    strict = false_nearest_neighbours(data, max_na=3, max_nb=3, max_nk=2, threshold=0.0)
    assert strict.pass_mark == pytest.approx(strict.percent.min()) or strict.pass_mark == 0.0


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        (dict(max_na=-1), ParameterError, "max_na must be an integer >= 0"),
        (dict(max_nb=0), ParameterError, "max_nb must be an integer >= 1"),
        (dict(max_nk=1.5), ParameterError, "max_nk must be an integer"),
        (dict(min_nk=3, max_nk=1), OrderError, "larger than max_nk"),
        (dict(r_tol=0), ParameterError, "r_tol must be a finite number > 0"),
        (dict(a_tol=float("nan")), ParameterError, "a_tol"),
        (dict(noise=-0.1), ParameterError, "noise must be a finite number >= 0"),
        (dict(threshold="x"), ParameterError, "threshold must be a number"),
        (dict(max_points=5), ParameterError, "max_points must be an integer >= 10"),
        (dict(output="y9"), DataError, "'y9' is not an output"),
        (dict(max_na=40, max_nb=40), OrderError, "samples with a full regressor"),
    ],
)
def test_bad_arguments_are_refused_clearly(kwargs, error, match):
    data, _ = plant_data("arx(2,2,1)", n=300)
    with pytest.raises(error, match=match):
        false_nearest_neighbours(data, **kwargs)


def test_bad_data_are_refused_clearly():
    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, 500)
    with pytest.raises(DataError, match="signal 'u1' is constant"):
        false_nearest_neighbours(Dataset.from_arrays(np.full(500, 3.0), u))
    with pytest.raises(DataError, match="signal 'y1' is constant"):
        false_nearest_neighbours(Dataset.from_arrays(u, np.full(500, 1e6)))
    with pytest.raises(OrderError, match="the data leave 24 samples"):
        false_nearest_neighbours(Dataset.from_arrays(u[:30], u[:30] ** 2))
    two = Dataset.from_arrays(u, np.column_stack([u, u + 0.2 * u**2]))
    with pytest.raises(DataError, match="2 outputs .* name it"):
        false_nearest_neighbours(two)
    assert false_nearest_neighbours(two, output="y2", max_na=1, max_nb=1).recommended == (0, 1, 0)


def test_the_noise_allowance_is_estimated_where_the_classic_test_asks_for_a_lag_too_many():
    """A second-order Hammerstein plant at 40 dB (noise at 1 % of the output's spread),
    driven by steps held for 4 samples: the classic test (noise 0) recommends na = 3,
    the one-lag-less share just above the pass mark; the default estimates the noise
    level (about 0.01) and recommends the plant's na = 2."""
    from blockid.blocks import Polynomial
    from blockid.models import Hammerstein

    rng = np.random.default_rng(0)
    plant = Hammerstein("u", "y", input_block=Polynomial([0.0, 1.0, 0.5, 0.3]), na=2, nb=2,
                        nk=1, a=[-1.5, 0.7], b=[1.0, 0.4])  # fmt: skip
    u = np.repeat(rng.uniform(-1, 1, 750), 4)
    y = with_noise(plant.simulate(u)[:, 0], 40, rng)
    data = Dataset.from_arrays(u, y)
    classic = false_nearest_neighbours(data, noise=0.0)
    auto = false_nearest_neighbours(data)
    assert classic.recommended[0] == 3 and classic.settings["noise_estimated"] is False
    assert auto.recommended[0] == 2 and auto.settings["noise_estimated"] is True
    assert 0.005 < auto.settings["noise"] < 0.02


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
def test_false_nearest_neighbour_shares_with_the_noise_allowance_by_brute_force():
    from blockid.fitting.orders import false_nearest_neighbours

    rng = np.random.default_rng(5)
    n = 90
    u = rng.standard_normal(n)
    y = np.convolve(u, [0.0, 1.0, 0.5])[:n] + 0.3 * rng.standard_normal(n)
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    r_tol, a_tol, noise = 2.0, 10.0, 0.1
    ev = false_nearest_neighbours(
        data, max_na=1, max_nb=2, max_nk=1, r_tol=r_tol, a_tol=a_tol, noise=noise,
        max_points=None, exclude=0,
    )  # fmt: skip
    us, ys = (u - u.mean()) / u.std(), (y - y.mean()) / y.std()
    lag = 2  # max(max_na, max_nk + max_nb - 1)
    for i, na in enumerate(ev.na):
        for j, nb in enumerate(ev.nb):
            for m, nk in enumerate(ev.nk):
                cols = [ys[lag - k : n - k] for k in range(1, na + 1)]
                cols += [us[lag - d : n - d] for d in range(nk, nk + nb)]
                x, out = np.column_stack(cols), ys[lag:]
                dist = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=2)
                np.fill_diagonal(dist, np.inf)
                nearest = dist.argmin(axis=1)
                dy = np.abs(out - out[nearest])
                slack = 2 * r_tol * np.sqrt(na * noise**2 + nb * noise**2) + 2 * noise
                false = (dy > r_tol * dist.min(axis=1) + slack) | (dy > a_tol)
                assert ev.percent[i, j, m] == pytest.approx(100.0 * false.mean(), abs=1e-9)
    assert ev.percent.max() > 50.0  # (0, 1, 0): a wrong order, mostly false neighbours


def test_order_test_names_the_bad_option():
    from blockid.fitting.orders import false_nearest_neighbours

    with pytest.raises(ParameterError, match=r"^max_na must be an integer >= 0, got -1") as info:
        false_nearest_neighbours(_dataset(), max_na=-1)
    assert info.value.parameter == "max_na"
