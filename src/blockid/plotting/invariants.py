"""What a state-space model's parameters say without its state basis.

A state space ``x(k+1) = A x + B u (+ E m(x, u))``, ``y = C x + D u (+ F m(x, u))`` is
the same model in any state basis ``x -> T x`` (``T A T^-1``, ``T B``, ``C T^-1``, ``D``):
the entries of ``A``, ``B``, ``C`` (and of ``E``, and of ``F`` on monomials of the
states) are unique only up to ``T``. A table of them, with standard errors "in the
fitted basis" and relative standard errors of thousands of per cent, says little about
the model. What the data do determine, whatever the basis:

.. math::

    p_i = \\operatorname{eig}(A), \\qquad
    G(1) = D + C (I - A)^{-1} B, \\qquad
    h(k) = C A^{k-1} B \\ (k \\ge 1), \\qquad
    \\sigma_i = \\sqrt{\\operatorname{eig}(P Q)}

the poles, the static gain, the Markov parameters (the impulse response; the first
``2 nx`` of them fix the transfer function) and the Hankel singular values (``P``, ``Q``
the controllability and observability Gramians, ``P = A P A^T + B B^T``,
``Q = A^T Q A + C^T C``: how much each direction of the state carries from input to
output). They are those of the linear part (for a nonlinear state space, its
linearisation at the operating point; for a block state space, its core from the input
blocks' outputs to the output blocks' arguments, in normalised units).

Their standard errors come from the fit's parameter covariance by the delta method,
``J Σ J^T`` with ``J`` by central differences: the covariance (a pseudo-inverse without
the basis directions, :mod:`blockid.evaluation.uncertainty`) holds nothing along the
directions in which these quantities do not change, so this is exact to first order.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from blockid.plotting.parameters import ParameterTable
from blockid.plotting.uncertainty import free_covariance

__all__ = ["BASIS_KEYS", "Invariants", "basis_dependent", "invariants", "matrix_rows"]

#: Matrices whose entries depend on the state basis (``F`` only on monomials of the
#: states): ``A``, ``B``, ``C``, ``E``; a block state space's loop maps ``Bq``, ``Cp``
#: and its state bias ``e``.
BASIS_KEYS = ("A", "B", "C", "E", "Bq", "Cp", "e")

#: At most this many Markov parameters per input-output pair, and this many rows of
#: them in all.
MAX_MARKOV, MAX_MARKOV_ROWS = 10, 40


def _key(name: str) -> str:
    """``"A"`` of ``"A[0,1]"``; ``""`` for names that are not matrix entries."""
    head, bracket, _ = name.partition("[")
    return head if bracket and name.endswith("]") and " " not in head else ""


def _exponents(model: Any) -> np.ndarray | None:
    for source in (model, getattr(model, "core", None)):
        expo = getattr(source, "exponents", None)
        if expo is not None:
            return np.asarray(expo)
    return None


def basis_dependent(model: Any) -> np.ndarray | None:
    """For each of ``model.free_parameter_names()``, whether it depends on the state
    basis (module docstring); None for a model without a state (no ``A[0,0]``).

    >>> from blockid.models.state_space import StateSpace
    >>> m = StateSpace(["u"], ["y"], A=[[0.5]], B=[[1.0]], C=[[1.0]], D=[[0.0]])
    >>> dict(zip(m.free_parameter_names(), basis_dependent(m).tolist()))
    {'A[0,0]': True, 'B[0,0]': True, 'C[0,0]': True, 'D[0,0]': False}
    """
    names = list(getattr(model, "free_parameter_names", list)())
    if "A[0,0]" not in names:
        return None
    nx = int(model.nx)
    expo = _exponents(model)
    out = []
    for name in names:
        key = _key(name)
        if key == "F":  # on a monomial of the states, or of the inputs only
            column = int(name[:-1].split(",")[1])
            out.append(expo is None or bool(np.any(expo[column, :nx])))
        else:
            out.append(key in BASIS_KEYS)
    return np.array(out, dtype=bool)


@dataclass(frozen=True)
class Invariants:
    """The basis-free quantities of a state space (module docstring).

    Attributes
    ----------
    names : list of str
        What each value is (``"static gain velocity / current"``,
        ``"|p| of pole 0.9 ± 0.1j"``, ``"Hankel singular value 1"``, ``"Markov
        parameter h(2) velocity / current"``).
    values : ndarray
    standard_errors : ndarray or None
        By the delta method from the fit's covariance; None without one.
    units : str
        The signals the numbers are in.
    n_markov : int
        Markov parameters listed per input-output pair.
    notes : list of str
        What is left out, and why.
    """

    names: list[str]
    values: np.ndarray
    standard_errors: np.ndarray | None
    units: str
    n_markov: int
    notes: list[str]

    def rows(self) -> list[list[Any]]:
        """``[quantity, value, standard error, relative SE in %]`` (text where none), as
        a parameter table's (:meth:`~blockid.plotting.parameters.ParameterTable.rows`)."""
        table = ParameterTable(self.names, self.values, self.standard_errors, "", 0, {})
        return table.rows()


def _pairs(lin: Any) -> list[tuple[int, int, str]]:
    return [
        (i, j, f"{y} / {u}") for i, y in enumerate(lin.outputs) for j, u in enumerate(lin.inputs)
    ]


def _gramian(A: np.ndarray, M: np.ndarray) -> np.ndarray:
    from scipy.linalg import solve_discrete_lyapunov

    return solve_discrete_lyapunov(A, M)


def _values(lin: Any, n_markov: int, order: np.ndarray | None) -> np.ndarray:
    """The invariants of one linear state space, in the order of :func:`_labels`.
    ``order``: the poles' positions sorted at the nominal model (so that a perturbed
    model's poles are matched to them, sorted the same way)."""
    A, D = lin.A, lin.D
    B = lin.B / lin.input_scale  # in the signals' units: u_n = (u - offset) / scale
    C = lin.output_scale[:, None] * lin.C
    scale = np.outer(lin.output_scale, 1.0 / lin.input_scale)
    out = []
    poles = np.linalg.eigvals(A)
    stable = bool(np.max(np.abs(poles)) < 1.0)
    if stable:
        gain = D * scale + C @ np.linalg.solve(np.eye(A.shape[0]) - A, B)
        out += [gain[i, j] for i, j, _ in _pairs(lin)]
    magnitudes = np.sort(np.abs(poles))[::-1]
    out += list(magnitudes if order is None else magnitudes[order])
    if stable:
        P = _gramian(A, B @ B.T)
        Q = _gramian(A.T, C.T @ C)
        hsv = np.sqrt(np.clip(np.sort(np.linalg.eigvals(P @ Q).real)[::-1], 0.0, None))
        out += list(hsv)
    markov, power = [], np.eye(A.shape[0])
    for _ in range(n_markov):
        markov.append(C @ power @ B)
        power = power @ A
    for i, j, _ in _pairs(lin):
        out += [h[i, j] for h in markov]
    return np.asarray(out, dtype=float)


def _labels(lin: Any, n_markov: int) -> tuple[list[str], np.ndarray]:
    """The names of :func:`_values` and the positions of the poles listed (each
    conjugate pair once)."""
    from blockid.plotting.linear import _complex

    poles = np.linalg.eigvals(lin.A)
    stable = bool(np.max(np.abs(poles)) < 1.0)
    names = [f"static gain {pair}" for *_, pair in _pairs(lin)] if stable else []
    ranked = sorted(poles, key=lambda p: (-abs(p), -p.imag))
    shown = [k for k, p in enumerate(ranked) if p.imag >= -1e-12 * max(abs(p), 1.0)]
    for k in shown:
        p = complex(ranked[k])
        text = _complex(p) if abs(p.imag) < 1e-12 else _complex(p).replace("+", "±")
        names.append(f"|p| of pole {text}")
    if stable:
        names += [f"Hankel singular value {k + 1}" for k in range(lin.A.shape[0])]
    names += [
        f"Markov parameter h({k + 1}) {pair}" for *_, pair in _pairs(lin) for k in range(n_markov)
    ]
    return names, np.array(shown, dtype=int)


def _delta_method(
    f: Callable[[np.ndarray], np.ndarray], theta: np.ndarray, cov: np.ndarray, moved: np.ndarray
) -> np.ndarray:
    """Standard errors of ``f(theta)``: ``sqrt(diag(J Σ J^T))``, ``J`` by central
    differences in the parameters ``moved`` (the others leave ``f`` unchanged)."""
    base = f(theta)
    J = np.zeros((base.size, theta.size))
    for k in np.flatnonzero(moved):
        step = 1e-6 * max(1.0, abs(theta[k]))
        up, down = theta.copy(), theta.copy()
        up[k] += step
        down[k] -= step
        J[:, k] = (f(up) - f(down)) / (2 * step)
    return np.sqrt(np.clip(np.einsum("ij,jk,ik->i", J, cov, J), 0.0, None))


def invariants(model: Any, fit: Any = None) -> Invariants | None:
    """The basis-free quantities of ``model``'s linear part (module docstring), with
    standard errors when ``fit`` carries a parameter covariance; None for a model
    without a state basis (:func:`basis_dependent`).

    >>> from blockid.models.state_space import StateSpace
    >>> m = StateSpace(["u"], ["y"], A=[[0.5]], B=[[1.0]], C=[[2.0]], D=[[0.0]])
    >>> q = invariants(m)
    >>> [(n, round(float(v), 4)) for n, v in zip(q.names[:3], q.values[:3])]
    [('static gain y / u', 4.0), ('|p| of pole 0.5', 0.5), ('Hankel singular value 1', 2.6667)]
    >>> q.names[3:5], q.values[3:5].tolist()
    (['Markov parameter h(1) y / u', 'Markov parameter h(2) y / u'], [2.0, 1.0])
    """
    if basis_dependent(model) is None or not hasattr(model, "linear_part"):
        return None
    lin = model.linear_part()
    nx, pairs = int(lin.A.shape[0]), len(_pairs(lin))
    n_markov = max(1, min(2 * nx, MAX_MARKOV, MAX_MARKOV_ROWS // pairs))
    names, order = _labels(lin, n_markov)
    values = _values(lin, n_markov, order)
    units = (
        "normalised signals of the linear core: from the input blocks' outputs w to the "
        "output blocks' arguments z"
        if hasattr(model, "core")
        else "the signals' own units"
    )
    notes = []
    if not np.max(np.abs(np.linalg.eigvals(lin.A))) < 1.0:
        notes.append(
            "The linear part is not stable: it has no static gain and no Hankel singular "
            "values (its Gramians do not exist)."
        )
    if getattr(model, "n_monomials", 0):
        notes.append(
            "They are those of the linear part, the model linearised at its operating "
            "point (the monomials of degree 2 and more have zero slope there)."
        )
    if n_markov < 2 * nx:
        notes.append(
            f"The first {n_markov} Markov parameters of each pair are listed; the first "
            f"{2 * nx} fix its transfer function."
        )
    se = _standard_errors(model, fit, n_markov, order, values.size)
    return Invariants(names, values, se, units, n_markov, notes)


def _standard_errors(
    model: Any, fit: Any, n_markov: int, order: np.ndarray, size: int
) -> np.ndarray | None:
    cov = free_covariance(fit) if fit is not None else None
    if cov is None:
        return None
    theta = np.asarray(model.free_parameters(), float)
    names = model.free_parameter_names()
    moved = np.array([_key(n) in ("A", "B", "C", "D") for n in names]) & (np.diag(cov) > 0)

    def f(t: np.ndarray) -> np.ndarray:
        out = _values(model.with_free_parameters(t).linear_part(), n_markov, order)
        return out if out.size == size else np.full(size, np.nan)

    with np.errstate(all="ignore"):
        se = _delta_method(f, theta, cov, moved)
    return se if np.all(np.isfinite(se)) else None


def matrix_rows(model: Any) -> list[list[str]]:
    """The basis-dependent parameters (:func:`basis_dependent`) a row of a matrix at a
    time: ``["A[0,:]", "0.9, -0.1, ..."]``, values in 6 significant digits."""
    mask = basis_dependent(model)
    if mask is None:
        return []
    rows: dict[str, list[str]] = {}
    values = np.asarray(model.free_parameters(), float)
    for name, value, dependent in zip(model.free_parameter_names(), values, mask, strict=True):
        if dependent:
            row = name.split(",")[0] + ",:]" if "," in name else _key(name) or name
            rows.setdefault(row, []).append(f"{value:.6g}")
    return [[row, ", ".join(v)] for row, v in rows.items()]
