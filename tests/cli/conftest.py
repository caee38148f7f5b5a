"""Fixtures of the command-line tests: the working folders the commands run in."""

import numpy as np
import pytest

from blockid.models import ARX, save_model
from cli import bad_input

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
