"""The estimator flags come from the registry and reach the library as typed.

Generated from :data:`blockid.fitting.registry.OPTIONS`: an option added there (and to a
method) without reaching ``fit`` and ``compare`` fails a test here.
"""

# Annotations stay text here, as in the CLI's modules: with_fit_options must evaluate them.
from __future__ import annotations

import inspect
import json
import re

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import blockid.fitting
import blockid.workflows
from blockid.blocks import DeadZone, Polynomial
from blockid.cli._options import INTERNAL, cli_options, structures_help, with_fit_options
from blockid.cli.main import app
from blockid.errors import ParameterError
from blockid.fitting.registry import OPTIONS, STRUCTURES, Option, option_flag
from blockid.models import Hammerstein, Wiener, load_model

runner = CliRunner()

FLAGGED = [name for name in OPTIONS if name not in INTERNAL]


def _text(name: str) -> object:
    """A value of the option that is not its default, as the user types it."""
    option = OPTIONS[name]
    low = 0.0 if option.low is None else option.low
    if option.kind == "choice":
        return option.choices[-1]
    return {
        "orders": "2",
        "count": str(int(low) + 2),
        "real": str(low + 0.5 if option.high is None else (low + option.high) / 2),
        "forgetting": "0.98:200,1",
        "numbers": "0.5,1",
        "block": "polynomial:degree=2",
        "bool": True,
    }[option.kind]


def _args(name: str, value: object) -> list[str]:
    flag = option_flag(name)
    if value is True:
        return [flag]
    if value is False:
        return [f"--no-{flag[2:]}"]
    return [flag, str(value)]


def _where(name: str) -> tuple[str, str]:
    """A structure and method that take the option."""
    for structure in STRUCTURES.values():
        for method in structure.method_names:
            if name in structure.accepted(method):
                return structure.name, method
    raise AssertionError(f"no structure takes {name}")


@pytest.fixture
def csv(tmp_path):
    path = tmp_path / "d.csv"
    rng = np.random.default_rng(0)
    pd.DataFrame({"u": rng.standard_normal(60), "y": rng.standard_normal(60)}).to_csv(
        path, index=False
    )
    return path


@pytest.fixture
def captured(monkeypatch):
    """What the command hands to the library; the library call then stops the command."""
    seen = {}

    def fake(*args, **kwargs):
        seen.update(args=args, kwargs=kwargs)
        raise ParameterError("captured")

    monkeypatch.setattr(blockid.fitting, "fit_model", fake)
    monkeypatch.setattr(blockid.workflows, "compare_structures", fake)
    return seen


def test_every_flagged_option_is_used_and_the_internal_ones_are_options():
    assert set(INTERNAL) <= set(OPTIONS)
    for name in FLAGGED:
        _where(name)


@pytest.mark.parametrize(
    ("name", "value"),
    [(n, _text(n)) for n in FLAGGED] + [(n, False) for n in FLAGGED if OPTIONS[n].kind == "bool"],
)
def test_fit_passes_each_option_through_unchanged(csv, captured, name, value):
    structure, method = _where(name)
    args = ["fit", str(csv), "-u", "u", "-y", "y", "--structure", structure, "--json"]
    r = runner.invoke(app, [*args, "--method", method, *_args(name, value)])
    assert r.exit_code == 2 and r.stderr == "error: captured\n", r.output
    assert captured["args"][1] == structure
    assert captured["kwargs"] == {"method": method, name: value}


@pytest.mark.parametrize("name", FLAGGED)
def test_compare_passes_each_option_to_compare_structures(csv, captured, name):
    value = _text(name)
    r = runner.invoke(
        app,
        [
            *("compare", str(csv), "-u", "u", "-y", "y"),
            *("--estimation", "0:40", "--validation", "40:60"),
            *_args(name, value),
        ],
    )
    assert r.exit_code == 2 and r.stderr == "error: captured\n", r.output
    # every option goes to the library, which gives each structure those it takes
    assert captured["kwargs"] == {"method": None, "options": {name: value}}


def test_fit_without_options_leaves_every_default_to_the_method(csv, captured):
    r = runner.invoke(app, ["fit", str(csv), "-u", "u", "-y", "y", "--json"])
    assert r.exit_code == 2, r.output
    assert captured["args"][1] == "arx" and captured["kwargs"] == {"method": None}


def test_fit_help_lists_every_flag_at_80_columns():
    r = runner.invoke(app, ["fit", "--help"], env={"COLUMNS": "80"})
    assert r.exit_code == 0
    assert max(len(line) for line in r.stdout.splitlines()) <= 80
    for name in FLAGGED:
        flag = option_flag(name)
        assert re.search(rf"(?<![\w-]){re.escape(flag)}(?![\w-])", r.stdout), flag
        if OPTIONS[name].kind == "bool":
            assert f"{flag} / --no-{flag[2:]}" in r.stdout
    for structure in STRUCTURES.values():  # the structures and their methods
        assert f"{structure.name}: " in r.stdout
        assert ", ".join(structure.method_names) in r.stdout
    assert "--record-history" not in r.stdout


