"""Tests of blockid.data.ranges: parse_range and check_disjoint."""

from __future__ import annotations

import pytest

from blockid.data import parse_range
from blockid.data.ranges import check_disjoint
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


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
def test_a_malformed_range_shows_the_form_and_its_examples():
    with pytest.raises(ParameterError) as info:
        parse_range("10", "--estimation")
    assert str(info.value).startswith(
        "--estimation expects START:STOP (0-based sample indices, STOP excluded), "
        "e.g. 0:1000, 1000: or :500"
    )


# check_disjoint: the shared samples and both ranges as typed, for open and closed ends
# (gaps found by mutation testing, see docs/testing.md)
_SCORED = "the model would be scored on data it was fitted on; give disjoint ranges"


@pytest.mark.parametrize(
    ("estimation", "validation", "text"),
    [
        ("0:1000", "900:2000", "--estimation 0:1000 and --validation 900:2000 overlap "
         "(samples 900:1000 are in both)"),
        ("0:1000", "0:500", "--estimation 0:1000 and --validation 0:500 overlap "
         "(samples 0:500 are in both)"),
        ("0:1000", "500:", "--estimation 0:1000 and --validation 500: overlap "
         "(samples 500:1000 are in both)"),
        ("500:", "0:1000", "--estimation 500: and --validation 0:1000 overlap "
         "(samples 500:1000 are in both)"),
        (":", "10:", "--estimation 0: and --validation 10: overlap (samples 10: are in both)"),
        ((0, None), (10, 20), "--estimation 0: and --validation 10:20 overlap "
         "(samples 10:20 are in both)"),
    ],
)  # fmt: skip
def test_overlapping_ranges_name_both_and_the_shared_samples(estimation, validation, text):
    with pytest.raises(ParameterError) as info:
        check_disjoint(estimation, validation)
    assert str(info.value) == f"{text}: {_SCORED}"


@pytest.mark.parametrize(
    ("estimation", "validation"),
    [("0:1000", "1000:"), ("1000:", "0:1000"), ((1000, None), (0, 1000)), ((0, 5), (5, 6))],
)
def test_ranges_that_only_touch_are_disjoint(estimation, validation):
    assert check_disjoint(estimation, validation) is None


def test_the_overlap_uses_the_names_given():
    with pytest.raises(ParameterError) as info:
        check_disjoint((0, 10), (5, None), names=("fit", "check"))
    assert str(info.value) == f"fit 0:10 and check 5: overlap (samples 5:10 are in both): {_SCORED}"


def test_a_malformed_range_is_reported_under_its_option():
    with pytest.raises(ParameterError) as info:
        check_disjoint("0:10", "abc")
    assert str(info.value) == (
        "--validation expects START:STOP (0-based sample indices, STOP excluded), "
        "e.g. 0:1000, 1000: or :500; got 'abc'"
    )


def test_names_must_be_one_per_range():
    with pytest.raises(ValueError, match="zip\\(\\) argument 2 is longer than argument 1"):
        check_disjoint("0:10", "10:", names=("--estimation", "--validation", "--test"))


def test_overlapping_ranges_are_refused():
    check_disjoint("0:100", "100:")
    check_disjoint((200, None), (0, 200))
    with pytest.raises(ParameterError, match=r"overlap \(samples 50:100 are in both\)"):
        check_disjoint("0:100", "50:")
    with pytest.raises(ParameterError, match=r"samples 10: are in both"):
        check_disjoint(":", "10:")
