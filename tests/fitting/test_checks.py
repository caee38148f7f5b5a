"""blockid.fitting.checks: the warnings a fit adds before its model misleads (issue 37):
poles at the Nyquist frequency or outside the unit circle, a free run that leaves the
measured output's range, blocks that have degenerated."""

from __future__ import annotations

import numpy as np
import pytest

from blockid.blocks import DeadZone, Polynomial
from blockid.blocks.linear import LinearBlock
from blockid.data import Dataset
from blockid.data.dataset import Experiment
from blockid.fitting import fit_model
from blockid.fitting.checks import degenerate_block_notes, linear_block_notes, output_range_warnings
from blockid.models import ARX, Hammerstein
from blockid.models.block import ChainModel
from blockid.models.block_state_space import BlockStateSpace


def _first_order(pole: float, n: int = 400, noise: float = 0.01) -> Dataset:
    """``y(t) = pole y(t-1) + u(t-1)`` (plus measurement noise) on a staircase in
    [-1, 1]."""
    rng = np.random.default_rng(1)
    u = np.repeat(rng.uniform(-1.0, 1.0, n // 10), 10)
    y = np.zeros(n)
    for t in range(1, n):
        y[t] = pole * y[t - 1] + u[t - 1]
    y += noise * rng.standard_normal(n)
    return Dataset(("u",), ("y",), 1.0, [Experiment("e", u[:, None], y[:, None])])


def _warnings(result) -> list[str]:
    return result.settings.get("warnings", [])


def test_a_fitted_pole_near_minus_one_is_named_a_nyquist_mode():
    data = _first_order(-0.97)
    for fit in (fit_model(data, "arx", na=1, nb=1, nk=1),
                fit_model(data, "state-space", nx=1, method="subspace")):  # fmt: skip
        (note,) = [w for w in _warnings(fit) if "Nyquist" in w]
        assert "a pole at -0.96" in note and "try lower orders" in note
    assert not any("Nyquist" in w for w in _warnings(fit_model(_first_order(0.9), "arx",
                                                               na=1, nb=1, nk=1)))  # fmt: skip


def test_an_arx_allowed_to_be_unstable_says_so():
    fit = fit_model(_first_order(1.01), "arx", na=1, nb=1, nk=1, allow_unstable=True)
    (note,) = _warnings(fit)
    assert note.startswith("the model is unstable: its linear part has a pole at 1.01")
    assert "predict one step ahead only" in note


def test_a_free_run_beyond_the_measured_range_is_warned():
    data = _first_order(0.9, noise=0.0)
    truth = ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [-0.9]}}, b={"y": {"u": [1.0]}})
    assert output_range_warnings(truth, data) == []
    loud = ARX(["u"], ["y"], 1, 1, 1, a={"y": {"y": [-0.9]}}, b={"y": {"u": [5.0]}})
    (note,) = output_range_warnings(loud, data)
    assert "free run of 'y' reaches" in note and "on the estimation data" in note


def test_a_degenerate_block_is_named_with_its_place():
    # a dead zone fitted to a plant without one: its edges meet at 0
    fit = fit_model(_first_order(0.8), "hammerstein", na=1, nb=1, nk=1,
                    input_block=DeadZone.template())  # fmt: skip
    (note,) = [w for w in _warnings(fit) if "dead-zone" in w]
    assert note.startswith("the input block (dead-zone) has its edges (lower = 0, upper = 0)")
    # the loop block: a lower edge at -292 313 with slope 6e-7
    far = DeadZone(-292313.0, 0.3, 6e-7, 1.0)
    loop = BlockStateSpace(["u"], ["y"], A=[[0.5]], B=[[1.0]], C=[[1.0]], D=[[0.0]],
                           loop_blocks=[far], Cp=[[1.0]], Dp=[[0.0]], Bq=[[0.1]],
                           Dq=[[0.0]], loop_range=[[-2.0, 3.0]])  # fmt: skip
    (note,) = degenerate_block_notes(loop)
    assert note.startswith("the loop block p1 (dead-zone) has lower = -292313")
    sound = Hammerstein("u", "y", input_block=DeadZone(-0.5, 0.5), na=1, nb=1, nk=1)
    assert degenerate_block_notes(sound.replace(ranges={"u": [-2.0, 3.0]})) == []
    assert degenerate_block_notes(sound) == []  # no recorded range: nothing to judge on


# ----------------------------------------------------------------------------- constant inputs
def test_a_constant_input_is_refused_by_name_before_any_fit():
    from blockid.errors import DataError
    from blockid.fitting import fit_model
    from blockid.workflows.identify import identify

    rng = np.random.default_rng(0)
    y = rng.standard_normal(300)
    data = Dataset.from_arrays(np.ones(300), y, ["valve"], ["flow"])
    for attempt in (lambda: fit_model(data, "arx"), lambda: identify(data, effort="quick")):
        with pytest.raises(
            DataError,
            match=r"input 'valve' is constant over the estimation data \(1 at every sample\)",
        ):
            attempt()
    two = Dataset.from_arrays(np.c_[rng.standard_normal(300), np.full(300, 2.5)], y,
                              ["u", "bias"], ["flow"])  # fmt: skip
    with pytest.raises(
        DataError, match=r"'bias' is constant .* \(2.5 at every sample\).*leave it out"
    ):
        fit_model(two, "arx")
    fit_model(Dataset.from_arrays(rng.standard_normal(300), y, ["valve"], ["flow"]), "arx")


def _chain(coefficients):
    return ChainModel(
        "u",
        "y",
        [Polynomial(coefficients, constant=False), LinearBlock(1, 1, 1, a=[-0.5], b=[1.0])],
    )


def test_linear_input_block_is_noted_not_refused():
    u = np.random.default_rng(1).uniform(-2, 2, 400)
    data = Dataset.from_arrays(u, np.zeros(400), ["u"], ["y"])
    notes = linear_block_notes(_chain([1.0, 1e-19, 1e-19]), data)
    assert len(notes) == 1 and "input block (polynomial) is linear" in notes[0]
    assert linear_block_notes(_chain([1.0, 0.3, -0.1]), data) == []
    assert linear_block_notes(ARX(["u"], ["y"], 1, 1, 1), data) == []