@pytest.mark.parametrize("args", [["-h"], ["fit", "-h"], ["reproduce", "windtunnel", "-h"]])
def test_short_help(args):
    r = runner.invoke(app, args)
    assert r.exit_code == 0 and r.stdout.startswith("Usage: ")


@pytest.mark.parametrize("command", ["fit", "simulate", "export", "example-data", "identify"])
def test_arguments_are_shown_by_their_name_not_a_python_type(command):
    r = runner.invoke(app, [command, "-h"], env={"COLUMNS": "100"})
    arguments = r.stdout.split("Arguments:")[1].split("Options:")[0]
    assert "<" not in arguments and "list[" not in arguments, arguments  # was DATA <list[Path]>


def test_bad_option_value_is_one_line_naming_the_flag(csv):
    r = runner.invoke(
        app,
        ["fit", str(csv), "-u", "u", "-y", "y", "--method", "rls", "--forgetting", "2", "--json"],
    )
    assert r.exit_code == 2 and r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: forgetting")
    assert "--forgetting" in lines[0]


def test_library_parameter_is_named_by_its_flag(tmp_path):
    path = tmp_path / "one.csv"
    path.write_text("t,u,y\n0,1,2\n")
    r = runner.invoke(app, ["fit", str(path), "-u", "u", "-y", "y", "--time-column", "t", "--json"])
    assert r.exit_code == 2
    assert r.stderr.startswith("error: ") and r.stderr.rstrip().endswith("(option --ts)")


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["fit", "DATA", "-u", "u"], "Missing option '--output'"),
        (["fit", "DATA", "-u", "u", "-y", "y", "--bogus"], "No such option: --bogus"),
        (["fit", "DATA", "-u", "u", "-y", "y", "--ts", "abc"], "Invalid value for '--ts'"),
        (["fit", "DATA", "-u", "u", "-y", "y", "--passes"], "'--passes' requires an argument"),
        (["nonsense"], "No such command 'nonsense'"),
    ],
)
def test_usage_errors_are_one_line_and_exit_2(csv, args, expected):
    r = runner.invoke(app, [str(csv) if a == "DATA" else a for a in args])
    assert r.exit_code == 2 and r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and expected in lines[0]
    assert "Traceback" not in r.output


@pytest.mark.parametrize(
    ("flag", "suggested"),
    [("--bogus", None), ("--estimaton", "--estimation"), ("--strucure", "--structure")],
)
def test_an_unknown_flag_suggests_only_flags_close_to_it(csv, flag, suggested):
    r = runner.invoke(app, ["fit", str(csv), "-u", "u", "-y", "y", flag])
    assert r.exit_code == 2
    line = r.stderr.strip()
    if suggested is None:
        assert "mean" not in line and "Possible" not in line, line
    else:
        assert f"(did you mean {suggested}?)" in line, line


# ------------------------------------------------------------ choosing the blocks
LINEAR = {"na": 2, "nb": 2, "nk": 1, "a": [-1.2, 0.5], "b": [1.0, 0.4]}
ORDERS = ["--na", "2", "--nb", "2", "--nk", "1", "--json"]


def _record(tmp_path, plant, name):
    u = np.random.default_rng(1).uniform(-2, 2, 2000)
    path = tmp_path / name
    pd.DataFrame({"u": u, "y": plant.simulate(u)[:, 0]}).to_csv(path, index=False)
    return path


def test_fit_hammerstein_with_a_dead_zone_input_block(tmp_path):
    plant = Hammerstein("u", "y", input_block=DeadZone(-0.5, 0.4), **LINEAR)
    path = _record(tmp_path, plant, "h.csv")
    out = tmp_path / "m.json"
    args = ["fit", str(path), "-u", "u", "-y", "y", "--structure", "hammerstein"]
    r = runner.invoke(app, [*args, "--input-block", "dead-zone", *ORDERS, "-o", str(out)])
    assert r.exit_code == 0, r.output
    model = load_model(out)
    assert isinstance(model.input_block, DeadZone)
    assert json.loads(out.read_text())["model"]["chain"][0]["kind"] == "dead-zone"
    assert model.parameters["lower"] == pytest.approx(-0.5, abs=1e-6)
    assert model.parameters["upper"] == pytest.approx(0.4, abs=1e-6)


@pytest.mark.parametrize(
    "block",
    [
        "polynomial:degree=2",
        "polynomial:degree=2;constant=false",
    ],
)
def test_fit_wiener_with_a_quadratic_output_block(tmp_path, block):
    plant = Wiener("u", "y", output_block=Polynomial([1.0, 0.3], constant=False), **LINEAR)
    path = _record(tmp_path, plant, "w.csv")
    args = ["fit", str(path), "-u", "u", "-y", "y", "--structure", "wiener"]
    r = runner.invoke(app, [*args, "--output-block", block, *ORDERS])
    assert r.exit_code == 0, r.output
    assert len(json.loads(r.stdout)["model"]["parameters"]["q"]) == 2


