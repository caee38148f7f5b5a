"""Block-oriented models: a chain of blocks between one input and one output.

.. math::

    s_0 = u - u_0, \\qquad s_{i+1} = G_i(s_i), \\qquad y = s_n + y_0

where every ``G_i`` is a block (:mod:`blockid.blocks`): a static nonlinearity, a
dynamic nonlinearity acting on the measured input (backlash), or a linear dynamic block
(:class:`~blockid.blocks.linear.LinearBlock`). :class:`ChainModel` simulates, predicts,
differentiates and stores any such chain without knowing the kinds of its blocks; the
named structures are chains of a fixed shape:

* :class:`Hammerstein` — static ``N_1`` then linear (two-segment polynomial B1 by
  default);
* :class:`Wiener` — linear then static ``N_2`` (a polynomial without constant, B3, by
  default);
* :class:`HammersteinWiener` — ``N_1``, linear, ``N_2`` (paper B, B1–B3);
* :class:`BacklashModel` — backlash (A3) then linear: paper A's pseudo-Hammerstein;
* :class:`WienerHammerstein` — linear, static, linear.

Linear blocks follow the MATLAB convention (``a = [a_1..a_na]``, ``b = [b_0..b_{nb-1}]``,
``b_0`` multiplies ``w(k - nk)``).

Normalisation (SPEC): a gain between two blocks is not identifiable. A linear block
that follows a nonlinear block fixes ``b_0 = 1``; a static block that follows a linear
block fixes its own input gain (:meth:`~blockid.blocks.base.Block.free_mask`: the output
polynomial fixes ``q_1 = 1``). Paper A's S2 (``v2(t) = x(t-1) + ... - a_1 v2(t-1) - a_2
v2(t-2)``) is ``na = 2, nb = 1, nk = 1`` with ``b_0 = 1``.

Initial state: a simulation given at most ``max_lag`` measured outputs starts the
*last* linear block from them, through the inverse of the static blocks after it where
they are monotone over the range seen in estimation (otherwise from rest); every other
block starts at rest (a backlash in the middle of its dead band). Given more, the first
outputs of every linear block are estimated from them
(:mod:`blockid.models.initial_state`). One-step-ahead prediction recovers the last
linear block's past outputs the same way, so a model with an output block predicts one
step ahead only where that block is invertible over the measured range.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from blockid.blocks import Backlash, Polynomial, TwoSegmentPolynomial
from blockid.blocks.base import BLOCK_TYPES, Block, StaticBlock, block_from_dict
from blockid.blocks.linear import LinearBlock
from blockid.defaults import DEGREE
from blockid.errors import BlockidError, ModelFileError, OrderError, ParameterError
from blockid.models.base import Model, OneChannel, excursion
from blockid.models.initial_state import estimated_starts

__all__ = [
    "ChainModel",
    "OneLinearBlock",
    "BlockModel",
    "Hammerstein",
    "Wiener",
    "HammersteinWiener",
    "BacklashModel",
    "OutputError",
    "WienerHammerstein",
    "BLOCK_STRUCTURES",
]


def _one_name(names: Any, what: str) -> tuple[str]:
    names = (names,) if isinstance(names, str) else tuple(names)
    if len(names) != 1:
        raise OrderError(
            f"a chain of blocks has one {what}; got {len(names)} ({list(names)}). For "
            "several signals use structure arx, state-space, polynomial-state-space or "
            "block-state-space (--structure / --structures), paper B's key-term-rls "
            "method, or a network of blocks"
        )
    return names


class ChainModel(OneChannel, Model):
    """A chain of blocks from one input to one output (module docstring).

    Parameters
    ----------
    input, output : str
        Signal names.
    blocks : sequence of Block
        The chain, input side first: at least one
        :class:`~blockid.blocks.linear.LinearBlock`; a dynamic block only first.
    sampling_time : float, optional
    input_offset, output_offset : float
        Operating point subtracted from ``u`` and ``y`` before the blocks (default 0).
    ranges : dict, optional
        Input ranges of the nonlinear blocks seen in estimation (see :attr:`ranges`).

    Examples
    --------
    A Wiener-Hammerstein chain (linear, static, linear):

    >>> from blockid.blocks import Polynomial
    >>> from blockid.blocks.linear import LinearBlock
    >>> m = ChainModel("u", "y", [LinearBlock(1, 1, 0, a=[-0.5], b=[0.5]),
    ...                           Polynomial([1.0, 0.0, -0.1], constant=False),
    ...                           LinearBlock(1, 1, 1, a=[-0.2], b=[1.0])])
    >>> m.free_parameters().round(3).tolist()
    [-0.5, 0.5, 0.0, -0.1, -0.2]
    """

    structure: ClassVar[str] = "chain"

    def __init__(
        self,
        input: Any,
        output: Any,
        blocks: Sequence[Block],
        *,
        sampling_time: float | None = None,
        input_offset: float = 0.0,
        output_offset: float = 0.0,
        ranges: dict[str, Any] | None = None,
    ) -> None:
        self.inputs = _one_name(input, "input")
        self.outputs = _one_name(output, "output")
        blocks = tuple(blocks)
        self._check_chain(blocks)
        self.blocks: tuple[Block, ...] = blocks
        #: ``ranges``: those of the nonlinear blocks' inputs seen in the estimation data
        #: (relative to the offsets): ``"u"`` for the chain input, ``"x"`` for the input of
        #: the output block, ``"s<i>"`` for a static block ``i`` inside the chain.
        self._set_channel(sampling_time, input_offset, output_offset, ranges)

    # ------------------------------------------------------------------ structure
    def _check_chain(self, blocks: tuple[Block, ...]) -> None:
        if not any(b.role == "linear" for b in blocks):
            raise OrderError("a block-oriented model needs a linear block")
        for i, block in enumerate(blocks):
            if not isinstance(block, Block):
                raise OrderError(f"block {i} is not a block: {block!r}")
            if block.role == "dynamic" and i > 0:
                raise OrderError(
                    f"a dynamic {block.kind} block acts on the measured input: put it first"
                )
            try:
                block.check_normalised(self._after(blocks, i))
            except ParameterError as exc:
                raise OrderError(str(exc)) from None

    @staticmethod
    def _after(blocks: tuple[Block, ...], i: int) -> bool:
        """For a linear block: whether a nonlinear block precedes it; for a nonlinear
        block: whether a linear block does (the normalisation, module docstring)."""
        if i == 0:
            return False
        before = blocks[i - 1].role == "linear"
        return not before if blocks[i].role == "linear" else before

    @property
    def linear_blocks(self) -> tuple[LinearBlock, ...]:
        return tuple(b for b in self.blocks if b.role == "linear")

    @property
    def last_linear_index(self) -> int:
        return max(i for i, b in enumerate(self.blocks) if b.role == "linear")

    @property
    def linear(self) -> LinearBlock:
        """The last linear block (the only one in the named cascades)."""
        return self.blocks[self.last_linear_index]  # type: ignore[return-value]

    @property
    def input_block(self) -> Block | None:
        """The first block when it is nonlinear, else None."""
        first = self.blocks[0]
        return None if first.role == "linear" else first

    @property
    def output_block(self) -> StaticBlock | None:
        """The last block when it is static after the last linear block, else None."""
        last = self.blocks[-1]
        return last if last.role == "static" and len(self.blocks) > 1 else None

    @property
    def max_lag(self) -> int:
        return self.linear.max_lag

    def linear_orders(self) -> tuple[int, int, int]:
        """Orders ``(na, nb, nk)`` of the product of all linear blocks (the chain's
        linear approximation; the only block's orders for one linear block)."""
        lin = self.linear_blocks
        na = sum(g.na for g in lin)
        nk = sum(g.nk for g in lin)
        nb = sum(g.nb for g in lin) - (len(lin) - 1)
        return na, nb, nk

    def is_stable(self, margin: float = 0.0) -> bool:
        """True when every linear block's poles lie inside the circle of radius 1 - margin."""
        return all(g.is_stable(margin) for g in self.linear_blocks)

    def poles(self) -> np.ndarray:
        """Poles of all linear blocks."""
        return np.concatenate([g.poles() for g in self.linear_blocks])

    def fitted_poles(self) -> np.ndarray:
        """Poles of the fitted linear blocks (an integrator's, at 1 by construction, left
        out)."""
        fitted = [g.poles() for g in self.linear_blocks if not g.integrates]
        return np.concatenate([np.zeros(0, dtype=complex), *fitted]).astype(complex)

    def _range_key(self, i: int) -> str:
        if i == 0:
            return "u"
        if i == len(self.blocks) - 1 and i > self.last_linear_index:
            return "x"
        return f"s{i}"

    @property
    def parameters(self) -> dict[str, Any]:
        """Parameters under SPEC's names: ``f, p`` / backlash names, ``a, b``, ``q``.

        With several linear blocks their parameters are ``a1, b1, a2, b2, ..``.
        """
        out: dict[str, Any] = {}
        several = len(self.linear_blocks) > 1
        n_lin = 0
        for i, block in enumerate(self.blocks):
            if block.role == "linear":
                n_lin += 1
                tag = str(n_lin) if several else ""
                out[f"a{tag}"] = block.a.tolist()
                out[f"b{tag}"] = block.b.tolist()
                continue
            rename = block.display_names(self._position(i))
            for key, value in block.parameters.items():
                if key == "constant" and value is (i == 0):
                    continue  # the usual case; kept only when unusual
                name = rename.get(key, key)
                out[name if name not in out else f"{name}_{i}"] = value
        return out

    # ------------------------------------------------------------------ dynamics
    def _u(self, u: Any) -> np.ndarray:
        u, _ = self._check_signals(u)
        return u[:, 0] - self.input_offset

    def _edge(self, i: int, s: np.ndarray) -> np.ndarray | None:
        """``s`` clipped to the input range block ``i`` saw in estimation, for a block
        that extrapolates unreliably (``warn_extrapolation``: polynomials); None for any
        other block or without a recorded range."""
        block = self.blocks[i]
        if not (block.warn_extrapolation and block.role == "static"):
            return None
        seen = self.ranges.get(self._range_key(i))
        return None if seen is None else np.clip(s, seen[0], seen[1])

    def _apply_at(self, i: int, s: np.ndarray) -> np.ndarray:
        """Block ``i`` on signal ``s``, from rest; a block that extrapolates unreliably
        (``warn_extrapolation``: polynomials) continues along its tangent beyond the input
        range recorded in estimation, instead of running away (a cubic does)."""
        block = self.blocks[i]
        out = block.run(s)
        edge = self._edge(i, s)
        if edge is None:
            return out
        outside = edge != s
        if not outside.any():
            return out
        tangent = np.asarray(block(edge[outside]), dtype=float) + block.derivative(
            edge[outside]
        ) * (s[outside] - edge[outside])
        out = np.array(out, dtype=float, copy=True)
        out[outside] = tangent
        return out

    def _slope_at(self, i: int, s: np.ndarray) -> np.ndarray:
        """``d/ds`` of :meth:`_apply_at` for a static block ``i``: the block's derivative,
        held at its value at the range's end where it continues along its tangent."""
        edge = self._edge(i, s)
        return self.blocks[i].derivative(s if edge is None else edge)

    def _run(self, s: np.ndarray, stop: int) -> np.ndarray:
        """The signal entering block ``stop`` (blocks before it from rest)."""
        for i in range(stop):
            s = self._apply_at(i, s)
        return s

    def block_inputs(self, u: Any) -> list[np.ndarray]:
        """The signal entering every block (relative to the input offset), from rest."""
        s, out = self._u(u), []
        for i in range(len(self.blocks)):
            out.append(s)
            s = self._apply_at(i, s)
        return out

    def internal(self, u: Any) -> np.ndarray:
        """The input of the last linear block for input ``u`` (``w = N_1(u)`` of the
        cascades; ``u`` itself when the chain starts with it)."""
        return self._run(self._u(u), self.last_linear_index)

    def x_from_y(self, y: np.ndarray) -> np.ndarray:
        """The last linear block's output from ``y`` (relative to the offset): the static
        blocks after it inverted over the ranges seen in estimation.

        Raises :class:`~blockid.errors.EstimationError` where a block is not invertible.
        """
        x = np.asarray(y, dtype=float)
        for i in range(len(self.blocks) - 1, self.last_linear_index, -1):
            seen = self.ranges.get(self._range_key(i))
            x = self.blocks[i].invert(x, None if seen is None else tuple(seen))
        return x

    def _measured(self, y_initial: Any) -> np.ndarray | None:
        """Measured outputs relative to the offset, shape (n,), or None."""
        if y_initial is None:
            return None
        _, y0 = self._check_signals(np.zeros((len(np.atleast_1d(y_initial)), 1)), y_initial)
        return y0[:, 0] - self.output_offset

    def initial_state(self, y_initial: Any) -> np.ndarray | None:
        """Initial outputs of the last linear block from (the first ``max_lag``)
        measured outputs, or None."""
        y0 = self._measured(y_initial)
        if y0 is None:
            return None
        try:
            return self.x_from_y(y0[: self.max_lag])
        except BlockidError:
            return None

    def simulate(self, u: Any, y_initial: Any = None) -> np.ndarray:
        """Free-run simulation from the input alone.

        Without ``y_initial`` every block starts at rest. With at most ``max_lag``
        measured outputs, the last linear block's first ``max_lag`` outputs are set from
        them (module docstring) and every other block starts at rest. With ``n >
        max_lag`` of them, the first outputs of every linear block are *estimated* so
        that the chain's first ``n`` outputs match them in least squares
        (:func:`~blockid.models.initial_state.estimated_starts`), falling back to the
        start from the first ``max_lag`` where that fails; a dynamic block (backlash)
        still starts at rest.
        """
        s = self._u(u)
        x0 = self.initial_state(y_initial)
        starts = {} if x0 is None else {self.last_linear_index: x0}
        y0 = self._measured(y_initial)
        if y0 is not None and min(y0.size, s.size) > self.max_lag:
            estimated = estimated_starts(self, s, y0, starts)
            if estimated is not None:
                with np.errstate(all="ignore"):
                    y = self._run_started(s, estimated)
                if np.all(np.isfinite(y)):
                    return (y + self.output_offset)[:, None]
        y = self._run_started(s, starts)
        return (y + self.output_offset)[:, None]

    def _run_started(self, s: np.ndarray, starts: dict[int, np.ndarray]) -> np.ndarray:
        """The chain's output (relative to the offset) for input ``s``: linear block ``i``
        started from its first outputs ``starts[i]``, every other block from rest."""
        for i, block in enumerate(self.blocks):
            if i in starts:
                s = block.simulate(s, starts[i])  # type: ignore[call-arg]
            else:
                s = self._apply_at(i, s)
        return s

    def _run_from(self, s: np.ndarray, start: int) -> np.ndarray:
        for i in range(start, len(self.blocks)):
            s = self._apply_at(i, s)
        return s

    def predict(self, u: Any, y: Any) -> np.ndarray:
        """One-step-ahead prediction: the last linear block's past outputs recovered
        from the measured ``y``, its input simulated from ``u``."""
        u_arr, y_arr = self._check_signals(u, y)
        x_meas = self.x_from_y(y_arr[:, 0] - self.output_offset)
        last = self.last_linear_index
        w = self._run(u_arr[:, 0] - self.input_offset, last)
        x_hat = self.blocks[last].predict(w, x_meas)  # type: ignore[attr-defined]
        out = self._run_from(x_hat, last + 1) + self.output_offset
        out[: self.max_lag] = y_arr[: self.max_lag, 0]
        return out[:, None]

    # ------------------------------------------------------------------ vectors
    def _position(self, i: int) -> str:
        """Where block ``i`` sits: ``"input"``, ``"output"`` or ``"middle"``."""
        if self.blocks[i] is self.output_block:
            return "output"
        return "input" if i == 0 and self.blocks[0].role != "linear" else "middle"

    def _masks(self) -> list[np.ndarray]:
        return [b.free_mask(self._after(self.blocks, i)) for i, b in enumerate(self.blocks)]

    def free_parameters(self) -> np.ndarray:
        """The identifiable parameters as one vector, block after block, without the
        entries the normalisation fixes (``b_0`` after a nonlinear block, ``q_1``)."""
        parts = [b.to_vector()[m] for b, m in zip(self.blocks, self._masks(), strict=True)]
        return np.concatenate(parts) if parts else np.zeros(0)

    def free_parameter_names(self) -> list[str]:
        """Names of :meth:`free_parameters`' entries, e.g. ``f_0``, ``a_1``, ``q_2``."""
        names: list[str] = []
        for i, (block, mask) in enumerate(zip(self.blocks, self._masks(), strict=True)):
            if block.role == "linear":
                full = [f"a_{j}" for j in range(1, block.na + 1)]
                full += [f"b_{j}" for j in range(block.nb)]
                if len(self.linear_blocks) > 1:
                    k = self.linear_blocks.index(block) + 1
                    full = [f"{n[0]}{k}{n[1:]}" for n in full]
            else:
                full = block.vector_names(block.display_names(self._position(i)))
            names += [n for n, keep in zip(full, mask, strict=True) if keep]
        return names

    def parameter_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Bounds of :meth:`free_parameters` (positive slopes, non-negative dead bands)."""
        lows, highs = [], []
        for block, mask in zip(self.blocks, self._masks(), strict=True):
            lo, hi = block.bounds()
            lows.append(lo[mask])
            highs.append(hi[mask])
        return np.concatenate(lows), np.concatenate(highs)

    def simulate_with_sensitivities(
        self, u: Any, y_initial: Any = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Free-run simulation ``y`` (N,) and its derivative ``dy`` (N, n_free) with
        respect to :meth:`free_parameters`, started from the first ``max_lag`` of
        ``y_initial`` (:func:`blockid.models.sensitivities.chain_sensitivities`)."""
        from blockid.models.sensitivities import chain_sensitivities

        return chain_sensitivities(self, u, y_initial)

    def block_columns(self) -> list[np.ndarray]:
        """For every block, the column of :meth:`free_parameters` of each entry of its
        vector (-1 for a fixed entry)."""
        cols, pos = [], 0
        for mask in self._masks():
            c = np.full(mask.size, -1)
            c[mask] = np.arange(pos, pos + int(mask.sum()))
            pos += int(mask.sum())
            cols.append(c)
        return cols

    def with_free_parameters(self, theta: Any) -> ChainModel:
        """A copy with :meth:`free_parameters` replaced by ``theta`` (ranges kept)."""
        theta = np.asarray(theta, dtype=float).reshape(-1)
        n = self.free_parameters().size
        if theta.size != n:
            raise OrderError(f"expected {n} free parameters, got {theta.size}")
        blocks, pos = [], 0
        for block, mask in zip(self.blocks, self._masks(), strict=True):
            full = block.to_vector()
            k = int(mask.sum())
            full[mask] = theta[pos : pos + k]
            pos += k
            blocks.append(block.with_vector(full) if k else block)
        return self.with_blocks(blocks)

    def with_blocks(self, blocks: Sequence[Block], **changes: Any) -> ChainModel:
        """A model of the same class, names and offsets with other blocks (ranges kept
        unless the offsets change)."""
        kwargs = self._channel_settings(changes)
        kwargs.update(changes)
        return type(self)._from_blocks(self.inputs[0], self.outputs[0], tuple(blocks), **kwargs)

    def replace(self, **changes: Any) -> ChainModel:
        """A copy with ``sampling_time``, offsets or ``ranges`` changed."""
        return self.with_blocks(self.blocks, **changes)

    @classmethod
    def _from_blocks(cls, input: str, output: str, blocks: tuple[Block, ...], **kwargs: Any):
        model = cls.__new__(cls)
        cls._check_shape(blocks)
        ChainModel.__init__(model, input, output, blocks, **kwargs)
        return model

    @classmethod
    def _check_shape(cls, blocks: tuple[Block, ...]) -> None:
        """Named structures check that ``blocks`` has their shape."""

    # ------------------------------------------------------------------ ranges
    def estimation_ranges(self, experiments: Any) -> dict[str, list[float]]:
        """Input ranges of the nonlinear blocks (and of ``u``) over estimation data, a
        sequence of ``(u, y)`` arrays, each simulated from rest."""
        seen: dict[str, list[np.ndarray]] = {}
        for u, _ in experiments:
            s = self._u(u)
            for i, block in enumerate(self.blocks):
                if i == 0 or not block.role == "linear":
                    seen.setdefault(self._range_key(i), []).append(s)
                s = _apply(block, s)
        out = {}
        for key, parts in seen.items():
            values = np.concatenate(parts)
            if key == "u" or np.all(np.isfinite(values)):
                out[key] = [float(values.min()), float(values.max())]
        return out

    def with_ranges(self, experiments: Any) -> ChainModel:
        """A copy that remembers the ranges seen in ``experiments`` (to flag
        extrapolation later and to bound inversions)."""
        return self.replace(ranges=self.estimation_ranges(experiments))

    def extrapolation(self, u: Any) -> list[str]:
        """Warnings when ``u`` (or a signal inside) leaves the recorded ranges of a block
        that extrapolates unreliably (polynomials: a cubic can run away there)."""
        notes: list[str] = []
        if not self.ranges:
            return notes
        s = self._u(u)
        for i, block in enumerate(self.blocks):
            key = self._range_key(i)
            if key in self.ranges and getattr(block, "warn_extrapolation", False):
                notes += self._leaves(key, s, i)
            s = self._apply_at(i, s)
        return notes

    def range_excursion(self, u: Any) -> dict[str, float]:
        """See :meth:`Model.range_excursion`: every recorded signal (``u``, the inputs
        of the nonlinear blocks), whether or not its block extrapolates reliably."""
        out: dict[str, float] = {}
        s = self._u(u)
        for i in range(len(self.blocks)):
            key = self._range_key(i)
            if key in self.ranges:
                out[key] = excursion(self.ranges[key], s)
            s = self._apply_at(i, s)
        return out

    def block_ranges(self) -> list[tuple[str, Block, tuple[float, float]]]:
        """See :meth:`Model.block_ranges`: the nonlinear blocks whose input range is
        recorded (relative to the input offset, as the blocks see it)."""
        out = []
        for i, block in enumerate(self.blocks):
            key = self._range_key(i)
            if block.role == "linear" or key not in self.ranges:
                continue
            name = "input block" if i == 0 else "output block" if key == "x" else f"block {i + 1}"
            out.append((name, block, (self.ranges[key][0], self.ranges[key][1])))
        return out

    def linear_signals(self, u: Any) -> list[tuple[LinearBlock, np.ndarray, np.ndarray]]:
        """See :meth:`Model.linear_signals`."""
        signals = self.block_inputs(u)
        signals.append(self._apply_at(len(self.blocks) - 1, signals[-1]))
        return [
            (block, signals[i], signals[i + 1])
            for i, block in enumerate(self.blocks)
            if block.role == "linear"
        ]

    def _leaves(self, key: str, values: np.ndarray, i: int) -> list[str]:
        lo, hi = self.ranges[key]
        if key == "u":  # report in the user's units, not relative to the offset
            lo, hi, values = (
                lo + self.input_offset,
                hi + self.input_offset,
                values + self.input_offset,
            )
            what = f"input {self.inputs[0]!r}"
        elif key == "x":
            what = "the linear block's output x (input of the output block)"
        else:
            what = f"the input of block {i} ({self.blocks[i].kind})"
        span = max(hi - lo, 1e-300)
        out = (values < lo - 0.02 * span) | (values > hi + 0.02 * span)
        if not out.any():
            return []
        worst = float(max(lo - values.min(), values.max() - hi)) / span
        return [
            f"{what} leaves the range seen in estimation [{lo:.4g}, {hi:.4g}] in "
            f"{int(out.sum())} of {values.size} samples (by up to {100 * worst:.0f} % "
            "of that range): the model extrapolates there (along the block's tangent at the "
            "range's end)"
        ]

    # ------------------------------------------------------------------ files
    def to_dict(self) -> dict[str, Any]:
        return {
            **self._file_header(),
            "chain": [b.to_dict() for b in self.blocks],
            **self._channel_file(),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ChainModel:
        if "chain" in data:
            blocks = tuple(block_from_dict(d) for d in data["chain"])
        else:
            blocks = cls._blocks_from_version1(data)
        kwargs = cls._channel_from_file(data, cls.structure, "a chain of blocks")
        try:
            return cls._from_blocks(data["inputs"][0], data["outputs"][0], blocks, **kwargs)
        except OrderError as exc:
            raise ModelFileError(f"the {cls.structure} model's blocks do not fit: {exc}") from None

    @classmethod
    def _blocks_from_version1(cls, data: dict[str, Any]) -> tuple[Block, ...]:
        """Blocks of a model file written before chains (orders, block kinds, SPEC names)."""
        params = dict(data["parameters"])
        kinds = data.get("blocks", {})
        orders = data["orders"]
        blocks: list[Block] = []
        if kinds.get("input"):
            kind = kinds["input"]
            back = {v: k for k, v in BLOCK_TYPES[kind].display_names("input").items()}
            block_params = {
                back.get(k, k): v for k, v in params.items() if k not in ("a", "b", "q")
            }
            if kind == "polynomial":
                block_params.setdefault("constant", True)
            blocks.append(block_from_dict({"kind": kind, **block_params}))
        blocks.append(
            LinearBlock(
                int(orders["na"]), int(orders["nb"]), int(orders["nk"]), params["a"], params["b"]
            )
        )
        if kinds.get("output"):
            if kinds["output"] != "polynomial" or "q" not in params:
                raise ModelFileError("the output block must be a polynomial with parameters 'q'")
            blocks.append(Polynomial(params["q"], constant=False))
        return tuple(blocks)


def _apply(block: Block, s: np.ndarray) -> np.ndarray:
    """One block on a signal, from rest."""
    return block.run(s)


class OneLinearBlock:
    """Orders and coefficients of a model with one linear block (``self.linear``)."""

    linear: LinearBlock

    @property
    def na(self) -> int:
        return self.linear.na

    @property
    def nb(self) -> int:
        return self.linear.nb

    @property
    def nk(self) -> int:
        return self.linear.nk

    @property
    def a(self) -> np.ndarray:
        """``[a_1..a_na]`` of the linear block."""
        return self.linear.a

    @property
    def b(self) -> np.ndarray:
        """``[b_0..b_{nb-1}]`` of the linear block."""
        return self.linear.b


class BlockModel(OneLinearBlock, ChainModel):
    """The ``N_1 - L - N_2`` cascade with optional outer blocks; use the named subclasses.

    Parameters
    ----------
    input, output : str
        Signal names.
    input_block : Block, optional
        Static block or backlash; ``None`` means ``w = u``.
    output_block : StaticBlock, optional
        Static block after the linear one (B3: a polynomial without constant term,
        ``y = q_1 x + q_2 x^2 + ...``, ``q_1 = 1``); ``None`` means ``y = x``.
    na, nb, nk : int
        Orders of the linear block (MATLAB convention).
    a, b : sequence of float, optional
        ``[a_1..a_na]`` and ``[b_0..b_{nb-1}]``; with an input block ``b_0`` must be 1,
        or -1 where the plant's gain is negative and the block's slopes must stay
        positive (a dead zone, a saturation, a backlash: the sign lives here).
    sampling_time : float, optional
    input_offset, output_offset : float
        Operating point subtracted from ``u`` and ``y`` before the blocks (default 0).
    """

    structure: ClassVar[str] = ""
    requires_input_block: ClassVar[bool | None] = None  # True, False or None (either)
    requires_output_block: ClassVar[bool | None] = None

    def __init__(
        self,
        input: Any,
        output: Any,
        *,
        input_block: Block | None = None,
        output_block: StaticBlock | None = None,
        na: int = 1,
        nb: int = 1,
        nk: int = 1,
        a: Any = None,
        b: Any = None,
        sampling_time: float | None = None,
        input_offset: float = 0.0,
        output_offset: float = 0.0,
    ) -> None:
        blocks: list[Block] = []
        if input_block is not None:
            blocks.append(input_block)
        blocks.append(LinearBlock(na, nb, nk, a, b, unit_b0=input_block is not None))
        if output_block is not None:
            blocks.append(output_block)
        type(self)._check_shape(tuple(blocks))
        super().__init__(
            input,
            output,
            blocks,
            sampling_time=sampling_time,
            input_offset=input_offset,
            output_offset=output_offset,
        )

    @classmethod
    def _check_shape(cls, blocks: tuple[Block, ...]) -> None:
        lin = [i for i, b in enumerate(blocks) if b.role == "linear"]
        if len(lin) != 1:
            raise OrderError(f"a {cls.structure or 'cascade'} model has one linear block")
        has_in, has_out = lin[0] == 1, len(blocks) > lin[0] + 1
        if lin[0] > 1 or len(blocks) > lin[0] + 2:
            raise OrderError(
                f"a {cls.structure or 'cascade'} model is input block - linear - output block"
            )
        for flag, present, what in (
            (cls.requires_input_block, has_in, "an input block"),
            (cls.requires_output_block, has_out, "an output block"),
        ):
            if flag is True and not present:
                raise OrderError(f"a {cls.structure} model needs {what}")
            if flag is False and present:
                raise OrderError(f"a {cls.structure} model has no {what[3:]}")
        if has_out and blocks[-1].role != "static":
            raise OrderError("the output block must be a static block")
        if has_out:
            try:
                blocks[-1].check_output_block()
            except ParameterError as exc:
                raise OrderError(str(exc)) from None

    @classmethod
    def default_blocks(
        cls, r1: int = DEGREE, r2: int = DEGREE
    ) -> tuple[Block | None, Block | None]:
        """Templates of the blocks this structure fits by default: the two-segment
        polynomial of order ``r1`` (B1) in, the identity polynomial of degree ``r2``
        (B3) out; None for a block the structure has not."""
        return (
            TwoSegmentPolynomial.template(r1) if cls.requires_input_block else None,
            Polynomial.template(r2, constant=False) if cls.requires_output_block else None,
        )

    @classmethod
    def cascade(
        cls,
        input: Any,
        output: Any,
        *,
        input_block: Block | None,
        output_block: Block | None,
        **kwargs: Any,
    ) -> BlockModel:
        """A model of this structure from its blocks, whatever its constructor takes."""
        model = cls.__new__(cls)
        BlockModel.__init__(
            model, input, output, input_block=input_block, output_block=output_block, **kwargs
        )
        return model

    @property
    def fixed_b0(self) -> bool:
        return self.input_block is not None


class Hammerstein(BlockModel):
    """Static input nonlinearity followed by a linear block (``N_1 - L``).

    .. math:: A(z^{-1}) y(k) = z^{-n_k} B(z^{-1}) N_1(u(k)),\\quad b_0 = 1

    Examples
    --------
    >>> from blockid.blocks import TwoSegmentPolynomial
    >>> m = Hammerstein("u", "y", input_block=TwoSegmentPolynomial([0, 1.0], [0, -0.5]),
    ...                 na=1, nb=1, nk=1, a=[-0.5])
    >>> m.simulate([1.0, 1.0, -1.0, -1.0])[:, 0].tolist()
    [0.0, 1.0, 1.5, 0.25]
    """

    structure = "hammerstein"
    requires_input_block = True
    requires_output_block = False

    def __init__(self, input: Any, output: Any, *, input_block: StaticBlock, **kwargs: Any):
        super().__init__(input, output, input_block=input_block, **kwargs)

    @classmethod
    def _check_shape(cls, blocks: tuple[Block, ...]) -> None:
        super()._check_shape(blocks)
        if blocks[0].role != "static":
            raise OrderError(
                f"a hammerstein model needs a static input block, got {blocks[0].kind}; "
                "use the backlash structure for a backlash"
            )


class Wiener(BlockModel):
    """Linear block followed by a static output block (``L - N_2``), by default the
    polynomial of B3 with ``q_1 = 1``.

    .. math:: A(z^{-1}) x(k) = z^{-n_k} B(z^{-1}) u(k),\\quad y(k) = \\sum_m q_m x(k)^m
    """

    structure = "wiener"
    requires_input_block = False
    requires_output_block = True

    def __init__(self, input: Any, output: Any, *, output_block: StaticBlock, **kwargs: Any):
        super().__init__(input, output, output_block=output_block, **kwargs)


class HammersteinWiener(BlockModel):
    """Paper B's ``N_1 - L - N_2`` model (B1–B3), normalised ``b_0 = q_1 = 1``."""

    structure = "hammerstein-wiener"
    requires_input_block = True
    requires_output_block = True

    def __init__(
        self,
        input: Any,
        output: Any,
        *,
        input_block: StaticBlock,
        output_block: StaticBlock,
        **kwargs: Any,
    ):
        super().__init__(
            input, output, input_block=input_block, output_block=output_block, **kwargs
        )

    @classmethod
    def _check_shape(cls, blocks: tuple[Block, ...]) -> None:
        super()._check_shape(blocks)
        if blocks[0].role != "static":
            raise OrderError(
                f"a hammerstein-wiener model needs a static input block, got {blocks[0].kind}"
            )


class BacklashModel(BlockModel):
    """Paper A's pseudo-Hammerstein model: backlash (A3) then a linear block (A5), b_0 = 1.

    Examples
    --------
    Paper A's choke finger (sign-corrected linear block, SPEC):

    >>> from blockid.blocks import Backlash
    >>> s2 = BacklashModel("u2", "v2", input_block=Backlash(0.9, 0.8, 0.9, 0.85),
    ...                    na=2, nb=1, nk=1, a=[-1.0, 0.17])
    >>> round(float(s2.simulate([0.0] * 5 + [10.0] * 200)[-1, 0]), 3)  # 0.9 (10 - 0.85)/0.17
    48.441
    """

    structure = "backlash"
    requires_input_block = True
    requires_output_block = False

    def __init__(self, input: Any, output: Any, *, input_block: Backlash, **kwargs: Any):
        super().__init__(input, output, input_block=input_block, **kwargs)

    @classmethod
    def default_blocks(
        cls, r1: int = DEGREE, r2: int = DEGREE
    ) -> tuple[Block | None, Block | None]:
        return Backlash.template(), None

    @classmethod
    def _check_shape(cls, blocks: tuple[Block, ...]) -> None:
        super()._check_shape(blocks)
        if blocks[0].kind != Backlash.kind:
            raise OrderError("a backlash model's input block must be a Backlash")


class OutputError(BlockModel):
    """Linear output-error model ``y = z^-nk B/A u`` (no nonlinear block), identified on
    its free-run simulation error rather than its one-step error as ARX is.

    .. math:: y(k) = z^{-n_k} \\frac{B(z^{-1})}{A(z^{-1})} u(k) + e(k)
    """

    structure = "output-error"
    requires_input_block = False
    requires_output_block = False

    def __init__(self, input: Any, output: Any, **kwargs: Any):
        super().__init__(input, output, **kwargs)


class WienerHammerstein(ChainModel):
    """Linear, static, linear (``L_1 - N - L_2``): e.g. the Wiener-Hammerstein benchmark.

    .. math::

        A_1 x = z^{-n_{k1}} B_1 u, \\quad v = N(x), \\quad
        A_2 y = z^{-n_{k2}} B_2 v, \\qquad b_{2,0} = 1

    and ``N`` fixes its own input gain (``q_1 = 1`` for the polynomial of B3).

    Parameters
    ----------
    input, output : str
    first, static, second : blocks
        :class:`~blockid.blocks.linear.LinearBlock`, a static block, a linear block.
    **kwargs
        ``sampling_time``, offsets, ``ranges`` as for :class:`ChainModel`.
    """

    structure = "wiener-hammerstein"

    def __init__(
        self,
        input: Any,
        output: Any,
        *,
        first: LinearBlock,
        static: StaticBlock,
        second: LinearBlock,
        **kwargs: Any,
    ) -> None:
        blocks = (first, static, second)
        self._check_shape(blocks)
        super().__init__(input, output, blocks, **kwargs)

    @classmethod
    def _check_shape(cls, blocks: tuple[Block, ...]) -> None:
        roles = [getattr(b, "role", "") for b in blocks]
        if roles != ["linear", "static", "linear"]:
            raise OrderError(
                "a wiener-hammerstein model is linear block, static block, linear block"
            )


#: Structure name -> class of the cascades with one linear block.
BLOCK_STRUCTURES = {
    cls.structure: cls for cls in (Hammerstein, Wiener, HammersteinWiener, BacklashModel)
}
