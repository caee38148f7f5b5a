"""Linear and polynomial nonlinear state-space models (discrete time, MIMO).

.. math::

    x(k+1) = A x(k) + B u(k) + E\\, \\zeta(x(k), u(k)), \\qquad
    y(k) = C x(k) + D u(k) + F\\, \\eta(x(k), u(k))

in normalised signals: the model works on ``u_n = (u - input_offset) / input_scale``
and returns ``y = output_offset + output_scale * y_n`` (offsets and scales are the
estimation data's means and spreads, so that the matrices are of order one whatever
the units). ``ζ`` and ``η`` are the same monomials of ``z = [x; u_n]`` (the rows of
``exponents``), of total degree 2 to ``degree`` (PNLSS: Paduart et al., Automatica 46,
2010), and a constant (the monomial 1, which the fits include: the nonlinear terms move
the operating point off the one the signals' means give). :class:`StateSpace` is the
linear model (no monomials).

**Bounded beyond the estimation range.** Before the monomials are taken, every
coordinate of ``z`` is clipped to ``[lower, upper]``, the range the fit let it span:
the monomials hold their boundary values beyond it (a saturated-monomial variant of
PNLSS), so with ``A`` stable a free run on a record whose input exceeds the estimation
range stays bounded, where a cubic in ``x`` would run away. Inside the range the model
is the polynomial one exactly. :meth:`range_excursion` reports how far data drive
``z`` out of it.

**Initial state.** :meth:`simulate` given ``n`` measured outputs estimates ``x(0)`` from
them by least squares (Gauss-Newton with the exact sensitivity of the first ``n``
outputs, :mod:`blockid._kernels.state_space`); without, it starts at ``x(0) = 0`` (the
operating point). ``max_lag`` is ``nx``: the default start of a free run is estimated
from the first ``nx`` outputs, the fewest that determine the state of an observable
single-output model.
"""

from __future__ import annotations

from collections.abc import Sequence
from itertools import combinations_with_replacement
from typing import Any, ClassVar

import numpy as np

from blockid._kernels import writable
from blockid._kernels.state_space import pnlss_columns, pnlss_simulate, pnlss_walk
from blockid.config import get_config
from blockid.errors import DataError, ModelFileError, OrderError
from blockid.models.base import Model, excursion

__all__ = [
    "ForwardSensitivities",
    "PolynomialStateSpace",
    "StateSpace",
    "monomial_exponents",
    "monomial_slopes",
]

#: Gauss-Newton iterations of the initial-state estimate.
INITIAL_ITERATIONS = 20


def monomial_exponents(
    nx: int, nu: int, degree: int, which: str = "full", constant: bool = False
) -> np.ndarray:
    """Exponents of the monomials of ``z = [x; u]`` of total degree ``2 .. degree``.

    ``which``: ``"full"`` (every monomial of states and inputs), ``"states"`` (of the
    states only) or ``"inputs"`` (of the inputs only: a Hammerstein-like nonlinearity
    entering the state equation). ``constant`` puts the monomial ``1`` first: constant
    terms in the state and output equations, which a polynomial model needs when its
    operating point is not where the signals' means put it (``(x + c)^2`` has a ``c^2``).

    >>> monomial_exponents(2, 1, 2, "states").tolist()
    [[2, 0, 0], [1, 1, 0], [0, 2, 0]]
    >>> monomial_exponents(1, 1, 2, "inputs", constant=True).tolist()
    [[0, 0], [0, 2]]
    """
    if which not in ("full", "states", "inputs"):
        raise OrderError(f"monomials={which!r}: choose full, states or inputs")
    if degree < 1:
        raise OrderError(f"degree must be >= 1 (1: linear), got {degree}")
    variables = {
        "full": range(nx + nu),
        "states": range(nx),
        "inputs": range(nx, nx + nu),
    }[which]
    rows = [[0] * (nx + nu)] if constant else []
    for d in range(2, degree + 1):
        for combo in combinations_with_replacement(variables, d):
            row = [0] * (nx + nu)
            for i in combo:
                row[i] += 1
            rows.append(row)
    return np.array(rows, dtype=np.int64).reshape(-1, nx + nu)


def monomial_slopes(z: Any, exponents: Any, lower: Any, upper: Any) -> np.ndarray:
    """``∂ζ/∂z`` (nm, nx + nu) at one point ``z``: the slope of each monomial of the
    clipped coordinates, ``p_i clip(z_i)^(p_i - 1) Π_{t≠i} clip(z_t)^(p_t)``, zero in a
    coordinate clipped or on its bound (the kernels' convention,
    :func:`~blockid._kernels.state_space.pnlss_local_jacobians`).

    >>> monomial_slopes([2.0, 3.0], [[0, 0], [2, 0], [1, 1]], [-9, -9], [9, 9]).tolist()
    [[0.0, 0.0], [4.0, 0.0], [3.0, 2.0]]
    """
    z = np.asarray(z, dtype=float)
    expo = np.asarray(exponents, dtype=np.int64).reshape(-1, z.size)
    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    clipped = np.clip(z, lo, hi)
    powers = clipped[None, :] ** expo  # (nm, nz): clip(z_t)^(p_t), 1 where p_t = 0
    slopes = np.zeros(expo.shape, dtype=float)
    for i in np.flatnonzero((lo < z) & (z < hi)):
        p = expo[:, i]
        others = np.prod(np.delete(powers, i, axis=1), axis=1)
        slopes[:, i] = np.where(p > 0, p * clipped[i] ** np.maximum(p - 1, 0) * others, 0.0)
    return slopes


