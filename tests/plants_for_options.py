"""Small plants and short records on which every (structure, method) of the registry
converges quickly: the fixtures of ``tests/fitting/test_every_option.py``.

Each case is a record of the structure's own plant and the options every fit of the
case is given (the orders, and a small ``max_nfev`` for the simulation-error fits), so
that a fit takes well under half a second. Records are built on demand, seeded.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from blockid.blocks import Backlash, LinearBlock, Polynomial, TwoSegmentPolynomial
from blockid.data import Dataset
from blockid.models import (
    ARX,
    BacklashModel,
    Hammerstein,
    HammersteinWiener,
    OutputError,
    Wiener,
    WienerHammerstein,
)
from blockid.models.state_space import PolynomialStateSpace, StateSpace, monomial_exponents

#: The linear block of every plant: poles 0.7 and 0.5 (na = 2, nb = 2, nk = 1).
A = [-1.2, 0.35]
B = [1.0, 0.4]
LINEAR = {"na": 2, "nb": 2, "nk": 1, "a": A, "b": B}
ORDERS = {"na": 2, "nb": 2, "nk": 1}

N1 = TwoSegmentPolynomial.from_segments(positive=[0, 0.8, 0.3], negative=[0, 0.5, -0.2])
N2 = Polynomial([1.0, 0.1], constant=False)
BACKLASH = Backlash(m_left=0.9, c_left=0.8, m_right=0.9, c_right=0.85)


def arx_plant() -> ARX:
    return ARX(["u"], ["y"], a={"y": {"y": A}}, b={"y": {"u": B}}, **ORDERS)


def hammerstein_plant() -> Hammerstein:
    return Hammerstein("u", "y", input_block=N1, **LINEAR)


def wiener_plant() -> Wiener:
    return Wiener("u", "y", output_block=N2, **LINEAR)


def hammerstein_wiener_plant() -> HammersteinWiener:
    return HammersteinWiener("u", "y", input_block=N1, output_block=N2, **LINEAR)


def backlash_plant() -> BacklashModel:
    return BacklashModel("u", "y", input_block=BACKLASH, na=2, nb=1, nk=1, a=[-1.0, 0.17], b=[1.0])


def output_error_plant() -> OutputError:
    return OutputError("u", "y", **LINEAR)


def state_space_plant() -> StateSpace:
    """Poles 0.7 and 0.5 (the other plants' linear block), as a state-space model."""
    return StateSpace(["u"], ["y"], A=[[1.2, -0.35], [1.0, 0.0]], B=[[1.0], [0.0]],
                      C=[[1.0, 0.4]], D=[[0.0]])  # fmt: skip


def polynomial_state_space_plant() -> PolynomialStateSpace:
    """The state-space plant with x1^2 and x1^3 feeding the first state."""
    expo = monomial_exponents(2, 1, 3, "states")
    E = np.zeros((2, expo.shape[0]))
    E[0, 0], E[0, 3] = 0.05, -0.02  # x1^2, x1^3
    lin = state_space_plant()
    return PolynomialStateSpace(["u"], ["y"], lin.A, lin.B, lin.C, lin.D, E,
                                np.zeros((1, expo.shape[0])), expo)  # fmt: skip


def block_state_space_plant() -> Any:
    """The state-space plant with a cubic input block (Hammerstein)."""
    from blockid.models.block_state_space import BlockStateSpace

    lin = state_space_plant()
    return BlockStateSpace(["u"], ["y"], lin.A, lin.B, lin.C, lin.D,
                           input_blocks=[Polynomial([0.0, 1.0, 0.0, -0.3])])  # fmt: skip


def wiener_hammerstein_plant() -> WienerHammerstein:
    return WienerHammerstein(
        "u",
        "y",
        first=LinearBlock(1, 1, 1, [-0.8], [0.5]),
        static=Polynomial([0.0, 1.0, 0.0, -0.3]),
        second=LinearBlock(1, 2, 0, [-0.5], [1.0, 0.4]),
    )


def feedback_plant() -> Any:
    from blockid.models.feedback import LinearFeedback

    return LinearFeedback(
        "u",
        "y",
        linear=LinearBlock(2, 1, 1, a=[-1.5, 0.7], b=[0.5]),
        feedback=Polynomial([0.0, 0.0, 0.8], constant=False),
    )


PLANTS = {
    "arx": arx_plant,
    "hammerstein": hammerstein_plant,
    "wiener": wiener_plant,
    "hammerstein-wiener": hammerstein_wiener_plant,
    "backlash": backlash_plant,
    "output-error": output_error_plant,
    "wiener-hammerstein": wiener_hammerstein_plant,
    "feedback": feedback_plant,
    "state-space": state_space_plant,
    "polynomial-state-space": polynomial_state_space_plant,
    "block-state-space": block_state_space_plant,
}


def record(
    plant: Any,
    n: int,
    *,
    amplitude: float = 1.0,
    mean: float = 0.0,
    snr_db: float | None = 30.0,
    seed: int = 0,
    delay: int = 0,
) -> Dataset:
    """``n`` samples of ``plant`` driven by uniform white noise around ``mean``, with
    white output noise at ``snr_db`` (None: none); ``delay`` more samples of input delay
    than the plant has."""
    rng = np.random.default_rng(seed)
    u = mean + rng.uniform(-amplitude, amplitude, n)
    delayed = np.concatenate((np.full(delay, mean), u[: n - delay]))
    y = plant.simulate(delayed)[:, 0]
    if snr_db is not None:
        y = y + rng.standard_normal(n) * np.std(y) * 10 ** (-snr_db / 20)
    return Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"], sampling_time=0.1)


@dataclass(frozen=True)
class Case:
    """One (structure, method) of the registry with the record and options it is fitted
    on; ``options`` go to every fit of the case, under any option being tested."""

    structure: str
    method: str
    n: int
    options: dict[str, Any] = field(default_factory=dict)
    amplitude: float = 1.0
    mean: float = 0.0
    snr_db: float | None = 30.0

    @property
    def id(self) -> str:
        return f"{self.structure}/{self.method}"

    def plant(self) -> Any:
        return PLANTS[self.structure]()

    def data(self, **changes: Any) -> Dataset:
        """The case's record (``changes``: other ``n``, ``snr_db``, ``seed``...)."""
        kw = {"amplitude": self.amplitude, "mean": self.mean, "snr_db": self.snr_db}
        kw.update(changes)
        n = kw.pop("n", self.n)
        return record(self.plant(), n, **kw)


_FAST = {"max_nfev": 5}

#: One case per (structure, method) of the registry.
CASES = {
    c.id: c
    for c in (
        Case("arx", "batch", 300, dict(ORDERS), mean=0.5),
        Case("arx", "rls", 300, dict(ORDERS), mean=0.5),
        Case("arx", "aw-rls", 300, dict(ORDERS), mean=0.5),
        Case(
            "arx",
            "hierarchical-rls",
            1000,
            {**ORDERS, "forgetting": "0.95", "passes": 3},
            mean=0.5,
        ),
        Case("hammerstein", "simulation-error", 200, {**ORDERS, "r1": 2, **_FAST}, mean=0.2),
        Case("hammerstein", "key-term-rls", 1500, {**ORDERS, "r1": 2}, snr_db=40.0),
        Case("wiener", "simulation-error", 200, {**ORDERS, "r2": 2, **_FAST}, mean=0.2),
        Case("wiener", "key-term-rls", 1500, {**ORDERS, "r2": 2}, snr_db=40.0),
        Case(
            "hammerstein-wiener",
            "simulation-error",
            200,
            {**ORDERS, "r1": 2, "r2": 2, **_FAST},
            mean=0.2,
        ),
        Case("hammerstein-wiener", "key-term-rls", 1500, {**ORDERS, "r1": 2, "r2": 2}, snr_db=40.0),
        Case(
            "backlash",
            "simulation-error",
            200,
            {"na": 2, "nb": 1, "nk": 1, **_FAST},
            amplitude=5.0,
            mean=0.5,
        ),
        Case("backlash", "aw-rls", 1000, {"na": 2, "nb": 1, "nk": 1}, amplitude=5.0, mean=0.5),
        Case("output-error", "simulation-error", 200, {**ORDERS, **_FAST}, mean=0.5),
        Case(
            "feedback",
            "simulation-error",
            200,
            {"na": 2, "nb": 1, "nk": 1, "r": 2, **_FAST},
            amplitude=0.8,
            mean=0.1,
        ),
        Case(
            "wiener-hammerstein",
            "simulation-error",
            200,
            {**ORDERS, "r2": 3, **_FAST},
            amplitude=1.5,
            mean=0.2,
        ),
        Case("state-space", "simulation-error", 300, {"max_nfev": 30}, mean=0.5, snr_db=50.0),
        Case("state-space", "subspace", 300, {}, mean=0.5, snr_db=50.0),
        Case(
            "polynomial-state-space",
            "simulation-error",
            500,
            {"nx": 2, "degree": 2, "max_nfev": 20},
            mean=0.2,
            snr_db=50.0,
        ),
        Case(
            "block-state-space",
            "simulation-error",
            400,
            {"nx": 2, "input_block": "polynomial:degree=3", "max_nfev": 20},
            mean=0.2,
            snr_db=50.0,
        ),
        Case("block-state-space", "batch", 400, {"na": 2, "nb": 2, "nk": 1}, snr_db=50.0),
        Case("block-state-space", "rls", 400, {"na": 2, "nb": 2, "nk": 1}, snr_db=50.0),
        Case(
            "block-state-space",
            "key-term-rls",
            400,
            {"input_block": "polynomial:degree=3", "na": 2, "nb": 2, "nk": 1},
            snr_db=50.0,
        ),
    )
}


def recursion_vector(structure: str, r1: int = 2, r2: int = 2) -> list[float]:
    """The plant's parameters in the order of a paper recursion's ``theta`` (the
    ``history["names"]`` of key-term RLS, B4, and of the backlash AW-RLS, A6), in the
    data's units: a ``theta(0)`` in ``initial_parameters``."""
    p = PLANTS[structure]().parameters
    if structure == "backlash":
        head = [p["m_left"], p["m_left"] * p["c_left"], p["m_right"], p["m_right"] * p["c_right"]]
        return head + p["b"][1:] + p["a"]
    theta: list[float] = []
    if "f" in p:
        theta += p["f"][: r1 + 1] + p["p"][: r1 + 1] + p["b"][1:]
    else:
        theta += p["b"]
    theta += p["a"]
    if "q" in p:
        theta += p["q"][1:r2]
    return theta
