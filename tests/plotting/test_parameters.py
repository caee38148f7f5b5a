"""Tests of blockid.plotting.parameters: the parameter table of every model kind, with the
standard errors a fit carries."""

import dataclasses

import numpy as np
import pytest

from blockid.data import Dataset
from blockid.fitting import fit_model
from blockid.plotting.parameters import parameter_table


def test_values_are_the_free_parameters_and_errors_the_covariance_diagonal(hammerstein_fit):
    fit, _, _ = hammerstein_fit
    t = parameter_table(fit.model, fit)
    assert t.names == fit.model.free_parameter_names()
    np.testing.assert_array_equal(t.values, fit.model.free_parameters())
    matrix = np.array(fit.settings["covariance"]["matrix"], float)
    np.testing.assert_allclose(t.standard_errors, np.sqrt(np.diag(matrix)))
    assert t.n_fixed == 1  # b_0 = 1 after the input block
    rows = t.rows()
    assert [r[0] for r in rows] == t.names
    assert [r[1] for r in rows] == t.values.tolist()
    k = t.names.index("a_1")
    assert rows[k][3] == pytest.approx(100 * t.standard_errors[k] / abs(t.values[k]), rel=1e-2)
    assert any("parameter covariance" in n for n in t.notes())


def test_without_a_fit_or_errors_the_table_says_so(hammerstein_fit):
    fit, _, _ = hammerstein_fit
    plain = parameter_table(fit.model)
    assert plain.standard_errors is None
    assert all(r[2] == "n/a" for r in plain.rows())
    assert plain.notes()[0].startswith("No standard errors")
    # only standard errors (by name), no covariance
    by_name = {n: 0.5 for n in fit.model.free_parameter_names()}
    only = dataclasses.replace(fit, settings={"standard_errors": by_name})
    t = parameter_table(fit.model, only)
    np.testing.assert_array_equal(t.standard_errors, 0.5)
    assert "settings['standard_errors']" in t.source


def test_an_undetermined_parameter_is_said_to_be_so(hammerstein_fit):
    fit, _, _ = hammerstein_fit
    record = dict(fit.settings["covariance"])
    matrix = [list(row) for row in record["matrix"]]
    matrix[0][0] = None  # infinite: written null in JSON
    record["matrix"] = matrix
    t = parameter_table(fit.model, dataclasses.replace(fit, settings={"covariance": record}))
    assert t.rows()[0][2] == "not determined"


def test_an_arx_model_lists_every_coefficient_with_its_error():
    rng = np.random.default_rng(0)
    u = rng.standard_normal(400)
    y = np.zeros(400)
    for k in range(2, 400):
        y[k] = 1.2 * y[k - 1] - 0.35 * y[k - 2] + u[k - 1] + 0.01 * rng.standard_normal()
    data = Dataset.from_arrays(u + 2.0, y + 5.0, ["u"], ["y"])
    fit = fit_model(data, "arx", na=2, nb=1, nk=1, center=True, standard_errors=True)
    t = parameter_table(fit.model, fit)
    assert t.names == fit.model.parameter_names(0)
    np.testing.assert_array_equal(t.values, fit.model.parameter_vector(0))
    np.testing.assert_allclose(t.values, [-1.2, 0.35, 1.0], atol=0.02)
    assert np.all(t.standard_errors > 0) and np.all(t.standard_errors < 0.02)
    assert t.n_fixed == 0
    assert set(t.operating_point) == {"u", "y"}  # centred: the means, not estimated
    assert any(n.startswith("Operating point") for n in t.notes())
