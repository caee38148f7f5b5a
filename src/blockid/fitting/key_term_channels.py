"""Paper B's key-term RLS for several inputs: a static block on every input channel, a
linear block of one output fed by all of them, and a polynomial output block.

.. math::

    w_c(k) = f_c(u_c(k)), \\qquad
    x(k) = \\sum_c B_c(z^{-1})\\, z^{-n_{k,c}}\\, w_c(k) - \\sum_{j=1}^{n_a} a_j x(k-j),
    \\qquad y(k) = x(k) + \\sum_{m=2}^{r_2} q_m x^m(k)

Key-term separation (B4) works channel by channel: with ``b_{c,0} = 1`` on every
channel and ``q_1 = 1``, the newest ``w_c(k - nk_c)`` enter ``y(k)`` through the
block's basis functions, the older ones and ``x`` through their estimates, so ``y(k)``
is linear in every parameter given the internal signals. The recursion (B5) estimates
``w_c`` and ``x`` sample by sample from the newest parameters and takes one RLS step;
passes repeat until the parameters settle (:mod:`blockid.fitting.recursive`). The
compiled pass is :func:`blockid._kernels.key_term_channels.key_term_channels_run`.

What is unique. Each channel's block shares its gain with ``B_c`` (fixed by
``b_{c,0} = 1``), and the output block its gain with the whole linear part (``q_1 =
1``). A constant on each input block would be one constant seen through different
gains, the same regressor column on every channel: the model carries one, on the
first channel's block (the family must have a constant function: the polynomial and
the two-segment polynomial do).

Choices beyond paper B (which has one input):

* Any input block linear in its parameters (its basis functions less the constant):
  paper B's two-segment polynomial (the default), a polynomial.
* The recursion runs on every basis function divided by its root mean square over the
  record and on ``y / std(y)`` (``normalize=True``), the parameters mapped back
  exactly: one scale per regressor column, so channels of different units meet
  ``P(0) = mu I`` alike (the single-input method divides ``u`` by its spread, which
  is the same for its powers up to constants).
* One output: the key term ``b_{c,0} = 1`` fixes each input block's scale through one
  output's linear block; with several outputs the blocks would be scaled differently
  for each, so several outputs are refused with what to do instead.
* Without input blocks (a Wiener model) ``w_c = u_c``, every ``b_{c,0}`` is free and
  the model's constant is an output bias, ``y = h + x + q_2 x^2 + ..`` (the block
  state space's ``h``);
  without an output block (a Hammerstein model) ``x = y`` is measured, the older block
  outputs still estimated; without either (an ARX) the method is plain RLS, equal to
  least squares (test).
* Like the single-input method, it converges only where the internal-variable
  iteration has a stable fixed point, and it is reported when it does not (``did not
  converge``, no model returned; docs/convergence.md). In our tests a constant in an
  input block (``f_0``, or a step at zero, ``p_0``) was enough to make it wander for
  some delays and not others (docs/models.md).

The model returned is a :class:`~blockid.models.block_state_space.BlockStateSpace`
whose core realises the linear block (a state of the last ``na`` values of ``x`` and
the last ``max(nk) + nb - 1`` block outputs of every channel: the channels of shorter
delay are padded with zero coefficients), so it simulates, saves,
exports, reports and compares as every block model of several channels.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from blockid._kernels import key_term_channels as _k
from blockid._kernels.rls import OK
from blockid.blocks import Polynomial
from blockid.blocks.base import block_template
from blockid.data.dataset import Dataset
from blockid.defaults import DEGREE, RECURSIVE
from blockid.errors import DataError, ParameterError
from blockid.estimators.forgetting import ForgettingSchedule
from blockid.fitting.block_arx import Basis, _realisation, scalar_orders
from blockid.fitting.options import checked
from blockid.fitting.recursive import (
    RecursiveAlgorithm,
    Signals,
    fit_recursive,
    int_at_least,
    largest_lag,
)
from blockid.fitting.result import FitResult
from blockid.fitting.state_space import signal_statistics
from blockid.models.arx import ARX
from blockid.models.block_state_space import BlockStateSpace

_KT = RECURSIVE["key-term-rls"]

__all__ = [
    "KEY_TERM_AT_LEAST",
    "ChannelKeyTermRLS",
    "fit_key_term_block",
    "fit_key_term_channels",
    "checked_scales",
    "key_term_algorithm",
]

#: The smallest orders key-term RLS (paper B's B5) takes, declared once for the batch
#: fit, its channels and its online form: one input coefficient at least, and a
#: nonlinear output block (the key-term separation needs degree 2 or more).
KEY_TERM_AT_LEAST = {"na": 0, "nb": 1, "nk": 0, "r2": 2}


def _input_basis(input_block: Any) -> tuple[Basis, int, float]:
    """The basis of the input blocks, and where the family's constant function is (its
    index in the block's vector and its value): the model's one constant goes there."""
    block = block_template(input_block) if isinstance(input_block, str) else input_block
    if not getattr(block, "linear_in_parameters", False) or getattr(block, "role", "") != "static":
        raise ParameterError(
            "key-term RLS needs input blocks linear in their parameters (a two-segment "
            f"polynomial, a polynomial), not {getattr(block, 'kind', block)!r}: use --method "
            "simulation-error for other families",
            parameter="input_block",
        )
    basis = Basis(block)
    probe = np.asarray(block.regressors(np.linspace(-3.0, 3.0, 61)), dtype=float)
    constant = [j for j in range(probe.shape[1]) if np.ptp(probe[:, j]) == 0 and probe[0, j]]
    if not constant:
        raise ParameterError(
            f"key-term RLS carries the model's constant on the first input block, and "
            f"{block.kind} has no constant term: use a polynomial or a two-segment "
            "polynomial",
            parameter="input_block",
        )
    return basis, constant[0], float(probe[0, constant[0]])


def _output_degree(output_block: Any) -> int:
    """The degree of the output polynomial (B3), refusing other families."""
    block = (
        block_template(output_block, output=True) if isinstance(output_block, str) else output_block
    )
    if getattr(block, "kind", None) != "polynomial" or getattr(block, "constant", True):
        raise ParameterError(
            "key-term RLS needs a polynomial output block without constant term (B3), e.g. "
            f"'polynomial:degree=3', not {getattr(block, 'kind', block)!r}: use --method "
            "simulation-error for other families",
            parameter="output_block",
        )
    return int_at_least("output block degree", block.degree, KEY_TERM_AT_LEAST["r2"])


def _delays(nk: Any, inputs: tuple[str, ...]) -> np.ndarray:
    """``nk`` of every input channel: one number for all, or one per input (also as the
    one row of an ARX delay matrix, ``--nk 8,5``)."""
    values = np.atleast_1d(np.asarray(nk, dtype=object))
    if values.ndim == 2 and values.shape[0] == 1:  # a matrix of the one output's row
        values = values[0]
    if values.size == 1:
        values = np.repeat(values, len(inputs))
    if values.ndim != 1 or values.size != len(inputs):
        raise ParameterError(
            f"give nk as one delay or one per input ({len(inputs)}: {', '.join(inputs)}), "
            f"got {nk!r}",
            parameter="nk",
        )
    return np.array([checked("nk", v) for v in values], dtype=np.int64)


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(x**2))) or 1.0


class ChannelKeyTermRLS(RecursiveAlgorithm):
    """Key-term RLS over several input channels (module docstring), on scaled basis
    columns and ``y / sy``."""

    method = "key-term RLS"
    label = "key-term-rls"
    reasons = {
        _k.REASON_STEP: "the RLS update became non-finite or lost positive definiteness "
        "(the first steps from P(0) = initial_covariance I were too large for the "
        "internal estimates: a smaller initial_covariance, e.g. 1e3, often helps)",
        _k.REASON_EXPLODED: "the estimated internal signal x exceeded 1e6 (1 + max|y|): "
        "the estimated linear block drives it unstable",
    }

    @property
    def advice(self) -> str | None:
        """Several inputs: ``refine`` does not apply, the simulation-error fit of the
        block state space does."""
        if len(self.inputs) == 1:
            return None
        return (
            "try other orders or delays, more passes, or fit structure block-state-space "
            "with method simulation-error (any blocks, from the linear state space)"
        )

    def __init__(
        self,
        inputs: tuple[str, ...],
        output: str,
        basis: tuple[Basis, int, float] | None,
        r2: int | None,
        orders: tuple[int, int, np.ndarray],
        schedule: ForgettingSchedule,
        mu: float,
    ) -> None:
        na, nb, delays = orders
        self.inputs, self.output = inputs, output
        self.basis = basis
        self.has_in, self.has_out = basis is not None, r2 is not None
        self.r2 = r2 if r2 is not None else 1
        self.na, self.nb, self.delays = na, nb, delays
        self.schedule = schedule
        self.mu = mu
        m = len(inputs)
        self.nf = basis[0].size if basis is not None else 1
        # a Wiener model's constant: an output bias (an input block carries its own)
        self.bias = self.has_out and not self.has_in
        self.names = self._names()
        self.n0 = max(largest_lag(na, nb, int(d)) for d in delays)
        ia = (1 + m * self.nf if self.has_in else int(self.bias)) + m * (nb - self.has_in)
        self.a = slice(ia, ia + na)
        self.set_scales(np.ones((m, self.nf)), 1.0, 0.0)
        self.x_range = np.array([np.inf, -np.inf])  # of x_hat in the last pass (data units)
        self.u_range: np.ndarray | None = None

    def set_scales(self, scales: np.ndarray, sy: float, y_max: float) -> None:
        """The recursion's units: every basis column divided by ``scales`` (m, nf), the
        output by ``sy``; ``y_max`` the largest ``|y| / sy`` (divergence limit)."""
        self.scales, self.sy = scales, sy
        self.limits = np.array([self.mu * len(self.names), 1e6 * (1.0 + y_max)])
        self.factors = self._factors()

    def given_scales(self, su: Any) -> np.ndarray:
        """Column scales from the inputs' scales ``su`` (one, or one per input): each
        basis function's largest magnitude at ``+su`` and ``-su`` (a power ``p`` scales
        by ``su^p``; 1 where it is 0 at both)."""
        m = len(self.inputs)
        su = np.broadcast_to(np.asarray(su, dtype=float), (m,))
        probe = np.column_stack([su, -su])  # (m, 2): both signs, one row per input
        values = np.abs(self._functions(probe.T))  # (2, m, nf)
        scales = values.max(axis=0)
        scales[scales == 0] = 1.0
        return scales

    def prepare(self, data: Dataset, normalize: bool, su: Any = None, sy: Any = None) -> Signals:
        """The record as the recursion sees it: basis columns divided by their RMS and
        ``y`` by its spread (``normalize``), by the scales the given ``su``, ``sy`` make
        (:meth:`given_scales`), or as they are."""
        functions = [self._functions(e.u) for e in data.experiments]
        all_f = np.concatenate(functions)
        y_all = np.concatenate([e.y[:, 0] for e in data.experiments])
        m = len(self.inputs)
        if su is not None:
            scales, sy = self.given_scales(su), float(sy)
        elif normalize:
            scales = np.array([[_rms(all_f[:, c, j]) for j in range(self.nf)]
                               for c in range(m)])  # fmt: skip
            if not self.has_in:  # the input itself: its spread, as the single-input method
                scales = np.array([[float(np.std(all_f[:, c, 0])) or _rms(all_f[:, c, 0])]
                                   for c in range(m)])  # fmt: skip
            sy = float(np.std(y_all)) or _rms(y_all)
        else:
            scales, sy = np.ones((m, self.nf)), 1.0
        records = [
            (e.name, np.ascontiguousarray(f / scales), np.ascontiguousarray(e.y[:, 0] / sy))
            for e, f in zip(data.experiments, functions, strict=True)
        ]
        signals = Signals(records, (0.0, 1.0), (0.0, sy), bool(normalize or su is not None))
        self.set_scales(scales, sy, signals.y_max)
        u_all = np.vstack([e.u for e in data.experiments])
        self.u_range = np.column_stack([u_all.min(axis=0), u_all.max(axis=0)])
        return signals

    def _functions(self, u: np.ndarray) -> np.ndarray:
        """Every channel's basis functions, shape (N, m, nf)."""
        if self.basis is None:
            return np.ascontiguousarray(u[:, :, None], dtype=float)
        return np.ascontiguousarray(
            np.stack([self.basis[0].functions(u[:, c]) for c in range(u.shape[1])], axis=1)
        )

    def _names(self) -> list[str]:
        names = ["output bias"] if self.bias else []
        if self.has_in:
            names.append("constant")
            names += [f"{u}[{b}]" for u in self.inputs for b in self.basis[0].names]
        first = 1 if self.has_in else 0
        names += [f"b_{i}[{u}]" for u in self.inputs for i in range(first, self.nb)]
        names += [f"a_{j}" for j in range(1, self.na + 1)]
        if self.has_out:
            names += [f"q_{m}" for m in range(2, self.r2 + 1)]
        return names

    def _factors(self) -> np.ndarray:
        """Element-wise factors from the recursion's units to the data's (``w``, ``x``
        in ``y``'s units)."""
        sy, m = self.sy, len(self.inputs)
        parts: list[Any] = [[sy]] if self.bias else []
        if self.has_in:
            parts += [[sy], (sy / self.scales).ravel(), np.ones(m * (self.nb - 1))]
        else:
            parts.append(np.repeat(sy / self.scales[:, 0], self.nb))
        parts.append(np.ones(self.na))
        if self.has_out:
            parts.append(sy ** (1.0 - np.arange(2, self.r2 + 1)))
        return np.concatenate([np.asarray(p, dtype=float) for p in parts])

    def run(self, theta, P, u, y, count, hist, stride):
        N, n0 = u.shape[0], self.n0
        lam = np.ones(N)
        lam[n0:] = self.schedule.factors(count, N - n0)
        orders = self.kernel_orders(n0, stride, 0)
        w, x = np.empty((N, u.shape[1])), np.empty(N)
        status, reason = _k.key_term_channels_run(
            theta, P, u, y, lam, orders, self.delays, self.limits, w, x, hist, np.empty(N)
        )
        detail = ""
        if status != OK and self.has_out:
            x_max = float(np.max(np.abs(x[:status]), initial=0.0)) * self.sy
            y_max = (self.limits[1] / 1e6 - 1.0) * self.sy
            detail = f" (largest |x_hat| so far {x_max:.3g}, largest |y| {y_max:.3g})"
        if count == 0:  # a new pass: the output block's range is that of its last pass
            self.x_range = np.array([np.inf, -np.inf])
        self.widen(x)
        return status, reason, detail

    def kernel_orders(self, n0: int, stride: int, start: int) -> np.ndarray:
        """The kernel's ``orders`` (:func:`~blockid._kernels.key_term_channels.
        key_term_channels_run`)."""
        return np.array(
            [self.nb, self.na, self.r2, self.has_in, self.has_out, n0, stride, start,
             self.bias],
            dtype=np.int64,
        )  # fmt: skip

    def widen(self, x: np.ndarray) -> None:
        """Take ``x_hat`` (the recursion's units) into the output block's range."""
        if x.size:
            self.x_range = np.array([min(self.x_range[0], float(x.min()) * self.sy),
                                     max(self.x_range[1], float(x.max()) * self.sy)])  # fmt: skip

    def to_data_units(self, theta):
        return theta * self.factors

    def from_data_units(self, theta):
        return theta / self.factors

    def _parts(
        self, theta: np.ndarray
    ) -> tuple[list[np.ndarray] | None, float, np.ndarray, np.ndarray, np.ndarray]:
        """``theta`` (data units) split: block coefficients per channel (or None), the
        constant (the first block's, or the output bias), ``b`` (m, nb), ``a`` and ``q``
        (from ``q_1 = 1``)."""
        m, nf, nb = len(self.inputs), self.nf, self.nb
        pos, gammas, constant = 0, None, 0.0
        if self.bias:
            constant, theta = float(theta[0]), theta[1:]
        if self.has_in:
            constant = float(theta[0])
            gammas = [theta[1 + c * nf : 1 + (c + 1) * nf] for c in range(m)]
            pos = 1 + m * nf
            free = theta[pos : pos + m * (nb - 1)].reshape(m, nb - 1)
            b = np.column_stack([np.ones(m), free])
            pos += m * (nb - 1)
        else:
            b = theta[pos : pos + m * nb].reshape(m, nb)
            pos += m * nb
        a = theta[pos : pos + self.na]
        q = np.concatenate(([1.0], theta[pos + self.na :]))
        return gammas, constant, b, a, q

    def model(self, theta, data):
        """The model of ``theta`` (data units); ``data`` gives the sampling time. The
        input blocks' ranges are the inputs seen, the output block's that of ``x_hat``
        in the last pass (:meth:`run`)."""
        sampling_time = getattr(data, "sampling_time", None)
        gammas, constant, b, a, q = self._parts(theta)
        m, nk0 = len(self.inputs), int(self.delays.min())
        width = self.nb + int(self.delays.max()) - nk0
        if not (self.has_in or self.has_out):  # both blocks removed: an ARX
            B = {self.output: {u: b[c] for c, u in enumerate(self.inputs)}}
            return ARX(
                list(self.inputs), [self.output], self.na,
                np.full((1, m), self.nb), self.delays.reshape(1, m),
                a={self.output: {self.output: a}}, b=B, sampling_time=sampling_time,
            )  # fmt: skip
        padded = np.zeros((m, 1, width))  # every channel from the shortest delay
        for c in range(m):
            shift = int(self.delays[c]) - nk0
            padded[c, 0, shift : shift + self.nb] = b[c]
        A, B, C, D = _realisation(a.reshape(-1, 1, 1), padded, nk0)
        blocks = None
        if gammas is not None:
            basis, at, value = self.basis
            blocks = [basis.block(g) for g in gammas]
            vector = blocks[0].to_vector().copy()
            vector[at] = constant / value
            blocks[0] = blocks[0].with_vector(vector)
        seen = self.has_out and bool(np.all(np.isfinite(self.x_range)))
        return BlockStateSpace(
            self.inputs, [self.output], A, B, C, D,
            input_blocks=blocks, output_bias=[constant] if self.bias else None,
            output_blocks=[Polynomial(q, constant=False)] if self.has_out else None,
            input_range=self.u_range if blocks is not None else None,
            output_range=[self.x_range.tolist()] if seen else None,
            sampling_time=sampling_time,
        )  # fmt: skip

    def model_to_check(self, model):
        return _Checked(model, self.na, self.nb, self.delays)

    def settings(self, common):
        settings = {
            "structure": "block-state-space",
            "blocks": {
                "input": self.basis[0].template.kind if self.has_in else None,
                "output": f"polynomial:degree={self.r2}" if self.has_out else None,
            },
            "na": self.na,
            "nb": self.nb,
            "nk": {u: int(d) for u, d in zip(self.inputs, self.delays, strict=True)},
            "forgetting": str(self.schedule),
            "scales": {"basis": self.scales.tolist(), "output": self.sy},
            **common,
        }
        return settings


