"""The registry of structures, methods and options (fitting/registry.py): option values
checked once, against the same ranges as the estimators that use them."""

import inspect

import numpy as np
import pytest

from blockid.errors import ParameterError
from blockid.estimators import AdaptiveWeightedRLS
from blockid.fitting.registry import OPTIONS, STRUCTURES, Option, parse_orders, resolve_options


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


#: The table in the registry's docstring, written out: methods (default first).
METHODS = {
    "arx": ("batch", "rls", "aw-rls", "hierarchical-rls"),
    "hammerstein": ("simulation-error", "key-term-rls"),
    "wiener": ("simulation-error", "key-term-rls"),
    "hammerstein-wiener": ("simulation-error", "key-term-rls"),
    "backlash": ("simulation-error", "aw-rls"),
}


def test_structures_and_their_methods_are_the_documented_table():
    assert {name: STRUCTURES[name].method_names for name in METHODS} == METHODS
    for s in STRUCTURES.values():
        assert s.method_names == tuple(m.name for m in s.methods)
        if s.name in METHODS:
            assert s.default_method.name == METHODS[s.name][0]


def test_every_method_resolves_to_its_fitter_with_the_keywords_it_takes():
    for s in STRUCTURES.values():
        for m in s.methods:
            function = m.function()
            assert callable(function)
            parameters = inspect.signature(function).parameters
            for keyword in m.passes:
                assert keyword in parameters
    from blockid.fitting.arx import fit_arx
    from blockid.fitting.key_term import fit_key_term_rls
    from blockid.fitting.simulation_error import fit_simulation_error

    arx = STRUCTURES["arx"]
    assert {m.function() for m in arx.methods} == {fit_arx}
    assert all(m.passes == ("method",) for m in arx.methods)
    assert [m.recursive for m in arx.methods] == [False, True, True, True]
    for name in ("hammerstein", "wiener", "hammerstein-wiener"):
        se, kt = STRUCTURES[name].methods
        assert se.function() is fit_simulation_error
        assert se.passes == ("structure",) and not se.recursive
        assert se.help == "minimise the free-run simulation error (converges; the default)"
        assert kt.function() is fit_key_term_rls
        assert kt.passes == ("structure",) and kt.recursive


def test_every_structure_holds_its_model_class_loader_not_a_string():
    """Issue 33 item 5 (no code in strings): the registry named its model classes as
    ``"module:Class"`` text, resolved by importlib, which refactoring tools and the import
    graph cannot see. They are loaders now (fitting/_targets.py), each returning the very
    class it is named after."""
    import dataclasses
    import re

    from blockid.fitting import _targets
    from blockid.models.base import Model

    dotted = re.compile(r"^[A-Za-z_][\w.]*:[A-Za-z_]\w*$")
    for s in STRUCTURES.values():
        for f in dataclasses.fields(s):
            value = getattr(s, f.name)
            assert not (isinstance(value, str) and dotted.match(value)), (s.name, f.name)
        assert callable(s.model_loader) and not isinstance(s.model_loader, str)
        assert s.model_loader.__module__ == _targets.__name__
        cls = s.model_class()
        assert isinstance(cls, type) and issubclass(cls, Model)
        assert s.model_loader.__name__ == cls.__name__  # named after what it returns
        assert cls.__module__.startswith("blockid.models.")


def test_the_registry_writes_no_code_as_text():
    """Issue 33 item 5: no ``"package.module:name"`` literal in the registry's source,
    neither a model class nor an estimator. Every method holds a loader of
    fitting/_targets.py named after the fitter it returns (importing the registry still
    imports none: test_importing_the_registry_loads_no_model_or_estimator)."""
    import ast
    import re

    from blockid.fitting import _targets, registry

    tree = ast.parse(inspect.getsource(registry))
    dotted = re.compile(r"^\s*[A-Za-z_]\w*(\.\w+)+:\w+\s*$")
    texts = [n.value for n in ast.walk(tree) if isinstance(n, ast.Constant)]
    assert not [t for t in texts if isinstance(t, str) and dotted.match(t)]
    for s in STRUCTURES.values():
        for m in s.methods:
            assert callable(m.loader) and m.loader.__module__ == _targets.__name__
            function = m.function()
            assert m.loader.__name__ == function.__name__  # named after what it returns
            assert function.__module__.startswith("blockid.fitting.")


def test_importing_the_registry_loads_no_model_or_estimator():
    """The loaders keep the registry cheap to import (the command line reads it before
    NumPy): no model, fitting module or numerical library is imported with it."""
    import subprocess
    import sys

    code = (
        "import sys, blockid.fitting.registry\n"
        "loaded = [m for m in sys.modules if m.split('.')[0] in "
        "('numpy', 'scipy', 'numba', 'pandas') or m.startswith('blockid.models')\n"
        "          or m.startswith('blockid.fitting.') and m not in "
        "('blockid.fitting.registry', 'blockid.fitting.options', 'blockid.fitting._targets')]\n"
        "assert not loaded, loaded\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_method_options_by_declaration():
    s = STRUCTURES["hammerstein-wiener"]
    se, kt = s.methods
    assert se.options == (
        "r1",
        "r2",
        "input_block",
        "output_block",
        "max_nfev",
        "tail_fraction",
        "patience",
        "ftol",
        "xtol",
        "gtol",
    )
    assert kt.options == (
        "r1",
        "r2",
        "forgetting",
        "passes",
        "tol",
        "initial_covariance",
        "initial_parameters",
        "normalize",
        "record_history",
    )
    arx = ("na", "nb", "nk", "center", "allow_unstable")
    assert STRUCTURES["arx"].method("batch").options[:5] == arx
    rls = STRUCTURES["arx"].method("rls").options
    assert rls[:5] == arx
    assert {
        "forgetting",
        "initial_covariance",
        "passes",
        "convergence_check",
        "max_mse_ratio",
    } <= set(rls)
    aw = STRUCTURES["backlash"].accepted("aw-rls")
    assert aw[:5] == ("na", "nb", "nk", "center", "refine")
    assert tuple(o for o in aw[5:] if o != "standard_errors") == (
        "eps1",
        "eps2",
        "passes",
        "tol",
        "initial_covariance",
        "initial_parameters",
        "normalize",
        "record_history",
    )


def test_count_without_a_declared_lower_bound_starts_at_zero():
    assert _convert("count", "0") == 0
    with pytest.raises(ParameterError, match=r"^x must be a whole number >= 0, got -1$"):
        _convert("count", "-1")


def test_an_unknown_structure_lists_the_known_ones():
    from blockid.fitting.registry import get_structure

    with pytest.raises(
        ParameterError, match=r"structure='nope' is unknown; choose one of arx, hammerstein, "
    ):
        get_structure("nope")


def test_block_option_refusals_name_the_option():
    option = Option("input_block", "block", "help")
    with pytest.raises(
        ParameterError,
        match=r"^input_block must be a block \(e\.g\. DeadZone\(0, 0\)\) or its name, such as 'dead-zone' or 'piecewise-linear:knots=7', got 3$",
    ):
        option.convert(3)
    with pytest.raises(ParameterError, match=r"^input_block: "):
        option.convert("no-such-block")


def test_key_term_method_help_is_declared():
    for name in ("hammerstein", "wiener", "hammerstein-wiener"):
        method = STRUCTURES[name].method("key-term-rls")
        assert method.help == "paper B's key-term RLS with internal-variable estimation (B4, B5)"


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
