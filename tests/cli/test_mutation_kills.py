"""The registry's declarations and value parsers, and the flags generated from them,
pinned against hand-written expectations (gaps found by mutation testing, see
docs/testing.md). The declarations run at import time, so only a test that reads
them back catches a wrong one."""

# Annotations stay text here, as in the CLI's modules: with_fit_options must evaluate them.
from __future__ import annotations

import inspect

import numpy as np
import pytest

from blockid.cli._options import cli_options, structures_help, with_fit_options
from blockid.errors import ParameterError
from blockid.fitting.registry import OPTIONS, STRUCTURES, Option, parse_orders


def _convert(kind, value, **bounds):
    return Option("x", kind, "help", **bounds).convert(value)


# ----------------------------------------------------------------------------- values
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


# ----------------------------------------------------------------------------- declarations
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
    arx = STRUCTURES["arx"]
    assert {m.target for m in arx.methods} == {"blockid.fitting.arx:fit_arx"}
    assert all(m.passes == ("method",) for m in arx.methods)
    assert [m.recursive for m in arx.methods] == [False, True, True, True]
    for name in ("hammerstein", "wiener", "hammerstein-wiener"):
        se, kt = STRUCTURES[name].methods
        assert se.target == "blockid.fitting.simulation_error:fit_simulation_error"
        assert se.passes == ("structure",) and not se.recursive
        assert se.help == "minimise the free-run simulation error (converges; the default)"
        assert kt.target == "blockid.fitting.key_term:fit_key_term_rls"
        assert kt.passes == ("structure",) and kt.recursive


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


# ----------------------------------------------------------------------------- flags
def test_cli_options_are_the_used_options_less_the_internal_ones():
    names = [o.name for o in cli_options()]
    assert "record_history" not in names
    assert names == [n for n in OPTIONS if n != "record_history"]  # every other option is used


def test_with_fit_options_puts_the_flags_after_method_as_keywords():
    def command(data: str, method: str | None = None, output: str = "x", **options):
        return options

    signature = inspect.signature(with_fit_options(command))
    names = list(signature.parameters)
    flags = [o.name for o in cli_options()]
    assert names == ["data", "method", *flags, "output"]
    p = signature.parameters
    assert p["data"].annotation is str  # evaluated, not the text "str"
    assert p["output"].kind is inspect.Parameter.KEYWORD_ONLY
    assert p["data"].kind is inspect.Parameter.POSITIONAL_OR_KEYWORD
    for name in flags:
        assert p[name].kind is inspect.Parameter.KEYWORD_ONLY
        assert p[name].default is None
    info = p["passes"].annotation.__metadata__[0]
    assert info.metavar == "N" and info.show_default is False
    assert info.help == OPTIONS["passes"].help
    assert p["tol"].annotation.__metadata__[0].metavar == "X"
    assert p["forgetting"].annotation.__metadata__[0].metavar == "SCHEDULE"
    assert p["input_block"].annotation.__metadata__[0].metavar == "KIND"
    assert p["initial_parameters"].annotation.__metadata__[0].metavar == "X[,X..]"
    assert p["center"].annotation.__metadata__[0].show_default is False


def test_with_fit_options_without_method_appends_the_flags():
    def command(data: str, **options):
        return options

    names = list(inspect.signature(with_fit_options(command)).parameters)
    assert names == ["data", *[o.name for o in cli_options()]]


def test_structures_help_lists_each_structure_and_its_methods():
    text = structures_help(width=200)
    lines = text.split("\n")
    assert lines[:2] == ["\b", "Structures, and their methods (the first is the default):"]
    for s in STRUCTURES.values():
        assert f"{s.name}: {s.help}" in lines
        assert "    " + ", ".join(s.method_names) in lines
    narrow = structures_help(width=30).split("\n")
    assert len(narrow) > len(lines)
    # help wrapped with an indent; the methods line starts indented
    assert narrow[2:6] == [
        "arx: linear ARX, multi-input",
        "    multi-output (MATLAB",
        "    na/nb/nk)",
        "    batch, rls, aw-rls,",
    ]
    for line in narrow[2:]:
        assert len(line) <= 30


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