class _Checked:
    """A model of several inputs (a block model, or the ARX without blocks) as
    :func:`~blockid.fitting.check_model` checks it: against the least-squares ARX of its
    linear block's orders."""

    def __init__(self, model: Any, na: int, nb: int, delays: np.ndarray) -> None:
        self.model, self.orders = model, (na, np.full((1, delays.size), nb),
                                          delays.reshape(1, -1))  # fmt: skip
        self.max_lag = model.max_lag

    def free_parameters(self) -> np.ndarray:
        if isinstance(self.model, ARX):
            return np.concatenate(
                [self.model.parameter_vector(i) for i in range(len(self.model.outputs))]
            )
        return self.model.free_parameters()

    def is_stable(self, margin: float = 0.0) -> bool:
        return self.model.is_stable(margin)

    def poles(self) -> np.ndarray:
        return self.model.poles()

    def linear_orders(self) -> tuple[Any, Any, Any]:
        return self.orders

    def simulate(self, u: Any, y_initial: Any = None) -> np.ndarray:
        return self.model.simulate(u, y_initial)


def fit_key_term_channels(
    data: Dataset,
    *,
    input_block: Any = None,
    output_block: Any = None,
    na: int = 3,
    nb: int = 3,
    nk: Any = 8,
    forgetting: float | str | ForgettingSchedule = _KT["forgetting"],  # type: ignore[assignment]
    passes: int = _KT["passes"],  # type: ignore[assignment]
    tol: float = _KT["tol"],  # type: ignore[assignment]
    initial_covariance: float = _KT["initial_covariance"],  # type: ignore[assignment]
    initial_parameters: Any = 0.01,
    normalize: bool = True,
    record_history: bool = False,
    scales: tuple[Any, float] | None = None,
) -> FitResult:
    """Key-term RLS (B4, B5) of a model with a block per input channel and one output
    (module docstring).

    Parameters
    ----------
    data : Dataset
        One or more inputs, one output; experiments processed one after another.
    input_block : str or StaticBlock, optional
        The family of every input block (linear in its parameters, with a constant
        term: ``two-segment-polynomial:degree=3`` is paper B's); None: no input blocks
        (``w = u``, a Wiener model).
    output_block : str or Polynomial, optional
        A polynomial without constant term of degree ``>= 2`` (``polynomial:degree=3``);
        None: no output block (a Hammerstein model). Neither block: an ARX by RLS.
    na, nb : int
        Orders of the linear block (MATLAB convention, ``nb`` counts ``b_{c,0}``).
    nk : int or sequence of int
        Delay of every input, or one per input.
    forgetting, passes, tol, initial_covariance, initial_parameters, normalize,
    record_history
        As :func:`~blockid.fitting.key_term.fit_key_term_rls` (``initial_parameters``
        as a sequence in the order of ``history["names"]``).
    scales : (input scale(s), output scale), optional
        Fixed scales instead of the measured ones: every basis column divided by its
        largest magnitude at plus and minus its input's scale (a power ``p`` by
        ``s^p``), the output by its scale. What online learning with ``input_scale``,
        ``output_scale`` runs on (:mod:`blockid.fitting.online`): one pass so scaled is
        the online estimate.

    Returns
    -------
    FitResult
        ``model`` a :class:`~blockid.models.block_state_space.BlockStateSpace` (an
        :class:`~blockid.models.ARX` without blocks).

    Raises
    ------
    DataError
        Several outputs (the key term fixes each input block's scale through one
        output's linear block).
    EstimationError
        The recursion diverged, did not converge, or its model fails the checks.
    """
    method = ChannelKeyTermRLS.method
    if not isinstance(data, Dataset):
        raise DataError(f"{method} needs a blockid Dataset, got {type(data).__name__}")
    if data.n_outputs != 1:
        raise DataError(
            f"{method} identifies one output at a time ({data.n_outputs} given: "
            f"{', '.join(data.outputs)}): the key term b_0 = 1 fixes each input block's "
            "scale through one output's linear block. Select one output (--output NAME), "
            "or fit all of them with structure block-state-space and method "
            "simulation-error (any blocks) or batch/rls (input blocks only)"
        )
    options = dict(input_block=input_block, output_block=output_block, na=na, nb=nb, nk=nk,
                   forgetting=forgetting, initial_covariance=initial_covariance)  # fmt: skip
    algorithm = key_term_algorithm(tuple(data.inputs), data.outputs[0], options)  # all checked
    signal_statistics(data)  # every signal must move, inputs not together: else named
    passes, tol = checked("passes", passes), checked("tol", tol)
    mu, na, nb, delays = algorithm.mu, algorithm.na, algorithm.nb, algorithm.delays
    su, sy = (None, None) if scales is None else checked_scales(scales, data.n_inputs)
    signals = algorithm.prepare(data, normalize, su, sy)
    data.check_orders(
        algorithm.n0, len(algorithm.names),
        what=f"key-term RLS na={na}, nb={nb}, nk={delays.tolist()}",
    )  # fmt: skip
    result = fit_recursive(
        data,
        signals,
        algorithm,
        initial_parameters=initial_parameters,
        initial_covariance=mu,
        passes=passes,
        tol=tol,
        record_history=record_history,
    )
    if isinstance(result.model, ARX):
        return result
    # a block model of several channels predicts by its free run (BlockStateSpace.predict)
    return replace(result, metrics_mode="simulation")


