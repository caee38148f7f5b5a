"""Every flag that several commands take is declared once, in ``blockid.cli._flags``:
walked over the whole command tree, a flag of its table made anywhere else fails here,
and the flags that mean the same on every command read the same everywhere."""

from collections import defaultdict
from typing import Any

import typer
from typer.testing import CliRunner

from blockid.cli import _flags
from blockid.cli.main import app


def _options() -> list[tuple[str, Any]]:
    """(command path, click option) of every option of the app."""
    found = []

    def walk(command: Any, path: tuple[str, ...]) -> None:
        for param in command.params:
            if param.param_type_name == "option":
                found.append((" ".join(path), param))
        for name, sub in getattr(command, "commands", {}).items():
            walk(sub, (*path, name))

    walk(typer.main.get_command(app), ())
    return found


#: Commands made by one function (their flags are declared once there).
ONE_FUNCTION = {"simulate": "simulate/predict", "predict": "simulate/predict"}


def _table_names() -> dict[str, str]:
    """Flag spelling -> its entry in the shared table."""
    return {flag: key for key, (names, _) in _flags.SHARED.items() for flag in names}


def test_every_shared_flag_of_every_command_comes_from_the_one_declaration():
    names = _table_names()
    options = _options()  # builds the commands (and their flags) first
    made = {help for _, help in _flags.MADE}
    strays = []
    for path, option in options:
        keys = {names[o] for o in (*option.opts, *option.secondary_opts) if o in names}
        if not keys:
            continue
        key = keys.pop()
        spelled = _flags.SHARED[key][0]
        if tuple(option.opts) != spelled or (option.help or "") not in made:
            strays.append(f"{path}: {option.opts} ({option.help!r})")
    assert not strays, "flags of the shared table declared outside blockid.cli._flags:\n" + (
        "\n".join(strays)
    )


def test_a_flag_outside_the_table_is_one_command_s_own():
    """A flag that two commands take belongs in the table (so its names and placeholder
    cannot drift apart)."""
    names = _table_names()
    commands = defaultdict(set)
    for path, option in _options():
        if option.hidden:  # the old name of a renamed flag, kept for scripts
            continue
        for flag in option.opts:
            if flag.startswith("--") and flag not in names and flag != "--help":
                # simulate and predict are one function's two commands (one declaration)
                commands[flag].add(ONE_FUNCTION.get(path, path))
    # the hidden old names of renamed flags, and the options generated from the
    # registry's one declaration of every estimator option (tests/cli/test_options.py)
    from blockid.cli._options import cli_options

    generated = {"--" + o.name.replace("_", "-") for o in cli_options()}
    several = {f: sorted(c) for f, c in commands.items() if len(c) > 1 and f not in generated}
    assert not several, f"flags of several commands missing from the shared table: {several}"


def test_the_flags_that_mean_one_thing_read_the_same_on_every_command():
    texts = defaultdict(set)
    for _, option in _options():
        texts[option.opts[0]].add(option.help)
    for flag in ("--input", "--ts", "--time-column", "--experiment-column", "--json", "--quiet"):
        assert len(texts[flag]) == 1, (flag, texts[flag])


def test_reads_data_shows_the_three_reading_flags_in_place_and_bundles_them():
    """A command's ``reading`` parameter is ``--ts``, ``--time-column`` and
    ``--experiment-column`` on the command line, where it stood; the command gets them
    back as one :class:`~blockid.cli._flags.Reading`."""
    import inspect

    got = {}

    @_flags.reads_data
    def command(
        data_paths: _flags.DataPaths,
        reading: _flags.Reading = _flags.DEFAULT_READING,
        force: _flags.Force = False,
    ) -> None:
        got.update(reading=reading, force=force)

    names = list(inspect.signature(command).parameters)
    assert names == ["data_paths", "ts", "time_column", "experiment_column", "force"]
    app = typer.Typer()
    app.command()(command)
    app.command("other")(lambda: None)  # two commands: the first is named on the line
    r = CliRunner().invoke(app, ["command", "d.csv", "--time-column", "t", "--force"])
    assert r.exit_code == 0, r.output
    assert got == {"reading": _flags.Reading(None, "t", None), "force": True}
    CliRunner().invoke(app, ["command", "d.csv", "--ts", "0.5", "--experiment-column", "e"])
    assert got["reading"] == _flags.Reading(0.5, None, "e")
    assert not got["force"]
