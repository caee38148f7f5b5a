"""The estimator flags, generated from :mod:`blockid.fitting.registry`.

Every option a structure's method takes becomes one flag (``initial_covariance`` ->
``--initial-covariance``) with the help text and placeholder of its declaration, and
default None so that the method's own default applies. Values reach
:func:`~blockid.fitting.fit_model` as typed (text; booleans as ``--flag/--no-flag``):
the registry converts and checks them and names the parameter when one is wrong.
An option added to the registry is a flag here without touching this package.
"""

from __future__ import annotations

import inspect
import textwrap
from collections.abc import Callable
from typing import Annotated, Any

import typer

from blockid.cli._flags import shared
from blockid.fitting.registry import (
    COMPARED_BY_DEFAULT,
    COMPARED_MULTIVARIABLE,
    OPTIONS,
    STRUCTURES,
    Option,
    option_flag,
)

__all__ = [
    "ComparedStructures",
    "EstimationRange",
    "SharedMethod",
    "ValidationRange",
    "DEFAULT_STRUCTURE",
    "INTERNAL",
    "Method",
    "Structure",
    "cli_options",
    "given",
    "structures_help",
    "with_fit_options",
]

#: Options that stay library-only (no flag): the parameter trajectory is drawn by
#: ``fit --plot``, which asks for it itself.
INTERNAL = ("record_history",)

#: Placeholder of a value by kind, where the declaration gives none.
_METAVARS = {"orders": "N", "count": "N", "real": "X"}


def cli_options() -> list[Option]:
    """The options some structure's method takes, in declaration order, less INTERNAL."""
    used = {
        name
        for structure in STRUCTURES.values()
        for method in structure.method_names
        for name in structure.accepted(method)
    }
    return [o for name, o in OPTIONS.items() if name in used and name not in INTERNAL]


def _parameter(option: Option) -> inspect.Parameter:
    name = option_flag(option.name)
    if option.kind == "bool":
        info = typer.Option(f"{name}/--no-{name[2:]}", help=option.help, show_default=False)
        annotation: Any = Annotated[bool | None, info]
    else:
        metavar = option.metavar or _METAVARS.get(option.kind, "VALUE")
        info = typer.Option(name, help=option.help, metavar=metavar, show_default=False)
        # a block flag repeats: one block per channel of a multivariable model
        kind = list[str] | None if option.kind == "block" else str | None
        annotation = Annotated[kind, info]
    keyword = inspect.Parameter.KEYWORD_ONLY
    return inspect.Parameter(option.name, keyword, default=None, annotation=annotation)


def with_fit_options(command: Callable[..., Any]) -> Callable[..., Any]:
    """Give ``command`` one flag per estimator option; they arrive in its ``**options``.

    The flags follow the parameter ``method``; typer reads the signature built here.
    """
    signature = inspect.signature(command, eval_str=True)
    own = [p for p in signature.parameters.values() if p.kind is not p.VAR_KEYWORD]
    names = [p.name for p in own]
    at = names.index("method") + 1 if "method" in names else len(own)
    generated = [_parameter(o) for o in cli_options()]
    keyword = [p.replace(kind=p.KEYWORD_ONLY) for p in own[at:]]
    command.__signature__ = signature.replace(parameters=[*own[:at], *generated, *keyword])
    return command


def given(options: dict[str, Any]) -> dict[str, Any]:
    """The options the user gave (a flag left out is None: the method's default); a
    repeatable flag given once is its one value."""
    out = {}
    for name, value in options.items():
        if isinstance(value, list):
            value = (value[0] if len(value) == 1 else value) if value else None
        if value is not None:
            out[name] = value
    return out


def structures_help(width: int = 74) -> str:
    """The structures and their methods, as a paragraph of a command's help."""
    lines = ["\b", "Structures, and their methods (the first is the default):"]
    for s in STRUCTURES.values():
        lines += textwrap.wrap(f"{s.name}: {s.help}", width, subsequent_indent="    ")
        lines += textwrap.wrap(", ".join(s.method_names), width, initial_indent="    ")
    return "\n".join(lines)


#: The structure ``fit`` identifies unless told (the registry's first).
DEFAULT_STRUCTURE = next(iter(STRUCTURES))

Structure = Annotated[
    str,
    shared(
        "structure", f"Model structure: {', '.join(STRUCTURES)} (see below).", show_default=True
    ),
]
Method = Annotated[
    str | None,
    shared(
        "method",
        "Estimator, one of the structure's methods (see below); default: its first.",
        show_default=False,
    ),
]


#: The options ``compare`` and ``report`` share (the structures, their ranges, a method).
EstimationRange = Annotated[
    str, shared("estimation", "Estimation samples (0-based, stop excluded).")
]
ValidationRange = Annotated[
    str, shared("validation", "Validation samples (0-based, stop excluded).")
]
ComparedStructures = Annotated[
    str | None,
    shared(
        "structures",
        f"Comma-separated structures to compare, of {', '.join(STRUCTURES)} "
        f"(default: {', '.join(COMPARED_BY_DEFAULT)}; with several inputs or outputs "
        f"{', '.join(COMPARED_MULTIVARIABLE)}).",
        show_default=False,
    ),
]
SharedMethod = Annotated[
    str | None,
    shared("method", "Method for the structures that offer it (others: their default)."),
]
