"""Tests of blockid.plotting.invariants: what a state space's parameters say without its
state basis (the same numbers in any basis), and which parameters depend on it."""

import numpy as np
import pytest

from blockid.blocks import Polynomial
from blockid.models.block_state_space import BlockStateSpace
from blockid.models.state_space import PolynomialStateSpace, StateSpace, monomial_exponents
from blockid.plotting.invariants import basis_dependent, invariants, matrix_rows


def _model(seed=0, nx=3, nu=2, ny=2):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((nx, nx))
    A *= 0.8 / np.max(np.abs(np.linalg.eigvals(A)))
    return StateSpace([f"u{j}" for j in range(nu)], [f"y{i}" for i in range(ny)], A,
                      rng.standard_normal((nx, nu)), rng.standard_normal((ny, nx)),
                      rng.standard_normal((ny, nu)), input_scale=[2.0, 0.5],
                      output_scale=[3.0, 0.1])  # fmt: skip


def test_the_invariants_are_the_same_in_any_state_basis():
    m = _model()
    T = np.random.default_rng(1).standard_normal((3, 3)) + 3 * np.eye(3)
    Ti = np.linalg.inv(T)
    other = m.replace(A=T @ m.A @ Ti, B=T @ m.B, C=m.C @ Ti)
    a, b = invariants(m), invariants(other)
    assert a.names == b.names
    np.testing.assert_allclose(a.values, b.values, rtol=1e-8, atol=1e-12)
    assert not np.allclose(m.free_parameters(), other.free_parameters())
    # in the signals' units: the static gain of each pair is the transfer function's
    gains = dict(zip(a.names, a.values, strict=True))
    for i in range(2):
        for j in range(2):
            num, den = m.transfer_function(i, j)
            expected = np.polyval(num, 1.0) / np.polyval(den, 1.0)
            assert gains[f"static gain y{i} / u{j}"] == pytest.approx(expected, rel=1e-9)
    assert a.standard_errors is None and a.rows()[0][2:] == ["n/a", "n/a"]
    # MIMO: the Markov parameters of every pair, at most 40 rows of them
    assert a.n_markov == 6 and sum(n.startswith("Markov") for n in a.names) == 24


def test_which_parameters_depend_on_the_basis():
    expo = monomial_exponents(2, 1, 2, "full")  # x1², x1 x2, x1 u, x2², x2 u, u²
    m = PolynomialStateSpace(["u"], ["y"], 0.5 * np.eye(2), np.ones((2, 1)), np.ones((1, 2)),
                             np.zeros((1, 1)), exponents=expo)  # fmt: skip
    mask = dict(zip(m.free_parameter_names(), basis_dependent(m), strict=True))
    on_input = [k for k, row in enumerate(expo.tolist()) if row[:2] == [0, 0]]
    assert on_input and all(not mask[f"F[0,{k}]"] for k in on_input)
    assert all(mask[f"F[0,{k}]"] for k in range(len(expo)) if k not in on_input)
    assert mask["A[1,0]"] and mask["E[1,3]"] and not mask["D[0,0]"]
    bss = BlockStateSpace(["u"], ["y"], A=[[0.5]], B=[[1.0]], C=[[1.0]], D=[[0.0]],
                          input_blocks=Polynomial([0.0, 1.0, 0.3]))  # fmt: skip
    mask = dict(zip(bss.free_parameter_names(), basis_dependent(bss), strict=True))
    assert mask["A[0,0]"] and mask["e[0]"]
    assert not any(v for n, v in mask.items() if n.startswith(("input u", "h[", "D[")))
    assert basis_dependent(Polynomial([0.0, 1.0])) is None
    assert matrix_rows(bss) == [["A[0,:]", "0.5"], ["B[0,:]", "1"], ["C[0,:]", "1"], ["e", "0"]]
