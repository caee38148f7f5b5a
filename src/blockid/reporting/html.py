"""The report's page: inline CSS, sections, no scripts, no external references.

Tables, paragraphs and figures are the plotting floor's (:mod:`blockid.plotting.html`),
shared with the notebook displays. The style sheet keeps everything inside the page's
column: table text wraps between words (hashes and paths, marked ``wrap``, anywhere),
nothing is cut, a command wraps at its spaces, and a table too wide for a narrow window
scrolls inside its own box.
"""

from __future__ import annotations

from collections.abc import Sequence
from html import escape

from blockid.plotting.html import figure, paragraph, table

__all__ = ["CSS", "figure", "page", "paragraph", "section", "table"]

CSS = """
body { font-family: sans-serif; max-width: 60em; margin: 1.5em auto; padding: 0 1em;
       color: #222; line-height: 1.4; overflow-wrap: break-word; }
h1 { font-size: 1.6em; border-bottom: 2px solid #444; padding-bottom: .2em; }
h2 { font-size: 1.25em; margin-top: 2em; border-bottom: 1px solid #aaa; }
h3 { font-size: 1.05em; margin-top: 1.5em; }
h4 { font-size: .95em; margin: 1em 0 .3em; }
table { border-collapse: collapse; margin: .6em 0; font-size: .88em; display: block;
        max-width: 100%; overflow-x: auto; }
th, td { border: 1px solid #bbb; padding: .2em .55em; overflow-wrap: normal;
         vertical-align: top; }
td.wrap { overflow-wrap: anywhere; }
th { background: #eee; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap;
         overflow-wrap: normal; }
tr.best td { background: #eef7ee; }
tr.baseline td { background: #eef2fb; }
tr.failed td { background: #fbeeee; }
figure { margin: 1em 0; }
figure img { max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption { font-size: .88em; color: #444; margin-top: .3em; }
.note { background: #fff8e0; border-left: 4px solid #e0b000; padding: .3em .6em; }
code, pre { font-family: monospace; font-size: .9em; background: #f4f4f4; }
pre { padding: .5em; white-space: pre-wrap; overflow-wrap: anywhere; }
nav ol { columns: 2; font-size: .9em; }
details { margin: .6em 0; }
summary { font-size: .92em; color: #333; }
"""


def page(title: str, body: Sequence[str]) -> str:
    """A complete HTML5 document: inline CSS, no scripts, no external references."""
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        f"<title>{escape(title)}</title>\n<style>{CSS}</style>\n</head>\n<body>\n"
        + "\n".join(body)
        + "\n</body>\n</html>\n"
    )


def section(anchor: str, title: str, parts: Sequence[str]) -> str:
    head = f'<section id="{escape(anchor)}">\n<h2>{escape(title)}</h2>\n'
    return head + "\n".join(parts) + "\n</section>"
