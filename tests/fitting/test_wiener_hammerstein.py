"""Wiener-Hammerstein from the split of the best linear approximation."""

import numpy as np

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
