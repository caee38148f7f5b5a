"""A small HTML reader for the report tests: what a person sees in each section."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from html.parser import HTMLParser

_TRACKED = ("h3", "p", "figcaption", "td", "th")


@dataclass
class Part:
    """What follows one ``<h3>`` of a section (or the section's head, ``title=""``)."""

    title: str = ""
    paragraphs: list[str] = field(default_factory=list)
    tables: list[list[list[str]]] = field(default_factory=list)
    captions: list[str] = field(default_factory=list)
    classes: list[list[str | None]] = field(default_factory=list)  # row classes per table


class Report(HTMLParser):
    """``sections[anchor]``: the parts of each ``<section id=anchor>``; ``texts``: every
    text node of the page (for checks on what is written)."""

    def __init__(self, html: str) -> None:
        super().__init__()
        self.sections: dict[str, list[Part]] = {}
        self.texts: list[str] = []
        self._stack: list[str] = []
        self._buffer: list[str] | None = None
        self._section: str | None = None
        self.feed(html)
        self.close()

    @property
    def _part(self) -> Part:
        return self.sections[self._section][-1]

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "section":
            self._section = attrs.get("id")
            self.sections[self._section] = [Part()]
        elif self._section is None:
            return
        elif tag in _TRACKED:
            self._buffer = []
        elif tag == "table":
            self._part.tables.append([])
            self._part.classes.append([])
        elif tag == "tr":
            self._part.tables[-1].append([])
            self._part.classes[-1].append(attrs.get("class"))

    def handle_endtag(self, tag):
        if tag == "section":
            self._section = None
        if self._section is None or self._buffer is None or tag not in _TRACKED:
            return
        text = " ".join("".join(self._buffer).split())
        self._buffer = None
        if tag == "h3":
            self.sections[self._section].append(Part(text))
        elif tag == "p":
            self._part.paragraphs.append(text)
        elif tag == "figcaption":
            self._part.captions.append(text)
        else:
            self._part.tables[-1][-1].append(text)

    def handle_data(self, data):
        self.texts.append(data)
        if self._buffer is not None:
            self._buffer.append(data)

    def part(self, section: str, title: str) -> Part:
        (found,) = [p for p in self.sections[section] if p.title == title]
        return found


IMG = re.compile(r'<img src="data:image/png;base64,([A-Za-z0-9+/=]+)"')


def _number(text: str) -> float:
    return float(text)
