"""Plot tests draw off-screen (Agg) and close their figures."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


@pytest.fixture(scope="session")
def hammerstein_fit():
    """A Hammerstein model fitted with standard errors on 600 samples of a known plant
    (sampling time 0.1 s), and its estimation and validation data."""
    import numpy as np

    from blockid.blocks import Polynomial
    from blockid.data import Dataset
    from blockid.fitting import fit_model
    from blockid.models import Hammerstein

    rng = np.random.default_rng(7)
    u = np.repeat(rng.uniform(-1.0, 1.0, 100), 10)
    plant = Hammerstein("u", "y", input_block=Polynomial([0.0, 1.0, 0.0, -0.4]), na=2, nb=2,
                        nk=1, a=[-1.5, 0.7], b=[1.0, 0.5])  # fmt: skip
    y = plant.simulate(u)[:, 0] + 0.02 * rng.standard_normal(u.size)
    data = Dataset.from_arrays(u, y, ["u"], ["y"], sampling_time=0.1)
    est, val = data.select(0, 600), data.select(600, 1000)
    fit = fit_model(est, "hammerstein", na=2, nb=2, nk=1, r1=3, standard_errors=True)
    return fit, est, val
