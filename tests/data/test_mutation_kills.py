"""The range syntax error shows the whole form with its examples (a gap found by
mutation testing, see docs/testing.md)."""

import pytest

from blockid.data.ranges import parse_range
from blockid.errors import ParameterError


def test_a_malformed_range_shows_the_form_and_its_examples():
    with pytest.raises(ParameterError) as info:
        parse_range("10", "--estimation")
    assert str(info.value).startswith(
        "--estimation expects START:STOP (0-based sample indices, STOP excluded), "
        "e.g. 0:1000, 1000: or :500"
    )
