"""The range syntax error shows the whole form with its examples; overlapping estimation
and validation ranges are refused with both ranges and the shared samples as typed (gaps
found by mutation testing, see docs/testing.md)."""

import pytest

from blockid.data.ranges import check_disjoint, parse_range
from blockid.errors import ParameterError


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
