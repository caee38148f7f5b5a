"""Sample ranges given on the command line, such as ``--estimation 0:1000``."""

from __future__ import annotations

from blockid.errors import ParameterError

__all__ = ["check_disjoint", "parse_range"]

Range = tuple[int, int | None]


def parse_range(text: str, what: str) -> tuple[int, int | None]:
    """Parse a half-open sample range ``START:STOP``.

    ``START`` and ``STOP`` are 0-based sample indices, ``STOP`` excluded, as in a Python
    slice. Either may be left out: ``"1000:"`` runs to the end, ``":500"`` starts at 0.
    Negative indices are not accepted.

    Parameters
    ----------
    text : str
        The range as typed.
    what : str
        Name of the option, e.g. ``"--estimation"``, used in error messages.

    Returns
    -------
    tuple of (int, int or None)
        ``(start, stop)``, with ``stop`` None for an open end; pass them to
        :meth:`blockid.data.Dataset.select`.

    Raises
    ------
    ParameterError
        If the text is not of that form, an index is negative, or the range is empty.

    Examples
    --------
    >>> parse_range("0:1000", "--estimation")
    (0, 1000)
    >>> parse_range("1000:", "--validation")
    (1000, None)
    >>> parse_range(":500", "--estimation")
    (0, 500)
    """
    form = (
        f"{what} expects START:STOP (0-based sample indices, STOP excluded), "
        "e.g. 0:1000, 1000: or :500"
    )
    raw = str(text).strip()
    if raw.count(":") != 1:
        raise ParameterError(f"{form}; got {text!r}")
    parts = [p.strip() for p in raw.split(":")]
    values: list[int | None] = []
    for part in parts:
        if not part:
            values.append(None)
            continue
        try:
            value = int(part)
        except ValueError:
            raise ParameterError(f"{form}; {part!r} in {text!r} is not a whole number") from None
        if value < 0:
            raise ParameterError(f"{form}; negative indices such as {part} are not allowed")
        values.append(value)
    start = 0 if values[0] is None else values[0]
    stop = values[1]
    if stop is not None and stop <= start:
        raise ParameterError(f"{form}; {text!r} is empty (STOP must be larger than START)")
    return start, stop


def check_disjoint(
    estimation: str | Range,
    validation: str | Range,
    names: tuple[str, str] = ("--estimation", "--validation"),
) -> None:
    """Refuse estimation and validation ranges that share samples.

    A model scored on samples it was fitted on looks better than it is. The ranges
    apply to every experiment alike (:meth:`blockid.data.Dataset.select`), so two
    ranges overlap when their index intervals do.

    Parameters
    ----------
    estimation, validation : str or (start, stop)
        Ranges as typed (``"0:1000"``, ``"1000:"``) or as :func:`parse_range` returns.
    names : (str, str)
        How the two ranges are named in the message (their options).

    Raises
    ------
    ParameterError
        If the ranges overlap; the message names both and the shared samples.

    Examples
    --------
    >>> check_disjoint("0:1000", "1000:")
    >>> check_disjoint("0:1000", "900:2000")
    Traceback (most recent call last):
    ...
    blockid.errors.ParameterError: --estimation 0:1000 and --validation 900:2000 overlap (samples 900:1000 are in both): the model would be scored on data it was fitted on; give disjoint ranges
    """  # noqa: E501
    (e0, e1), (v0, v1) = (
        parse_range(r, name) if isinstance(r, str) else r
        for r, name in zip((estimation, validation), names, strict=True)
    )
    end = float("inf")
    lo = max(e0, v0)
    hi = min(end if e1 is None else e1, end if v1 is None else v1)
    if lo < hi:
        shared = f"{lo}:{'' if hi == end else int(hi)}"
        raise ParameterError(
            f"{names[0]} {_text(e0, e1)} and {names[1]} {_text(v0, v1)} overlap (samples "
            f"{shared} are in both): the model would be scored on data it was fitted on; "
            "give disjoint ranges"
        )


def _text(start: int, stop: int | None) -> str:
    return f"{start}:{'' if stop is None else stop}"
