"""TaskRunner: results in the items' order, data shared with the workers, a time cap."""

import time

import numpy as np
import pytest

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


def _threads_seen(data, item):
    """Runs in a worker: the threads a fit may take now ("short") or, polled for up to
    20 s, once the other item has finished ("long")."""
    from blockid.fitting.threads import threads_for_fit

    if item == "short":
        return threads_for_fit()
    end = time.monotonic() + 20.0
    while threads_for_fit() < 2 and time.monotonic() < end:
        time.sleep(0.01)
    return threads_for_fit()


def test_the_last_running_fit_takes_the_cores_the_others_left():
    """Two items on two workers: one thread each while both run; once the short one has
    finished, the long one's fit may take both cores (the allowance is read at each
    iteration); here, in this process, nothing changes."""
    from blockid.fitting.threads import threads_for_fit
    from blockid.workflows.parallel import available_cores

    if available_cores() < 2:
        pytest.skip("needs two cores")
    before = threads_for_fit()
    with TaskRunner(_data(), 2) as pool:
        short, long = pool.map(_threads_seen, ["short", "long"])
    assert short == 1 and long == 2
    assert threads_for_fit() == before


def _fit_cpu_share(data, item):
    """Runs in a worker: CPU time of the whole process over that of this thread during a
    fit (1.0 when no other thread of the worker runs)."""
    from blockid.fitting.dispatch import fit_model

    t0, c0 = time.thread_time(), time.process_time()
    fit_model(data, "hammerstein-wiener", na=2, nb=2, nk=1, max_nfev=15)
    return (time.process_time() - c0) / max(time.thread_time() - t0, 1e-9)


@pytest.mark.slow  # a measurement of CPU time, disturbed by and disturbing the other tests
def test_no_thread_of_a_worker_spins_beside_its_fit():
    """Workers forked from this process kept an OpenBLAS thread spinning beside every fit
    (process CPU 1.5-2.0 times the fitting thread's; two workers were slower than
    one on a long record); fresh workers with one-thread pools have none."""
    rng = np.random.default_rng(1)
    u = rng.uniform(-1, 1, 10_000)
    x = np.zeros_like(u)
    for k in range(2, u.size):
        x[k] = 1.2 * x[k - 1] - 0.5 * x[k - 2] + u[k - 1] + 0.3 * u[k - 1] ** 3
    y = x + 0.1 * x**2 + 0.01 * rng.standard_normal(u.size)
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    with TaskRunner(data, 2) as pool:
        shares = pool.map(_fit_cpu_share, [0, 1, 2, 3])
    assert max(shares) < 1.2, shares


def test_a_plain_script_without_a_main_guard_runs_once_with_two_workers(tmp_path):
    """The workers neither re-run the user's script from the top nor need its functions
    importable: a function defined in the script itself runs in them."""
    import subprocess
    import sys

    script = tmp_path / "plain.py"
    script.write_text(
        "print('TOP')\n"
        "import numpy as np\n"
        "from blockid.data import Dataset\n"
        "from blockid.workflows.parallel import TaskRunner\n"
        "def total(data, k):\n"
        "    return k + float(data.experiments[0].u.sum())\n"
        "data = Dataset.from_arrays(np.ones(10), np.zeros(10), ['u'], ['y'])\n"
        "with TaskRunner(data, 2) as pool:\n"
        "    print('RESULTS', pool.map(total, [0, 1, 2]))\n"
    )
    run = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                         timeout=120, cwd=tmp_path)  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert run.stdout.splitlines() == ["TOP", "RESULTS [10.0, 11.0, 12.0]"]
