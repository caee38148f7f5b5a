"""Option declarations and their conversion (fitting/options.py): every value kind's
refusals with their exact messages, the order matrices, and one range per option."""

import numpy as np
import pytest

from blockid.errors import ParameterError
from blockid.estimators import AdaptiveWeightedRLS
from blockid.fitting.options import OPTIONS, Option, parse_orders


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


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
def _convert(kind, value, **bounds):
    return Option("x", kind, "help", **bounds).convert(value)


@pytest.mark.parametrize(
    ("value", "expected"),
    [("2.5", 2.5), (" 3 ", 3.0), (4, 4.0), (np.float64(0.25), 0.25), ("1e-3", 1e-3)],
)
def test_real_accepts_text_and_numbers(value, expected):
    assert _convert("real", value) == expected


@pytest.mark.parametrize("value", ["nan", float("nan"), True, "abc", [1.0]])
def test_real_refuses_what_is_not_a_number(value):
    with pytest.raises(ParameterError, match="x must be a number, got"):
        _convert("real", value)


def test_real_bounds_are_closed_unless_open_low():
    assert _convert("real", "0", low=0.0) == 0.0
    with pytest.raises(ParameterError, match=r"^x must be >= 0, got -1$"):
        _convert("real", "-1", low=0.0)
    with pytest.raises(ParameterError, match=r"^x must be > 0, got 0$"):
        _convert("real", "0", low=0.0, open_low=True)
    assert _convert("real", "0.5", low=0.0, open_low=True) == 0.5
    assert _convert("real", "0.9", low=0.0, high=0.9) == 0.9
    with pytest.raises(ParameterError, match=r"^x must be <= 0.9, got 0.91$"):
        _convert("real", "0.91", low=0.0, high=0.9)
    assert _convert("real", "1e300") == 1e300  # no bounds declared: anything finite or not


@pytest.mark.parametrize("text", ["true", "TRUE", "Yes", "1", "on", "ON"])
def test_boolean_text_true(text):
    assert _convert("bool", text) is True


@pytest.mark.parametrize("text", ["false", "No", "0", "off", "OFF"])
def test_boolean_text_false(text):
    assert _convert("bool", text) is False


def test_boolean_values_and_refusals():
    assert _convert("bool", True) is True
    with pytest.raises(ParameterError, match=r"^x must be true or false, got 'maybe'$"):
        _convert("bool", "maybe")
    with pytest.raises(ParameterError, match=r"^x must be True or False, got 1$"):
        _convert("bool", 1)


def test_numbers_parse_one_or_many():
    assert _convert("numbers", "0.5") == 0.5
    assert _convert("numbers", "0.5, 1,2") == [0.5, 1.0, 2.0]
    assert _convert("numbers", "3,") == 3.0
    assert _convert("numbers", [1, 2]) == [1, 2]  # Python values pass through
    with pytest.raises(
        ParameterError, match=r"x must be a number or comma-separated numbers, got 'a,b'"
    ):
        _convert("numbers", "a,b")
    with pytest.raises(
        ParameterError, match=r"x must be a number or comma-separated numbers, got ''"
    ):
        _convert("numbers", ",")


def test_count_takes_numpy_integers_and_its_lower_bound():
    assert _convert("count", np.int64(3), low=1) == 3
    assert _convert("count", 1, low=1) == 1
    assert _convert("count", "2", low=1) == 2
    for bad in (True, 2.0, 0):
        with pytest.raises(ParameterError, match=r"x must be a whole number >= 1"):
            _convert("count", bad, low=1)


def test_parse_orders_text_forms():
    assert parse_orders("2", "na") == 2
    assert parse_orders("2,1;1,2", "na") == [[2, 1], [1, 2]]
    assert parse_orders("2 1;1 2", "na") == [[2, 1], [1, 2]]
    assert parse_orders("2;3", "na") == [[2], [3]]
    assert parse_orders("2,1", "na") == [[2, 1]]
    with pytest.raises(ParameterError, match=r"^na must be a whole number >= 0, got True$"):
        parse_orders(True, "na")
    with pytest.raises(
        ParameterError, match=r"na='x': give a whole number, or a matrix .* e\.g\. 2 or '2,1;1,2'$"
    ):
        parse_orders("x", "na")


