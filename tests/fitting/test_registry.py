"""The registry of structures, methods and options (fitting/registry.py): option values
checked once, against the same ranges as the estimators that use them."""

import numpy as np
import pytest

from blockid.errors import ParameterError
from blockid.estimators import AdaptiveWeightedRLS
from blockid.fitting.registry import OPTIONS, parse_orders, resolve_options


@pytest.mark.parametrize(
    ("name", "value", "accepted"),
    [("eps1", 0.0, True), ("eps1", -1e-9, False), ("eps2", 0.0, False), ("eps2", 1e-9, True)],
)
def test_aw_rls_weights_have_the_estimators_ranges(name, value, accepted):
    """The weight is lambda = eps1 s + eps2 (A8): eps1 = 0 is a constant weight, eps2 = 0
    an unbounded one as P shrinks. The registry had it the other way round, so
    --eps1 0 was refused and --eps2 0 passed it to fail in the estimator."""
    params = {"eps1": 1.0, "eps2": 0.1, name: value}

    def estimator_accepts() -> bool:
        try:
            AdaptiveWeightedRLS(**params).fit(np.eye(3), np.ones(3))
        except (ValueError, ParameterError):
            return False
        return True

    def registry_accepts() -> bool:
        try:
            OPTIONS[name].convert(str(value))
        except ParameterError:
            return False
        return True

    assert registry_accepts() is accepted
    assert estimator_accepts() is accepted


def test_orders_text_below_zero_is_refused_with_the_name():
    with pytest.raises(ParameterError, match="na must hold whole numbers >= 0"):
        parse_orders("-1", "na")
    assert parse_orders("2,1;1,2", "na") == [[2, 1], [1, 2]]


def test_a_light_check_leaves_block_values_to_the_fit_but_checks_everything_else():
    """The command line checks options before NumPy is imported (light=True): a block
    name is passed through as text, every other value is converted and checked."""
    _, method, typed = resolve_options(
        "hammerstein", None, {"input_block": "dead-zone", "na": "2"}, light=True
    )
    assert typed == {"input_block": "dead-zone", "na": 2} and method == "simulation-error"
    with pytest.raises(ParameterError, match="not used by hammerstein"):
        resolve_options("hammerstein", None, {"eps1": "1"}, light=True)
    with pytest.raises(ParameterError, match="unknown"):
        resolve_options("nope", None, {}, light=True)
