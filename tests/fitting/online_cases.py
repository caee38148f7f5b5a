"""Plants, records and checks the online learners' tests share (test_online.py,
test_online_arx.py, test_online_paper.py, test_online_base.py)."""

import numpy as np

from blockid.blocks import Backlash, Polynomial, TwoSegmentPolynomial
from blockid.data import Dataset
from blockid.errors import EstimationError
from blockid.fitting.online import online_estimator
from blockid.models import ARX, BacklashModel, Hammerstein, HammersteinWiener, Wiener

# paper B's orders and a stable third-order linear block
N1 = TwoSegmentPolynomial.from_segments(
    positive=[0, 0.3, 0.1, -0.05], negative=[0, 0.15, -0.05, 0.03]
)


N2 = Polynomial([1.0, 0.2, 0.05], constant=False)


LINEAR = dict(na=3, nb=3, nk=8, a=np.real(np.poly([0.7, 0.5, -0.3]))[1:], b=[1.0, 0.5, 0.2])


ORDERS = dict(na=3, nb=3, nk=8)


PLANTS = {
    "hammerstein-wiener": HammersteinWiener("u", "y", input_block=N1, output_block=N2, **LINEAR),
    "hammerstein": Hammerstein("u", "y", input_block=N1, **LINEAR),
    "wiener": Wiener("u", "y", output_block=N2, **LINEAR),
}


BACKLASH = BacklashModel(
    "u", "y", input_block=Backlash(0.9, 0.8, 0.9, 0.85), na=2, nb=1, nk=1, a=[-1.0, 0.17]
)


# two inputs, two outputs, unequal orders (every lag bookkeeping path)
ARX_ORDERS = dict(na=[[2, 1], [1, 2]], nb=[[2, 1], [1, 2]], nk=[[1, 2], [1, 1]])


TITO = ARX(
    ["u1", "u2"],
    ["y1", "y2"],
    **ARX_ORDERS,
    a={"y1": {"y1": [-0.5, 0.1], "y2": [0.05]}, "y2": {"y1": [0.1], "y2": [-0.3, 0.05]}},
    b={"y1": {"u1": [1.0, 0.3], "u2": [0.2]}, "y2": {"u1": [0.4], "u2": [1.0, -0.2]}},
)


ARX_METHODS = {
    "rls": {"forgetting": "0.98:100,0.999"},
    "aw-rls": {},
    "hierarchical-rls": {"forgetting": 0.98},
}


def _record(plant, n, amplitude=1.0, seed=1, noise=0.0):
    rng = np.random.default_rng(seed)
    u = amplitude * rng.uniform(-1.0, 1.0, (n, len(plant.inputs)))
    y = plant.simulate(u)
    return u, y + noise * rng.standard_normal(y.shape)


def _dataset(plant, u, y):
    return Dataset.from_arrays(u, y, inputs=list(plant.inputs), outputs=list(plant.outputs))


def _vector(online):
    return np.array(list(online.estimate().values()))


def _three_ways(structure, method, options, plant, u, y, seed=0):
    """Estimates after the whole record, random chunks, and sample-by-sample updates."""
    names = (list(plant.inputs), list(plant.outputs))
    whole = online_estimator(structure, method, options, *names).partial_fit(u, y)
    chunked = online_estimator(structure, method, options, *names)
    cuts = np.sort(np.random.default_rng(seed).choice(np.arange(4, len(u)), 12, replace=False))
    for a, b in zip(np.r_[0, 1, 2, 3, cuts], np.r_[1, 2, 3, cuts, len(u)], strict=True):
        chunked.partial_fit(u[a:b], y[a:b])  # incl. chunks of one sample within max_lag
    single = online_estimator(structure, method, options, *names)
    for k in range(len(u)):
        single.update(u[k], y[k])
    for est in (whole, chunked, single):
        assert est.n_samples == len(u)
    return whole, chunked, single


def _same(estimates, reference, names=None):
    for est in estimates:
        if names is not None:
            assert list(est.estimate()) == names
        np.testing.assert_allclose(_vector(est), reference, rtol=1e-9, atol=1e-12)
        np.testing.assert_array_equal(_vector(est), reference)  # in fact bit for bit


def _offline_history(fit, *args, **kwargs):
    """The one-pass offline estimate (recursion order, data units), also when the fit
    refuses its model (one pass of H-W key-term RLS does not converge)."""
    try:
        return fit(*args, passes=1, record_history=True, **kwargs).history
    except EstimationError as exc:
        return exc.history


LEARNERS = {
    "arx-rls": ("arx", "rls", ARX_ORDERS, TITO),
    "arx-aw-rls": ("arx", "aw-rls", ARX_ORDERS, TITO),
    "arx-hierarchical-rls": ("arx", "hierarchical-rls", ARX_ORDERS, TITO),
    "hammerstein-wiener": (
        "hammerstein-wiener",
        "key-term-rls",
        ORDERS,
        PLANTS["hammerstein-wiener"],
    ),
    "backlash": ("backlash", "aw-rls", {"na": 2, "nb": 1, "nk": 1}, BACKLASH),
}
