import matplotlib
import pytest

matplotlib.use("Agg")


@pytest.fixture
def rng():
    import numpy as np

    return np.random.default_rng(12345)


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    """Twenty small ARX records for ``fleet``, one corrupt (:func:`reference.fleet_records`)."""
    from reference import fleet_records

    return fleet_records(tmp_path_factory.mktemp("logs"))


@pytest.fixture(scope="module")
def cluster():
    """A local dask cluster of two worker processes for the module (its start-up is most of
    the time of the tests that use it): its scheduler's address."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        dashboard_address=":0",
        silence_logs=50,
    ) as running:
        yield running.scheduler_address
