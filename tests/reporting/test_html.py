"""The report's style sheet is a file of the package (report.css), not a Python string:
found through importlib.resources, declared as package data so that an installed
blockid has it, and embedded in every page as it stands."""

from __future__ import annotations

import fnmatch
import tomllib
from importlib import resources
from pathlib import Path

from blockid.reporting import html

ROOT = Path(__file__).parents[2]


def test_the_style_sheet_file_is_found_and_not_empty():
    sheet = resources.files("blockid.reporting").joinpath("report.css")
    assert sheet.is_file()
    text = sheet.read_text(encoding="utf-8")
    assert text.strip() and "body {" in text and text.endswith("}\n")
    assert html.stylesheet() == text
    assert html.stylesheet() is html.stylesheet()  # read once


def test_the_page_embeds_the_style_sheet_unchanged():
    doc = html.page("t", ["<p>x</p>"])
    assert f"<style>\n{html.stylesheet()}</style>\n" in doc
    assert html.CSS == "\n" + html.stylesheet()  # the style element's text, as before


def test_the_style_sheet_is_package_data():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    patterns = config["tool"]["setuptools"]["package-data"]["blockid"]
    assert any(fnmatch.fnmatch("reporting/report.css", p) for p in patterns)


def test_no_style_sheet_is_written_in_python():
    source = (ROOT / "src" / "blockid" / "reporting" / "html.py").read_text(encoding="utf-8")
    assert "font-family" not in source and "border-collapse" not in source
