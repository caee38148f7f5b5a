"""The example records (workflows/examples.py): the names offered, one record whose time
runs on from the estimation into the validation experiment, the same for the same seed."""

import numpy as np
import pytest

from blockid.errors import ParameterError
from blockid.workflows.examples import EXAMPLES, check_example, example_record


def test_an_unknown_example_is_refused_with_the_names_offered():
    for name in EXAMPLES:
        check_example(name)
    with pytest.raises(
        ParameterError,
        match=r"^unknown example 'arm'; choose one of electrohydraulic, windtunnel-110kPa, "
        r"windtunnel-130kPa$",
    ) as caught:
        example_record("arm")
    assert caught.value.parameter == "name"


def test_the_two_experiments_form_one_record_the_same_for_the_same_seed():
    record = example_record("windtunnel-130kPa", seed=2)
    t = record.frame["t"].to_numpy()
    steps = np.diff(t)
    np.testing.assert_allclose(steps, steps[0], rtol=1e-9)  # no jump at the join
    assert record.estimation == (0, record.validation[0])
    assert record.validation[1] == len(record.frame) and record.seed == 2
    again = example_record("windtunnel-130kPa", seed=2).frame
    assert again.equals(record.frame)
    other = example_record("windtunnel-130kPa", seed=3).frame
    assert not np.allclose(other["y1"], record.frame["y1"])