NEW_OPTION = """
import dataclasses, sys
from blockid.fitting import registry
registry.OPTIONS["smoothing"] = registry.Option("smoothing", "real", "A new option.", low=0.0)
arx = registry.STRUCTURES["arx"]
batch = dataclasses.replace(arx.methods[0], options=arx.methods[0].options + ("smoothing",))
registry.STRUCTURES["arx"] = dataclasses.replace(arx, methods=(batch, *arx.methods[1:]))

import blockid.fitting
from typer.testing import CliRunner
from blockid.cli.main import app

seen = {}
def fake(data, structure, **kwargs):
    seen.update(kwargs)
    raise blockid.errors.ParameterError("captured")
blockid.fitting.fit_model = fake
help = CliRunner().invoke(app, ["fit", "-h"], env={"COLUMNS": "80"}).stdout
assert "--smoothing X" in help and "A new option." in help, help
r = CliRunner().invoke(app, ["fit", sys.argv[1], "-u", "u", "-y", "y", "--smoothing", "0.5", "--json"])
assert r.exit_code == 2 and seen == {"method": None, "smoothing": "0.5"}, (r.output, seen)
"""


def test_a_new_registry_option_is_a_flag_without_touching_the_cli(csv):
    """Declared in the registry only, before the command line is imported."""
    import subprocess
    import sys

    subprocess.run([sys.executable, "-c", NEW_OPTION, str(csv)], check=True)


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
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


def test_boolean_flags_carry_their_declared_help():
    def command(data: str, **options):
        return options

    p = inspect.signature(with_fit_options(command)).parameters
    bools = [o.name for o in cli_options() if o.kind == "bool"]
    assert "center" in bools
    for name in bools:
        info = p[name].annotation.__metadata__[0]
        assert info.help == OPTIONS[name].help and info.help


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


def test_the_docs_flag_table_has_a_row_for_every_generated_flag_and_no_other():
    """docs/cli.md's table of estimator flags names every flag the registry generates,
    and no flag the registry does not have (a removed or renamed option leaves no stale
    row behind)."""
    import re
    from pathlib import Path

    from blockid.fitting.registry import option_flag

    doc = (Path(__file__).parents[2] / "docs" / "cli.md").read_text()
    start = doc.index("| flag | meaning |")
    rows = doc[start : doc.index("\n\n", start)].splitlines()[2:]
    documented = set()
    for row in rows:
        first = re.match(r"^\|(.*?)(?<!\\)\|", row).group(1)
        documented |= {f.removeprefix("--no-") for f in re.findall(r"--[a-z0-9-]+", first)}
    documented = {f if f.startswith("--") else f"--{f}" for f in documented}
    generated = {option_flag(o.name) for o in cli_options()}
    assert generated - documented == set(), "flags without a row in docs/cli.md"
    assert documented - generated == set(), "rows in docs/cli.md for flags that do not exist"


def _spellings(value: float) -> set[str]:
    """How a default number may be written in the docs: ``0.1``, ``1e-10``, ``1e5``."""
    out = {str(value), f"{value:g}"}
    if value > 0 and float(f"{value:.0e}") == value:
        mantissa, exponent = f"{value:.0e}".split("e")
        out.add(f"{mantissa}e{int(exponent)}")
    if float(value).is_integer():
        out.add(str(int(value)))
    return out


def test_the_docs_flag_table_states_every_numeric_default():
    """Each number a method's signature (or ``blockid/defaults.py`` for the recursive
    estimators) takes as an option's default is stated in that option's row of
    docs/cli.md: a default changed in one place fails here until the docs say it
    too (seen failing on the AW-RLS weights, the recursive P(0) and the solver
    tolerances, which the table did not state)."""
    import inspect
    import re
    from pathlib import Path

    from blockid.defaults import RECURSIVE
    from blockid.fitting.registry import STRUCTURES, option_flag

    doc = (Path(__file__).parents[2] / "docs" / "cli.md").read_text()
    start = doc.index("| flag | meaning |")
    rows = doc[start : doc.index("\n\n", start)].splitlines()[2:]

    def row(name: str) -> str:
        flag = option_flag(name)
        for r in rows:
            first = re.match(r"^\|(.*?)(?<!\\)\|", r).group(1)
            if re.search(re.escape(flag) + r"(?![a-z-])", first):
                return r
        raise AssertionError(f"no row for {flag}")

    defaults: dict[str, set[float]] = {}
    for structure in STRUCTURES.values():
        for method in structure.methods:
            params = inspect.signature(method.function()).parameters
            for option in structure.accepted(method.name):
                d = params[option].default if option in params else None
                if isinstance(d, int | float) and not isinstance(d, bool):
                    defaults.setdefault(option, set()).add(d)
    for table in RECURSIVE.values():
        for option, d in table.items():
            if isinstance(d, int | float) and not isinstance(d, bool):
                defaults.setdefault(option, set()).add(d)
    # orders have no default through fit_model outside ARX (it asks for all three), so
    # the signatures' paper orders are not the flags' defaults
    used = {o.name for o in cli_options() if o.kind != "orders"}
    missing = {
        option: sorted(d for d in values if not _spellings(d) & set(re.findall(r"[\d.e+-]+", row(option))))
        for option, values in defaults.items()
        if option in used
    }  # fmt: skip
    assert {k: v for k, v in missing.items() if v} == {}
