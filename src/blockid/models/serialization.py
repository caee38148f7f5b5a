"""Model files: JSON with a format name and a version.

.. code-block:: json

    {"format": "blockid-model", "version": 1,
     "model": {"structure": "arx", "inputs": [...], "outputs": [...], ...},
     "estimation": {"method": "rls", ...}}

Floats are written with Python's shortest round-trip representation, so a saved and
reloaded model gives bit-identical predictions. An undefined number in the estimation
record (the fit percent of a constant output) is written as ``null``; a model whose
parameters are not all finite is refused, when written and when read, naming the entry.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from blockid.data.io import json_safe
from blockid.errors import ModelFileError
from blockid.models.base import Model, model_from_dict

__all__ = [
    "FORMAT",
    "VERSION",
    "check_finite",
    "model_document",
    "model_from_document",
    "save_model",
    "load_model",
]

FORMAT = "blockid-model"
VERSION = 1


def model_document(model: Model, estimation: dict[str, Any] | None = None) -> dict[str, Any]:
    """The JSON document of a model file (also what ``blockid fit --json`` prints)."""
    doc: dict[str, Any] = {"format": FORMAT, "version": VERSION, "model": model.to_dict()}
    if estimation:
        doc["estimation"] = json_safe(estimation)
    return doc


def _non_finite(value: Any, path: str) -> Iterator[tuple[str, Any]]:
    """``(path, value)`` of every NaN or infinite number (or its JSON spelling) inside."""
    if isinstance(value, dict):
        for key, item in value.items():
            yield from _non_finite(item, f"{path}.{key}" if path else str(key))
    elif isinstance(value, list):
        for k, item in enumerate(value):
            yield from _non_finite(item, f"{path}[{k}]")
    elif isinstance(value, float) and not math.isfinite(value):
        yield path, value


def check_finite(description: Any, source: str = "the model") -> None:
    """Raise :class:`ModelFileError` naming the first non-finite number of a model's
    :meth:`~blockid.models.base.Model.to_dict` form (parameters, offsets, ranges).

    A NaN parameter would otherwise show up only when the model runs, as a simulation
    that "diverged on these data", blaming the data for the model file.

    >>> try:
    ...     check_finite({"parameters": {"a": [0.5, float("nan")]}}, "m.json")
    ... except ModelFileError as exc:
    ...     print(str(exc).split(";")[0])
    m.json has a non-finite parameter: parameters.a[1] is nan
    """
    for path, value in _non_finite(description, ""):
        raise ModelFileError(
            f"{source} has a non-finite parameter: {path} is {value}; the model file is "
            "damaged or was written by a fit that diverged: refit the model or restore the file"
        )


def model_from_document(doc: Any, source: str = "the model document") -> Model:
    """Check format and version, then rebuild the model."""
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise ModelFileError(f'{source} is not a blockid model file (no "format": "{FORMAT}")')
    version = doc.get("version")
    if version != VERSION:
        raise ModelFileError(
            f"{source} has model-file version {version!r}; this blockid reads version {VERSION}. "
            "Upgrade blockid or refit the model"
        )
    if "model" not in doc:
        raise ModelFileError(f'{source} has no "model" entry; the file is damaged')
    check_finite(doc["model"], source)
    ts = doc["model"].get("sampling_time") if isinstance(doc["model"], dict) else None
    if ts is not None and (isinstance(ts, bool) or not isinstance(ts, int | float) or ts <= 0):
        raise ModelFileError(
            f"{source} has sampling_time {ts!r}; a model's sampling time is a positive number "
            "of seconds (or null): the file was edited or damaged, refit or restore it"
        )
    try:
        return model_from_dict(doc["model"])
    except ModelFileError as exc:
        raise ModelFileError(f"{source}: {exc}") from None


def save_model(
    model: Model,
    path: str | Path,
    estimation: dict[str, Any] | None = None,
    overwrite: bool = False,
) -> Path:
    """Write a model file atomically; an existing file is kept unless ``overwrite``."""
    from blockid.data.io import write_text_atomic

    text = json.dumps(model_document(model, estimation), indent=2, allow_nan=False)
    path = Path(path)
    write_text_atomic(text + "\n", path, overwrite=overwrite)
    return path


def load_model(path: str | Path) -> Model:
    """Read a model file written by :func:`save_model`."""
    from blockid.data.files import read_model_document

    doc = read_model_document(path)
    return model_from_document(doc, source=str(path))
