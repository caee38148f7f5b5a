"""TaskRunner: results in the items' order, data shared with the workers, a time cap."""

import time

import numpy as np

from blockid.data import Dataset
from blockid.workflows.parallel import TaskRunner


def _sum_and_share(data, item):
    """Runs in a worker: the data arrive whole, read-only, and the BLAS pool is single."""
    from threadpoolctl import threadpool_info

    exp = data.experiments[item % len(data.experiments)]
    time.sleep(0.05 * (3 - item % 3))  # later items finish first
    threads = {p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"}
    return item, float(exp.u.sum() + exp.y.sum()), exp.u.flags.writeable, threads


def _data():
    rng = np.random.default_rng(0)
    return Dataset.from_arrays(rng.standard_normal((500, 2)), rng.standard_normal(500),
                               ["a", "b"], ["y"])  # fmt: skip


def test_workers_return_results_in_the_items_order_with_the_same_numbers():
    data = _data()
    with TaskRunner(data, 1) as here:
        serial = here.map(_sum_and_share, list(range(6)))
    seen = []
    with TaskRunner(data, 2) as pool:
        parallel = pool.map(_sum_and_share, list(range(6)), done=lambda i, r: seen.append(i))
    assert [r[:2] for r in parallel] == [r[:2] for r in serial]
    assert [r[0] for r in parallel] == list(range(6)) and sorted(seen) == list(range(6))
    assert all(not r[2] for r in parallel)  # views of the shared record, read-only
    assert all(r[3] <= {1} for r in parallel + serial)  # one BLAS thread per fit


def test_items_not_started_by_the_deadline_give_none():
    with TaskRunner(_data(), 1) as here:
        out = here.map(_sum_and_share, [0, 1, 2], deadline=time.monotonic() - 1.0)
    assert out == [None, None, None]
    with TaskRunner(_data(), 2) as pool:
        out = pool.map(_sum_and_share, list(range(20)), deadline=time.monotonic() + 0.12)
    assert out[0] is not None and out[-1] is None