def key_term_algorithm(
    inputs: tuple[str, ...], output: str, options: dict[str, Any]
) -> ChannelKeyTermRLS:
    """The recursion of ``options`` (``input_block``, ``output_block``, ``na``, ``nb``,
    ``nk``, ``forgetting``, ``initial_covariance``), each checked and named when wrong:
    what the offline fit and online learning share."""
    schedule = ForgettingSchedule.parse(options["forgetting"])
    block, out = options["input_block"], options["output_block"]
    basis = _input_basis(block) if block is not None else None
    r2 = _output_degree(out) if out is not None else None
    na, nb, _ = scalar_orders(options["na"], options["nb"], 0)  # nb >= 1: the inputs enter
    delays = _delays(options["nk"], tuple(inputs))
    mu = checked("initial_covariance", options["initial_covariance"])
    return ChannelKeyTermRLS(tuple(inputs), output, basis, r2, (na, nb, delays), schedule, mu)


def checked_scales(scales: Any, n_inputs: int) -> tuple[np.ndarray, float]:
    """``(input scales, output scale)``: positive finite, one input scale or one per
    input."""
    try:
        su, sy = scales
        su = np.broadcast_to(np.asarray(su, dtype=float), (n_inputs,)).copy()
        sy = float(sy)
    except (TypeError, ValueError):
        raise ParameterError(
            f"scales must be (input scale or one per input, output scale), got {scales!r}",
            parameter="scales",
        ) from None
    if not (np.all(np.isfinite(su)) and np.all(su > 0) and np.isfinite(sy) and sy > 0):
        raise ParameterError(
            f"scales must be positive finite numbers, got {scales!r}", parameter="scales"
        )
    return su, sy


