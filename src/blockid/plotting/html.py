"""HTML pieces shared by the report and the notebook displays: escaped text, tables, and
figures embedded as PNG (no scripts, no external references).

They live on the plotting floor because a model's ``_repr_html_`` may reach no higher
(``docs/architecture.md``); :mod:`blockid.reporting.html` builds the report's page from
them. Text is never shortened here: long words wrap in the browser (the report's style
sheet), they are not cut.

>>> print(table(["name", "value"], [["a_1", -1.5], ["n", 3]]))
<table>
<thead><tr><th>name</th><th>value</th></tr></thead>
<tbody>
<tr><td>a_1</td><td class="num">-1.5</td></tr>
<tr><td>n</td><td class="num">3</td></tr>
</tbody>
</table>
"""

from __future__ import annotations

import base64
import io
from collections.abc import Sequence
from html import escape
from typing import Any

__all__ = ["DPI", "details", "encode_png", "figure", "image", "paragraph", "table"]

#: Resolution of the embedded figures.
DPI = 100


def encode_png(fig: Any, dpi: int = DPI) -> str:
    """The figure as base64 PNG text (no metadata, so nothing names a web site); a
    pyplot figure is closed afterwards."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi, metadata={"Software": None})
    if getattr(fig, "number", None) is not None:  # made by pyplot: release it
        import matplotlib.pyplot as plt

        plt.close(fig)
    return base64.b64encode(buffer.getvalue()).decode("ascii")


def image(png_base64: str, alt: str, style: str = "") -> str:
    """An ``<img>`` of embedded PNG text."""
    attr = f' style="{escape(style)}"' if style else ""
    return f'<img src="data:image/png;base64,{png_base64}" alt="{escape(alt)}"{attr}>'


def paragraph(text: str, cls: str | None = None) -> str:
    """A paragraph of plain text (escaped)."""
    attr = f' class="{cls}"' if cls else ""
    return f"<p{attr}>{escape(text)}</p>"


def details(summary: str, parts: Sequence[str]) -> str:
    """A folded block (``<details>``, no script): ``summary`` shown, ``parts`` (HTML)
    when the reader opens it."""
    return f"<details>\n<summary>{escape(summary)}</summary>\n" + "\n".join(parts) + "\n</details>"


def figure(png_base64: str, alt: str, caption: str) -> str:
    """An embedded PNG with its caption."""
    return (
        f"<figure>\n{image(png_base64, alt)}\n<figcaption>{escape(caption)}</figcaption>\n</figure>"
    )


def _cell(value: Any, digits: int, wrap: bool) -> str:
    if isinstance(value, float):
        return f'<td class="num">{value:.{digits}g}</td>'
    if isinstance(value, int) and not isinstance(value, bool):
        return f'<td class="num">{value}</td>'
    attr = ' class="wrap"' if wrap else ""
    return f"<td{attr}>{escape('' if value is None else str(value))}</td>"


def table(
    header: Sequence[str],
    rows: Sequence[Sequence[Any]],
    classes: Sequence[str | None] = (),
    *,
    digits: int = 4,
    wrap: Sequence[int] = (),
) -> str:
    """A table; floats in ``digits`` significant digits, right-aligned; ``classes`` per
    row (``"best"``, ``"failed"``, ``"baseline"``); the text of the columns ``wrap``
    (hashes, paths) may break anywhere to fit, other text wraps between words only."""
    head = "".join(f"<th>{escape(h)}</th>" for h in header)
    body = []
    for k, row in enumerate(rows):
        cls = classes[k] if k < len(classes) and classes[k] else None
        attr = f' class="{cls}"' if cls else ""
        cells = "".join(_cell(v, digits, c in wrap) for c, v in enumerate(row))
        body.append(f"<tr{attr}>{cells}</tr>")
    rows_html = "\n".join(body)
    return f"<table>\n<thead><tr>{head}</tr></thead>\n<tbody>\n{rows_html}\n</tbody>\n</table>"
