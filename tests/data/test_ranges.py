"""Tests of blockid.data.ranges.parse_range."""

from __future__ import annotations

import pytest

from blockid.data import parse_range
from blockid.errors import ParameterError


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("0:1000", (0, 1000)),
        ("1000:", (1000, None)),
        (":500", (0, 500)),
        (" 10 : 20 ", (10, 20)),
        (":", (0, None)),
        ("1_000:2_000", (1000, 2000)),
    ],
)
def test_parse_range_forms(text, expected):
    assert parse_range(text, "--estimation") == expected


@pytest.mark.parametrize("text", ["100", "1..5", "1:2:3", "", "a:b", "1.5:3"])
def test_parse_range_bad_form_names_option_and_form(text):
    with pytest.raises(ParameterError) as info:
        parse_range(text, "--validation")
    message = str(info.value)
    assert message.startswith("--validation expects START:STOP")
    assert "e.g. 0:1000, 1000: or :500" in message


def test_parse_range_rejects_negative():
    with pytest.raises(ParameterError, match=r"--estimation .*negative indices such as -5"):
        parse_range("-5:", "--estimation")


def test_parse_range_rejects_empty_range():
    with pytest.raises(ParameterError, match=r"'30:10' is empty"):
        parse_range("30:10", "--estimation")