def _matrix(value: Any, shape: tuple[int, int], name: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.size == 0 and 0 in shape:
        return np.zeros(shape)
    arr = arr.reshape(shape) if arr.size == shape[0] * shape[1] else arr
    if arr.shape != shape:
        raise OrderError(f"{name} must have shape {shape}, got {np.shape(value)}")
    out = np.ascontiguousarray(arr, dtype=float)
    out.setflags(write=False)
    return out


def _vector(value: Any, n: int, name: str, default: float) -> np.ndarray:
    arr = np.full(n, default) if value is None else np.asarray(value, dtype=float).reshape(-1)
    if arr.size == 1 and n > 1:
        arr = np.full(n, float(arr[0]))
    if arr.size != n:
        raise OrderError(f"{name} needs {n} value(s), got {arr.size}")
    return arr


class ForwardSensitivities:
    """What a model whose output sensitivity is walked forward in time gets from it:
    the initial state fitted to measured outputs, the Gauss-Newton information of its
    free-run error (the standard errors read it) and its output sensitivities.

    The model gives ``jacobian_piece(un, *carried) -> (y_n, J)`` (normalised outputs of
    a piece of a record and ``∂y_n/∂[θ, x(0)]``, rows ``k * ny + i``, the carried
    state and sensitivities updated in place), ``_sensitivity_start(x0)`` (what to
    carry from ``x0``), ``linear_in_state`` and the usual ``nx``, ``outputs``,
    ``free_parameters``, ``input_offset``/``input_scale``, ``output_offset``/
    ``output_scale`` and ``max_lag``; the signals' normalisation is here too.
    :class:`PolynomialStateSpace` and
    :class:`~blockid.models.block_state_space.BlockStateSpace` are such models. A model
    whose ``_sensitivity_start(x0, columns)`` can keep some of the columns (indices
    into ``[θ, x(0)]``) sets :attr:`selects_columns`: a fit then walks only those it
    fits, and the initial state's fit only the state's.
    """

    #: Whether ``_sensitivity_start`` takes ``columns`` (see the class docstring).
    selects_columns: ClassVar[bool] = False

    def normalised_input(self, u: Any) -> np.ndarray:
        u, _ = self._check_signals(u)
        return np.ascontiguousarray((u - self.input_offset) / self.input_scale)

    def normalised_output(self, y: Any) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        y = y.reshape(-1, 1) if y.ndim == 1 else y
        if y.ndim != 2 or y.shape[1] != len(self.outputs):
            raise DataError(
                f"the model has {len(self.outputs)} output(s) {list(self.outputs)} but got an "
                f"output array of shape {np.shape(y)}"
            )
        return (y - self.output_offset) / self.output_scale

    def initial_state(self, u: Any, y_initial: Any) -> np.ndarray:
        """``x(0)`` fitted to the measured outputs ``y_initial`` (their number ``n``; the
        first ``n`` inputs of ``u``): least squares, Gauss-Newton from 0 with the exact
        sensitivity (one step for a model linear in the state)."""
        yn = self.normalised_output(y_initial)
        n = yn.shape[0]
        un = self.normalised_input(u)[:n]
        nx = self.nx

        P = self.free_parameters().size + nx

        def linearised(x0: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
            with np.errstate(all="ignore"):
                if self.selects_columns:  # the initial state's columns alone
                    start = self._sensitivity_start(x0, np.arange(P - nx, P))
                else:
                    start = self._sensitivity_start(x0)
                y, J = self.jacobian_piece(un, *start)
            r = (yn - y).reshape(-1)
            return float(r @ r), r, J[:, -nx:]

        best_x = np.zeros(nx)
        best, r, J = linearised(best_x)
        if not np.isfinite(best):
            return best_x
        for _ in range(INITIAL_ITERATIONS):
            if not np.all(np.isfinite(J)):
                break
            step = np.linalg.lstsq(J, r, rcond=None)[0]
            for _halving in range(10):  # Gauss-Newton, the step halved until it helps
                trial = best_x + step
                cost, r_new, J_new = linearised(trial)
                if np.isfinite(cost) and cost < best:
                    break
                step = step / 2
            else:
                break  # no step lowers the cost: the best state so far
            gain = (best - cost) / max(best, 1e-300)
            best_x, best, r, J = trial, cost, r_new, J_new
            if self.linear_in_state or gain < 1e-12:
                break  # exact in one step for a linear model; converged otherwise
        return best_x

    def _walk(
        self, un: np.ndarray, yn: np.ndarray, x0: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``J^T J``, ``J^T r``, the residuals ``r`` and each output's column sums of
        ``J`` (rows: outputs) of a free run from ``x0`` on normalised signals, over
        ``[θ, x(0)]``, walked in pieces of ``state_space_rows`` samples
        (:mod:`blockid.config`)."""
        carried = self._sensitivity_start(x0)
        P, ny = self.free_parameters().size + self.nx, yn.shape[1]
        H, g, sums, parts = np.zeros((P, P)), np.zeros(P), np.zeros((ny, P)), []
        piece = get_config()["state_space_rows"]
        for k0 in range(0, un.shape[0], piece):
            out, J = self.jacobian_piece(un[k0 : k0 + piece], *carried)
            r = (yn[k0 : k0 + piece] - out).reshape(-1)
            H += J.T @ J
            g += J.T @ r
            sums += J.reshape(out.shape[0], ny, P).sum(axis=0)
            parts.append(r)
        return H, g, np.concatenate(parts), sums

    def information(
        self, records: Sequence[tuple[Any, Any]]
    ) -> tuple[np.ndarray, list[np.ndarray], np.ndarray]:
        """The Gauss-Newton information ``J^T J`` of the free-run simulation error (in
        the normalised units a fit minimises) over ``θ`` (:meth:`free_parameters`) and
        every record's initial state, each record's residuals (N, ny), and ``J^T 1_i``
        per output ``i`` (rows; ``1_i``: a unit step of output ``i``'s offset).

        ``records``: ``(u, y)`` pairs. Rows and columns: ``θ``, then ``nx`` per record.
        The initial states are those that best fit each whole record at this ``θ`` (one
        Gauss-Newton step from the state its first samples give: exact for a linear
        model), as a fit estimates them.
        """
        p, nx = self.free_parameters().size, self.nx
        H = np.zeros((p + nx * len(records), p + nx * len(records)))
        sums = np.zeros((len(self.outputs), H.shape[0]))
        residuals = []
        for e, (u, y) in enumerate(records):
            un = self.normalised_input(u)
            yn = np.ascontiguousarray(self.normalised_output(y))
            x0 = self.initial_state(u, np.asarray(y)[: min(len(yn), max(50, 10 * nx))])
            with np.errstate(all="ignore"):
                He, ge, _, _ = self._walk(un, yn, x0)
                step = np.linalg.lstsq(He[p:, p:], ge[p:], rcond=None)[0]
                He, _, r, se = self._walk(un, yn, x0 + step)
            cols = np.r_[np.arange(p), p + e * nx + np.arange(nx)]
            H[np.ix_(cols, cols)] += He
            sums[:, cols] += se
            residuals.append(r.reshape(-1, yn.shape[1]))
        return H, residuals, sums

    def output_sensitivities(self, u: Any, y_initial: Any = None) -> tuple[np.ndarray, np.ndarray]:
        """The free run (N, ny) and its derivative (N, ny, p) to the parameters ``θ``, in
        the data's units, from the initial state that ``y_initial`` gives (held fixed);
        the first ``min(n, max_lag)`` outputs are the measured ones, as :meth:`simulate`
        gives them."""
        un = self.normalised_input(u)
        x0, n = np.zeros(self.nx), 0
        if y_initial is not None and len(np.atleast_1d(y_initial)):
            n = min(len(y_initial), un.shape[0])
            x0 = self.initial_state(u, np.asarray(y_initial, dtype=float)[:n])
        p, ny = self.free_parameters().size, len(self.outputs)
        carried = self._sensitivity_start(x0)
        y = np.zeros((un.shape[0], ny))
        dy = np.zeros((un.shape[0], ny, p))
        piece = get_config()["state_space_rows"]
        for k0 in range(0, un.shape[0], piece):
            out, J = self.jacobian_piece(un[k0 : k0 + piece], *carried)
            y[k0 : k0 + out.shape[0]] = out
            dy[k0 : k0 + out.shape[0]] = J[:, :p].reshape(out.shape[0], ny, p)
        scale = np.asarray(self.output_scale, dtype=float).reshape(-1)
        y, dy = y * scale + self.output_offset, dy * scale[None, :, None]
        dy[: self._measured_head(y, y_initial, n)] = 0.0
        return y, dy

    def _measured_head(self, y: np.ndarray, y_initial: Any, n: int) -> int:
        """Set the first ``min(n, max_lag)`` outputs of a run ``y`` to the measured ones
        ``y_initial`` (``n`` of them gave the initial state), as every model's free run
        starts; return how many."""
        k = min(n, self.max_lag)
        if k:
            y[:k] = np.asarray(y_initial, dtype=float).reshape(-1, len(self.outputs))[:k]
        return k


class PolynomialStateSpace(ForwardSensitivities, Model):
    """Polynomial nonlinear state-space model (module docstring).

    Parameters
    ----------
    inputs, outputs : sequence of str
    A, B, C, D : array_like
        Linear part, shapes (nx, nx), (nx, nu), (ny, nx), (ny, nu).
    E, F : array_like, optional
        Coefficients of the monomials, (nx, nm) and (ny, nm) (zeros by default).
    exponents : array_like of int, optional
        (nm, nx + nu): the monomials (:func:`monomial_exponents`); none by default.
    lower, upper : array_like, optional
        Clipping range of ``z = [x; u_n]`` for the monomials (default unbounded).
    observed_lower, observed_upper : array_like, optional
        The range ``z`` covered on the estimation data with the fitted parameters (the
        fit records it), against which :meth:`range_excursion` measures new data;
        default the clipping range.
    input_offset, input_scale, output_offset, output_scale : array_like, optional
        Normalisation of the signals (default 0 and 1).
    K : array_like, optional
        (nx, ny) gain of the one-step predictor ``x(k+1) = ... + K (y - ŷ)`` (a subspace
        estimate's innovation form); None: :meth:`predict` is the free run.
    sampling_time : float, optional

    Examples
    --------
    >>> m = StateSpace(["u"], ["y"], A=[[0.5]], B=[[1.0]], C=[[1.0]], D=[[0.0]])
    >>> m.simulate([1.0, 1.0, 1.0])[:, 0].tolist()
    [0.0, 1.0, 1.5]
    """

    structure: ClassVar[str] = "polynomial-state-space"
    selects_columns: ClassVar[bool] = True

    def __init__(
        self,
        inputs: Any,
        outputs: Any,
        A: Any,
        B: Any,
        C: Any,
        D: Any,
        E: Any = None,
        F: Any = None,
        exponents: Any = None,
        *,
        lower: Any = None,
        upper: Any = None,
        observed_lower: Any = None,
        observed_upper: Any = None,
        input_offset: Any = None,
        input_scale: Any = None,
        output_offset: Any = None,
        output_scale: Any = None,
        K: Any = None,
        sampling_time: float | None = None,
    ) -> None:
        self.inputs = tuple(str(v) for v in ([inputs] if isinstance(inputs, str) else inputs))
        self.outputs = tuple(str(v) for v in ([outputs] if isinstance(outputs, str) else outputs))
        nu, ny = len(self.inputs), len(self.outputs)
        A = np.asarray(A, dtype=float)
        nx = int(A.shape[0]) if A.ndim == 2 else 0
        if nx < 1 or A.shape != (nx, nx):
            raise OrderError(f"A must be a square matrix with at least one state, got {A.shape}")
        self.A = _matrix(A, (nx, nx), "A")
        self.B = _matrix(B, (nx, nu), "B")
        self.C = _matrix(C, (ny, nx), "C")
        self.D = _matrix(D, (ny, nu), "D")
        expo = np.zeros((0, nx + nu), dtype=np.int64) if exponents is None else exponents
        expo = np.asarray(expo, dtype=np.int64).reshape(-1, nx + nu)
        if (expo < 0).any():
            raise OrderError("monomial exponents must be whole numbers >= 0")
        self.exponents = np.ascontiguousarray(expo)
        self.exponents.setflags(write=False)
        nm = expo.shape[0]
        self.E = _matrix(np.zeros((nx, nm)) if E is None else E, (nx, nm), "E")
        self.F = _matrix(np.zeros((ny, nm)) if F is None else F, (ny, nm), "F")
        self.lower = _vector(lower, nx + nu, "lower", -np.inf)
        self.upper = _vector(upper, nx + nu, "upper", np.inf)
        if (self.lower > self.upper).any():
            raise OrderError("every lower bound of the monomials' range must be <= its upper")
        self.observed_lower = _vector(observed_lower, nx + nu, "observed_lower", -np.inf)
        self.observed_upper = _vector(observed_upper, nx + nu, "observed_upper", np.inf)
        if observed_lower is None or observed_upper is None:
            self.observed_lower, self.observed_upper = self.lower, self.upper
        self.input_offset = _vector(input_offset, nu, "input_offset", 0.0)
        self.input_scale = _vector(input_scale, nu, "input_scale", 1.0)
        self.output_offset = _vector(output_offset, ny, "output_offset", 0.0)
        self.output_scale = _vector(output_scale, ny, "output_scale", 1.0)
        if (self.input_scale <= 0).any() or (self.output_scale <= 0).any():
            raise OrderError("signal scales must be positive")
        self.K = None if K is None else _matrix(K, (nx, ny), "K")
        self.sampling_time = sampling_time

    # ------------------------------------------------------------------ structure
    @property
    def nx(self) -> int:
        return int(self.A.shape[0])

    @property
    def n_monomials(self) -> int:
        return int(self.exponents.shape[0])

    @property
    def degree(self) -> int:
        """Largest total degree of the monomials (1 for a linear model)."""
        return max(int(self.exponents.sum(axis=1).max()), 1) if self.n_monomials else 1

    @property
    def max_lag(self) -> int:
        return self.nx

    def poles(self) -> np.ndarray:
        """Eigenvalues of ``A``: the poles of the linear part, those of the model
        linearised at ``x = 0, u_n = 0`` (where the monomials of degree 2 and more have
        zero slope). With a constant monomial the model rests elsewhere; its poles at an
        equilibrium are those of :func:`blockid.models.linearise.linearise`."""
        return np.linalg.eigvals(self.A)

    def is_stable(self, margin: float = 0.0) -> bool:
        return bool(np.max(np.abs(self.poles())) < 1.0 - margin)

    def linear_part(self) -> StateSpace:
        """The model without its monomials (``E = F = 0``)."""
        return StateSpace(
            self.inputs, self.outputs, self.A, self.B, self.C, self.D,
            input_offset=self.input_offset, input_scale=self.input_scale,
            output_offset=self.output_offset, output_scale=self.output_scale, K=self.K,
            sampling_time=self.sampling_time,
        )  # fmt: skip

    # ------------------------------------------------------------------ parameters
    def shaped(self, values: Any) -> dict[str, Any]:
        """Numbers, one per entry of :meth:`free_parameters` (standard errors), shaped
        like the matrices of :attr:`parameters` (``E`` and ``F`` only with monomials)."""
        values = np.asarray(values, dtype=float).reshape(-1)
        mats = [self.A, self.B, self.C, self.D, self.E, self.F]
        parts = np.split(values, np.cumsum([m.size for m in mats])[:-1])
        keys = "ABCDEF" if self.n_monomials else "ABCD"
        return {
            k: part.reshape(m.shape).tolist()
            for k, part, m in zip("ABCDEF", parts, mats, strict=True)
            if k in keys
        }

    def free_parameters(self) -> np.ndarray:
        """``[A, B, C, D, E, F]``, each row-major (the state basis is not fixed: any
        invertible ``T`` gives the same model, so the parameters are unique only up to
        it)."""
        return np.concatenate(
            [m.reshape(-1) for m in (self.A, self.B, self.C, self.D, self.E, self.F)]
        )

    @property
    def parameters(self) -> dict[str, Any]:
        """The matrices by name (normalised units, module docstring), as lists of rows."""
        out: dict[str, Any] = {k: getattr(self, k).tolist() for k in "ABCD"}
        if self.n_monomials:
            out.update(E=self.E.tolist(), F=self.F.tolist())
        return out

    def parameter_table(self) -> list[tuple[str, str]]:
        """One row per matrix row (``A[0]``, ...), and the monomials' count."""
        rows = []
        for key, m in zip("ABCDEF", (self.A, self.B, self.C, self.D, self.E, self.F), strict=True):
            for i, row in enumerate(m):
                if row.size:
                    rows.append((f"{key}[{i}]", ", ".join(f"{v:.6g}" for v in row)))
        if self.n_monomials:
            rows.append(("monomials", f"{self.n_monomials} up to degree {self.degree}"))
        return rows

    def parameter_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Bounds of :meth:`free_parameters`: none."""
        n = self.free_parameters().size
        return np.full(n, -np.inf), np.full(n, np.inf)

    def parameter_mask(self, feedthrough: bool) -> np.ndarray:
        """Which entries of :meth:`free_parameters` a fit moves: all but ``D`` without
        ``feedthrough`` (held at zero)."""
        names = self.free_parameter_names()
        return np.array([feedthrough or not n.startswith("D[") for n in names])

    def free_parameter_names(self) -> list[str]:
        names = []
        for key, m in zip("ABCDEF", (self.A, self.B, self.C, self.D, self.E, self.F), strict=True):
            names += [f"{key}[{i},{j}]" for i in range(m.shape[0]) for j in range(m.shape[1])]
        return names

    def with_free_parameters(self, theta: Any) -> PolynomialStateSpace:
        theta = np.asarray(theta, dtype=float).reshape(-1)
        shapes = [m.shape for m in (self.A, self.B, self.C, self.D, self.E, self.F)]
        sizes = [a * b for a, b in shapes]
        if theta.size != sum(sizes):
            raise OrderError(f"the model takes {sum(sizes)} parameters, got {theta.size}")
        parts = np.split(theta, np.cumsum(sizes)[:-1])
        mats = [p.reshape(s) for p, s in zip(parts, shapes, strict=True)]
        return self.replace(A=mats[0], B=mats[1], C=mats[2], D=mats[3], E=mats[4], F=mats[5])

    def with_monomials(self, exponents: Any) -> PolynomialStateSpace:
        """The same model over the monomials ``exponents`` (rows as in ``exponents``):
        a monomial it has keeps its coefficients, a new one starts at zero, so the model
        simulates as before. The start of a fit one degree up (a warm start).

        >>> m = PolynomialStateSpace(["u"], ["y"], [[0.5]], [[1.0]], [[1.0]], [[0.0]],
        ...                          E=[[0.1]], F=[[0.0]], exponents=[[2, 0]])
        >>> g = m.with_monomials(monomial_exponents(1, 1, 3, "full"))
        >>> g.exponents.tolist()
        [[2, 0], [1, 1], [0, 2], [3, 0], [2, 1], [1, 2], [0, 3]]
        >>> g.E.tolist()
        [[0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]]
        """
        expo = np.asarray(exponents, dtype=np.int64).reshape(-1, self.exponents.shape[1])
        have = {tuple(row): i for i, row in enumerate(self.exponents.tolist())}
        lost = [row for row in have if row not in {tuple(r) for r in expo.tolist()}]
        if lost:
            raise OrderError(f"with_monomials keeps every monomial the model has; {lost} missing")
        E = np.zeros((self.nx, expo.shape[0]))
        F = np.zeros((self.C.shape[0], expo.shape[0]))
        for j, row in enumerate(expo.tolist()):
            i = have.get(tuple(row))
            if i is not None:
                E[:, j], F[:, j] = self.E[:, i], self.F[:, i]
        return self.replace(exponents=expo, E=E, F=F)

    @property
    def has_noise_model(self) -> bool:
        """A predictor gain ``K`` (a subspace estimate's innovation form): its one-step
        residual should be white (:func:`~blockid.evaluation.residual_analysis`)."""
        return self.K is not None

    def replace(self, **changes: Any) -> PolynomialStateSpace:
        """A copy with some constructor arguments changed."""
        kwargs = dict(
            A=self.A, B=self.B, C=self.C, D=self.D, E=self.E, F=self.F, exponents=self.exponents,
            lower=self.lower, upper=self.upper, observed_lower=self.observed_lower,
            observed_upper=self.observed_upper, input_offset=self.input_offset,
            input_scale=self.input_scale, output_offset=self.output_offset,
            output_scale=self.output_scale, K=self.K, sampling_time=self.sampling_time,
        )  # fmt: skip
        defaulted = np.array_equal(self.observed_lower, self.lower) and np.array_equal(
            self.observed_upper, self.upper
        )
        if defaulted and {"lower", "upper"} & set(changes) and "observed_lower" not in changes:
            kwargs.update(observed_lower=None, observed_upper=None)  # follow the new range
        kwargs.update(changes)
        cls = PolynomialStateSpace if np.asarray(kwargs["exponents"]).size else type(self)
        if cls is StateSpace:
            for key in (
                "E",
                "F",
                "exponents",
                "lower",
                "upper",
                "observed_lower",
                "observed_upper",
            ):
                kwargs.pop(key)
        return cls(self.inputs, self.outputs, **kwargs)

    def _arrays(self) -> tuple[np.ndarray, ...]:
        arrays = (self.A, self.B, self.C, self.D, self.E, self.F, self.exponents, self.lower,
                  self.upper)  # fmt: skip
        return tuple(writable(a) for a in arrays)

    # ------------------------------------------------------------------ signals
    def run(self, un: np.ndarray, x0: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Free run on a normalised input from ``x0`` (default 0): normalised outputs
        (N, ny) and the state after the last sample."""
        x = np.zeros(self.nx) if x0 is None else np.array(x0, dtype=float)
        y = np.zeros((un.shape[0], len(self.outputs)))
        pnlss_simulate(*self._arrays(), writable(un), x, y)
        return y, x

    def states(self, u: Any, x0: np.ndarray | None = None) -> np.ndarray:
        """The states of a free run on input ``u`` (rows: samples), with ``x(0) = x0``."""
        un = self.normalised_input(u)
        out = np.empty((un.shape[0], self.nx))
        x = np.zeros(self.nx) if x0 is None else np.array(x0, dtype=float)
        # one run whose output is the state (C = I, D = F = 0: each output is exactly
        # 1 * x_i plus zeros), not one kernel call per sample
        A, B, _, _, E, F, expo, lo, hi = self._arrays()
        nu, nm = B.shape[1], F.shape[1]
        eye, no_d, no_f = np.eye(self.nx), np.zeros((self.nx, nu)), np.zeros((self.nx, nm))
        with np.errstate(all="ignore"):
            pnlss_simulate(A, B, eye, no_d, E, no_f, expo, lo, hi,
                           writable(un), x, out)  # fmt: skip
        return out

    def settled_state(self, un0: np.ndarray, samples: int = 1000) -> np.ndarray:
        """The state the model settles in under the constant normalised input ``un0``
        (one row) from ``x = 0``: rest at the record's first input, where a free run
        "from rest" starts (``x = 0`` is rest only at the estimation data's mean)."""
        x = np.zeros(self.nx)
        y = np.zeros((samples, len(self.outputs)))
        with np.errstate(all="ignore"):
            pnlss_simulate(*self._arrays(), np.repeat(np.atleast_2d(un0), samples, 0), x, y)
        return x if np.all(np.isfinite(x)) else np.zeros(self.nx)

    def step(self, x: Any, un: Any) -> tuple[np.ndarray, np.ndarray]:
        """One sample on normalised signals: ``x(k+1)`` and ``y_n(k)`` from ``x(k)`` and
        ``u_n(k)`` (the simulation's own arithmetic)."""
        x = np.array(x, dtype=float).reshape(self.nx)
        y = np.zeros((1, len(self.outputs)))
        un = np.asarray(un, dtype=float).reshape(1, self.B.shape[1])
        with np.errstate(all="ignore"):
            pnlss_simulate(*self._arrays(), writable(un), x, y)
        return x, y[0]

    def step_jacobians(self, x: Any, un: Any) -> tuple[np.ndarray, ...]:
        """The one-step map's derivatives at ``(x, u_n)`` (normalised signals):
        ``∂x(k+1)/∂x = A + E ∂ζ/∂x``, ``∂x(k+1)/∂u_n = B + E ∂ζ/∂u``,
        ``∂y_n/∂x = C + F ∂ζ/∂x``, ``∂y_n/∂u_n = D + F ∂ζ/∂u`` (:func:`monomial_slopes`)."""
        z = np.r_[np.asarray(x, dtype=float).reshape(-1), np.asarray(un, dtype=float).reshape(-1)]
        slopes = monomial_slopes(z, self.exponents, self.lower, self.upper)
        dx, du = slopes[:, : self.nx], slopes[:, self.nx :]
        return (self.A + self.E @ dx, self.B + self.E @ du, self.C + self.F @ dx,
                self.D + self.F @ du)  # fmt: skip

    # ------------------------------------------------------------------ derivatives
    def _sensitivity_start(
        self, x0: Any, columns: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, ...]]:
        """The state ``x0``, its sensitivity ``[0 | I]`` over ``[θ, x(0)]`` and the
        columns' descriptions for the kernel; ``columns`` (indices into ``[θ, x(0)]``)
        keeps only those, in that order (a fit's free parameters)."""
        P = self.free_parameters().size + self.nx
        nu, ny = self.B.shape[1], len(self.outputs)
        desc = pnlss_columns(self.nx, nu, ny, self.n_monomials)
        cols = np.arange(P) if columns is None else np.asarray(columns, dtype=np.int64)
        desc = tuple(np.ascontiguousarray(d[cols]) for d in desc)
        S = np.zeros((self.nx, cols.size))
        initial = cols >= P - self.nx
        S[cols[initial] - (P - self.nx), np.flatnonzero(initial)] = 1.0
        return np.array(x0, dtype=float), S, desc

    def jacobian_piece(
        self,
        un: np.ndarray,
        x: np.ndarray,
        S: np.ndarray,
        columns: Any = None,
        buffer: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Normalised outputs (n, ny) and ``∂y/∂[θ, x(0)]`` (rows ``k * ny + i``; the
        columns of :meth:`_sensitivity_start`) over a piece of a record, ``x`` and ``S``
        carried in place (:func:`~blockid._kernels.state_space.pnlss_walk`, on the
        threads numba has). ``buffer``: a C-contiguous float array of at least that many
        rows and exactly those columns to write the Jacobian into (a view of it is
        returned; a long walk reuses two instead of touching fresh memory each piece)."""
        ny = len(self.outputs)
        out = np.zeros((un.shape[0], ny))
        rows = un.shape[0] * ny
        J = np.empty((rows, S.shape[1])) if buffer is None else buffer[:rows]
        pnlss_walk(*self._arrays(), writable(un), x, S, out, J, columns)
        return out, J

    @property
    def linear_in_state(self) -> bool:
        """Whether the output is linear in ``x(0)`` (no monomials)."""
        return self.n_monomials == 0

    # ------------------------------------------------------------------ Model
    def simulate(self, u: Any, y_initial: Any = None) -> np.ndarray:
        """Free run; with measured outputs ``y_initial`` the initial state is estimated
        from all of them (module docstring) and the first ``min(n, max_lag)`` outputs are
        copied from them, as every model does."""
        un = self.normalised_input(u)
        x0 = None
        n = 0
        if y_initial is not None and len(np.atleast_1d(y_initial)):
            y0 = np.asarray(y_initial, dtype=float)
            n = min(y0.shape[0], un.shape[0])
            x0 = self.initial_state(u, y0[:n])
        yn, _ = self.run(un, x0)
        y = yn * self.output_scale + self.output_offset
        self._measured_head(y, y_initial, n)
        return y

    def predict(self, u: Any, y: Any) -> np.ndarray:
        """One step ahead. With a predictor gain ``K`` (subspace estimates) the state is
        corrected by every measured output; without (an output-error model, fitted on
        its free run) the one-step prediction is the free run from the state estimated
        from the first ``max_lag`` outputs, as MATLAB's for ``K = 0``."""
        u, y = self._check_signals(u, y)
        if self.K is None:
            return self.simulate(u, y[: self.max_lag])
        un = self.normalised_input(u)
        yn = self.normalised_output(y)
        x = self.initial_state(u, y[: self.max_lag])
        out = np.zeros_like(yn)
        one = np.zeros((1, len(self.outputs)))
        arrays, un = self._arrays(), writable(un)
        for k in range(un.shape[0]):
            before = x.copy()
            pnlss_simulate(*arrays, un[k : k + 1], x, one)
            out[k] = one[0]
            x = x + self.K @ (yn[k] - one[0]) if np.all(np.isfinite(before)) else x
        pred = out * self.output_scale + self.output_offset
        pred[: self.max_lag] = y[: self.max_lag]
        return pred

    def range_excursion(self, u: Any) -> dict[str, float]:
        """How far a free run on ``u`` from rest at its first sample
        (:meth:`settled_state`) drives ``z = [x; u_n]`` beyond the range it covered on
        the estimation data (``observed_lower``/``observed_upper``; fractions of each
        range's width): ``"x1"``, ... for the states, ``"u"`` the inputs' own (the
        largest over the inputs, as :func:`~blockid.evaluation.trust.assess` subtracts
        it); empty for a linear model or an unbounded range."""
        if not self.n_monomials:
            return {}
        un = self.normalised_input(u)
        z = np.hstack([self.states(u, self.settled_state(un[:1])), un])
        out: dict[str, float] = {}
        lo, hi = self.observed_lower, self.observed_upper
        for i in range(z.shape[1]):
            if np.isfinite(lo[i]) and np.isfinite(hi[i]):
                value = excursion((lo[i], hi[i]), z[:, i])
                if i < self.nx:
                    out[f"x{i + 1}"] = value
                else:  # the inputs' own excursion: the largest over the inputs
                    out["u"] = max(out.get("u", 0.0), value)
        return out

    def extrapolation(self, u: Any) -> list[str]:
        """Warnings when ``u`` drives the monomials' arguments beyond their range."""
        notes = []
        for name, value in self.range_excursion(u).items():
            if value > 0.02:
                what = f"state {name}" if name.startswith("x") else f"input {name}"
                notes.append(
                    f"the {what} leaves the range it covered in the estimation data by up to "
                    f"{100 * value:.0f} % of it: the nonlinear terms hold their boundary "
                    "values there"
                )
        return notes

    def to_dict(self) -> dict[str, Any]:
        def finite(v: np.ndarray) -> list[float | None]:
            return [float(x) if np.isfinite(x) else None for x in v]

        out: dict[str, Any] = {
            **self._file_header(),
            "nx": self.nx,
            "A": self.A.tolist(),
            "B": self.B.tolist(),
            "C": self.C.tolist(),
            "D": self.D.tolist(),
            "normalisation": {
                "input_offset": self.input_offset.tolist(),
                "input_scale": self.input_scale.tolist(),
                "output_offset": self.output_offset.tolist(),
                "output_scale": self.output_scale.tolist(),
            },
        }
        if self.K is not None:
            out["K"] = self.K.tolist()
        if self.n_monomials:
            out.update(
                exponents=self.exponents.tolist(), E=self.E.tolist(), F=self.F.tolist(),
                lower=finite(self.lower), upper=finite(self.upper),
                observed_lower=finite(self.observed_lower),
                observed_upper=finite(self.observed_upper),
            )  # fmt: skip
        return out

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> PolynomialStateSpace:
        norm = data.get("normalisation") or {}
        if not isinstance(norm, dict) or (norm and set(norm) != set(_NORMALISATION)):
            raise ModelFileError(
                f"the state-space model file's normalisation ({str(norm)[:80]}) must give "
                f"{', '.join(_NORMALISATION)}: the file was edited or damaged, refit or "
                "restore it"
            )

        def bound(key: str, default: float) -> Any:
            values = data.get(key)
            return None if values is None else [default if v is None else v for v in values]

        try:
            kwargs = dict(
                input_offset=norm.get("input_offset"), input_scale=norm.get("input_scale"),
                output_offset=norm.get("output_offset"), output_scale=norm.get("output_scale"),
                K=data.get("K"), sampling_time=data.get("sampling_time"),
            )  # fmt: skip
            args = (data["inputs"], data["outputs"], data["A"], data["B"], data["C"], data["D"])
            if cls is StateSpace or "exponents" not in data:
                return StateSpace(*args, **kwargs)
            return PolynomialStateSpace(
                *args, data["E"], data["F"], data["exponents"], lower=bound("lower", -np.inf),
                upper=bound("upper", np.inf), observed_lower=bound("observed_lower", -np.inf),
                observed_upper=bound("observed_upper", np.inf), **kwargs,
            )  # fmt: skip
        except OrderError as exc:
            raise ModelFileError(f"the state-space model description is invalid: {exc}") from None


#: The fields of a state-space model file's ``normalisation``.
_NORMALISATION = ("input_offset", "input_scale", "output_offset", "output_scale")


class StateSpace(PolynomialStateSpace):
    """Linear state-space model, ``x(k+1) = A x + B u``, ``y = C x + D u`` (normalised
    signals, module docstring)."""

    structure: ClassVar[str] = "state-space"

    def __init__(self, inputs: Any, outputs: Any, A: Any, B: Any, C: Any, D: Any, **kwargs: Any):
        for key in ("E", "F", "exponents", "lower", "upper"):
            if kwargs.get(key) is not None:
                raise OrderError(f"a linear state-space model has no {key}")
            kwargs.pop(key, None)
        super().__init__(inputs, outputs, A, B, C, D, **kwargs)

    def transfer_function(self, i: int = 0, j: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """Numerator and denominator of output ``i`` over input ``j`` in ``z`` (descending
        powers), in the signals' own units: ``y_i = G(z) u_j``."""
        from scipy.signal import ss2tf

        num, den = ss2tf(self.A, self.B[:, [j]], self.C[[i], :], self.D[[i], [j]].reshape(1, 1))
        gain = self.output_scale[i] / self.input_scale[j]
        return np.asarray(num[0]) * gain, np.asarray(den)
