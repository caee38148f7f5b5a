"""A linear block with a static nonlinearity of the output in feedback (Lur'e form).

.. math::

    A(z^{-1})\\, y(k) = z^{-n_k} B(z^{-1}) \\bigl[u(k) - N(y(k))\\bigr], \\qquad
    N(y) = \\sum_{m=2}^{r} c_m\\, y^m, \\qquad n_k \\ge 1

with ``u`` and ``y`` taken relative to the model's offsets. This is the discrete form of
a Duffing oscillator such as the Silverbox benchmark (``m y'' + d y' + k y + k_3 y^3 =
u``: a linear second-order system whose cubic stiffness feeds the output back to the
input), and more generally of any linear plant with a memoryless nonlinear feedback.

Choices (and why):

* **The feedback acts through the same ``z^-nk B / A`` as the input**, so the loop is
  one linear block driven by ``v = u - N(y)``: simulation, one-step prediction and the
  Jacobian are recursions of that one block (:mod:`blockid._kernels.feedback`).
* **``n_k >= 1``**: ``y(k)`` depends on ``N(y)`` of past samples only, so the loop has
  no algebraic equation to solve (a sampled plant has at least one sample of delay).
* **No linear term in ``N``** (``c_1 = 0``): a linear feedback ``c_1 y`` only moves
  the poles, ``(A + c_1 z^{-n_k} B) y = z^{-n_k} B u``, which ``a`` already does when
  ``n_k + n_b - 1 <= n_a`` (e.g. ``n_a = 2, n_b \\le 2, n_k = 1``). So ``A`` holds the
  linearisation around the operating point (:meth:`poles`, :meth:`is_stable` are those
  of the small-signal model) and ``b`` is free, because ``u`` enters with unit gain.
  The feedback block is a :class:`~blockid.blocks.Polynomial` without constant whose
  first coefficient (``c_1``) is fixed to 0; its other coefficients are free.
* **No constant in ``N``**: the operating point is the model's offsets (``u_0, y_0``,
  :meth:`replace`, or ``center`` when fitting): at ``u = u_0`` the model rests at
  ``y = y_0``.
* **Other static blocks** may be fed back too (``feedback=DeadZone(..)``,
  ``Saturation``, ``PiecewiseLinear``, ``FreePiecewiseLinear`` or a user's block): a
  friction or a spring with a gap, a stiffness that saturates. Their entries are free as
  :meth:`~blockid.blocks.base.StaticBlock.feedback_mask` says (all, but the end
  breakpoints of a free piecewise-linear map). The piecewise-linear family runs in the
  compiled kernels (:func:`~blockid._kernels.feedback.feedback_simulate_table`); any
  other block is evaluated one sample at a time in Python (correct, some 160 times
  slower). Their sensitivities use the block's own ``derivative`` and ``jacobian``
  (:func:`~blockid._kernels.feedback.feedback_sensitivity_given`). Such a block may
  have a slope at the operating point: :meth:`poles` are then those of
  ``A + N'(0) z^{-n_k} B``, the loop linearised there. With a piecewise-linear map,
  adding a line to ``N`` and taking it out of ``A`` gives the same model (when
  ``n_k + n_b - 1 <= n_a``): the fit is not unique in that one direction, which the
  trust-region steps tolerate, but the standard errors of those entries are then
  meaningless.

Initial state: like :meth:`blockid.models.ChainModel.simulate`, a simulation given
measured outputs starts from the first ``max_lag`` of them (the loop's state is the past
outputs, so the start is exact, no inversion needed); one-step prediction is exact
because the feedback is of measured outputs.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from blockid._kernels import writable
from blockid._kernels.feedback import (
    feedback_sensitivity,
    feedback_sensitivity_given,
    feedback_simulate,
    feedback_simulate_table,
    lagged_sum,
)
from blockid.blocks import Polynomial
from blockid.blocks.base import Block, StaticBlock, block_from_dict
from blockid.blocks.linear import LinearBlock
from blockid.errors import ModelFileError, OrderError
from blockid.models.base import Model, OneChannel, excursion
from blockid.models.block import OneLinearBlock

__all__ = ["LinearFeedback"]


def _one_name(names: Any, what: str) -> tuple[str]:
    names = (names,) if isinstance(names, str) else tuple(names)
    if len(names) != 1:
        raise OrderError(f"a feedback model has one {what}; got {len(names)} ({list(names)})")
    return names


def _checked_linear(linear: Any) -> LinearBlock:
    if getattr(linear, "role", None) != "linear":
        raise OrderError(f"linear must be a LinearBlock, got {linear!r}")
    if linear.nk < 1:
        raise OrderError(
            f"a feedback model needs nk >= 1 (got nk={linear.nk}): with nk = 0 the output "
            "would depend on N of itself, an equation the model does not solve"
        )
    return linear


def _checked_feedback(feedback: Any) -> StaticBlock:
    if getattr(feedback, "role", None) != "static":
        kind = getattr(feedback, "kind", type(feedback).__name__)
        raise OrderError(
            f"the feedback block must be a static block (polynomial, dead-zone, saturation, "
            f"piecewise-linear, ...), got {kind}; a dynamic or linear block cannot be fed back"
        )
    if feedback.kind == Polynomial.kind and (feedback.constant or feedback.coefficients[0] != 0.0):
        raise OrderError(
            "the feedback polynomial has no constant and no linear term (the offsets and "
            "A hold them): use Polynomial([0.0, c_2, .., c_r], constant=False); got "
            f"{feedback.parameters}"
        )
    return feedback


class LinearFeedback(OneLinearBlock, OneChannel, Model):
    """Linear block with a static nonlinearity of the output fed back to its input
    (module docstring).

    .. math::

        A(z^{-1}) y(k) = z^{-n_k} B(z^{-1}) [u(k) - \\textstyle\\sum_{m=2}^r c_m y(k)^m]

    Parameters
    ----------
    input, output : str
        Signal names.
    linear : LinearBlock
        ``A`` and ``B`` (MATLAB convention, ``n_k >= 1``, ``b`` free).
    feedback : StaticBlock, optional
        ``N``: ``Polynomial([0, c_2, .., c_r], constant=False)`` (default the zero cubic)
        or any other static block (module docstring).
    sampling_time : float, optional
    input_offset, output_offset : float
        Operating point subtracted from ``u`` and ``y`` (default 0).
    ranges : dict, optional
        ``{"u": [lo, hi], "y": [lo, hi]}`` seen in estimation, relative to the offsets
        (see :meth:`estimation_ranges`).

    Examples
    --------
    A discrete Duffing oscillator with a hardening cubic:

    >>> from blockid.blocks import Polynomial
    >>> from blockid.blocks.linear import LinearBlock
    >>> m = LinearFeedback("u", "y", linear=LinearBlock(2, 1, 1, a=[-1.6, 0.8], b=[0.2]),
    ...                    feedback=Polynomial([0.0, 0.0, 2.0], constant=False))
    >>> m.free_parameter_names()
    ['a_1', 'a_2', 'b_0', 'c_2', 'c_3']
    >>> m.simulate([1.0, 1.0, 1.0, 1.0])[:, 0].round(4).tolist()
    [0.0, 0.2, 0.5168, 0.8117]
    """

    structure: ClassVar[str] = "feedback"

    def __init__(
        self,
        input: Any,
        output: Any,
        *,
        linear: LinearBlock,
        feedback: StaticBlock | None = None,
        sampling_time: float | None = None,
        input_offset: float = 0.0,
        output_offset: float = 0.0,
        ranges: dict[str, Any] | None = None,
    ) -> None:
        self.inputs = _one_name(input, "input")
        self.outputs = _one_name(output, "output")
        #: ``A`` and ``B`` of the loop.
        self.linear = _checked_linear(linear)
        #: ``N``: the static block fed back (a polynomial has ``c_1 = 0``).
        self.feedback = _checked_feedback(
            Polynomial([0.0, 0.0, 0.0], constant=False) if feedback is None else feedback
        )
        self._mask = np.asarray(self.feedback.feedback_mask(), dtype=bool)
        self._polynomial = self.feedback.kind == Polynomial.kind
        #: ``ranges``: those of ``u`` and ``y`` (relative to the offsets) seen in estimation.
        self._set_channel(sampling_time, input_offset, output_offset, ranges)

    @classmethod
    def template(
        cls, input: Any, output: Any, *, na: int, nb: int, nk: int, r: int = 3, **kwargs: Any
    ) -> LinearFeedback:
        """A model of the given orders and feedback degree ``r`` with zero parameters."""
        if isinstance(r, bool) or not isinstance(r, int | np.integer) or r < 1:
            raise OrderError(f"the feedback degree r must be a whole number >= 1, got {r!r}")
        return cls(
            input,
            output,
            linear=LinearBlock(na, nb, nk),
            feedback=Polynomial(np.zeros(int(r)), constant=False),
            **kwargs,
        )

    # ------------------------------------------------------------------ structure
    @property
    def c(self) -> np.ndarray:
        """The free entries of the feedback block: ``[c_2..c_r]`` of a polynomial."""
        return self.feedback.to_vector()[self._mask]

    @property
    def degree(self) -> int | None:
        """``r``, the degree of the feedback polynomial (None for another block)."""
        return int(self.feedback.coefficients.size) if self._polynomial else None

    @property
    def blocks(self) -> tuple[Block, ...]:
        """The linear block and the feedback block."""
        return (self.linear, self.feedback)

    # what code written for chains asks of a model (fitting settings, figures)
    @property
    def linear_blocks(self) -> tuple[LinearBlock, ...]:
        return (self.linear,)

    @property
    def input_block(self) -> None:
        """None: ``u`` enters the linear block directly."""
        return None

    @property
    def output_block(self) -> None:
        """None: ``y`` is the linear block's output (the nonlinearity is in feedback)."""
        return None

    @property
    def max_lag(self) -> int:
        return self.linear.max_lag

    def linear_orders(self) -> tuple[int, int, int]:
        """``(na, nb, nk)`` of the linear block (the orders of a comparable ARX model)."""
        return self.na, self.nb, self.nk

    def _slope_at_rest(self) -> float:
        """``N'(0)``: zero for a polynomial, a saturation's slope, ..."""
        if self._polynomial:
            return 0.0
        with np.errstate(all="ignore"):
            slope = float(np.asarray(self.feedback.derivative(np.zeros(1)), dtype=float)[0])
        return slope if np.isfinite(slope) else 0.0

    def poles(self) -> np.ndarray:
        """The poles of the model linearised at the operating point: roots of ``A``, or
        of ``A + N'(0) z^{-n_k} B`` when the fed-back block has a slope there."""
        slope = self._slope_at_rest()
        if slope == 0.0:
            return self.linear.poles()
        na, nb, nk = self.na, self.nb, self.nk
        char = np.zeros(max(na, nk + nb - 1) + 1)
        char[0] = 1.0
        char[1 : na + 1] += self.a
        char[nk : nk + nb] += slope * self.b
        return np.roots(np.trim_zeros(char, "b"))

    def is_stable(self, margin: float = 0.0) -> bool:
        """True when the :meth:`poles` lie inside the circle of radius ``1 - margin``.

        This is stability of the small-signal model around the operating point; a
        softening feedback (``N(y) y < 0``) can still make large excursions diverge,
        which a simulation shows.
        """
        if self._slope_at_rest() == 0.0:
            return self.linear.is_stable(margin)
        poles = self.poles()
        return bool(poles.size == 0 or np.max(np.abs(poles)) < 1.0 - margin)

    @property
    def parameters(self) -> dict[str, Any]:
        """``a``, ``b`` and ``c = [c_2..c_r]`` (another block: its own parameters as
        ``N.lower``, ``N.values``, ...)."""
        out: dict[str, Any] = {"a": self.a.tolist(), "b": self.b.tolist()}
        if self._polynomial:
            out["c"] = self.c.tolist()
        else:  # flat, as every model's parameters: numbers or lists of numbers
            own = self.feedback.parameters.items()
            out.update({f"N.{k}": v for k, v in own if not isinstance(v, bool)})
        return out

    # ------------------------------------------------------------------ vectors
    def free_parameters(self) -> np.ndarray:
        """``[a_1..a_na, b_0..b_{nb-1}, c_2..c_r]`` (another block: its free entries)."""
        return np.concatenate((self.a, self.b, self.c))

    def free_parameter_names(self) -> list[str]:
        names = [f"a_{j}" for j in range(1, self.na + 1)]
        names += [f"b_{i}" for i in range(self.nb)]
        if self._polynomial:
            return names + [f"c_{m}" for m in range(2, self.degree + 1)]  # type: ignore[operator]
        own = self.feedback.vector_names()
        return names + [f"N.{own[i]}" for i in np.flatnonzero(self._mask)]

    def parameter_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """None on ``a`` and ``b``; the fed-back block's own (positive slopes, ..)."""
        n = self.na + self.nb
        lo, hi = self.feedback.bounds()
        return (
            np.concatenate((np.full(n, -np.inf), np.asarray(lo, dtype=float)[self._mask])),
            np.concatenate((np.full(n, np.inf), np.asarray(hi, dtype=float)[self._mask])),
        )

    def with_free_parameters(self, theta: Any) -> LinearFeedback:
        """A copy with :meth:`free_parameters` replaced by ``theta`` (ranges kept)."""
        theta = np.asarray(theta, dtype=float).reshape(-1)
        na, nb = self.na, self.nb
        n = na + nb + int(self._mask.sum())
        if theta.size != n:
            raise OrderError(f"expected {n} free parameters, got {theta.size}")
        vector = self.feedback.to_vector()
        vector[self._mask] = theta[na + nb :]
        return self.replace(
            linear=LinearBlock(na, nb, self.nk, theta[:na], theta[na : na + nb]),
            feedback=self.feedback.with_vector(vector),
        )

    def replace(self, **changes: Any) -> LinearFeedback:
        """A copy with ``linear``, ``feedback``, ``sampling_time``, offsets or ``ranges``
        changed (ranges are dropped when an offset changes, unless given)."""
        kwargs = dict(linear=self.linear, feedback=self.feedback, **self._channel_settings(changes))
        unknown = set(changes) - set(kwargs)
        if unknown:
            raise TypeError(f"replace() got unknown field(s) {sorted(unknown)}")
        kwargs.update(changes)
        return type(self)(self.inputs[0], self.outputs[0], **kwargs)

    # ------------------------------------------------------------------ dynamics
    def _arrays(self) -> tuple[np.ndarray, np.ndarray]:
        return (
            writable(self.a, float),
            writable(self.b, float),
        )

    def _start(self, u: Any, y_initial: Any) -> tuple[np.ndarray, np.ndarray, int]:
        """``u - u_0``, the output buffer with the initial outputs, and where to start.

        As :meth:`ChainModel.simulate`: with measured outputs the first ``max_lag``
        samples are set from them (fewer if fewer are given) and the recursion starts at
        ``max_lag``; without, from rest at sample 0.
        """
        u_arr, _ = self._check_signals(u)
        s = np.ascontiguousarray(u_arr[:, 0] - self.input_offset)
        N = s.shape[0]
        y = np.zeros(N)
        n0 = 0
        if y_initial is not None:
            _, y0 = self._check_signals(np.zeros((len(np.atleast_1d(y_initial)), 1)), y_initial)
            n0 = min(self.max_lag, N)
            k = min(n0, y0.shape[0])
            y[:k] = y0[:k, 0] - self.output_offset
        return s, y, n0

    def _loop(self, s: np.ndarray, y: np.ndarray, n0: int) -> np.ndarray:
        """Run the loop in place on ``y`` (rows from ``n0``); returns ``v = u - N(y)``."""
        a, b = self._arrays()
        if self._polynomial:
            c = writable(self.feedback.coefficients, float)
            return feedback_simulate(a, b, c, self.nk, s, y, n0)
        table = self.feedback.piecewise_linear()
        if table is not None:
            xs, ys, left, right = table
            xs = writable(xs, float)
            ys = writable(ys, float)
            return feedback_simulate_table(
                a, b, xs, ys, float(left), float(right), self.nk, s, y, n0
            )
        return self._loop_python(a, b, s, y, n0)

    def _loop_python(
        self, a: np.ndarray, b: np.ndarray, s: np.ndarray, y: np.ndarray, n0: int
    ) -> np.ndarray:
        """The loop for a block the kernels cannot evaluate: one call of it per sample."""
        N, block = y.shape[0], self.feedback
        v = np.full(N, np.nan)
        one = np.zeros(1)
        with np.errstate(all="ignore"):
            for t in range(N):
                if t >= n0:
                    y[t] = lagged_sum(a, b, self.nk, y, v, t)
                one[0] = y[t]
                v[t] = s[t] - float(np.asarray(block(one), dtype=float).reshape(-1)[0])
                if not np.isfinite(v[t]):  # diverged: the rest is not a simulation
                    y[t + 1 :] = np.nan
                    break
        return v

    def block_inputs(self, u: Any) -> list[np.ndarray]:
        """The signal entering each of :attr:`blocks` in a free run from rest: ``v = u -
        N(y)`` into the linear block, ``y`` into the feedback block (relative to the
        offsets)."""
        s, y, n0 = self._start(u, None)
        v = self._loop(s, y, n0)
        return [v, y]

    def simulate(self, u: Any, y_initial: Any = None) -> np.ndarray:
        """Free-run simulation; with ``y_initial`` the first ``max_lag`` outputs are set
        from the measurement (module docstring). Returns shape (N, 1)."""
        s, y, n0 = self._start(u, y_initial)
        self._loop(s, y, n0)
        return (y + self.output_offset)[:, None]

    def simulate_with_sensitivities(
        self, u: Any, y_initial: Any = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Free-run simulation and its derivative with respect to :meth:`free_parameters`.

        Returns ``y`` (N,), equal to ``simulate(u, y_initial)[:, 0]``, and ``dy`` (N,
        n_free) with ``dy[k, i] = ∂y(k)/∂θ_i`` (the recursions of
        :mod:`blockid._kernels.feedback`, through ``A``, ``B`` and ``N'(y)``).
        """
        s, y, n0 = self._start(u, y_initial)
        a, b = self._arrays()
        if self._polynomial:
            c = writable(self.feedback.coefficients, float)
            _, dy = feedback_sensitivity(a, b, c, self.nk, s, y, n0)
            skip = self.na + self.nb  # the row of c_1, fixed to 0
            free = np.concatenate((dy[:skip], dy[skip + 1 :]))
            return y + self.output_offset, free.T
        v = self._loop(s, y, n0)
        block = self.feedback
        with np.errstate(all="ignore"):
            slope = np.ascontiguousarray(np.asarray(block.derivative(y), dtype=float).reshape(-1))
            jac = np.asarray(block.jacobian(y), dtype=float).reshape(y.shape[0], -1)
        forcing = np.ascontiguousarray(jac[:, self._mask].T)
        dy = feedback_sensitivity_given(a, b, self.nk, y, v, slope, forcing, n0)
        return y + self.output_offset, dy.T

    def predict(self, u: Any, y: Any) -> np.ndarray:
        """One step ahead: exact, since the fed-back ``N(y)`` is of measured outputs."""
        u_arr, y_arr = self._check_signals(u, y)
        s = u_arr[:, 0] - self.input_offset
        x = y_arr[:, 0] - self.output_offset
        v = s - self.feedback(x)
        out = self.linear.predict(v, x) + self.output_offset
        out[: self.max_lag] = y_arr[: self.max_lag, 0]
        return out[:, None]

    # ------------------------------------------------------------------ ranges
    def estimation_ranges(self, experiments: Any) -> dict[str, list[float]]:
        """Ranges of ``u`` and of ``y`` (the feedback block's input), relative to the
        offsets, over a sequence of ``(u, y)`` arrays: ``y`` spans both the measured
        outputs (where the equation-error start evaluates ``N``) and the model's free run
        from rest (where the simulation error and :meth:`extrapolation` evaluate it)."""
        us, ys = [], []
        for u, y in experiments:
            u_arr, y_arr = self._check_signals(u, y)
            us.append(u_arr[:, 0] - self.input_offset)
            ys.append(y_arr[:, 0] - self.output_offset)
            ys.append(self.simulate(u_arr)[:, 0] - self.output_offset)
        out = {}
        for key, parts in (("u", us), ("y", ys)):
            values = np.concatenate(parts)
            if values.size and np.all(np.isfinite(values)):
                out[key] = [float(values.min()), float(values.max())]
            elif key == "y":  # a diverging free run: the measured outputs only
                measured = np.concatenate(parts[::2])
                out[key] = [float(measured.min()), float(measured.max())]
        return out

    def range_excursion(self, u: Any) -> dict[str, float]:
        """See :meth:`Model.range_excursion`: ``u`` and the simulated output ``y`` (the
        fed-back block's input), from rest."""
        v, y = self.block_inputs(u)
        u_arr, _ = self._check_signals(u)
        signals = {"u": u_arr[:, 0] - self.input_offset, "y": y}
        return {k: excursion(self.ranges[k], x) for k, x in signals.items() if k in self.ranges}

    def linear_signals(self, u: Any) -> list[tuple[LinearBlock, np.ndarray, np.ndarray]]:
        """See :meth:`Model.linear_signals`: ``v = u - N(y)`` into the linear block, ``y``
        out of it."""
        v, y = self.block_inputs(u)
        return [(self.linear, v, y)]

    def with_ranges(self, experiments: Any) -> LinearFeedback:
        """A copy that remembers the ranges seen in ``experiments``."""
        return self.replace(ranges=self.estimation_ranges(experiments))

    def block_ranges(self) -> list[tuple[str, Any, tuple[float, float]]]:
        """See :meth:`Model.block_ranges`: the fed-back block on the range of ``y``."""
        if "y" not in self.ranges:
            return []
        return [("feedback block", self.feedback, (self.ranges["y"][0], self.ranges["y"][1]))]

    def extrapolation(self, u: Any) -> list[str]:
        """Warnings when the simulated output (from rest) leaves the range of ``y`` seen
        in estimation and the fed-back block is one that says nothing reliable there
        (a polynomial: ``warn_extrapolation``)."""
        if "y" not in self.ranges:
            return []
        y = self.simulate(u)[:, 0] - self.output_offset
        lo, hi = self.ranges["y"]
        span = max(hi - lo, 1e-300)
        out = (y < lo - 0.02 * span) | (y > hi + 0.02 * span)
        if not np.isfinite(y).all():
            kind = self.feedback.kind
            return [f"the simulated output is not finite: the feedback {kind} diverges"]
        if not out.any() or not self.feedback.warn_extrapolation:
            return []
        worst = float(max(lo - y.min(), y.max() - hi)) / span
        return [
            f"the output {self.outputs[0]!r} (input of the feedback {self.feedback.kind}) "
            f"leaves the range seen in estimation [{lo + self.output_offset:.4g}, "
            f"{hi + self.output_offset:.4g}] in {int(out.sum())} of {y.size} samples (by up "
            f"to {100 * worst:.0f} % of that range): the model extrapolates there"
        ]

    # ------------------------------------------------------------------ files
    def to_dict(self) -> dict[str, Any]:
        return {
            **self._file_header(),
            "linear": self.linear.to_dict(),
            "feedback": self.feedback.to_dict(),
            **self._channel_file(),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> LinearFeedback:
        kwargs = cls._channel_from_file(data, "feedback", "the model")
        try:
            return cls(
                data["inputs"][0],
                data["outputs"][0],
                linear=block_from_dict(data["linear"]),  # type: ignore[arg-type]
                feedback=block_from_dict(data["feedback"]),  # type: ignore[arg-type]
                **kwargs,
            )
        except OrderError as exc:
            raise ModelFileError(f"the feedback model's blocks do not fit: {exc}") from None
