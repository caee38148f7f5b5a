"""The search space of identify, generated from the registry and the block families."""

from typing import ClassVar

import numpy as np

from blockid.blocks.base import BLOCK_TYPES, StaticBlock
from blockid.data import Dataset
from blockid.fitting.registry import STRUCTURES, searched_structures
from blockid.workflows.search_space import (
    Candidate,
    grown,
    integrating_candidates,
    order_grid,
    output_error_orders,
    structure_candidates,
    unique,
)

FAST = {"max_nfev": 5, "tail_fraction": 0.0}


def _data(u_mean=0.0, y_mean=0.0, n=400):
    rng = np.random.default_rng(0)
    u = u_mean + rng.uniform(-1, 1, n)
    return Dataset.from_arrays(u, y_mean + np.convolve(u, [0.5, 0.3], "same"), ["u"], ["y"])


def test_the_searched_structures_are_the_registrys_ranked_ones():
    names = searched_structures()
    assert names[0] == "arx"
    assert set(names) == {s.name for s in STRUCTURES.values() if s.search_rank is not None}
    ranks = [STRUCTURES[n].search_rank for n in names]
    assert ranks == sorted(ranks)


def test_every_block_family_fills_every_slot_it_declares():
    out = structure_candidates(["hammerstein", "wiener", "feedback"], [(2, 2, 1)], _data(), FAST)
    for structure, option, role in [("hammerstein", "input_block", "input"),
                                    ("wiener", "output_block", "output"),
                                    ("feedback", "feedback_block", "feedback")]:  # fmt: skip
        tried = {c.options[option] for c in out if c.structure == structure}
        declared = {cls.search_specs[role] for cls in BLOCK_TYPES.values()
                    if role in cls.search_specs}  # fmt: skip
        assert tried == declared, structure
    assert {"dead-zone", "saturation", "piecewise-linear-free:knots=5", "polynomial:degree=3"} <= {
        c.options["output_block"] for c in out if c.structure == "wiener"
    }


def test_a_new_block_family_is_searched_without_editing_the_search():
    class Cube(StaticBlock):
        kind = "test-cube"
        search_specs: ClassVar[dict[str, str]] = {"input": "test-cube"}

        def __init__(self, gain: float = 1.0) -> None:
            self.gain = float(gain)

        @classmethod
        def template(cls):
            return cls(1.0)

        @property
        def parameters(self):
            return {"gain": self.gain}

        def __call__(self, u):
            return self.gain * np.asarray(u) ** 3

    try:
        out = structure_candidates(["hammerstein"], [(2, 2, 1)], _data(), FAST)
        assert any(c.options.get("input_block") == "test-cube" for c in out)
    finally:
        del BLOCK_TYPES["test-cube"]


def test_two_slots_vary_one_at_a_time_around_the_defaults():
    out = [c for c in structure_candidates(["hammerstein-wiener"], [(2, 2, 1)], _data(), FAST)]
    pairs = [(c.options["input_block"], c.options["output_block"]) for c in out]
    assert len(pairs) == len(set(pairs))
    inputs = {a for a, _ in pairs}
    outputs = {b for _, b in pairs}
    assert all(b == "polynomial:degree=3" for a, b in pairs if a != "polynomial:degree=3")
    assert len(inputs) >= 5 and len(outputs) >= 4


def test_centring_is_decided_from_the_data():
    """Blocks anchored at their signal's zero are uncentred when it takes both signs."""
    both = structure_candidates(["hammerstein", "wiener"], [(2, 2, 1)], _data(), FAST)
    positive = structure_candidates(["hammerstein", "wiener"], [(2, 2, 1)],
                                    _data(u_mean=6.0, y_mean=6.0), FAST)  # fmt: skip

    def centre(cands, structure, option, spec):
        (c,) = [c for c in cands if c.structure == structure and c.options[option] == spec]
        return c.options["center"]

    assert centre(both, "hammerstein", "input_block", "dead-zone") is False
    assert centre(positive, "hammerstein", "input_block", "dead-zone") is True
    assert centre(both, "wiener", "output_block", "saturation") is False
    assert centre(positive, "wiener", "output_block", "saturation") is True
    assert centre(both, "hammerstein", "input_block", "polynomial:degree=3") is True


