"""The ``blockid`` command line: thin commands over library functions.

One module per command group (:mod:`~blockid.cli.fit`, :mod:`~blockid.cli.running`,
:mod:`~blockid.cli.examples`); the estimator flags are generated from the registry of
structures and options (:mod:`blockid.cli._options`).

Every command that reports numbers prints them as one JSON document with ``--json``.
Errors in the user's input, whether the library's or the command line's own (a missing
or unknown option, a value of the wrong type), are printed as one line ``error: ...``
on stderr and the exit status is 2; output files are written atomically and only after
the work succeeded, and an existing file is replaced only with ``--force``.
"""

from __future__ import annotations

import errno
import sys
from collections.abc import Sequence
from typing import Annotated, Any

import typer
from typer.core import TyperGroup

from blockid.cli import (
    bla,
    design,
    examples,
    export,
    fit,
    fleet_cli,
    identify,
    orders,
    report,
    residuals,
    running,
    streaming,
)
from blockid.cli._common import stdout

try:  # typer >= 0.20 carries its own copy of click
    from typer._click import exceptions as click_exceptions
except ImportError:  # pragma: no cover - older typer depends on click
    from click import exceptions as click_exceptions  # type: ignore[no-redef]

__all__ = ["app", "main"]

_HELP_WITHOUT_ARGS = getattr(click_exceptions, "NoArgsIsHelpError", ())


def _no_type(ctx: Any = None) -> None:
    return None


class _OneLineErrors(TyperGroup):
    """The root group: a usage error (missing, unknown or bad option) is one line.

    typer and click would print a usage box over several lines; scripts and people
    reading a log get ``error: <message> (see 'blockid fit -h')`` and exit status 2,
    the same form as the library's errors.
    """

    def get_command(self, ctx: Any, name: str) -> Any:
        """The command, its arguments shown by their metavar alone in ``-h``
        (``DATA``, not typer's ``DATA <list[Path]>``)."""
        command = super().get_command(ctx, name)
        for param in getattr(command, "params", ()):
            if param.param_type_name == "argument" and param.metavar:
                param.display_type_rich = _no_type
        return command

    def main(
        self,
        args: Sequence[str] | None = None,
        prog_name: str | None = None,
        complete_var: str | None = None,
        standalone_mode: bool = True,
        **extra: Any,
    ) -> Any:
        try:
            rv = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except _HELP_WITHOUT_ARGS as exc:  # `blockid` or `blockid reproduce` alone: help
            if not standalone_mode:
                raise
            exc.show()
            sys.exit(exc.exit_code)
        except click_exceptions.ClickException as exc:
            if not standalone_mode:
                raise
            hint = ""
            ctx = getattr(exc, "ctx", None)
            if ctx is not None:
                hint = f" (see '{ctx.command_path} -h')"
            message = " ".join(_message(exc).split())
            print(f"error: {message}{hint}", file=sys.stderr)
            sys.exit(exc.exit_code)
        except typer.Abort:
            if not standalone_mode:
                raise
            print("aborted", file=sys.stderr)
            sys.exit(1)
        except OSError as exc:  # output piped into a closed reader (`| head`)
            if not standalone_mode or exc.errno != errno.EPIPE:
                raise
            sys.exit(1)
        if not standalone_mode:
            return rv
        sys.exit(rv if isinstance(rv, int) else 0)


#: How alike an unknown flag and a real one must be for the error to suggest it (the
#: ratio of :func:`difflib.get_close_matches`; click's 0.6 offered ``--out`` for
#: ``--bogus``).
SUGGEST = 0.75


def _message(exc: Any) -> str:
    """The error's message; an unknown flag suggests only flags close to it."""
    if isinstance(exc, click_exceptions.NoSuchOption):
        from difflib import get_close_matches

        close = get_close_matches(exc.option_name, exc.possibilities or [], 3, SUGGEST)
        hint = f" (did you mean {' or '.join(sorted(close))}?)" if close else ""
        return f"No such option: {exc.option_name}{hint}"
    return str(exc.format_message())


app = typer.Typer(
    name="blockid",
    cls=_OneLineErrors,
    help="Identify block-oriented nonlinear models (Hammerstein, Wiener, "
    "Hammerstein-Wiener, backlash, networks) from input/output data.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,  # plain help: readable at 80 columns, no names cut
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _version(value: bool) -> None:
    if value:
        from blockid import __version__

        stdout.print(f"blockid {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option("--version", callback=_version, is_eager=True, help="Print the version."),
    ] = False,
) -> None:
    """Identify block-oriented nonlinear models (Hammerstein, Wiener, Hammerstein-Wiener,
    backlash, networks) from input/output data."""


#: One line per command in ``blockid -h``, whole (click would cut the docstring's first
#: sentence at 45 characters).
SHORT_HELP = {
    "fit": "Identify a model and save it as a model file.",
    "compare": "Identify several structures, score them on validation data.",
    "fit-network": "Identify a network of subsystems connected by signal names.",
    "simulate": "Free-run simulation of a model on data.",
    "predict": "One-step-ahead prediction of a model on data.",
    "residuals": "Test a model's residual: white, and independent of the input?",
    "orders": "Choose na, nb, nk by false nearest neighbours.",
    "design": "Design an excitation: multisine, odd multisine, PRBS.",
    "bla": "Measure the best linear approximation: noise and distortion levels.",
    "identify": "Search structures and orders; keep the best model.",
    "export": "Export a model as a Python module or transfer functions.",
    "stream": "Learn a model sample by sample from standard input.",
    "fleet": "Fit one model per record, many records in parallel.",
    "report": "Compare structures and write an HTML report.",
    "demo": "Run the built-in example (paper B's excavator arm).",
    "example-data": "Write a record of a built-in simulated plant.",
}
for _name, _command in (
    ("fit", fit.fit),
    ("compare", fit.compare),
    ("fit-network", fit.fit_network),
    ("simulate", running.simulate),
    ("predict", running.predict),
    ("residuals", residuals.residuals),
    ("orders", orders.orders),
    ("design", design.design),
    ("bla", bla.bla),
    ("identify", identify.identify),
    ("export", export.export),
    ("stream", streaming.stream),
    ("fleet", fleet_cli.fleet),
    ("report", report.report),
    ("demo", examples.demo),
):
    app.command(_name, short_help=SHORT_HELP[_name])(_command)
app.add_typer(
    examples.reproduce_app,
    name="reproduce",
    short_help="Reproduce the seed papers on the simulated plants.",
)
app.command("example-data", short_help=SHORT_HELP["example-data"])(examples.example_data)


def _terminated(signum: int, frame: Any) -> None:
    """SIGTERM (a job killed, a CI step timed out) ends the command as Ctrl-C does: by an
    exception, so that open ``with`` blocks close (identify's worker processes are shut
    down and its shared memory freed; without this they outlived the command)."""
    raise SystemExit(128 + signum)


def main() -> None:
    """Console-script entry point."""
    import signal

    signal.signal(signal.SIGTERM, _terminated)
    app()


if __name__ == "__main__":
    main()