def fit_key_term_block(
    data: Dataset,
    *,
    input_block: Any = None,
    output_block: Any = None,
    center: bool | None = None,
    **options: Any,
) -> FitResult:
    """``block-state-space`` by ``key-term-rls``: without blocks named, paper B's
    Hammerstein-Wiener (``two-segment-polynomial:degree=3`` on every input,
    ``polynomial:degree=3`` on the output); otherwise the blocks named (only an input
    block: Hammerstein; only an output block: Wiener).

    ``center`` fits on signals less their means (per channel, over every experiment) and
    keeps the means as the model's offsets; default: without input blocks (a Wiener
    model), as the chain structures. The model carries a constant of its own too (the
    first input block's, or a Wiener model's output bias ``h``), but the recursion on
    signals far from zero wandered where the centred one converged (test)."""
    for key, value in (("input_block", input_block), ("output_block", output_block)):
        if isinstance(value, dict):
            raise ParameterError(
                f"key-term RLS takes one {key.replace('_', ' ')} family for every channel "
                "(one KIND); per-channel blocks need --method simulation-error",
                parameter=key,
            )
    if input_block is None and output_block is None:
        input_block = f"two-segment-polynomial:degree={DEGREE}"
        output_block = f"polynomial:degree={DEGREE}"
    center = input_block is None if center is None else bool(checked("center", center))
    if not center:
        result = fit_key_term_channels(
            data, input_block=input_block, output_block=output_block, **options
        )
        return replace(result, settings={**result.settings, "center": False})
    if not isinstance(data, Dataset):
        raise DataError(f"key-term RLS needs a blockid Dataset, got {type(data).__name__}")
    u_off = np.vstack([e.u for e in data.experiments]).mean(axis=0)
    y_off = np.vstack([e.y for e in data.experiments]).mean(axis=0)
    shifted = data.shifted(u_off, y_off)
    result = fit_key_term_channels(
        shifted, input_block=input_block, output_block=output_block, **options
    )
    model = result.model.replace(input_offset=u_off, output_offset=y_off)
    return replace(result, model=model, settings={**result.settings, "center": True})
