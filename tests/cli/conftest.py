"""Fixtures of the command-line tests: the records and working folders the commands run
on, and :data:`FIT`, the ``fit`` command line of :func:`tito_csv` (the file name goes
after its first word)."""

import numpy as np
import pandas as pd
import pytest

from blockid.models import ARX, save_model
from cli import bad_input

import reference

N = 300  # samples of const.csv (constant_output)


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    """The working folder of a bad-input case (:func:`cli.bad_input.workdir`)."""
    monkeypatch.chdir(tmp_path)
    return bad_input.workdir(tmp_path)


@pytest.fixture
def constant_output(tmp_path, monkeypatch):
    rng = np.random.default_rng(3)
    t = np.arange(N) * 0.05
    u = rng.standard_normal(N)
    (tmp_path / "const.csv").write_text(
        "t,u,y\n" + "".join(f"{t[k]:.2f},{float(u[k])!r},1.5\n" for k in range(N))
    )
    model = ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [-0.5]}}, b={"y": {"u": [0.2]}})
    save_model(model, tmp_path / "model.json")
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.fixture
def tito_csv(tmp_path, rng):
    plant = reference.tito_arx(inputs=("u1", "u2"))
    u = rng.standard_normal((1200, 2))
    y = plant.simulate(u) + 0.001 * rng.standard_normal((1200, 2))
    path = tmp_path / "tito.csv"
    pd.DataFrame(
        {"t": np.arange(1200) * 0.05, "u1": u[:, 0], "u2": u[:, 1], "y1": y[:, 0], "y2": y[:, 1]}
    ).to_csv(path, index=False)
    return path


#: ``fit`` of the two-input, two-output ARX record of :func:`tito_csv`.
FIT = ["fit", "-u", "u1", "-u", "u2", "-y", "y1", "-y", "y2", "--na", "2", "--nb", "2", "--nk", "1"]


@pytest.fixture
def cubic_csv(tmp_path):
    from reference import squared_state_record

    data = squared_state_record(600)
    e = data.experiments[0]
    path = tmp_path / "cubic.csv"
    pd.DataFrame({"u": e.u[:, 0], "y": e.y[:, 0]}).to_csv(path, index=False)
    return path
