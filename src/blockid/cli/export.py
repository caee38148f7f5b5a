"""``blockid export``: a saved model as a NumPy-only Python module or as transfer
functions for ``scipy.signal``.

Parses, calls :func:`blockid.models.export.export_text`, writes the file (atomically,
an existing one only with ``--force``) or prints it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from blockid.cli._common import cli_errors, print_json, refuse_to_overwrite, stdout
from blockid.cli._data import check_arguments
from blockid.cli._flags import Force, Json, ModelPath, shared

__all__ = ["export"]

#: ``--to`` choices (kept here so that ``blockid -h`` does not import the exporter).
_FORMATS = ("python", "scipy-json")


@cli_errors
def export(
    model_path: ModelPath,
    to: Annotated[
        str,
        typer.Option(
            "--to",
            metavar="FORMAT",
            help="python: a module with simulate(u, y0=None) that needs NumPy only; "
            "scipy-json: the linear blocks' transfer functions for scipy.signal.dlti.",
        ),
    ] = "python",
    out: Annotated[
        Path | None,
        shared("out", "File to write (default: print it)."),
    ] = None,
    force: Force = False,
    json_out: Json = False,
) -> None:
    """Export a model: a self-contained Python module or transfer functions."""
    from blockid.errors import ParameterError

    if to not in _FORMATS:
        raise ParameterError(f"--to must be one of {', '.join(_FORMATS)}, got {to!r}")
    refuse_to_overwrite(out, force)
    check_arguments(model=model_path)
    from blockid.data.io import write_text_atomic
    from blockid.models import load_model
    from blockid.models.export import export_text

    model = load_model(model_path)
    text = export_text(model, to)
    if out is not None:
        write_text_atomic(text, out, overwrite=force)
    if json_out:
        doc = {"model": str(model_path), "to": to, "out": None if out is None else str(out)}
        if out is None:
            doc["text"] = text
        print_json(doc)
    elif out is None:
        typer.echo(text, nl=False)
    else:
        stdout.print(f"{model.structure} model exported ({to}) to {out}", markup=False)