def test_count_without_a_declared_lower_bound_starts_at_zero():
    assert _convert("count", "0") == 0
    with pytest.raises(ParameterError, match=r"^x must be a whole number >= 0, got -1$"):
        _convert("count", "-1")


def test_block_option_refusals_name_the_option():
    option = Option("input_block", "block", "help")
    with pytest.raises(
        ParameterError,
        match=r"^input_block must be a block \(e\.g\. DeadZone\(0, 0\)\) or its name, such as 'dead-zone' or 'piecewise-linear:knots=7', got 3$",
    ):
        option.convert(3)
    with pytest.raises(ParameterError, match=r"^input_block: "):
        option.convert("no-such-block")


def test_real_strips_text_as_str_strip_does():
    # str.strip() also removes the ASCII separators \x1c-\x1f, which float() refuses
    assert _convert("real", "\x1f2.5\x1c") == 2.5
    assert _convert("real", "\t 0.5\n", low=0.0) == 0.5


def test_count_refuses_text_that_is_not_a_whole_number_with_its_message():
    with pytest.raises(ParameterError, match=r"^x must be a whole number >= 1, got 'abc'$"):
        _convert("count", "abc", low=1)


def test_an_undeclared_option_kind_is_an_internal_error_naming_it():
    with pytest.raises(AssertionError, match=r"^unknown option kind 'nope'$"):
        _convert("nope", 1)


#: Ranges checked outside the registry on purpose, each a minimum of its own (not the
#: option's range restated): orders a structure needs (a backlash needs a delay; every
#: structure with an input block at least one input coefficient), key-term RLS needing a
#: nonlinear output block (r2 >= 2), and a block's or a model's own constructor whose
#: argument only shares a name with an option (``degree`` of a polynomial block).
_OWN_MINIMA = {
    ("fitting/backlash.py", "na"), ("fitting/backlash.py", "nb"), ("fitting/backlash.py", "nk"),
    ("fitting/key_term.py", "na"), ("fitting/key_term.py", "nb"), ("fitting/key_term.py", "nk"),
    ("fitting/key_term.py", "r2"), ("fitting/online_paper.py", "na"), ("fitting/online_paper.py", "nb"),
    ("fitting/online_paper.py", "nk"), ("fitting/online_paper.py", "r2"), ("fitting/initial.py", "r2"),
    ("blocks/polynomial.py", "degree"), ("models/state_space.py", "degree"),
    ("fitting/feedback.py", "feedback_block"), ("fitting/recursive.py", "initial_parameters"),
    # nb >= 1 of the block model on an ARX core (the inputs must enter; an ARX allows 0)
    ("fitting/block_arx.py", "nb"),
}  # fmt: skip


def test_no_fitter_restates_an_options_range():
    """Each option's range is written once, in its declaration (``OPTIONS``); a fitter
    called directly checks its arguments with ``checked(name, value)``, never with a range
    of its own. Seen failing on the contradictions issue 19 found: the backlash AW-RLS
    refused ``eps1 = 0``, which the registry and the ARX AW-RLS allow (lambda = eps1 s +
    eps2 > 0), and the simulation-error fit allowed ``tail_fraction`` up to 1, the registry
    up to 0.9."""
    import re
    from pathlib import Path

    import blockid

    src = Path(blockid.__file__).parent
    found = set()
    for path in src.rglob("*.py"):
        rel = path.relative_to(src).as_posix()
        if rel == "fitting/registry.py":
            continue
        text = path.read_text()
        for name in OPTIONS:
            pattern = (
                rf'["\']{name}(=\{{[^}}]*\}})? must be|(int_at_least|positive_number)\("{name}"'
            )
            if re.search(pattern, text):
                found.add((rel, name))
    assert found - _OWN_MINIMA == set(), sorted(found - _OWN_MINIMA)


def test_a_ragged_order_matrix_is_refused_naming_its_rows():
    """``--na '1,1;1'`` once ended in a NumPy traceback (inhomogeneous shape)."""
    from blockid.errors import ParameterError
    from blockid.fitting.registry import parse_orders

    with pytest.raises(ParameterError, match="as many entries .* got rows of 2, 1"):
        parse_orders("1,1;1", "na")
    assert parse_orders("1,1;2,0", "na") == [[1, 1], [2, 0]]
