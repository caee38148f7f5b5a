"""The linear dynamic block of a block-oriented model (single input, single output).

.. math::

    A(z^{-1})\\,x(k) = z^{-n_k} B(z^{-1})\\,w(k), \\qquad
    A = 1 + a_1 z^{-1} + \\dots + a_{n_a} z^{-n_a}, \\quad
    B = b_0 + b_1 z^{-1} + \\dots + b_{n_b - 1} z^{-n_b + 1}

in the MATLAB convention of :class:`~blockid.models.ARX` (SPEC (A5), (B2)): ``b_0``
multiplies ``w(k - n_k)``. Its parameter vector is ``[a_1..a_na, b_0..b_{nb-1}]``; after a
nonlinear block ``b_0 = 1`` is fixed (the normalisation of the cascade).

The block simulates with the compiled ARX recursion and carries the sensitivities of
its output with respect to its own parameters and to everything upstream through one
compiled all-pole recursion (:func:`blockid._kernels.simulation.allpole_run`).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from blockid._kernels import writable
from blockid._kernels.arx import arx_simulate
from blockid._kernels.simulation import allpole_run
from blockid.blocks.base import Block
from blockid.errors import OrderError

__all__ = ["LinearBlock"]


def _order(name: str, value: Any, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < low:
        raise OrderError(
            f"{name}={value!r}: a block-oriented (single-input single-output) model takes "
            f"one whole number >= {low} per order"
        )
    return int(value)


class LinearBlock(Block):
    """SISO linear block ``x = z^-nk B/A w`` (module docstring).

    Parameters
    ----------
    na, nb, nk : int
        Orders (``nb >= 1``).
    a, b : sequence of float, optional
        ``[a_1..a_na]`` and ``[b_0..b_{nb-1}]``; zeros by default (``b_0 = 1`` when
        ``unit_b0``).
    unit_b0 : bool
        Default ``b`` starts with 1 (for a block after a nonlinear one).

    Examples
    --------
    >>> g = LinearBlock(1, 1, 1, a=[-0.5], b=[1.0])
    >>> g.simulate(np.ones(4)).tolist()
    [0.0, 1.0, 1.5, 1.75]
    """

    kind: ClassVar[str] = "linear"
    role: ClassVar[str] = "linear"

    def run(self, w: np.ndarray) -> np.ndarray:
        """The block's output for ``w``, from rest."""
        return self.simulate(w)

    def __init__(
        self,
        na: int = 1,
        nb: int = 1,
        nk: int = 1,
        a: Any = None,
        b: Any = None,
        *,
        unit_b0: bool = False,
    ) -> None:
        self.na = _order("na", na, 0)
        self.nb = _order("nb", nb, 1)
        self.nk = _order("nk", nk, 0)
        a = np.zeros(self.na) if a is None else np.asarray(a, dtype=float).reshape(-1)
        if b is None:
            b = np.zeros(self.nb)
            if unit_b0:
                b[0] = 1.0
        b = np.asarray(b, dtype=float).reshape(-1)
        if a.size != self.na or b.size != self.nb:
            raise OrderError(
                f"the linear block has na={self.na}, nb={self.nb} but got {a.size} value(s) "
                f"for a and {b.size} for b"
            )
        self.a = a
        self.b = b
        self.a.setflags(write=False)
        self.b.setflags(write=False)

    # ------------------------------------------------------------------ structure
    @property
    def parameters(self) -> dict[str, Any]:
        return {"na": self.na, "nb": self.nb, "nk": self.nk, "a": self.a.tolist(),
                "b": self.b.tolist()}  # fmt: skip

    @property
    def max_lag(self) -> int:
        return max(self.na, self.nk + self.nb - 1, 1)

    def to_vector(self) -> np.ndarray:
        """``[a_1..a_na, b_0..b_{nb-1}]``."""
        return np.concatenate((self.a, self.b))

    def with_vector(self, theta: Any) -> LinearBlock:
        theta = np.asarray(theta, dtype=float).reshape(-1)
        if theta.size != self.na + self.nb:
            raise OrderError(f"the linear block takes {self.na + self.nb} values, got {theta.size}")
        return LinearBlock(self.na, self.nb, self.nk, theta[: self.na], theta[self.na :])

    def free_mask(self, after_nonlinear: bool) -> np.ndarray:
        """After a nonlinear block ``b_0`` is fixed (to 1, or to -1: the sign of a plant
        whose block's slopes must stay positive, :func:`~blockid.fitting.initial.
        absorbed_gain`)."""
        mask = np.ones(self.na + self.nb, dtype=bool)
        if after_nonlinear:
            mask[self.na] = False
        return mask

    def check_normalised(self, after_nonlinear: bool) -> None:
        if after_nonlinear and self.b[0] not in (1.0, -1.0):
            raise OrderError(
                f"b_0 is fixed to 1 (or -1, the sign of a negative gain) when there is an "
                f"input block (got {self.b[0]})"
            )

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, **self.parameters}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> LinearBlock:
        return cls(int(data["na"]), int(data["nb"]), int(data["nk"]), data["a"], data["b"])

    # ------------------------------------------------------------------ dynamics
    def _lag_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        A = np.zeros((1, 1, self.na + 1))
        A[0, 0, 1:] = self.a
        B = np.zeros((1, 1, self.max_lag + 1))
        B[0, 0, self.nk : self.nk + self.nb] = self.b
        return A, B

    def poles(self) -> np.ndarray:
        """Roots of ``z^na A(z^{-1})``, the eigenvalues of the companion matrix."""
        if self.na == 0:
            return np.zeros(0)
        C = np.zeros((self.na, self.na))
        C[0, :] = -self.a
        C[1:, :-1] = np.eye(self.na - 1)
        return np.linalg.eigvals(C)

    def is_stable(self, margin: float = 0.0) -> bool:
        """True when every pole lies strictly inside the circle of radius ``1 - margin``."""
        p = self.poles()
        return bool(p.size == 0 or np.max(np.abs(p)) < 1.0 - margin)

    def static_gain(self) -> float:
        """``B(1) / A(1)`` (infinite for a pole at 1)."""
        den = 1.0 + float(np.sum(self.a))
        return float(np.sum(self.b)) / den if den != 0 else float("inf")

    @property
    def integrates(self) -> int:
        """How many integrations the block holds by construction: 0 for a fitted linear
        block (:class:`~blockid.blocks.integrator.Integrator` overrides it)."""
        return 0

    def zeros(self) -> np.ndarray:
        """Roots of ``z^{nb-1} B(z^{-1})`` (the finite zeros besides those of the delay).

        >>> LinearBlock(1, 2, 1, a=[-0.5], b=[1.0, -0.25]).zeros().tolist()
        [0.25]
        """
        b = np.trim_zeros(self.b, "f")
        return np.roots(b) if b.size > 1 else np.zeros(0)

    def simulate(self, w: np.ndarray, x_init: np.ndarray | None = None) -> np.ndarray:
        """Output for input ``w``; the first ``len(x_init)`` (at most ``max_lag``) outputs
        are set to ``x_init``, else the block starts at rest (zero before ``k = 0``)."""
        w = np.ascontiguousarray(np.asarray(w, dtype=float).reshape(-1, 1))
        x = np.zeros((w.shape[0], 1))
        n0 = self._initial_outputs(x[:, 0], x_init)
        A, B = self._lag_arrays()
        arx_simulate(A, B, writable(w), x, n0)
        return x[:, 0]

    def predict(self, w: np.ndarray, x: np.ndarray) -> np.ndarray:
        """One step ahead from measured past outputs ``x`` (first ``max_lag`` copied)."""
        w = np.asarray(w, dtype=float).reshape(-1)
        x = np.asarray(x, dtype=float).reshape(-1)
        n0, N = self.max_lag, w.size
        cols = [-x[n0 - k : N - k] for k in range(1, self.na + 1)]
        cols += [w[n0 - self.nk - i : N - self.nk - i] for i in range(self.nb)]
        out = x.copy()
        if N > n0:
            out[n0:] = np.column_stack(cols) @ self.to_vector()
        return out

    def forward(
        self, w: np.ndarray, S_in: np.ndarray, own: np.ndarray, init: Any = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Output and sensitivities (see :meth:`sensitivity`); ``init = (x0, S0)`` sets the
        first ``min(max_lag, len(x0))`` outputs and their sensitivities, else from rest."""
        x = np.zeros(w.shape[0])
        S = np.zeros_like(S_in)
        start = self._initial_sensitivities(x, S, init)
        self.sensitivity(np.asarray(w, dtype=float), S_in, own, x, S, start)
        return x, S

    def _initial_outputs(self, x: np.ndarray, x_init: Any) -> int:
        """Set the first outputs ``x`` (N,) to ``x_init`` as :meth:`simulate` takes it (at
        most ``max_lag`` of them, the rest of the first ``max_lag`` left at rest) and
        return the sample the run starts at: ``min(max_lag, N)``, 0 without ``x_init``."""
        if x_init is None:
            return 0
        x0 = np.asarray(x_init, dtype=float).reshape(-1)
        start = min(self.max_lag, x.shape[0])
        k = min(start, x0.size)
        x[:k] = x0[:k]
        return start

    def _initial_sensitivities(self, x: np.ndarray, S: np.ndarray, init: Any) -> int:
        """Set the first outputs ``x`` and their sensitivities ``S`` to ``init = (x0, S0)``
        as :meth:`forward` takes it and return the sample the run starts at: ``min(max_lag,
        len(x0), N)``, 0 without ``init``."""
        if init is None:
            return 0
        x0, S0 = init
        start = min(self.max_lag, np.shape(x0)[0], x.shape[0])
        x[:start] = np.asarray(x0, dtype=float)[:start]
        S[:start] = np.asarray(S0, dtype=float)[:start]
        return start

    def sensitivity(
        self,
        w: np.ndarray,
        S_in: np.ndarray,
        own: np.ndarray,
        x: np.ndarray,
        S: np.ndarray,
        start: int,
    ) -> None:
        """Output and sensitivities, in place (the simulation-error Jacobian).

        ``S_in`` (N, n) holds ``dw/dθ`` for every parameter of the model; ``own`` are
        the model columns of this block's free ``[a, b]`` entries (-1 for a fixed one).
        ``x`` and ``S`` hold the initial values in rows ``:start`` and receive
        ``x = z^-nk B/A w`` and ``dx/dθ`` from row ``start``: upstream columns are
        filtered by the block, own columns are forced by ``-x(k-j)`` (``a_j``) and
        ``w(k-nk-i)`` (``b_i``) (B2).
        """
        N = w.shape[0]
        F = np.zeros_like(S)
        fx = np.zeros((N, 1))
        for i in range(self.nb):
            d = self.nk + i
            if d < N:
                fx[d:, 0] += self.b[i] * w[: N - d]
                F[d:] += self.b[i] * S_in[: N - d]
        xs = x[:, None].copy()
        allpole_run(writable(self.a), fx, xs, start)
        x[:] = xs[:, 0]
        for j in range(1, self.na + 1):
            col = own[j - 1]
            if col >= 0:
                F[j:, col] = -x[: N - j]
        for i in range(self.nb):
            col, d = own[self.na + i], self.nk + i
            if col >= 0 and d < N:
                F[d:, col] = w[: N - d]
        allpole_run(writable(self.a), F, S, start)
