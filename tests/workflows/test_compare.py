"""compare_structures: the default structures follow the data's shape, and a chain
that cannot take several signals says which structures can."""

from __future__ import annotations

import pytest

from blockid.errors import BlockidError
from blockid.workflows import compare_structures

from reference import mimo_hw_record


def test_several_signals_get_the_state_spaces_and_arx_by_default():
    data, _ = mimo_hw_record(1200)
    est, val = data.select(0, 800), data.select(800, 1200)
    result = compare_structures(est, val, options={"na": 2, "nb": 2, "nk": 1})
    assert [m.structure for m in result.models] == [
        "arx", "state-space", "polynomial-state-space",
    ]  # fmt: skip
    fitted = [m for m in result.models if m.error is None]
    assert {m.structure for m in fitted} >= {"state-space", "polynomial-state-space"}
    with pytest.raises(BlockidError, match="arx, state-space, polynomial-state-space"):
        compare_structures(est, val, ["arx", "wiener"], options={"na": 2, "nb": 2, "nk": 1})
