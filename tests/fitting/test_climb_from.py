"""``climb_from``: a polynomial state space fitted degree by degree, continued from the
fit of its lower degree on the same data (identify's climb on a fold). It must give the
whole climb's model bit for bit, and refuse what it cannot continue."""

from __future__ import annotations

import numpy as np
import pytest

from blockid.errors import ParameterError
from blockid.fitting import fit_model
from blockid.fitting.dispatch import climb_from

BASE = {"nx": 2, "monomials": "full", "max_nfev": 25}


@pytest.fixture(scope="module")
def data():
    from reference import cubic_state_record

    return cubic_state_record(800)


def _params(fit):
    return fit.model.free_parameters()


def test_the_continued_climb_is_the_whole_climb_bit_for_bit(data):
    low = fit_model(data, "polynomial-state-space", degree=2, **BASE)
    climb = dict(BASE, degree=3, start_degree=2, rung_nfev=10)
    whole = fit_model(data, "polynomial-state-space", **climb)
    continued = climb_from(low.model, 2, data, "polynomial-state-space", **climb)
    assert np.array_equal(_params(continued), _params(whole))
    assert np.array_equal(continued.model.observed_upper, whole.model.observed_upper)
    assert continued.settings["continued_from_degree"] == 2
    assert continued.estimation_metrics == whole.estimation_metrics
    # a rung further: from the climbed model, as the climb to degree 4 goes
    four = dict(climb, degree=4)
    whole4 = fit_model(data, "polynomial-state-space", **four)
    assert np.array_equal(
        _params(climb_from(whole.model, 3, data, "polynomial-state-space", **four)),
        _params(whole4),
    )


def test_what_it_cannot_continue_is_refused_by_name(data):
    low = fit_model(data, "polynomial-state-space", degree=2, **BASE)
    climb = dict(BASE, degree=3, start_degree=2)
    with pytest.raises(ParameterError, match="continues from a degree in 2..2, not 3"):
        climb_from(low.model, 3, data, "polynomial-state-space", **climb)
    with pytest.raises(ParameterError, match="not state-space"):
        climb_from(low.model, 2, data, "state-space", nx=2)
