"""The online learners of the papers' recursive algorithms (:mod:`blockid.fitting.online`):
paper B's key-term RLS (one input; several, channel by channel) and paper A's backlash
AW-RLS."""

from __future__ import annotations

from abc import abstractmethod
from typing import Any

import numpy as np

from blockid._kernels import backlash_awrls as _kb
from blockid._kernels import key_term as _kk
from blockid._kernels import key_term_channels as _kc
from blockid._kernels import rls as _kr
from blockid.errors import EstimationError, ParameterError
from blockid.estimators.forgetting import ForgettingSchedule
from blockid.fitting.backlash import BACKLASH_AT_LEAST, BacklashAWRLS, fit_backlash_aw_rls
from blockid.fitting.key_term import KEY_TERM_STRUCTURES, KeyTermRLS, fit_key_term_rls
from blockid.fitting.key_term_channels import KEY_TERM_AT_LEAST
from blockid.fitting.online_base import (
    OnlineEstimator,
    _defaults,
    _paper_scales,
    _schedule_factor,
)
from blockid.fitting.options import checked
from blockid.fitting.recursive import (
    Signals,
    initial_vector,
    largest_lag,
    orders_at_least,
)

__all__: list[str] = []  # built by online_estimator


class _PaperOnline(OnlineEstimator):
    """Shared state handling of the two internal-variable recursions (B5, A6–A8).

    The window ``self._buf`` holds the last ``L`` samples of every signal the kernel
    reads (rows: ``self._rows``) and one free slot for the per-sample path; before the
    record it holds the values the offline pass assumes there (0, or the backlash at
    rest). Subclasses set the kernel call.
    """

    _rows: tuple[str, ...]  # signals in the window, the kernel's order
    _state = ("n_samples", "theta", "P", "_buf", "_y_max")

    def _setup(self, algorithm: Any, theta0: np.ndarray, mu: float, lag: int) -> None:
        n = len(algorithm.names)
        self.algorithm = algorithm  # names, n0, unit maps, reasons, read-back
        self.theta = theta0  # estimate on the scaled signals
        self.P = mu * np.eye(n)  # covariance P
        self.L = lag  # samples of history the kernel reaches back to
        self._buf = np.zeros((len(self._rows), lag + 1))  # history | one free slot
        self._err1 = np.full(lag + 1, np.nan)  # a-priori error of the per-sample path
        self._y_max = 0.0  # largest |y| (scaled) seen: the x_hat divergence limit
        self._bak = (theta0.copy(), self.P.copy())  # theta, P before a step (roll-back)
        self._y_max_bak = 0.0  # max|y| before a step (revert)
        self._views = [self._buf[i] for i in range(len(self._rows))]  # rows of the window

    @abstractmethod
    def _run(self, theta, P, arrays, n0, count, err, y_max, single=False):
        """Run the kernel on ``arrays`` (window then chunk; ``single``: the window's
        free slot holds the one new sample) with the first update at ``n0``, ``count``
        updates before it and ``max|y| = y_max``; returns (status, reason)."""

    def _first(self, us: np.ndarray) -> None:
        """Hook before the first sample (the backlash's rest state)."""

    def _n0(self) -> tuple[int, int]:
        """Index of the first update in the window + chunk arrays, and the number of
        updates before it (where a forgetting schedule stands)."""
        n0 = self.algorithm.n0
        return self.L + max(n0 - self.n_samples, 0), max(self.n_samples - n0, 0)

    def _learn(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        us, ys = u[:, 0] / self.su, y[:, 0] / self.sy
        if self.n_samples == 0:
            self._first(us)
        L, m = self.L, us.size
        hist = self._buf[:, :L]
        arrays = [np.empty(L + m) for _ in self._rows]
        for i, arr in enumerate(arrays):
            arr[:L] = hist[i]
        arrays[0][L:] = us
        arrays[1][L:] = ys
        err = np.full(L + m, np.nan)
        n0, count = self._n0()
        y_max = max(self._y_max, float(np.max(np.abs(ys))))
        theta, P = self.theta.copy(), self.P.copy()
        status, reason = self._run(theta, P, arrays, n0, count, err, y_max)
        if status != _kr.OK:
            raise self._diverged(self.algorithm.method, status - L, self.algorithm.reasons[reason])
        np.copyto(self._bak[0], self.theta)
        np.copyto(self._bak[1], self.P)
        self._y_max_bak = self._y_max
        self.theta, self.P, self._y_max = theta, P, y_max
        for i, arr in enumerate(arrays):
            hist[i] = arr[m:]
        self.n_samples += m
        return ((ys - err[L:]) * self.sy)[:, None]

    def _step(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        us, ys = float(u[0]) / self.su, float(y[0]) / self.sy
        buf, L = self._buf, self.L
        if self.n_samples == 0:
            self._first(np.array([us]))
        buf[0, L] = us
        buf[1, L] = ys
        self._err1[L] = np.nan
        n0, count = self._n0()
        y_max = ys if ys > self._y_max else -ys if -ys > self._y_max else self._y_max
        theta_bak, P_bak = self._bak
        np.copyto(theta_bak, self.theta)
        np.copyto(P_bak, self.P)
        status, reason = self._run(
            self.theta, self.P, self._views, n0, count, self._err1, y_max, single=True
        )
        if status != _kr.OK:
            np.copyto(self.theta, theta_bak)
            np.copyto(self.P, P_bak)
            raise self._diverged(self.algorithm.method, 0, self.algorithm.reasons[reason])
        self._y_max_bak, self._y_max = self._y_max, y_max
        buf[:, :L] = buf[:, 1:]
        self.n_samples += 1
        return np.array([(ys - self._err1[L]) * self.sy])

    def _revert(self) -> None:
        np.copyto(self.theta, self._bak[0])
        np.copyto(self.P, self._bak[1])
        self._y_max = self._y_max_bak

    def model(self) -> Any:
        theta = self.algorithm.to_data_units(self.theta)
        return self._read_back(theta)

    def estimate(self) -> dict[str, float]:
        theta = self.algorithm.to_data_units(self.theta)
        return dict(zip(self.algorithm.names, theta.tolist(), strict=True))

    def _read_back(self, theta: np.ndarray) -> Any:
        return self.algorithm.model(theta, self.names)

    def _theta0(self, opts: dict[str, Any], initial_vector_data: Any) -> np.ndarray:
        """``theta(0)`` on the scaled signals, as :func:`fit_recursive` makes it."""
        names = self.algorithm.names
        value = opts["initial_parameters"] if initial_vector_data is None else initial_vector_data
        theta = initial_vector(value, len(names), names)
        if np.ndim(value) != 0:  # given in the data's units
            theta = self.algorithm.from_data_units(theta)
        return np.ascontiguousarray(theta, dtype=float)


def _signals(scales: Any) -> Signals:
    """The unit maps of the recursion (one dummy record: the divergence limit the
    algorithm derives from the record is replaced by the running one)."""
    su, sy = scales if scales is not None else (1.0, 1.0)
    one = np.zeros(1)
    return Signals([("online", one, one)], (0.0, su), (0.0, sy), scales is not None)


def _orders_from(initial: Any, opts: dict[str, Any], fitter: Any) -> dict[str, Any]:
    """Orders not given in ``opts`` taken from the starting model: those of ``fitter``'s
    options (a block degree only where the fitter has one)."""
    if initial is None:
        return opts
    keys = tuple(_defaults(fitter, {}))
    found = {"na": initial.na, "nb": initial.nb, "nk": initial.nk}
    for key, side, size in (("r1", "input", "order"), ("r2", "output", "degree")):
        block = getattr(initial, f"{side}_block", None)
        if key not in keys or block is None:
            continue
        if getattr(block, size, None) is None:  # not the polynomial the papers' RLS learns
            raise ParameterError(
                f"the starting model's {side} block is a {block.kind!r} block; key-term RLS "
                f"learns paper B's polynomial blocks ({key}: the "
                f"{'two-segment polynomial' if key == 'r1' else 'polynomial'}'s degree), so "
                "it cannot continue this model: start the stream without the model (give "
                f"the orders and {key}), or from a model fitted by key-term RLS",
                parameter="initial",
            )
        found[key] = getattr(block, size)
    return {**{k: v for k, v in found.items() if k in keys}, **opts}


class _OnlineKeyTerm(_PaperOnline):
    _state = (*_PaperOnline._state, "_limits")

    """Paper B's key-term RLS (B5) online; window rows ``u, y, w_hat, x_hat``."""

    _rows = ("u", "y", "w", "x")

    def __init__(self, structure, method, opts, names, scales, initial) -> None:
        super().__init__(names)
        scales = _paper_scales(scales)
        opts = _defaults(fit_key_term_rls, _orders_from(initial, opts, fit_key_term_rls))
        has_in, has_out = KEY_TERM_STRUCTURES[structure]
        na, nb, nk = orders_at_least(KEY_TERM_AT_LEAST, na=opts["na"], nb=opts["nb"],
                                     nk=opts["nk"])  # fmt: skip
        r1 = checked("r1", opts["r1"]) if has_in else 0
        r2 = orders_at_least(KEY_TERM_AT_LEAST, r2=opts["r2"])[0] if has_out else 1
        mu = checked("initial_covariance", opts["initial_covariance"])
        schedule = ForgettingSchedule.parse(opts["forgetting"])
        signals = _signals(scales)
        algorithm = KeyTermRLS(structure, (na, nb, nk, r1, r2), schedule, mu, signals)
        self.su, self.sy = signals.u_map[1], signals.y_map[1]  # scales of u and y
        self.schedule = schedule  # lambda over the updates since the record start
        self.structure = structure
        lag = largest_lag(na, nb, nk)
        self.algorithm = algorithm
        theta0 = self._theta0(opts, None if initial is None else self._vector(initial))
        self._setup(algorithm, theta0, mu, lag)
        # kernel arguments of the per-sample path, reused
        self._orders = np.array([r1, nb, na, r2, nk, has_in, has_out, 0, 1, lag], dtype=np.int64)
        self._limits = np.array([algorithm.limits[0], 0.0])
        self._lam1 = np.ones(lag + 1)
        self._no_hist = np.zeros((0, len(algorithm.names)))
        n = len(algorithm.names)
        self._saved = np.empty(n + n * n)  # theta and P before a step (roll-back)
        self._saved[:n], self._saved[n:] = self.theta, self.P.ravel()
        self._bak = (self._saved[:n], self._saved[n:].reshape(n, n))  # the same, as views

    def _step(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The lean per-sample path: one compiled call (:func:`key_term_step`)."""
        if self.n_samples == 0:
            return super()._step(u, y)
        us, ys = float(u[0]) / self.su, float(y[0]) / self.sy
        y_max = self._y_max
        if abs(ys) > y_max:  # the divergence limit grows with max|y| (as offline)
            self._limits[1] = 1e6 * (1.0 + abs(ys))
        n0, count = self._n0()
        lam = _schedule_factor(self.schedule, count) if n0 <= self.L else 1.0
        status, reason, e = _kk.key_term_step(
            self.theta,
            self.P,
            self._buf,
            us,
            ys,
            lam,
            n0,
            self._orders,
            self._limits,
            self._saved,
            self._no_hist,
        )
        if status != _kr.OK:
            self._limits[1] = 1e6 * (1.0 + y_max)
            raise self._diverged(self.algorithm.method, 0, self.algorithm.reasons[reason])
        self._y_max_bak, self._y_max = y_max, max(y_max, abs(ys))
        self.n_samples += 1
        return np.array([(ys - e) * self.sy])

    def _revert(self) -> None:
        super()._revert()
        self._limits[1] = 1e6 * (1.0 + self._y_max)  # the limit follows max|y|

    def _vector(self, model: Any) -> np.ndarray:
        """``theta`` of a model in the data's units, in the order of (B4)."""
        has_in, has_out = self.algorithm.has_in, self.algorithm.has_out
        na, nb, nk, r1, r2 = self.algorithm.orders
        if (model.na, model.nb, model.nk) != (na, nb, nk):
            raise ParameterError(
                f"initial has orders na={model.na}, nb={model.nb}, nk={model.nk}, not "
                f"na={na}, nb={nb}, nk={nk}"
            )
        parts = []
        if has_in:
            block = model.input_block
            if getattr(block, "kind", None) != "two-segment-polynomial" or block.order != r1:
                raise ParameterError(
                    f"initial's input block must be a two-segment polynomial of order {r1}"
                )
            parts += [block.f, block.p, model.b[1:]]
        else:
            parts.append(model.b)
        parts.append(model.a)
        if has_out:
            block = model.output_block
            coef = getattr(block, "coefficients", None)
            if coef is None or block.degree != r2 or block.parameters.get("constant", False):
                raise ParameterError(
                    f"initial's output block must be a polynomial of degree {r2} without constant"
                )
            parts.append(np.asarray(coef)[1:])
        return np.concatenate([np.asarray(p, dtype=float) for p in parts])

    def _run(self, theta, P, arrays, n0, count, err, y_max, single=False):
        u, y, w, x = arrays
        N = u.size
        if single:  # lam of the window's free slot only
            lam = self._lam1
            if n0 <= self.L:
                lam[self.L] = _schedule_factor(self.schedule, count)
        else:
            lam = np.ones(N)
            lam[n0:] = self.schedule.factors(count, max(N - n0, 0))
        orders = self._orders
        orders[7] = n0
        limits = self._limits
        limits[1] = 1e6 * (1.0 + y_max)  # as offline, with max|y| so far
        return _kk.key_term_run(theta, P, u, y, lam, orders, limits, w, x, self._no_hist, err)


class _OnlineKeyTermChannels(OnlineEstimator):
    """Paper B's key-term RLS of several inputs (one output) online
    (:mod:`blockid.fitting.key_term_channels`): the kernel continued from a window of
    the last ``L`` samples of every channel's basis functions, the output and the
    internal estimates ``w_hat``, ``x_hat``; the inputs and ``x_hat`` seen so far are the
    blocks' ranges. Ends with the estimate of ``fit_key_term_channels(.., passes=1)``
    on the same scales (``scales=(input_scale, output_scale)``, or ``normalize=False``
    without them), bit for bit."""

    _state = ("n_samples", "theta", "P", "_phi", "_y", "_w", "_x", "_y_max", "_ranges")

    def __init__(self, structure, method, opts, names, scales, initial) -> None:
        from blockid.fitting.key_term_channels import checked_scales, key_term_algorithm

        super().__init__(names)
        if initial is not None:
            raise ParameterError(
                "key-term RLS of several inputs learns online from no model (its model file "
                "holds the realised state space, not the recursion's parameters); leave "
                "--model out, or give initial_parameters",
                parameter="initial",
            )
        if len(self.names.outputs) != 1:
            raise ParameterError(
                f"key-term RLS identifies one output at a time ({len(self.names.outputs)} "
                "given): learn each output with its own stream, or use --method rls "
                "(Hammerstein, several outputs)",
                parameter="outputs",
            )
        from blockid.fitting.key_term_channels import fit_key_term_channels

        values = _defaults(fit_key_term_channels, opts)
        if structure in KEY_TERM_STRUCTURES:  # a chain structure: paper B's blocks
            has_in, has_out = KEY_TERM_STRUCTURES[structure]
            r = _defaults(fit_key_term_rls, opts)
            values["input_block"] = f"two-segment-polynomial:degree={r['r1']}" if has_in else None
            values["output_block"] = f"polynomial:degree={r['r2']}" if has_out else None
        elif "input_block" not in opts and "output_block" not in opts:
            values["input_block"] = "two-segment-polynomial:degree=3"  # as offline
            values["output_block"] = "polynomial:degree=3"
        algorithm = key_term_algorithm(self.names.inputs, self.names.outputs[0], values)
        if scales is not None:
            su, sy = checked_scales(scales, len(self.names.inputs))
            algorithm.set_scales(algorithm.given_scales(su), sy, 0.0)
        self.algorithm = algorithm
        n = len(algorithm.names)
        value = values["initial_parameters"]
        theta = initial_vector(value, n, algorithm.names)
        if np.ndim(value) != 0:  # given in the data's units
            theta = algorithm.from_data_units(theta)
        self.theta = np.ascontiguousarray(theta, dtype=float)
        self.P = algorithm.mu * np.eye(n)
        self.L = L = algorithm.n0
        m, nf = len(self.names.inputs), algorithm.nf
        self._phi, self._y = np.zeros((L, m, nf)), np.zeros(L)
        self._w, self._x = np.zeros((L, m)), np.zeros(L)
        self._y_max = 0.0
        self._ranges = np.array([[np.inf, -np.inf]] * (m + 1))  # inputs, then x_hat
        self._previous = (self.theta, self.P, self._y_max, self._ranges.copy())  # revert

    def _learn(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        alg, L, N = self.algorithm, self.L, u.shape[0]
        ys = y[:, 0] / alg.sy
        phi = np.concatenate([self._phi, alg._functions(u) / alg.scales])
        yy = np.concatenate([self._y, ys])
        w = np.concatenate([self._w, np.empty((N, self._w.shape[1]))])
        x = np.concatenate([self._x, np.empty(N)])
        n0 = L + max(alg.n0 - self.n_samples, 0)
        count = max(self.n_samples - alg.n0, 0)
        lam = np.ones(L + N)
        lam[n0:] = alg.schedule.factors(count, max(L + N - n0, 0))
        y_max = max(self._y_max, float(np.max(np.abs(ys))))
        limits = np.array([alg.limits[0], 1e6 * (1.0 + y_max)])
        orders = alg.kernel_orders(n0, 1, L)
        err = np.full(L + N, np.nan)
        theta, P = self.theta.copy(), self.P.copy()
        status, reason = _kc.key_term_channels_run(
            theta, P, phi, yy, lam, orders, alg.delays, limits, w, x,
            np.zeros((0, theta.size)), err,
        )  # fmt: skip
        if status != _kr.OK:
            raise self._diverged(alg.method, status - L, alg.reasons[reason])
        self._previous = (self.theta, self.P, self._y_max, self._ranges.copy())
        self.theta, self.P, self._y_max = theta, P, y_max
        self._phi, self._y, self._w, self._x = phi[N:], yy[N:], w[N:], x[N:]
        self._ranges[:-1, 0] = np.minimum(self._ranges[:-1, 0], u.min(axis=0))
        self._ranges[:-1, 1] = np.maximum(self._ranges[:-1, 1], u.max(axis=0))
        if alg.has_out:
            self._ranges[-1] = [min(self._ranges[-1, 0], float(x[L:].min()) * alg.sy),
                                max(self._ranges[-1, 1], float(x[L:].max()) * alg.sy)]  # fmt: skip
        self.n_samples += N
        return ((ys - err[L:]) * alg.sy)[:, None]

    def _revert(self) -> None:
        self.theta, self.P, self._y_max, ranges = self._previous
        np.copyto(self._ranges, ranges)

    def rewind(self, snapshot: dict[str, Any]) -> None:
        self.theta, self.P = self.theta.copy(), self.P.copy()  # _previous keeps its own
        super().rewind(snapshot)

    def model(self) -> Any:
        alg = self.algorithm
        if np.all(np.isfinite(self._ranges[:-1])):
            alg.u_range = self._ranges[:-1].copy()
        alg.x_range = self._ranges[-1].copy()
        return alg.model(alg.to_data_units(self.theta), None)

    def estimate(self) -> dict[str, float]:
        theta = self.algorithm.to_data_units(self.theta)
        return dict(zip(self.algorithm.names, theta.tolist(), strict=True))


class _OnlineBacklash(_PaperOnline):
    """Paper A's AW-RLS (A6–A8) online; window rows ``u, v, x_hat, f1_hat, f2_hat``."""

    _rows = ("u", "v", "x", "f1", "f2")

    def __init__(self, structure, method, opts, names, scales, initial) -> None:
        super().__init__(names)
        scales = _paper_scales(scales)
        opts = _defaults(fit_backlash_aw_rls, _orders_from(initial, opts, fit_backlash_aw_rls))
        na, nb, nk = orders_at_least(BACKLASH_AT_LEAST, na=opts["na"], nb=opts["nb"],
                                     nk=opts["nk"])  # fmt: skip
        eps = (checked("eps1", opts["eps1"]), checked("eps2", opts["eps2"]))
        mu = checked("initial_covariance", opts["initial_covariance"])
        signals = _signals(scales)
        algorithm = BacklashAWRLS((na, nb, nk), eps, signals)
        self.su, self.sy = signals.u_map[1], signals.y_map[1]
        self.algorithm = algorithm
        lag = max(largest_lag(na, nb, nk), nk + 1)  # (A6) reaches x(t - nk - 1)
        theta0 = self._theta0(opts, None if initial is None else self._vector(initial))
        self._setup(algorithm, theta0, mu, lag)
        self._orders = np.array([nb, na, nk, 0, 1, lag], dtype=np.int64)
        self._params = np.array([eps[0], eps[1], 0.0])
        self._no_hist = np.zeros((0, len(algorithm.names)))

    def _vector(self, model: Any) -> np.ndarray:
        na, nb, nk = self.algorithm.orders
        if (model.na, model.nb, model.nk) != (na, nb, nk):
            raise ParameterError(
                f"initial has orders na={model.na}, nb={model.nb}, nk={model.nk}, not "
                f"na={na}, nb={nb}, nk={nk}"
            )
        return np.concatenate((model.input_block.to_theta(), model.b[1:], model.a))

    def _first(self, us: np.ndarray) -> None:
        # before the record the backlash rests mid-dead-band at u(0), as offline
        self._buf[2, : self.L] = _kb.backlash_rest(self.theta, us[0])

    def _run(self, theta, P, arrays, n0, count, err, y_max, single=False):
        u, v, x, f1, f2 = arrays
        orders = self._orders
        orders[3] = n0
        params = self._params
        params[2] = 1e6 * (1.0 + y_max)
        return _kb.backlash_aw_rls_run(
            theta, P, u, v, orders, params, x, f1, f2, self._no_hist, err
        )

    def _read_back(self, theta: np.ndarray) -> Any:
        if not np.all(np.isfinite(theta)):  # pragma: no cover - the kernel checks steps
            raise EstimationError("AW-RLS: the online estimate is not finite")
        return self.algorithm.read_back(theta, self.names)


# ---------------------------------------------------------------------- ARX
