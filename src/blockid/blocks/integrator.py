"""The integrator: ``n`` discrete integrations with one sample of delay, unit gain.

.. math::

    (1 - z^{-1})^{n}\\, x(k) = w(k - 1), \\qquad
    n = 1:\\; x(k) = x(k-1) + w(k-1), \\qquad
    n = 2:\\; x(k) = 2 x(k-1) - x(k-2) + w(k-1)

(forward Euler with the sampling time folded into the gain; the delay is one sample
whatever ``n``). A plant that integrates (position from force, level from flow) has a
pole at 1 that a fitted linear block can only approach: the fit keeps every fitted pole
inside the stability margin, and a pole at ``1 - 1e-3`` leaks, so a simulated position
drifts away. The integrator puts that pole in the model *by construction*: it has no
free parameters (the linear block before it carries the gain) and the stability checks
apply to the fitted linear blocks only.

In a chain it is a linear block with fixed coefficients ``a`` of :math:`(1 - z^{-1})^n`
and ``b = [1]``, ``nk = 1``, after the last fitted linear block (and before an output
block, if any): as the chain's *last* linear block it starts a simulation from the
measured outputs (the measured position), while the blocks before it start at rest.
Its output and the sensitivities it passes on are ``n`` cumulative sums of its input and
of the incoming sensitivities (:meth:`Integrator.forward`). It is a
:class:`~blockid.blocks.linear.LinearBlock` rather than a
:class:`~blockid.blocks.base.DynamicBlock` **(choice)**: a dynamic block acts on the
measured input and a chain accepts it first only, while the integrator is linear
dynamics inside the chain, whose state is the measured output.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from blockid.blocks.linear import LinearBlock
from blockid.errors import ParameterError

__all__ = ["Integrator"]


def _coefficients(order: int) -> np.ndarray:
    """``[a_1..a_n]`` of :math:`(1 - z^{-1})^n`: ``[-1]``, ``[-2, 1]``, ..."""
    return np.poly(np.ones(order))[1:]


class Integrator(LinearBlock):
    """``order`` integrations with one sample of delay (module docstring).

    Parameters
    ----------
    order : int, default 1
        1 for an integrator, 2 for a double integrator.

    Examples
    --------
    >>> Integrator().simulate(np.ones(4)).tolist()
    [0.0, 1.0, 2.0, 3.0]
    >>> Integrator(2).simulate(np.ones(4)).tolist()
    [0.0, 1.0, 3.0, 6.0]
    >>> Integrator(2).a.tolist(), Integrator(2).b.tolist(), Integrator(2).nk
    ([-2.0, 1.0], [1.0], 1)
    """

    kind: ClassVar[str] = "integrator"

    def __init__(self, order: int = 1) -> None:
        if isinstance(order, bool) or not isinstance(order, int | np.integer) or order < 1:
            raise ParameterError(
                f"order={order!r}: an integrator takes a whole number of integrations >= 1 "
                "(1: integrator, 2: double integrator)"
            )
        self.order = int(order)
        super().__init__(self.order, 1, 1, _coefficients(self.order), [1.0])

    # ------------------------------------------------------------------ parameters
    @property
    def parameters(self) -> dict[str, Any]:
        """``{"order": n}``: the form; there is nothing to fit."""
        return {"order": self.order}

    def with_vector(self, theta: Any) -> Integrator:
        """The integrator itself: its coefficients are fixed."""
        theta = np.asarray(theta, dtype=float).reshape(-1)
        if not np.array_equal(theta, self.to_vector()):
            raise ParameterError(
                "an integrator has no free parameters; its coefficients are those of "
                f"(1 - z^-1)^{self.order}"
            )
        return self

    def free_mask(self, after_nonlinear: bool) -> np.ndarray:
        """Nothing is free."""
        return np.zeros(self.to_vector().size, dtype=bool)

    def check_normalised(self, after_nonlinear: bool) -> None:
        """Always normalised (``b_0 = 1`` by construction)."""

    def is_stable(self, margin: float = 0.0) -> bool:
        """True: the poles at 1 are the block's purpose, not an estimate, so the stability
        checks (the refinement's margin, the model check) pass it and judge the fitted
        linear blocks. :meth:`poles` still returns them (at 1)."""
        return True

    @property
    def integrates(self) -> int:
        """The number of integrations (a fitted linear block integrates 0 times)."""
        return self.order

    @classmethod
    def template(cls, order: int = 1) -> Integrator:
        """An integrator of the given order (``block_template("integrator:order=2")``)."""
        return cls(order)

    def rest_state(self, u0: float) -> float:
        """The output before the first sample at rest: 0 (a simulation given measured
        outputs starts from them instead)."""
        return 0.0

    def differenced(self, u: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The integrator's input ``w`` that produces the output ``x``, paired with ``u``.

        ``w(k) = Δ^n x(k + 1)`` (backward differences) for ``k = n-1 .. N-2``, returned
        with ``u(k)`` of the same samples (both of length ``N - n``, along the first
        axis): what the blocks before the integrator must map ``u`` to, for their
        initial estimate on the differenced output.

        >>> Integrator(2).differenced(np.arange(5.0), np.array([0.0, 1, 3, 6, 10]))
        (array([1., 2., 3.]), array([1., 1., 1.]))
        """
        u = np.asarray(u, dtype=float)
        x = np.asarray(x, dtype=float)
        n, N = self.order, x.shape[0]
        if N <= n:
            raise ParameterError(
                f"{N} sample(s) cannot be differenced {n} time(s): give a longer record"
            )
        return u[n - 1 : N - 1], np.diff(x, n, axis=0)

    # ------------------------------------------------------------------ files
    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "order": self.order}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Integrator:
        return cls(int(data.get("order", 1)))

    # ------------------------------------------------------------------ dynamics
    def simulate(self, w: np.ndarray, x_init: np.ndarray | None = None) -> np.ndarray:
        """Output for input ``w``: from rest, or with the first ``len(x_init)`` (at most
        ``order``) outputs set to ``x_init`` (as :meth:`LinearBlock.simulate`)."""
        w = np.asarray(w, dtype=float).reshape(-1)
        x = np.zeros(w.shape[0])
        return self._integrate(w, x, self._initial_outputs(x, x_init))

    def forward(
        self, w: np.ndarray, S_in: np.ndarray, own: np.ndarray, init: Any = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Output and its sensitivities: the incoming sensitivities ``dw/dθ`` integrated
        as the signal is (the block has no parameters of its own); ``init = (x0, S0)``
        sets the first ``min(order, len(x0))`` outputs and their sensitivities."""
        w = np.asarray(w, dtype=float).reshape(-1)
        x = np.zeros(w.shape[0])
        S = np.zeros_like(S_in, dtype=float)
        start = self._initial_sensitivities(x, S, init)
        return self._integrate(w, x, start), self._integrate(S_in, S, start)

    def _integrate(self, w: np.ndarray, x: np.ndarray, start: int) -> np.ndarray:
        """``(1 - z^-1)^n x(k) = w(k-1)`` for ``k >= start`` along the first axis, with
        ``x[:start]`` given and rest (zeros) before ``k = 0``: ``n`` cumulative sums.

        With ``D_j`` the ``j``-th backward difference of ``x``, ``D_n(k) = w(k-1)`` and
        ``D_j(k) = D_j(k-1) + D_{j+1}(k)``: each level is its start value plus the
        cumulative sum of the level above.
        """
        n = self.order
        N = x.shape[0]
        pad = np.zeros((n, *x.shape[1:]))
        xp = np.concatenate((pad, x))  # xp[i + n] = x(i); zeros before k = 0
        s = start + n
        if s >= N + n:
            return x
        # backward differences of the given start at k = s - 1, for j = 0 .. n-1
        heads = []
        level = xp[:s]
        for _ in range(n):
            heads.append(level[-1])
            level = np.diff(level, axis=0)
        # D_n(k) = w(k - 1) for k = s .. N + n - 1, i.e. w(i - 1) for i = start .. N - 1
        upper = np.concatenate((pad[:1], np.asarray(w, dtype=float)))[start:N]
        for j in reversed(range(n)):
            upper = heads[j] + np.cumsum(upper, axis=0)
        out = x.copy()
        out[start:] = upper
        return out