def test_the_order_grids():
    grid = order_grid((2, 2, 1), [1, 3], 3)
    orders = [(c.options["na"], c.options["nb"], c.options["nk"]) for c in grid]
    assert orders[0][:2] in {(1, 1), (1, 2), (2, 1), (2, 2), (2, 3), (3, 1)}
    assert len(orders) == len(set(orders)) == 2 * (2 + 3 + 4)
    oe = output_error_orders((4, 5, 2), 4, FAST)
    assert [(c.options["na"], c.options["nb"], c.options["nk"]) for c in oe] == [
        (3, 4, 2), (4, 5, 2), (3, 4, 1), (4, 5, 1), (3, 4, 0), (4, 5, 0),
    ]  # fmt: skip
    assert all(c.structure == "output-error" and c.options["max_nfev"] == 5 for c in oe)


def test_integrating_candidates_take_poles_and_a_delay_off_the_linear_block():
    out = integrating_candidates(["arx", "output-error", "hammerstein", "wiener", "backlash"],
                                 [(3, 2, 8)], _data(), FAST, 2)  # fmt: skip
    labels = [(c.structure, c.options["integrator"], c.options["na"], c.options["nk"]) for c in out]
    assert labels == [
        ("output-error", 1, 2, 7), ("hammerstein", 1, 2, 7), ("backlash", 1, 2, 7),
        ("output-error", 2, 1, 7), ("hammerstein", 2, 1, 7), ("backlash", 2, 1, 7),
    ]  # fmt: skip
    assert integrating_candidates(["output-error"], [(3, 2, 8)], _data(), FAST, 0) == []


def test_growth_raises_one_size_at_a_time_and_stops_at_the_limit():
    c = Candidate("hammerstein-wiener", {"na": 2, "input_block": "piecewise-linear-free:knots=5",
                                         "output_block": "polynomial:degree=3", "r2": 7})  # fmt: skip
    out = grown(c)
    assert [o.options for o in out] == [
        {**c.options, "input_block": "piecewise-linear-free:knots=7"},
        {**c.options, "output_block": "polynomial:degree=5"},
        {**c.options, "r2": 9},
    ]
    assert grown(Candidate("wiener", {"r2": 9, "output_block": "dead-zone"})) == []


def test_a_state_space_degree_grows_from_the_degree_below():
    c = Candidate("polynomial-state-space", {"nx": 2, "degree": 2, "monomials": "full"})
    (up,) = grown(c)
    assert up.options == {**c.options, "degree": 3, "start_degree": 2}
    (further,) = grown(up)  # the climb starts where the first rung was
    assert further.options == {**c.options, "degree": 4, "start_degree": 2}


def test_candidates_are_told_apart_by_every_option_and_kept_once():
    a = Candidate("arx", {"na": 1, "nb": 1})
    b = Candidate("arx", {"nb": 1, "na": 1})
    c = a.with_options(max_nfev=3)
    assert a == b and hash(a) == hash(b) and a != c and a.model_key == c.model_key
    assert unique([a, b, c, a]) == [a, c]
    assert c.label == "arx(na=1, nb=1)"


def test_block_state_candidates_cover_the_plans_then_each_loop_family():
    from blockid.workflows.search_space import block_state_candidates

    plans = [("polynomial:degree=3", None)]
    found = block_state_candidates(
        ["polynomial-state-space", "block-state-space"], [2, 3], plans, {"max_nfev": 5},
        ("saturation", "dead-zone"),
    )  # fmt: skip
    assert [(c.options["nx"], c.options.get("input_block"), c.options.get("loop_block"))
            for c in found] == [
        (2, "polynomial:degree=3", None), (2, None, "saturation"), (2, None, "dead-zone"),
        (3, "polynomial:degree=3", None), (3, None, "saturation"), (3, None, "dead-zone"),
    ]  # fmt: skip
    assert all(c.structure == "block-state-space" for c in found)
    only_loops = block_state_candidates(["block-state-space"], [2], (), {}, ("saturation",))
    assert [c.options for c in only_loops] == [{"nx": 2, "loop_block": "saturation"}]
