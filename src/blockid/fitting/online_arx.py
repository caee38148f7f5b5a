"""The online learners of ARX models (:mod:`blockid.fitting.online`): RLS, AW-RLS,
hierarchical RLS and the block ARX of several channels."""

from __future__ import annotations

from typing import Any

import numpy as np

from blockid._kernels import rls as _kr
from blockid.errors import ParameterError
from blockid.estimators.forgetting import ForgettingSchedule
from blockid.fitting.arx import fit_arx, make_estimator, regressor_scale, signal_scales
from blockid.fitting.block_arx import (
    arx_core_model,
    fit_block_arx,
    input_basis,
    regression_orders,
    scalar_orders,
)
from blockid.fitting.online_base import (
    _ARX_NAMES,
    OnlineEstimator,
    _decode_into,
    _defaults,
    _encode,
    _Names,
)
from blockid.models.arx import ARX

__all__: list[str] = []  # built by online_estimator


class _Item:
    """A dict seen as an object (for :func:`_decode_into`)."""

    def __init__(self, d: dict[str, Any]) -> None:
        object.__setattr__(self, "_d", d)

    def __getattr__(self, name: str) -> Any:
        return self._d[name]

    def __setattr__(self, name: str, value: Any) -> None:
        self._d[name] = value


class _OnlineARX(OnlineEstimator):
    """ARX by RLS, AW-RLS or H-RLS online: one recursion per output, as
    :func:`~blockid.fitting.arx.fit_arx` runs them, on the regressor columns divided by
    the given signal scales (or by nothing)."""

    def __init__(self, structure, method, opts, names, scales, initial) -> None:
        super().__init__(names)
        if initial is not None:
            given = {"na": initial.na, "nb": initial.nb, "nk": initial.nk}
            opts = {**{k: v.tolist() for k, v in given.items()}, **opts}
        opts = _defaults(fit_arx, opts)
        self.method = method
        self.schedule = ForgettingSchedule.parse(opts["forgetting"])
        self._last_factor = np.full(1, self.schedule.values[-1])
        inputs, outputs = names
        self.template = ARX(inputs, outputs, opts["na"], opts["nb"], opts["nk"])
        model = self.template
        if initial is not None and (
            initial.inputs != model.inputs or initial.outputs != model.outputs
        ):
            raise ParameterError(
                f"initial has signals {list(initial.inputs)} -> {list(initial.outputs)}, "
                f"not {list(model.inputs)} -> {list(model.outputs)}"
            )
        scaling = "none" if scales is None else signal_scales(scales, len(inputs), len(outputs))
        self.L = model.max_lag  # samples of history the regressors reach back to
        self._u = np.zeros((0, len(inputs)))  # the last L samples (fewer at the start)
        self._y = np.zeros((0, len(outputs)))
        self.outputs = []  # per output: [scale, theta, P, perm, bounds, updates]
        for i in range(len(outputs)):
            n = model.n_parameters(i)
            est = make_estimator(  # the offline defaults of every method
                method,
                forgetting=self.schedule,
                initial_covariance=opts["initial_covariance"],
                eps1=opts["eps1"],
                eps2=opts["eps2"],
                groups=model.hierarchical_groups(i),
            )
            scale = regressor_scale(model, i, scaling)
            theta = np.full(n, float(est.initial_parameters))
            if initial is not None:
                theta = initial.parameter_vector(i) * scale
            groups = model.hierarchical_groups(i) if method == "hierarchical-rls" else [range(n)]
            perm = np.array([c for g in groups for c in g], dtype=np.int64)
            bounds = np.cumsum([0] + [len(g) for g in groups]).astype(np.int64)
            trace = getattr(est, "max_covariance_trace", None) or est.initial_covariance * n
            self.outputs.append(
                {
                    "scale": scale,  # divisors of the regressor columns
                    "theta": np.ascontiguousarray(theta[perm]),  # in group order
                    "P": float(est.initial_covariance) * np.eye(n),
                    "perm": perm,  # column order of the kernel (H-RLS groups contiguous)
                    "bounds": bounds,  # H-RLS group boundaries
                    "trace": float(trace),  # trace bound of P while lambda < 1
                    "eps": (float(getattr(est, "eps1", 0.0)), float(getattr(est, "eps2", 0.0))),
                    "updates": 0,  # updates so far (where the schedule stands)
                }
            )
        self._previous = self._estimates()  # per output before the last step (revert)

    def _estimates(self) -> list[tuple[np.ndarray, np.ndarray, int]]:
        """``(theta, P, updates)`` of every output, by reference (a step replaces the
        arrays, never writes into them)."""
        return [(o["theta"], o["P"], o["updates"]) for o in self.outputs]

    def _revert(self) -> None:
        for out, (theta, P, updates) in zip(self.outputs, self._previous, strict=True):
            out["theta"], out["P"], out["updates"] = theta, P, updates

    @property
    def n_parameters(self) -> int:
        return max(int(o["theta"].size) for o in self.outputs)

    def snapshot(self) -> dict[str, Any]:
        return {"outputs": self.state()["outputs"]}

    def rewind(self, snapshot: dict[str, Any]) -> None:
        for out, saved in zip(self.outputs, snapshot["outputs"], strict=True):
            for key in ("theta", "P"):  # fresh arrays: _previous keeps its own
                out[key] = np.asarray(saved[key]["values"], dtype=float).reshape(
                    saved[key]["shape"]
                )
            out["updates"] = int(saved["updates"])

    def state(self) -> dict[str, Any]:
        out = {name: _encode(getattr(self, name)) for name in ("n_samples", "_u", "_y")}
        out["outputs"] = [
            {"theta": _encode(o["theta"]), "P": _encode(o["P"]), "updates": o["updates"]}
            for o in self.outputs
        ]
        return out

    def restore(self, state: dict[str, Any]) -> _OnlineARX:
        if len(state.get("outputs", ())) != len(self.outputs):
            raise ParameterError("the saved learner state is of another model (its outputs differ)")
        for name in ("n_samples", "_u", "_y"):
            _decode_into(self, name, state[name])
        for out, saved in zip(self.outputs, state["outputs"], strict=True):
            for key in ("theta", "P"):
                _decode_into(_Item(out), key, saved[key])
            out["updates"] = int(saved["updates"])
        return self

    def _lean_regressors(self) -> None:
        """For the per-sample path: where every regressor column of every output sits in
        the vector ``[y(t-L) .. y(t), u(t-L) .. u(t)]`` (rows flattened), its sign and
        its scale, in the kernel's column order."""
        model, L = self.template, self.L
        ny, nu = len(model.outputs), len(model.inputs)
        for i, out in enumerate(self.outputs):
            index, sign = [], []
            for j in range(ny):
                for k in range(1, model.na[i, j] + 1):
                    index.append((L - k) * ny + j)
                    sign.append(-1.0)
            for m in range(nu):
                for lag in range(model.nb[i, m]):
                    index.append((L + 1) * ny + (L - model.nk[i, m] - lag) * nu + m)
                    sign.append(1.0)
            perm = out["perm"]
            out["index"] = np.asarray(index, dtype=np.int64)[perm]
            out["sign"] = np.asarray(sign)[perm]
            out["divisor"] = np.asarray(out["scale"], dtype=float)[perm]

    def _step(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        """One sample without building regressor matrices: the regressor rows gathered
        from the last ``L`` samples and this one, the same kernels (bit-identical to
        :meth:`_learn` on a one-sample chunk)."""
        L = self.L
        if L == 0 or self._u.shape[0] < L:  # still filling the regressor
            return self._learn(u[None, :], y[None, :])[0]
        if "index" not in self.outputs[0]:
            self._lean_regressors()
        ny = y.shape[0]
        V = np.concatenate((self._y.ravel(), y, self._u.ravel(), u))
        pred = np.full(ny, np.nan)
        new = []
        for i, out in enumerate(self.outputs):
            if out["theta"].size == 0:
                new.append(None)
                continue
            # negated, then divided, as the chunk path: the same bits
            Phi = (out["sign"] * V[out["index"]] / out["divisor"])[None, :]
            target = y[i : i + 1].copy()
            theta, P = out["theta"].copy(), out["P"].copy()
            E = np.empty(1)
            status = self._kernel(out, Phi, target, theta, P, E)
            if status != _kr.OK or not np.isfinite(theta).all():
                raise self._diverged(
                    f"{_ARX_NAMES[self.method]} of output {self.template.outputs[i]!r}",
                    0,
                    "the covariance or the estimate became non-finite or lost positive "
                    "definiteness",
                )
            pred[i] = target[0] - E[0]
            new.append((theta, P))
        self._previous = self._estimates()
        for out, state in zip(self.outputs, new, strict=True):  # commit every output
            if state is not None:
                out["theta"], out["P"] = state
                out["updates"] += 1
        n_y = (L + 1) * ny
        self._y = V[ny:n_y].reshape(L, ny)
        self._u = V[n_y + u.shape[0] :].reshape(L, u.shape[0])
        self.n_samples += 1
        return pred

    def _hold(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The sample into the window, no kernel: the prediction ``phi^T theta`` of
        every output (NaN while the window fills), the estimate untouched."""
        L, ny = self.L, y.shape[0]
        pred = np.full(ny, np.nan)
        if self._u.shape[0] < L:  # still filling the regressor
            self._u = np.vstack((self._u, u[None, :]))
            self._y = np.vstack((self._y, y[None, :]))
        else:
            if "index" not in self.outputs[0]:
                self._lean_regressors()
            V = np.concatenate((self._y.ravel(), y, self._u.ravel(), u))
            with np.errstate(over="ignore", invalid="ignore"):  # a glitch may overflow
                for i, out in enumerate(self.outputs):
                    if out["theta"].size:
                        phi = out["sign"] * V[out["index"]] / out["divisor"]
                        pred[i] = float(phi @ out["theta"])
            n_y = (L + 1) * ny
            self._y = V[ny:n_y].reshape(L, ny)
            self._u = V[n_y + u.shape[0] :].reshape(L, u.shape[0])
        self.n_samples += 1
        return pred

    def _kernel(self, out: dict, Phi: np.ndarray, target: np.ndarray, theta, P, E) -> int:
        m = target.size
        if self.method == "aw-rls":
            eps1, eps2 = out["eps"]
            return _kr.aw_rls_run(theta, P, Phi, target, eps1, eps2, np.empty(m), E)
        if m == 1 and out["updates"] >= self.schedule.settled_after:  # the per-sample path
            lam = self._last_factor
        else:
            lam = self.schedule.factors(out["updates"], m)
        if self.method == "rls":
            return _kr.rls_run(theta, P, Phi, target, lam, out["trace"], E)
        return _kr.hierarchical_rls_run(theta, P, Phi, target, out["bounds"], lam, out["trace"], E)

    def _learn(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        m = u.shape[0]
        U, Y = np.vstack((self._u, u)), np.vstack((self._y, y))
        pred = np.full(y.shape, np.nan)
        new = []
        for i, out in enumerate(self.outputs):
            if out["theta"].size == 0:
                new.append(None)
                continue
            Phi, target = self.template.regressors(U, Y, i)
            Phi = np.ascontiguousarray((Phi / out["scale"])[:, out["perm"]])
            theta, P = out["theta"].copy(), out["P"].copy()
            E = np.empty(target.size)
            status = self._kernel(out, Phi, np.ascontiguousarray(target), theta, P, E)
            if status != _kr.OK or not np.all(np.isfinite(theta)):
                row = status if status != _kr.OK else target.size - 1
                raise self._diverged(
                    f"{_ARX_NAMES[self.method]} of output {self.template.outputs[i]!r}",
                    m - target.size + row,
                    "the covariance or the estimate became non-finite or lost positive "
                    "definiteness",
                )
            pred[m - target.size :, i] = target - E
            new.append((theta, P, target.size))
        self._previous = self._estimates()
        for out, state in zip(self.outputs, new, strict=True):  # commit every output
            if state is not None:
                out["theta"], out["P"] = state[0], state[1]
                out["updates"] += state[2]
        self._u, self._y = U[-self.L :], Y[-self.L :]
        self.n_samples += m
        return pred

    def estimate(self) -> dict[str, float]:
        """The recursion's coefficients by name, as the ARX it fits names them (for the
        block model on an ARX core, ``b[y1][u1[coefficients_2]][0]``: the product of a
        block's and the core's coefficients)."""
        arx = self._arx()
        return {
            name: float(value)
            for i in range(len(arx.outputs))
            for name, value in zip(arx.parameter_names(i), arx.parameter_vector(i), strict=True)
        }

    def model(self) -> Any:
        return self._arx()

    def _arx(self) -> ARX:
        """The ARX of the current estimate, on the regressors' own signals."""
        t = self.template
        model = ARX(t.inputs, t.outputs, t.na, t.nb, t.nk)
        for i, out in enumerate(self.outputs):
            if out["theta"].size:
                theta = np.empty_like(out["theta"])
                theta[out["perm"]] = out["theta"]
                model.set_parameter_vector(i, theta / out["scale"])
        return model


class _OnlineBlockARX(_OnlineARX):
    """A Hammerstein model of several inputs and outputs on an ARX core, online: the ARX
    recursion on the input blocks' basis functions and a constant
    (:mod:`blockid.fitting.block_arx`),
    split into blocks and core when :meth:`model` is asked for. The ranges the inputs
    covered so far are the blocks' ranges (a polynomial continues along its tangent
    beyond them)."""

    def __init__(self, structure, method, opts, names, scales, initial) -> None:
        if initial is not None:
            raise ParameterError(
                "a block model on an ARX core learns online from no model (its regression "
                "holds products of block and core coefficients that a model file does not "
                "give); leave --model out",
                parameter="initial",
            )
        opts = dict(opts)
        self.basis = input_basis(opts.pop("input_block", None), opts.pop("output_block", None))
        inputs, outputs = (tuple(n) for n in names)
        orders = _defaults(fit_block_arx, opts)
        na, nb, nk = scalar_orders(orders["na"], orders["nb"], orders["nk"])
        NA, NB, NK = regression_orders(len(outputs), len(inputs), self.basis.size, na, nb, nk)
        opts.update(na=NA.tolist(), nb=NB.tolist(), nk=NK.tolist())
        if scales is not None:  # a basis function's column is scaled by its value at the
            # input's scale (a power p by s^p), the constant by 1
            su = np.broadcast_to(np.asarray(scales[0], dtype=float), (len(inputs),))
            parts = [np.abs(self.basis.functions(np.array([s])))[0] for s in su]
            su = np.r_[np.concatenate(parts), 1.0]
            su[su == 0] = 1.0
            scales = (su, scales[1])
        virtual = self.basis.inputs(inputs)
        super().__init__("arx", method, opts, (virtual, outputs), scales, None)
        self.names = _Names(inputs, outputs)
        self._nu = len(inputs)
        self._range = np.tile([np.inf, -np.inf], (len(inputs), 1))

    def state(self) -> dict[str, Any]:
        return {**super().state(), "_range": _encode(self._range)}

    def restore(self, state: dict[str, Any]) -> _OnlineBlockARX:
        if "_range" not in state:
            raise ParameterError("the saved learner state is of another model (no input ranges)")
        super().restore(state)
        _decode_into(self, "_range", state["_range"])
        return self

    def _widen(self, u: np.ndarray) -> None:
        if u.shape[0]:
            self._range[:, 0] = np.minimum(self._range[:, 0], u.min(axis=0))
            self._range[:, 1] = np.maximum(self._range[:, 1], u.max(axis=0))

    def partial_fit(self, u: Any, y: Any) -> _OnlineBlockARX:
        u, y = self._check(u, y)
        learned = self._learn(self.basis.expanded(u), y) if u.shape[0] else np.zeros_like(y)
        self.predictions_ = learned
        self._widen(u)
        return self

    def update(self, u: Any, y: Any, learn: bool = True) -> np.ndarray:
        u, y = self._sample(u, y)
        expanded = self.basis.expanded(u[None, :])[0]
        if not learn:  # a held sample does not widen the blocks' ranges
            return self._hold(expanded, y)
        prediction = self._step(expanded, y)
        self._widen(u[None, :])
        return prediction

    def model(self) -> Any:
        seen = np.all(np.isfinite(self._range))
        model, _ = arx_core_model(
            self._arx(), self.names.inputs, self.basis,
            input_range=self._range if seen else None,
        )  # fmt: skip
        return model
