"""Multi-input multi-output ARX models (SPEC A1, A5, A9; MATLAB order convention).

.. math::

    y_i(t) = -\\sum_{j=1}^{n_y}\\sum_{k=1}^{n_{a,ij}} a_{ij,k}\\, y_j(t-k)
             + \\sum_{m=1}^{n_u}\\sum_{l=0}^{n_{b,im}-1} b_{im,l}\\, u_m(t - n_{k,im} - l)

``na`` is an ``ny x ny`` matrix of own- and cross-output lag counts, ``nb`` and ``nk``
are ``ny x nu`` matrices of input coefficient counts and delays (a scalar fills every
entry, as MATLAB's ``arx`` does). Paper A's S1 is ``na = nb = nk = 1``; its flow field S3
is ``na = 2, nb = 2, nk = 1`` with two outputs and two inputs.

Signals may be given relative to an operating point: the model subtracts
``input_offset`` from the inputs and ``output_offset`` from the outputs, and adds the
latter back to what it returns.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from blockid._kernels.arx import arx_simulate
from blockid.errors import ModelFileError, OrderError
from blockid.models.base import Model, file_offsets

__all__ = ["ARX", "order_matrix"]


def order_matrix(value: Any, shape: tuple[int, int], name: str, minimum: int = 0) -> np.ndarray:
    """Expand an order given as a scalar, a list or a matrix to an integer ``shape`` array."""
    arr = np.asarray(value)
    if arr.ndim == 0:
        arr = np.full(shape, arr)
    elif arr.ndim == 1 and arr.size == shape[0] * shape[1]:
        arr = arr.reshape(shape)
    if arr.shape != shape:
        raise OrderError(
            f"{name} must be a whole number or a {shape[0]}x{shape[1]} matrix (rows: outputs, "
            f"columns: {'outputs' if name == 'na' else 'inputs'}); got {value!r}"
        )
    try:
        as_int = arr.astype(np.int64)
    except (TypeError, ValueError):
        raise OrderError(f"{name} must hold whole numbers; got {value!r}") from None
    if not np.array_equal(as_int, arr.astype(float)) or (as_int < minimum).any():
        raise OrderError(f"{name} must hold whole numbers >= {minimum}; got {value!r}")
    return as_int


class ARX(Model):
    """Multi-input multi-output ARX model.

    Parameters
    ----------
    inputs, outputs : sequence of str
        Signal names.
    na, nb, nk : int or matrix
        Orders and delays (see the module docstring).
    a : dict or sequence, optional
        ``a[output][output_j]`` = ``[a_1 .. a_na]``; zeros when omitted. With one
        output, the list ``[a_1 .. a_na]`` alone.
    b : dict or sequence, optional
        ``b[output][input]`` = ``[b_0 .. b_{nb-1}]``; zeros when omitted. With one
        input and one output, the list alone.
    sampling_time : float, optional
    input_offset, output_offset : sequence of float, optional
        Operating point subtracted from the signals (default 0).

    Examples
    --------
    Paper A's exhaust-valve loop S1, ``v1(t) = 0.39 u1(t-1) + 0.62 v1(t-1)``:

    >>> s1 = ARX(["u1"], ["v1"], na=1, nb=1, nk=1,
    ...          a={"v1": {"v1": [-0.62]}}, b={"v1": {"u1": [0.39]}})
    >>> s1.simulate([1.0, 1.0, 1.0, 1.0])[:, 0].round(4).tolist()
    [0.0, 0.39, 0.6318, 0.7817]
    """

    structure = "arx"
    #: Fitted with its noise model (equation error): its one-step residual should be
    #: white (:func:`~blockid.evaluation.residual_analysis`).
    has_noise_model = True

    def __init__(
        self,
        inputs: Any,
        outputs: Any,
        na: Any = 1,
        nb: Any = 1,
        nk: Any = 1,
        *,
        a: dict[str, dict[str, Any]] | None = None,
        b: dict[str, dict[str, Any]] | None = None,
        sampling_time: float | None = None,
        input_offset: Any = None,
        output_offset: Any = None,
    ) -> None:
        self.inputs = tuple(inputs)
        self.outputs = tuple(outputs)
        ny, nu = len(self.outputs), len(self.inputs)
        self.na = order_matrix(na, (ny, ny), "na")
        self.nb = order_matrix(nb, (ny, nu), "nb")
        self.nk = order_matrix(nk, (ny, nu), "nk")
        self.sampling_time = sampling_time
        self.input_offset = (
            np.zeros(nu) if input_offset is None else np.asarray(input_offset, float)
        )
        self.output_offset = (
            np.zeros(ny) if output_offset is None else np.asarray(output_offset, float)
        )
        self.a = {
            yi: {yj: np.zeros(self.na[i, j]) for j, yj in enumerate(self.outputs)}
            for i, yi in enumerate(self.outputs)
        }
        self.b = {
            yi: {um: np.zeros(self.nb[i, m]) for m, um in enumerate(self.inputs)}
            for i, yi in enumerate(self.outputs)
        }
        for src, dst, what in ((a, self.a, "a"), (b, self.b, "b")):
            for yi, row in self._nested(src, what).items():
                for name, coeffs in row.items():
                    self._set(dst, what, yi, name, coeffs)

    def _nested(self, src: Any, what: str) -> dict[str, Any]:
        """``a`` or ``b`` as ``{output: {signal: coefficients}}``: a plain sequence is
        taken as the one such list when there is one output (and, for ``b``, one input)."""
        if src is None or isinstance(src, Mapping):
            return dict(src or {})
        columns = self.outputs if what == "a" else self.inputs
        if len(self.outputs) == 1 and len(columns) == 1:
            return {self.outputs[0]: {columns[0]: src}}
        raise OrderError(
            f"{what} must be a dict {what}[output][{'output' if what == 'a' else 'input'}] "
            f"= coefficients when the model has several "
            f"{'outputs' if len(self.outputs) > 1 else 'inputs'}; got a "
            f"{type(src).__name__}"
        )

    def _set(self, dst: dict, what: str, yi: str, name: str, coeffs: Any) -> None:
        if yi not in dst or name not in dst[yi]:
            raise OrderError(f"{what}[{yi!r}][{name!r}] names a signal the model does not have")
        coeffs = np.asarray(coeffs, dtype=float).reshape(-1)
        if coeffs.shape != dst[yi][name].shape:
            raise OrderError(
                f"{what}[{yi!r}][{name!r}] has {coeffs.size} coefficients but the orders call "
                f"for {dst[yi][name].size}"
            )
        dst[yi][name] = coeffs

    # ------------------------------------------------------------------ structure
    @property
    def max_lag(self) -> int:
        lag_a = int(self.na.max(initial=0))
        active = self.nb > 0
        lag_b = int((self.nk + self.nb - 1)[active].max(initial=0)) if active.any() else 0
        return max(lag_a, lag_b, 1)

    def parameter_table(self) -> list[tuple[str, str]]:
        """One row per coefficient, ``a[y1,y1,1]``-style names."""
        rows = []
        for i in range(len(self.outputs)):
            for name, value in zip(self.parameter_names(i), self.parameter_vector(i), strict=True):
                rows.append((name, f"{value:.6g}"))
        return rows

    @property
    def n_free_parameters(self) -> int:
        """Estimated coefficients over every output (offsets are not estimated: means)."""
        return int(sum(self.n_parameters(i) for i in range(len(self.outputs))))

    def n_parameters(self, i: int) -> int:
        """Number of parameters of output ``i``."""
        return int(self.na[i].sum() + self.nb[i].sum())

    def parameter_names(self, i: int) -> list[str]:
        """Names of the entries of :meth:`parameter_vector`, e.g. ``a[y1][y2][1]``."""
        yi = self.outputs[i]
        names = [
            f"a[{yi}][{yj}][{k}]"
            for j, yj in enumerate(self.outputs)
            for k in range(1, self.na[i, j] + 1)
        ]
        names += [
            f"b[{yi}][{um}][{l}]" for m, um in enumerate(self.inputs) for l in range(self.nb[i, m])
        ]
        return names

    def parameter_vector(self, i: int) -> np.ndarray:
        """Parameters of output ``i`` in regressor order: all a's, then all b's."""
        yi = self.outputs[i]
        parts = [self.a[yi][yj] for yj in self.outputs] + [self.b[yi][um] for um in self.inputs]
        return np.concatenate(parts) if parts else np.zeros(0)

    def set_parameter_vector(self, i: int, theta: Any) -> None:
        """Inverse of :meth:`parameter_vector`."""
        theta = np.asarray(theta, dtype=float).reshape(-1)
        if theta.size != self.n_parameters(i):
            raise OrderError(
                f"output {self.outputs[i]!r} has {self.n_parameters(i)} "
                f"parameters, got {theta.size}"
            )
        yi, pos = self.outputs[i], 0
        for j, yj in enumerate(self.outputs):
            self.a[yi][yj] = theta[pos : pos + self.na[i, j]].copy()
            pos += self.na[i, j]
        for m, um in enumerate(self.inputs):
            self.b[yi][um] = theta[pos : pos + self.nb[i, m]].copy()
            pos += self.nb[i, m]

    def hierarchical_groups(self, i: int) -> list[list[int]]:
        """Paper A's H-RLS split of output ``i``'s regressor: output lags | input lags."""
        n_a = int(self.na[i].sum())
        groups = [list(range(n_a)), list(range(n_a, self.n_parameters(i)))]
        return [g for g in groups if g]

    def regressors(self, u: Any, y: Any, i: int) -> tuple[np.ndarray, np.ndarray]:
        """Regressor matrix and target of output ``i`` for samples ``max_lag .. N-1``.

        Columns follow :meth:`parameter_vector`: ``-y_j(t-k)`` then ``u_m(t-nk-l)``.
        Signals are taken relative to the model's offsets.
        """
        u, y = self._check_signals(u, y)
        u = u - self.input_offset
        y = y - self.output_offset
        n0, N = self.max_lag, u.shape[0]
        if N <= n0:  # no sample has a full regressor yet (slices would wrap around)
            return np.zeros((0, self.n_parameters(i))), y[:0, i]
        cols = [
            -y[n0 - k : N - k, j]
            for j in range(len(self.outputs))
            for k in range(1, self.na[i, j] + 1)
        ]
        for m in range(len(self.inputs)):
            for lag in range(self.nb[i, m]):
                d = self.nk[i, m] + lag
                cols.append(u[n0 - d : N - d, m])
        Phi = np.column_stack(cols) if cols else np.zeros((max(N - n0, 0), 0))
        return Phi, y[n0:, i]

    # ------------------------------------------------------------------ dynamics
    def lag_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """Dense ``A[i, j, k]`` (k = lag) and ``B[i, m, l]`` (l = total input lag)."""
        ny, nu = len(self.outputs), len(self.inputs)
        A = np.zeros((ny, ny, int(self.na.max(initial=0)) + 1))
        B = np.zeros((ny, nu, self.max_lag + 1))
        for i, yi in enumerate(self.outputs):
            for j, yj in enumerate(self.outputs):
                A[i, j, 1 : self.na[i, j] + 1] = self.a[yi][yj]
            for m, um in enumerate(self.inputs):
                d = self.nk[i, m]
                B[i, m, d : d + self.nb[i, m]] = self.b[yi][um]
        return A, B

    def poles(self) -> np.ndarray:
        """Eigenvalues of the block-companion matrix of ``A(z)``."""
        A, _ = self.lag_arrays()
        ny, La = A.shape[0], A.shape[2] - 1
        if La == 0:
            return np.zeros(0)
        C = np.zeros((ny * La, ny * La))
        for k in range(1, La + 1):
            C[:ny, (k - 1) * ny : k * ny] = -A[:, :, k]
        C[ny:, : ny * (La - 1)] = np.eye(ny * (La - 1))
        return np.linalg.eigvals(C)

    def is_stable(self, margin: float = 0.0) -> bool:
        """True when every pole lies strictly inside the circle of radius ``1 - margin``."""
        p = self.poles()
        return bool(p.size == 0 or np.max(np.abs(p)) < 1.0 - margin)

    def output_sensitivities(self, u: Any, y_initial: Any = None) -> tuple[np.ndarray, np.ndarray]:
        """Free-run output (N, ny) and its derivative (N, ny, p) to the parameters, output
        by output in the order of :meth:`parameter_vector`, by central differences of
        :meth:`simulate` (a step of ``1e-6`` relative to each parameter, at least 1e-6):
        ``2 p`` compiled simulations, where the free run is linear in the inputs and the
        sensitivities need no model of their own."""
        y = self.simulate(u, y_initial)
        cols = []
        for i in range(len(self.outputs)):
            theta = self.parameter_vector(i)
            for k in range(theta.size):
                h = 1e-6 * max(1.0, abs(theta[k]))
                sims = []
                for step in (h, -h):
                    moved = type(self).from_dict(self.to_dict())
                    t = theta.copy()
                    t[k] += step
                    moved.set_parameter_vector(i, t)
                    sims.append(moved.simulate(u, y_initial))
                cols.append((sims[0] - sims[1]) / (2 * h))
        dy = np.stack(cols, axis=2) if cols else np.zeros(y.shape + (0,))
        return y, dy

    def simulate(self, u: Any, y_initial: Any = None) -> np.ndarray:
        """Free-run simulation; ``y_initial`` gives (at least) the first ``max_lag`` outputs.

        Without ``y_initial`` the model starts at rest at its operating point: inputs and
        outputs before the first sample are taken as the operating point, and every
        sample is simulated.
        """
        u, _ = self._check_signals(u)
        N = u.shape[0]
        n0 = 0 if y_initial is None else self.max_lag
        y = np.zeros((N, len(self.outputs)))
        if y_initial is not None:
            _, y0 = self._check_signals(u[: len(np.atleast_1d(y_initial))], y_initial)
            k = min(n0, y0.shape[0], N)
            y[:k] = y0[:k] - self.output_offset
        A, B = self.lag_arrays()
        arx_simulate(A, B, np.ascontiguousarray(u - self.input_offset), y, min(n0, N))
        return y + self.output_offset

    def predict(self, u: Any, y: Any) -> np.ndarray:
        """One-step-ahead prediction from measured past outputs."""
        u, y = self._check_signals(u, y)
        out = y.copy()
        n0, N = self.max_lag, u.shape[0]
        if N <= n0:
            return out
        u = u - self.input_offset
        y = y - self.output_offset
        # the sum over the columns of regressors(), without building them: a long
        # record costs one column of memory per output instead of the regressor matrix
        for i in range(len(self.outputs)):
            theta, c = self.parameter_vector(i), 0
            acc = np.zeros(N - n0)
            for j in range(len(self.outputs)):
                for k in range(1, self.na[i, j] + 1):
                    acc -= theta[c] * y[n0 - k : N - k, j]
                    c += 1
            for m in range(len(self.inputs)):
                for lag in range(self.nb[i, m]):
                    d = self.nk[i, m] + lag
                    acc += theta[c] * u[n0 - d : N - d, m]
                    c += 1
            out[n0:, i] = acc + self.output_offset[i]
        return out

    # ------------------------------------------------------------------ files
    def to_dict(self) -> dict[str, Any]:
        return {
            **self._file_header(),
            "orders": {"na": self.na.tolist(), "nb": self.nb.tolist(), "nk": self.nk.tolist()},
            "offsets": {
                "inputs": dict(zip(self.inputs, self.input_offset.tolist(), strict=True)),
                "outputs": dict(zip(self.outputs, self.output_offset.tolist(), strict=True)),
            },
            "parameters": {
                yi: {
                    "a": {yj: self.a[yi][yj].tolist() for yj in self.outputs},
                    "b": {um: self.b[yi][um].tolist() for um in self.inputs},
                }
                for yi in self.outputs
            },
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ARX:
        params = data["parameters"]
        offsets = file_offsets(data, "arx")
        for yi in data["outputs"]:
            for what in ("a", "b"):
                for name, coeffs in params[yi][what].items():
                    if not isinstance(coeffs, list) or not all(_is_number(c) for c in coeffs):
                        raise ModelFileError(
                            f"parameters.{yi}.{what}.{name} must be a list of numbers, got "
                            f"{coeffs!r}: the file was edited or damaged, refit or restore it"
                        )
        return cls(
            data["inputs"],
            data["outputs"],
            data["orders"]["na"],
            data["orders"]["nb"],
            data["orders"]["nk"],
            a={yi: params[yi]["a"] for yi in data["outputs"]},
            b={yi: params[yi]["b"] for yi in data["outputs"]},
            sampling_time=data.get("sampling_time"),
            input_offset=offsets["inputs"],
            output_offset=offsets["outputs"],
        )


def _is_number(value: Any) -> bool:
    """A JSON number (not a boolean, a string or null)."""
    return isinstance(value, int | float) and not isinstance(value, bool)
