"""The state-space kernels against slow references written from their equations."""

import numpy as np

from blockid._kernels.state_space import channel_response


def _channel_response_reference(A, B, C, D, chans, G, X0):
    """x_q(k+1) = A x_q(k) + B[:, chans[q]] G[k, q];  out[k, :, q] = C x_q(k) + D[:, chans[q]] G[k, q]."""
    N, p = G.shape
    out = np.zeros((N, C.shape[0], p))
    X = X0.copy()
    for q in range(p):
        x = X0[:, q].copy()
        for k in range(N):
            out[k, :, q] = C @ x + D[:, chans[q]] * G[k, q]
            x = A @ x + B[:, chans[q]] * G[k, q]
        X[:, q] = x
    return out, X


def test_channel_response_matches_the_equations_and_carries_its_state():
    rng = np.random.default_rng(0)
    nx, nu, ny, p, N = 3, 2, 2, 4, 150
    A = 0.4 * rng.standard_normal((nx, nx))
    B, C, D = (
        rng.standard_normal((nx, nu)),
        rng.standard_normal((ny, nx)),
        rng.standard_normal((ny, nu)),
    )
    chans = np.array([0, 1, 1, 0], dtype=np.int64)
    G = rng.standard_normal((N, p))
    X0 = rng.standard_normal((nx, p))
    want, X_end = _channel_response_reference(A, B, C, D, chans, G, X0)
    # in two pieces, the state carried between them
    X = X0.copy()
    first, second = np.zeros((60, ny, p)), np.zeros((N - 60, ny, p))
    channel_response(A, B, C, D, chans, G[:60].copy(), X, first)
    channel_response(A, B, C, D, chans, G[60:].copy(), X, second)
    np.testing.assert_allclose(np.concatenate((first, second)), want, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(X, X_end, rtol=1e-12, atol=1e-12)


# ------------------------------------------------------------ the two-pass parallel walk
def _pnlss_arrays(rng, nx, nu, ny, degree=3, bound=1.0):
    from blockid.models.state_space import monomial_exponents

    expo = monomial_exponents(nx, nu, degree, "full", constant=True)
    nm = expo.shape[0]
    A = np.diag(rng.uniform(0.3, 0.8, nx)) + 0.05 * rng.standard_normal((nx, nx))
    return (A, rng.standard_normal((nx, nu)), rng.standard_normal((ny, nx)),
            rng.standard_normal((ny, nu)), 0.05 * rng.standard_normal((nx, nm)),
            0.05 * rng.standard_normal((ny, nm)), expo, np.full(nx + nu, -bound),
            np.full(nx + nu, bound))  # fmt: skip


def _walked(arrays, u, x0, columns=None, pieces=(0,)):
    """``pnlss_walk`` over ``u`` cut at ``pieces``, the state carried: (y, J, x, S)."""
    from blockid._kernels.state_space import INITIAL, pnlss_columns, pnlss_walk

    nx, nu, ny, nm = arrays[0].shape[0], arrays[1].shape[1], arrays[2].shape[0], arrays[6].shape[0]
    desc = pnlss_columns(nx, nu, ny, nm) if columns is None else columns
    S = np.zeros((nx, desc[0].size))
    init = np.flatnonzero(desc[0] == INITIAL)
    S[desc[1][init], init] = 1.0
    x = x0.copy()
    ys, Js = [], []
    for a, b in zip(pieces, [*pieces[1:], u.shape[0]], strict=True):
        y, J = np.zeros((b - a, ny)), np.zeros(((b - a) * ny, desc[0].size))
        pnlss_walk(*arrays, np.ascontiguousarray(u[a:b]), x, S, y, J, desc)
        ys.append(y)
        Js.append(J)
    return np.vstack(ys), np.vstack(Js), x, S


def test_the_parallel_walk_is_its_single_threaded_twin_bit_for_bit():
    """The two-pass walk (trajectory, then column blocks on numba's threads) gives the
    one-pass walk's (``reference.py``) outputs, sensitivities, carried state and carried sensitivity
    exactly, over more columns than one block and in pieces."""
    from blockid._kernels.state_space import COLUMN_BLOCK

    from reference import pnlss_jacobian

    for seed, (nx, nu, ny) in enumerate([(2, 1, 2), (3, 2, 1), (5, 1, 1)]):
        rng = np.random.default_rng(seed)
        arrays = _pnlss_arrays(rng, nx, nu, ny)
        u = rng.standard_normal((400, nu))
        x0 = 0.3 * rng.standard_normal(nx)
        y, J, x, S = _walked(arrays, u, x0, pieces=(0, 150, 151))
        P = J.shape[1]
        S0 = np.zeros((nx, P))
        S0[:, P - nx :] = np.eye(nx)
        y1, J1, x1 = np.zeros((400, ny)), np.zeros((400 * ny, P)), x0.copy()
        pnlss_jacobian(*arrays, u, x1, S0, y1, J1)
        assert P > COLUMN_BLOCK or seed < 2
        assert np.array_equal(y, y1) and np.array_equal(J, J1)
        assert np.array_equal(x, x1) and np.array_equal(S, S0)


def test_the_parallel_passes_are_their_serial_twins_bit_for_bit():
    """``pnlss_walk`` runs a small model's local Jacobians and a walk of one column
    block on the calling thread, a larger one's in parallel regions: both forms of each
    pass give the same numbers (each called here directly, over several sample blocks
    and column blocks, in a region of one thread or two), and the free run's sparse
    powers give the trajectory's outputs (and the one-pass trajectory with its Jacobians
    the two passes' numbers)."""
    import numba

    from blockid._kernels.state_space import (
        COLUMN_BLOCK,
        SAMPLE_BLOCK,
        pnlss_columns,
        pnlss_local_jacobians,
        pnlss_sensitivities,
        pnlss_sensitivities_serial,
        pnlss_simulate,
        pnlss_trajectory,
        pnlss_trajectory_jacobians,
    )

    rng = np.random.default_rng(7)
    nx, nu, ny, n = 4, 1, 2, 3 * SAMPLE_BLOCK + 17
    arrays = _pnlss_arrays(rng, nx, nu, ny, degree=4, bound=0.8)  # clipping active
    A, B, C, D, E, F, expo, lo, hi = arrays
    u = rng.standard_normal((n, nu))
    nm = expo.shape[0]
    V, y = np.empty((n, nx + nu + nm)), np.zeros((n, ny))
    pnlss_trajectory(*arrays, u, 0.2 * np.ones(nx), y, V)
    y_free = np.zeros((n, ny))
    pnlss_simulate(*arrays, u, 0.2 * np.ones(nx), y_free)
    assert np.array_equal(y, y_free)
    kind, row, src = pnlss_columns(nx, nu, ny, nm)
    assert kind.size > 2 * COLUMN_BLOCK
    before = numba.get_num_threads()
    for threads in sorted({1, min(2, numba.config.NUMBA_NUM_THREADS)}):
        numba.set_num_threads(threads)
        JX, JY = np.full((n, nx, nx), np.nan), np.full((n, ny, nx), np.nan)
        pnlss_local_jacobians(A, C, E, F, expo, lo, hi, V, JX, JY)  # blocks of samples
        JX1, JY1, V1 = np.empty((n, nx, nx)), np.empty((n, ny, nx)), np.empty_like(V)
        y1, x1 = np.zeros((n, ny)), 0.2 * np.ones(nx)
        pnlss_trajectory_jacobians(*arrays, u, x1, y1, V1, JX1, JY1)  # both passes in one
        assert np.array_equal(V1, V) and np.array_equal(y1, y)
        assert np.array_equal(JX1, JX) and np.array_equal(JY1, JY)
        assert np.all(np.isfinite(JX))
        walks = []
        for walk in (pnlss_sensitivities, pnlss_sensitivities_serial):
            S = np.zeros((nx, kind.size))
            S[:, -nx:] = np.eye(nx)
            J = np.full((n * ny, kind.size), np.nan)
            walk(V, JX, JY, kind, row, src, S, J)
            walks.append((S, J))
        assert all(np.array_equal(a, b) for a, b in zip(*walks, strict=True))
        assert np.all(np.isfinite(walks[0][1]))
    numba.set_num_threads(before)


def test_the_walk_of_chosen_columns_is_those_columns_of_the_whole_walk():
    """A fit asks for its free columns only, in its order: the same numbers."""
    from blockid._kernels.state_space import pnlss_columns

    rng = np.random.default_rng(4)
    arrays = _pnlss_arrays(rng, 3, 1, 2)
    u = rng.standard_normal((200, 1))
    x0 = 0.2 * rng.standard_normal(3)
    _, J_all, _, _ = _walked(arrays, u, x0)
    chosen = np.r_[40 : J_all.shape[1], 5, 0:3]  # any subset, any order
    desc = tuple(
        np.ascontiguousarray(d[chosen]) for d in pnlss_columns(3, 1, 2, arrays[6].shape[0])
    )
    _, J, _, _ = _walked(arrays, u, x0, columns=desc)
    assert np.array_equal(J, J_all[:, chosen])
