"""HTML pieces of the report: one page, inline CSS, no scripts, no external references."""

from __future__ import annotations

from collections.abc import Sequence
from html import escape
from typing import Any

__all__ = ["CSS", "figure", "page", "paragraph", "section", "table"]

CSS = """
body { font-family: sans-serif; max-width: 60em; margin: 1.5em auto; padding: 0 1em;
       color: #222; line-height: 1.4; }
h1 { font-size: 1.6em; border-bottom: 2px solid #444; padding-bottom: .2em; }
h2 { font-size: 1.25em; margin-top: 2em; border-bottom: 1px solid #aaa; }
h3 { font-size: 1.05em; margin-top: 1.5em; }
table { border-collapse: collapse; margin: .6em 0; font-size: .88em; }
th, td { border: 1px solid #bbb; padding: .2em .55em; }
th { background: #eee; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.best td { background: #eef7ee; }
tr.failed td { background: #fbeeee; }
figure { margin: 1em 0; }
figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: .88em; color: #444; margin-top: .3em; }
.note { background: #fff8e0; border-left: 4px solid #e0b000; padding: .3em .6em; }
code, pre { font-family: monospace; font-size: .9em; background: #f4f4f4; }
pre { padding: .5em; white-space: pre-wrap; word-break: break-all; }
nav ol { columns: 2; font-size: .9em; }
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


def paragraph(text: str, cls: str | None = None) -> str:
    """A paragraph of plain text (escaped)."""
    attr = f' class="{cls}"' if cls else ""
    return f"<p{attr}>{escape(text)}</p>"


def figure(png_base64: str, alt: str, caption: str) -> str:
    """An embedded PNG with its caption."""
    return (
        f'<figure>\n<img src="data:image/png;base64,{png_base64}" alt="{escape(alt)}">\n'
        f"<figcaption>{escape(caption)}</figcaption>\n</figure>"
    )


def _cell(value: Any) -> str:
    if isinstance(value, float):
        return f'<td class="num">{value:.4g}</td>'
    if isinstance(value, int) and not isinstance(value, bool):
        return f'<td class="num">{value}</td>'
    return f"<td>{escape('' if value is None else str(value))}</td>"


def table(
    header: Sequence[str], rows: Sequence[Sequence[Any]], classes: Sequence[str | None] = ()
) -> str:
    """A table; floats in 4 significant digits, right-aligned; ``classes`` per row."""
    head = "".join(f"<th>{escape(h)}</th>" for h in header)
    body = []
    for k, row in enumerate(rows):
        cls = classes[k] if k < len(classes) and classes[k] else None
        attr = f' class="{cls}"' if cls else ""
        body.append(f"<tr{attr}>" + "".join(_cell(v) for v in row) + "</tr>")
    rows_html = "\n".join(body)
    return f"<table>\n<thead><tr>{head}</tr></thead>\n<tbody>\n{rows_html}\n</tbody>\n</table>"
