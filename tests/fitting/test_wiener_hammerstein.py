"""Wiener-Hammerstein from the split of the best linear approximation."""

import numpy as np
import pytest

from blockid.blocks import LinearBlock, Polynomial
from blockid.data import Dataset
from blockid.fitting import fit_model
from blockid.fitting.wiener_hammerstein import split_candidates
from blockid.models import WienerHammerstein


def plant():
    return WienerHammerstein(
        "u",
        "y",
        first=LinearBlock(2, 1, 1, a=[-1.3, 0.5], b=[0.4]),
        static=Polynomial([0.05, 1.0, 0.2, -0.15]),
        second=LinearBlock(2, 2, 0, a=[-0.9, 0.3], b=[1.0, 0.5]),
    )


def _poles(block):
    return np.sort_complex(np.roots(np.concatenate(([1.0], block.a))))


def test_splits_cover_every_assignment_of_pole_and_zero_units():
    g = LinearBlock(4, 3, 1, a=np.real(np.poly([0.5, 0.8, 0.6 + 0.3j, 0.6 - 0.3j]))[1:],
                    b=[1.0, -0.2, 0.3])  # fmt: skip
    splits = split_candidates(g)
    # poles: two real + one pair = 3 units; zeros: a complex pair = 1 unit -> 2^4 splits
    assert len(splits) == 16
    for g1, g2 in splits:
        assert g1.na + g2.na == 4 and (g1.nb - 1) + (g2.nb - 1) == 2
        assert g2.nk == 0 and g2.b[0] == 1.0 and g1.nk == 1


def test_at_40_db_both_linear_blocks_and_the_nonlinearity_are_recovered_within_5_percent():
    truth = plant()
    rng = np.random.default_rng(0)
    u = rng.standard_normal(6000)
    y_clean = truth.simulate(u)[:, 0]
    noise = rng.standard_normal(u.size)
    noise *= np.std(y_clean) / np.std(noise) * 10 ** (-40 / 20)  # 40 dB
    data = Dataset.from_arrays(u, y_clean + noise, ["u"], ["y"])
    fit = fit_model(data, "wiener-hammerstein", na=4, nb=2, nk=1, r2=3, center=False)
    model = fit.model
    for got, want in ((model.blocks[0], truth.blocks[0]), (model.blocks[2], truth.blocks[2])):
        np.testing.assert_allclose(_poles(got), _poles(want), rtol=0.05)
    # the nonlinearity, compared where the data put x, through the normalisation
    x_true = truth.blocks[0].simulate(u)
    x_fit = model.blocks[0].simulate(u)
    gain = np.dot(x_fit, x_true) / np.dot(x_true, x_true)
    grid = np.linspace(np.percentile(x_true, 1), np.percentile(x_true, 99), 50)
    n_true = truth.blocks[1](grid)
    n_fit = model.blocks[1](gain * grid)
    spread = np.ptp(n_true)
    assert np.max(np.abs(n_fit - n_true)) < 0.05 * spread
    assert fit.settings["final_simulation_mse"] < 1.5 * np.var(noise)


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
def test_bla_arx_start_skips_the_first_sample_even_for_a_static_gain():
    # na = 0, nb = 1, nk = 0: y(k) = b u(k); the regression still starts at k = 1
    from blockid.fitting.wiener_hammerstein import _arx

    rng = np.random.default_rng(1)
    u, y = rng.standard_normal(20), rng.standard_normal(20)
    a, b = _arx([u], [y], 0, 1, 0)
    assert a.size == 0
    assert b[0] == pytest.approx(np.dot(u[1:], y[1:]) / np.dot(u[1:], u[1:]), rel=1e-12)


def test_roots_with_a_tiny_imaginary_part_are_a_conjugate_pair():
    from blockid.fitting.wiener_hammerstein import _units

    # |imag| = 1.5e-9 > 1e-9 * max(1, |r|) for |r| = 0.5: a pair, not two real roots
    roots = np.array([0.5 + 1.5e-9j, 0.3, 0.5 - 1.5e-9j])
    units = _units(roots)
    assert [u.size for u in units] == [2, 1]
    np.testing.assert_array_equal(units[0], [0.5 + 1.5e-9j, 0.5 - 1.5e-9j])
    # within the tolerance: real
    assert [u.size for u in _units(np.array([0.5 + 0.5e-9j, 0.5 - 0.5e-9j]))] == [1, 1]
    # the tolerance grows with |r| beyond 1
    assert [u.size for u in _units(np.array([3.0 + 2e-9j, 3.0 - 2e-9j]))] == [1, 1]


def test_wiener_hammerstein_passes_gtol_to_the_refinement():
    from blockid.blocks import LinearBlock, Polynomial
    from blockid.fitting.wiener_hammerstein import fit_wiener_hammerstein
    from blockid.models import WienerHammerstein

    truth = WienerHammerstein(
        "u",
        "y",
        first=LinearBlock(1, 1, 1, a=[-0.5], b=[0.4]),
        static=Polynomial([0.0, 1.0, 0.2]),
        second=LinearBlock(1, 1, 0, a=[-0.3], b=[1.0]),
    )
    u = np.random.default_rng(0).standard_normal(400)
    data = Dataset.from_arrays(u, truth.simulate(u)[:, 0] + 0.01, ["u"], ["y"])
    kwargs = dict(na=2, nb=1, nk=1, r2=2, starts=1, tail_fraction=0.0, max_nfev=20)
    loose = fit_wiener_hammerstein(data, gtol=1e6, **kwargs)
    assert loose.settings["stop_reason"] == "`gtol` termination condition is satisfied."
    assert loose.settings["iterations"] == 0
    tight = fit_wiener_hammerstein(data, **kwargs)
    assert tight.settings["iterations"] > 0  # the default gtol lets it iterate


def test_wiener_hammerstein_records_the_bla():
    from blockid.blocks import LinearBlock, Polynomial
    from blockid.fitting.wiener_hammerstein import fit_wiener_hammerstein
    from blockid.models import WienerHammerstein

    truth = WienerHammerstein(
        "u",
        "y",
        first=LinearBlock(1, 1, 1, a=[-0.5], b=[0.4]),
        static=Polynomial([0.0, 1.0, 0.2]),
        second=LinearBlock(1, 1, 0, a=[-0.3], b=[1.0]),
    )
    u = np.random.default_rng(0).standard_normal(300)
    data = Dataset.from_arrays(u, truth.simulate(u)[:, 0], ["u"], ["y"])
    fit = fit_wiener_hammerstein(data, na=2, nb=1, nk=1, r2=2, starts=1, max_nfev=3)
    bla = fit.settings["bla"]
    assert (bla["na"], bla["nb"], bla["nk"]) == (2, 1, 1)
    assert 0.0 < bla["simulation_mse"] < np.var(data.experiments[0].y)


def test_bla_arx_with_a_zero_regressor_column_reports_rank_deficiency():
    # u is 0 up to its last sample: the column u(t-1) is all zero (its scale is set to 1)
    from blockid.errors import EstimationError
    from blockid.fitting.wiener_hammerstein import _arx

    u = np.zeros(20)
    u[-1] = 1.0
    y = np.random.default_rng(0).standard_normal(20)
    with pytest.raises(EstimationError, match=r"^least squares is rank deficient: regressor col"):
        _arx([u], [y], 1, 1, 1)
