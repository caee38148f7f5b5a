"""The bad-input tables as a whole (``tests/cli/test_<module>_bad_input.py``, one table
per command beside its tests): many cases, each named once, over every kind of input and
every command, each case filed beside the module of the command it runs, and every
command module with a table."""

from __future__ import annotations

import functools
import importlib.util
import sys
from pathlib import Path

import typer

from blockid.cli.main import app
from cli.bad_input import Accepted, Case

HERE = Path(__file__).parent


@functools.cache
def _tables() -> dict[str, list[Case | Accepted]]:
    """Every case of every bad-input file (refused and accepted), by the cli module the
    file is named after."""
    found = {}
    for path in sorted(HERE.glob("test_*_bad_input.py")):
        name = f"_tables_of_{path.stem}"
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        try:
            spec.loader.exec_module(module)
        finally:
            del sys.modules[name]
        cases = [
            case
            for value in vars(module).values()
            if isinstance(value, list)
            and value
            and all(isinstance(c, Case | Accepted) for c in value)
            for case in value
        ]
        found[path.stem.removeprefix("test_").removesuffix("_bad_input")] = cases
    return found


@functools.cache
def _root() -> typer.core.TyperGroup:
    return typer.main.get_command(app)


def _module_of(args: list[str]) -> str:
    """The cli module whose function runs the command line ``args``."""
    command = _root()
    for word in args:
        if not hasattr(command, "commands"):
            break
        command = command.commands[word]
    return command.callback.__module__


def test_at_least_150_cases_over_every_kind_and_command():
    every = [case for cases in _tables().values() for case in cases]
    CASES = [case for case in every if isinstance(case, Case)]
    assert len(CASES) >= 150
    assert len({c.id for c in every}) == len(every), "case ids must be unique"
    kinds = {c.id.split()[0] for c in CASES}
    assert {
        "file", "column", "value", "ts", "range", "order", "model", "option", "export", "network"
    } <= kinds  # fmt: skip
    commands = {c.args[0] for c in CASES}
    assert {
        "fit", "compare", "identify", "simulate", "predict", "export", "orders", "stream",
        "report", "fit-network", "example-data", "fleet", "bla", "design", "residuals",
    } <= commands  # fmt: skip


def _commands(command: typer.core.TyperGroup | None = None) -> list[list[str]]:
    """Every command line of the app, as the words that name its command."""
    group = command or _root()
    found = []
    for name, sub in group.commands.items():
        found += (
            [[name, *words] for words in _commands(sub)] if hasattr(sub, "commands") else [[name]]
        )
    return found


def test_every_command_module_has_a_table():
    modules = {_module_of(words).removeprefix("blockid.cli.") for words in _commands()}
    assert len(modules) >= 12
    assert modules == set(_tables())


def test_each_case_is_filed_beside_its_command():
    misfiled = [
        (module, case.id, _module_of(case.args))
        for module, cases in _tables().items()
        for case in cases
        if _module_of(case.args) != f"blockid.cli.{module}"
    ]
    assert len(_tables()) >= 9
    assert not misfiled
