"""The threads of one fit: fixed tiles of ``J^T J`` summed in the record's order, and
the same model bit for bit with one thread or two (numba's threads included)."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from blockid.config import config_context, get_config
from blockid.fitting import threads as th

TILE = get_config()["tile_columns"]


def test_the_tiles_sum_to_the_dense_normal_equations():
    """Pieces of a Jacobian over part of the unknowns (an experiment's own columns):
    the tiles (about 7 columns wide: 4 column blocks of a piece's 25 columns) add up to
    ``J^T J`` and ``-J^T r`` of the whole, mirrored exactly."""
    rng = np.random.default_rng(0)
    n = 30
    cols = np.r_[0:20, 25:30]
    pieces = [(rng.standard_normal((50, cols.size)), rng.standard_normal(50)) for _ in range(3)]
    results = []
    for threads in (1, 2, 3):
        with config_context(tile_columns=7), th.NormalSums(n, threads) as sums:
            assert len(th._tiles(cols.size)) == 10  # 4 x 5 / 2 upper tiles
            for J, r in pieces:
                sums.add(J, r, cols)
            H, g = sums.result()
        results.append((H, g, sums.cost))
    J_all = np.zeros((150, n))
    J_all[:, cols] = np.vstack([J for J, _ in pieces])
    r_all = np.concatenate([r for _, r in pieces])
    H, g, cost = results[0]
    np.testing.assert_allclose(H, J_all.T @ J_all, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(g, -J_all.T @ r_all, rtol=1e-12, atol=1e-12)
    assert cost == pytest.approx(r_all @ r_all)
    assert np.array_equal(H, H.T)
    for other in results[1:]:
        assert np.array_equal(other[0], H) and np.array_equal(other[1], g)


def test_the_tiles_are_fixed_by_the_size_alone():
    assert len(th._tiles(2 * TILE)) == 3  # two column blocks: (0, 0), (0, 1), (1, 1)
    assert len(th._tiles(4 * TILE)) == 10
    assert len(th._tiles(2 * th.MIN_TILE)) == 3  # a mid-sized problem: still two blocks
    assert th._tiles(10) == ((slice(0, 10), slice(0, 10)),)
    covered = np.zeros((300, 300), dtype=int)
    for a, b in th._tiles(300):
        covered[a, b] += 1
    assert np.all(covered[np.triu_indices(300)] == 1)  # every upper entry, once


def test_a_problem_of_one_tile_is_summed_without_a_pool():
    """Handing a small problem's only tile to a pool thread bought nothing but the
    hand-over (the Silverbox's 62 unknowns: 13 ms an iteration waiting on it); it is
    summed by the caller, and a larger problem still gets its threads."""
    with th.NormalSums(10, 2) as sums:
        assert sums.threads == 1 and sums.pool is None
    with th.NormalSums(4 * TILE, 2) as sums:
        assert sums.threads == 2 and sums.pool is not None


def test_fit_threads_limits_and_restores():
    before = th.threads_for_fit()
    with th.fit_threads(1):
        assert th.threads_for_fit() == 1
        with th.fit_threads(None):
            assert th.threads_for_fit() == before
    assert th.threads_for_fit() == before


_FIT = """
import json, sys
import numpy as np
from blockid.data import Dataset
from blockid.fitting import fit_model
from blockid.fitting.threads import fit_threads
from blockid.models.state_space import PolynomialStateSpace, monomial_exponents
rng = np.random.default_rng(0)
expo = monomial_exponents(3, 1, 3, "full", constant=True)
plant = PolynomialStateSpace(["u"], ["y"], [[0.7, 0.2, 0], [-0.2, 0.7, 0], [0, 0, 0.5]],
    [[1.0], [0.3], [0.5]], [[1.0, 0.0, 0.5]], [[0.0]],
    0.02 * rng.standard_normal((3, expo.shape[0])), np.zeros((1, expo.shape[0])), expo,
    lower=np.full(4, -3.0), upper=np.full(4, 3.0))
u = rng.uniform(-1, 1, 3000)
y = plant.simulate(u)[:, 0] + 0.01 * rng.standard_normal(3000)
data = Dataset.from_arrays(u, y)
out = {}
for n in (1, 2):
    with fit_threads(n):
        fit = fit_model(data, "polynomial-state-space", nx=3, degree=3, max_nfev=6)
    out[n] = fit.model.free_parameters().tobytes().hex()
import numba
print(json.dumps({"same": out[1] == out[2], "numba": numba.config.NUMBA_NUM_THREADS}))
"""


def test_one_thread_or_two_give_the_same_model_bit_for_bit():
    """In a fresh process allowed two numba threads (the tests run with one): the
    kernel's column blocks and the tiles on one thread or two, the same parameters."""
    env = {**os.environ, "NUMBA_NUM_THREADS": "2", "OPENBLAS_NUM_THREADS": "2",
           "OMP_NUM_THREADS": "2"}  # fmt: skip
    code = _FIT.replace("from blockid.fitting.threads import fit_threads",
                        "from blockid.config import set_config\nset_config(tile_columns=16)\n"
                        "from blockid.fitting.threads import fit_threads")  # fmt: skip
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         timeout=600)  # fmt: skip
    assert run.returncode == 0, run.stderr[-2000:]
    result = json.loads(run.stdout.strip().splitlines()[-1])
    assert result == {"same": True, "numba": 2}
