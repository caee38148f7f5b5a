"""The registry of structures, methods and options (fitting/registry.py): option values
checked once, against the same ranges as the estimators that use them."""

import inspect

import pytest

from blockid.errors import ParameterError
from blockid.fitting.registry import STRUCTURES, resolve_options


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


def test_an_unknown_structure_lists_the_known_ones():
    from blockid.fitting.registry import get_structure

    with pytest.raises(
        ParameterError, match=r"structure='nope' is unknown; choose one of arx, hammerstein, "
    ):
        get_structure("nope")


def test_key_term_method_help_is_declared():
    for name in ("hammerstein", "wiener", "hammerstein-wiener"):
        method = STRUCTURES[name].method("key-term-rls")
        assert method.help == "paper B's key-term RLS with internal-variable estimation (B4, B5)"
