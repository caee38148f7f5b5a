"""The report's page: inline CSS, sections, no scripts, no external references.

Tables, paragraphs and figures are the plotting floor's (:mod:`blockid.plotting.html`),
shared with the notebook displays. The style sheet (``report.css`` beside this module,
installed as package data) keeps everything inside the page's column: table text wraps
between words (hashes and paths, marked ``wrap``, anywhere), nothing is cut, a command
wraps at its spaces, and a table too wide for a narrow window scrolls inside its own box.
``CSS`` (the style element's text, as before) is still read as an attribute.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cache
from html import escape
from importlib import resources

from blockid.plotting.html import figure, paragraph, table

__all__ = ["figure", "page", "paragraph", "section", "stylesheet", "table"]

#: The style sheet, a file of the package (installed with it as package data).
_STYLESHEET = "report.css"


@cache
def stylesheet() -> str:
    """The report's style sheet (:file:`report.css` next to this module), read once."""
    return resources.files(__package__).joinpath(_STYLESHEET).read_text(encoding="utf-8")


def __getattr__(name: str) -> str:
    # CSS: the style element's text as the page embeds it, read on first use
    if name == "CSS":
        return "\n" + stylesheet()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def page(title: str, body: Sequence[str]) -> str:
    """A complete HTML5 document: inline CSS, no scripts, no external references."""
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        f"<title>{escape(title)}</title>\n<style>\n{stylesheet()}</style>\n</head>\n<body>\n"
        + "\n".join(body)
        + "\n</body>\n</html>\n"
    )


def section(anchor: str, title: str, parts: Sequence[str]) -> str:
    head = f'<section id="{escape(anchor)}">\n<h2>{escape(title)}</h2>\n'
    return head + "\n".join(parts) + "\n</section>"
