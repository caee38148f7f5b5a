"""compare_structures: the default structures follow the data's shape, and a chain
that cannot take several signals says which structures can."""

from __future__ import annotations

import pytest

from blockid.errors import BlockidError
from blockid.workflows import compare_structures

from reference import fourth_order_arx_halves, mimo_hw_record


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


def test_each_model_gets_its_residual_tests_and_an_under_modelled_one_fails():
    est, val = fourth_order_arx_halves()
    short = compare_structures(est, val, ["arx"], options={"na": 1, "nb": 2, "nk": 1})
    right = compare_structures(est, val, ["arx"], options={"na": 4, "nb": 2, "nk": 1})
    poor = short.to_dict()["models"][0]["residuals"]
    good = right.to_dict()["models"][0]["residuals"]
    assert poor["passed"] is False and poor["verdict"].startswith("fails")
    assert not poor["whiteness"]["y"]["white"] and poor["whiteness"]["y"]["p_value"] < 1e-6
    assert good["passed"] is True and good["verdict"].startswith("passes: white")
    assert good["independence"]["u->y"]["independent"] and good["whiteness"]["y"]["white"]
    assert good["mode"] == "one-step" and good["noise_model"] is True
    assert len(good["autocorrelation"]["y"]) == 26 and good["n_samples"] == 996