def test_boolean_flags_carry_their_declared_help():
    def command(data: str, **options):
        return options

    p = inspect.signature(with_fit_options(command)).parameters
    bools = [o.name for o in cli_options() if o.kind == "bool"]
    assert "center" in bools
    for name in bools:
        info = p[name].annotation.__metadata__[0]
        assert info.help == OPTIONS[name].help and info.help


def test_key_term_method_help_is_declared():
    for name in ("hammerstein", "wiener", "hammerstein-wiener"):
        method = STRUCTURES[name].method("key-term-rls")
        assert method.help == "paper B's key-term RLS with internal-variable estimation (B4, B5)"


def test_real_strips_text_as_str_strip_does():
    # str.strip() also removes the ASCII separators \x1c-\x1f, which float() refuses
    assert _convert("real", "\x1f2.5\x1c") == 2.5
    assert _convert("real", "\t 0.5\n", low=0.0) == 0.5


def _option_info(option):
    import typing

    from blockid.cli._options import _parameter

    parameter = _parameter(option)
    return parameter, typing.get_args(parameter.annotation)


def test_generated_flags_carry_their_names_and_metavars():
    parameter, (kind, info) = _option_info(OPTIONS["normalize"])
    assert parameter.name == "normalize"
    assert kind == bool | None
    assert info.default == "--normalize/--no-normalize"
    parameter, (kind, info) = _option_info(OPTIONS["max_nfev"])
    assert kind == str | None
    assert info.default == "--max-nfev"
    assert info.metavar == "N"
    # a kind without a metavar of its own falls back to VALUE
    _, (_, info) = _option_info(Option("some_list", "numbers", "help"))
    assert info.default == "--some-list"
    assert info.metavar == "VALUE"


def test_a_boolean_flag_and_its_negation_reach_the_command():
    import typer
    from typer.testing import CliRunner

    app = typer.Typer()

    @app.command()
    @with_fit_options
    def fit(method: str = "x", **options) -> None:
        print(repr(options["normalize"]), repr(options["max_nfev"]))

    runner = CliRunner()
    assert runner.invoke(app, ["--no-normalize"]).output == "False None\n"
    assert runner.invoke(app, ["--normalize", "--max-nfev", "7"]).output == "True '7'\n"
    assert runner.invoke(app, []).output == "None None\n"


def test_count_refuses_text_that_is_not_a_whole_number_with_its_message():
    with pytest.raises(ParameterError, match=r"^x must be a whole number >= 1, got 'abc'$"):
        _convert("count", "abc", low=1)


def test_integrator_fit_passes_refine_options_and_times_the_start():
    from blockid.blocks import Integrator, LinearBlock
    from blockid.data import Dataset
    from blockid.fitting import fit_model
    from blockid.models import ChainModel

    rng = np.random.default_rng(0)
    u = 0.2 + rng.uniform(-1, 1, 200)
    plant = [LinearBlock(2, 2, 1, [-1.2, 0.35], [1.0, 0.4]), Integrator(1)]
    y = ChainModel("u", "y", plant).simulate(u)[:, 0] + 0.01 * rng.standard_normal(200)
    data = Dataset.from_arrays(u, y, ["u"], ["y"], sampling_time=0.01)
    fit = fit_model(data, "output-error", na=2, nb=2, nk=1, integrator=1, max_nfev=1)
    assert fit.settings["max_nfev"] == 1
    assert fit.settings["stop_reason"] == "max_nfev reached"
    assert fit.settings["integrator"] == 1
    assert fit.model.sampling_time == 0.01
    assert set(fit.history) == {"fit_mse", "tail_mse", "seconds", "initial_seconds"}
    assert isinstance(fit.history["initial_seconds"], float)
    assert 0.0 < fit.history["initial_seconds"] < 60.0


def test_an_undeclared_option_kind_is_an_internal_error_naming_it():
    with pytest.raises(AssertionError, match=r"^unknown option kind 'nope'$"):
        _convert("nope", 1)
