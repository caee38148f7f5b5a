"""Block-oriented models of several inputs and outputs: a static block on every input
channel (Hammerstein), on every output channel (Wiener), or on both, around one
multivariable linear state-space core.

.. math::

    w_i(k) = f_i(u_{n,i}(k)), \\qquad
    x(k+1) = A x(k) + B w(k) + e, \\qquad
    z(k) = C x(k) + D w(k), \\qquad
    y_{n,j}(k) = g_j(z_j(k)) + h_j

in normalised signals, as the state-space models (:mod:`blockid.models.state_space`):
``u_n = (u - input_offset) / input_scale`` and ``y = output_offset + output_scale y_n``.
A channel without a block passes its signal through (``f_i(u) = u``). The state bias
``e`` (zero in fitted models, see below) and the output bias ``h`` carry the operating
point the nonlinear blocks move (the signals' means are not where ``w`` and ``z`` have
mean zero).

**Parameters and what is unique.** The core's parameters are unique up to the state
basis; each block's gain is shared with its column of ``B`` (input) or row of ``C``
and ``D`` (output) unless the block fixes its own input gain
(:meth:`~blockid.blocks.base.Block.free_mask` with ``after_linear=True``: a polynomial's
linear coefficient is 1, a free piecewise-linear map fixes a breakpoint). A fit holds
``e = 0``: an input block's constant (the input polynomial has one) carries the
operating point into the core, and an output block's argument shifted by a free ``e``
would be another block of the same family (a cubic of ``z + β`` is a cubic of ``z``),
so its shape would not be unique. The fit (:mod:`blockid.fitting.block_state_space`)
leaves the remaining directions (the state basis, gains a block does not fix) alone.

**Derivatives.** :meth:`BlockStateSpace.jacobian_piece` gives the exact sensitivity of
the simulated output to every parameter and to ``x(0)``, walked forward in time: the
core's by :func:`~blockid._kernels.state_space.pnlss_walk` (the bias ``e`` is its
constant monomial), an input block's through the core by
:func:`~blockid._kernels.state_space.channel_response`, and an output block's by the
chain rule (the block's ``derivative`` times the core's sensitivity, plus its own
``jacobian``).

**Beyond the estimation range.** A block that extrapolates unreliably (a polynomial:
``warn_extrapolation``) continues along its tangent beyond the range its argument
covered in estimation (``input_range``, ``output_range``, recorded by the fit), as the
chains' polynomial blocks do: a cubic would run away on an input a little larger than
any it was fitted on. Inside the ranges the blocks are exactly themselves.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

import numpy as np

from blockid._kernels import writable
from blockid._kernels.loop import (
    KIND_POLYNOMIAL,
    KIND_TABLE,
    KIND_TWO_SEGMENT,
    loop_sensitivity,
    loop_simulate,
)
from blockid._kernels.state_space import channel_response, pnlss_walk
from blockid.blocks.base import Block, StaticBlock, block_from_dict
from blockid.errors import ModelFileError, OrderError
from blockid.models.base import Model, excursion
from blockid.models.state_space import ForwardSensitivities, PolynomialStateSpace, StateSpace

__all__ = ["BlockStateSpace", "channel_blocks"]


def _names(value: Any) -> tuple[str, ...]:
    return tuple(str(v) for v in ([value] if isinstance(value, str) else value))


def channel_blocks(
    blocks: Any, channels: Sequence[str], what: str
) -> tuple[StaticBlock | None, ...]:
    """One block (or None) per channel from ``blocks``: None (no blocks), one block (a
    copy on every channel), a sequence with one entry per channel, or a mapping from
    channel names to blocks (channels not named get none)."""
    n = len(channels)
    if blocks is None:
        return (None,) * n
    if isinstance(blocks, Block):
        return (blocks,) * n
    if isinstance(blocks, Mapping):
        unknown = [k for k in blocks if k not in channels]
        if unknown:
            raise OrderError(
                f"{what} blocks name {unknown}, which are not among the {what}s {list(channels)}"
            )
        out = tuple(blocks.get(c) for c in channels)
    else:
        out = tuple(blocks)
        if len(out) != n:
            raise OrderError(f"{n} {what} channel(s) need {n} {what} block(s), got {len(out)}")
    for block in out:
        if block is not None and getattr(block, "role", None) != "static":
            raise OrderError(
                f"{what} blocks of a state-space block model must be static blocks, got "
                f"{type(block).__name__}"
            )
    return out


def _range(value: Any, n: int, name: str) -> np.ndarray:
    if value is None or (n == 0 and np.size(value) == 0):
        return np.tile([-np.inf, np.inf], (n, 1))
    arr = np.array(
        [[-np.inf if v is None else v for v in row] for row in np.asarray(value, dtype=object)],
        dtype=float,
    )
    if arr.shape != (n, 2):
        raise OrderError(f"{name} needs one (low, high) pair per channel ({n}), got {arr.shape}")
    return arr


def _loop_blocks(blocks: Any) -> tuple[StaticBlock, ...]:
    if blocks is None:
        return ()
    out = (blocks,) if isinstance(blocks, Block) else tuple(blocks)
    for block in out:
        if getattr(block, "role", None) != "static":
            raise OrderError(
                "loop blocks of a state-space block model must be static blocks, got "
                f"{type(block).__name__}"
            )
    return out


def _matrix(value: Any, shape: tuple[int, int], name: str) -> np.ndarray:
    if value is None:
        return np.zeros(shape)
    arr = np.asarray(value, dtype=float)
    if arr.size == 0 and 0 in shape:
        return np.zeros(shape)
    if arr.shape != shape:
        raise OrderError(f"{name} needs shape {shape}, got {arr.shape}")
    return arr


def _pack(blocks: tuple[StaticBlock, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The loop blocks as the compiled loop's codes, packed coefficients and offsets
    (:mod:`blockid._kernels.loop`); None if one of them is not of a compiled kind."""
    codes = {"polynomial": KIND_POLYNOMIAL, "table": KIND_TABLE,
             "two-segment-polynomial": KIND_TWO_SEGMENT}  # fmt: skip
    kinds, parts = [], []
    for b in blocks:
        form = b.compiled_form()
        if form is None:
            return None
        kinds.append(codes[form[0]])
        parts.append(form[1])
    ptr = np.r_[0, np.cumsum([len(c) for c in parts])].astype(np.int64)
    coef = np.concatenate(parts) if parts else np.zeros(0)
    return np.array(kinds, dtype=np.int64), np.ascontiguousarray(coef, dtype=float), ptr


class BlockStateSpace(ForwardSensitivities, Model):
    """Static blocks per channel around a linear state-space core (module docstring).

    Parameters
    ----------
    inputs, outputs : sequence of str
    A, B, C, D : array_like
        The core, shapes (nx, nx), (nx, nu), (ny, nx), (ny, nu), in normalised units.
    input_blocks, output_blocks : optional
        A static block per channel (None: the signal passes through); one block for every
        channel, a sequence, or a mapping from channel names (:func:`channel_blocks`).
    state_bias, output_bias : array_like, optional
        ``e`` (nx,) and ``h`` (ny,); zeros by default.
    input_offset, input_scale, output_offset, output_scale : array_like, optional
        Normalisation of the signals (default 0 and 1).
    input_range, output_range : array_like, optional
        (channels, 2): the range each block's argument covered in estimation (``u_n``
        for an input block, ``z`` for an output block), against which
        :meth:`range_excursion` measures new data.
    sampling_time : float, optional

    Examples
    --------
    >>> from blockid.blocks import Polynomial
    >>> m = BlockStateSpace(["u1", "u2"], ["y"], A=[[0.5]], B=[[1.0, 1.0]], C=[[1.0]],
    ...                     D=[[0.0, 0.0]], input_blocks={"u1": Polynomial([0.0, 1.0, 0.5])})
    >>> m.simulate([[2.0, 1.0], [2.0, 1.0], [0.0, 0.0]])[:, 0].tolist()
    [0.0, 5.0, 7.5]
    """

    structure: ClassVar[str] = "block-state-space"

    def __init__(
        self,
        inputs: Any,
        outputs: Any,
        A: Any,
        B: Any,
        C: Any,
        D: Any,
        *,
        input_blocks: Any = None,
        output_blocks: Any = None,
        state_bias: Any = None,
        output_bias: Any = None,
        input_offset: Any = None,
        input_scale: Any = None,
        output_offset: Any = None,
        output_scale: Any = None,
        input_range: Any = None,
        output_range: Any = None,
        loop_blocks: Any = None,
        Cp: Any = None,
        Dp: Any = None,
        Bq: Any = None,
        Dq: Any = None,
        loop_range: Any = None,
        sampling_time: float | None = None,
    ) -> None:
        self.inputs, self.outputs = _names(inputs), _names(outputs)
        nu, ny = len(self.inputs), len(self.outputs)
        A = np.asarray(A, dtype=float)
        nx = int(A.shape[0]) if A.ndim == 2 else 0
        e = np.zeros(nx) if state_bias is None else np.asarray(state_bias, dtype=float)
        if e.shape != (nx,):
            raise OrderError(f"state_bias needs {nx} value(s), got {np.shape(state_bias)}")
        self.loop_blocks = _loop_blocks(loop_blocks)
        nl = len(self.loop_blocks)
        self.Cp = _matrix(Cp, (nl, nx), "Cp")
        self.Dp = _matrix(Dp, (nl, nu), "Dp")
        Bq, Dq = _matrix(Bq, (nx, nl), "Bq"), _matrix(Dq, (ny, nl), "Dq")
        B = np.asarray(B, dtype=float)
        D = np.asarray(D, dtype=float)
        if nl:
            if B.shape != (nx, nu) or D.shape != (ny, nu):
                raise OrderError(
                    f"B and D need shapes {(nx, nu)} and {(ny, nu)}, got {B.shape} and {D.shape}"
                )
            B, D = np.hstack((B, Bq)), np.hstack((D, Dq))
        self.core = PolynomialStateSpace(
            [f"w{i + 1}" for i in range(nu)] + [f"q{i + 1}" for i in range(nl)],
            [f"z{j + 1}" for j in range(ny)], A, B, C, D,
            E=e.reshape(nx, 1), F=np.zeros((ny, 1)), exponents=np.zeros((1, nx + nu + nl)),
        )  # fmt: skip
        self.input_blocks = channel_blocks(input_blocks, self.inputs, "input")
        self.output_blocks = channel_blocks(output_blocks, self.outputs, "output")
        h = np.zeros(ny) if output_bias is None else np.asarray(output_bias, dtype=float)
        if h.shape != (ny,):
            raise OrderError(f"output_bias needs {ny} value(s), got {np.shape(output_bias)}")
        self.output_bias = h
        # the core's normalisation is the identity: the model holds the signals' own
        norm = PolynomialStateSpace(
            self.inputs, self.outputs, np.zeros((1, 1)), np.zeros((1, nu)), np.zeros((ny, 1)),
            np.zeros((ny, nu)), input_offset=input_offset, input_scale=input_scale,
            output_offset=output_offset, output_scale=output_scale,
        )  # fmt: skip
        self.input_offset, self.input_scale = norm.input_offset, norm.input_scale
        self.output_offset, self.output_scale = norm.output_offset, norm.output_scale
        self.input_range = _range(input_range, nu, "input_range")
        self.output_range = _range(output_range, ny, "output_range")
        self.loop_range = _range(loop_range, nl, "loop_range")
        self.sampling_time = sampling_time

    # ------------------------------------------------------------------ structure
    @property
    def A(self) -> np.ndarray:
        return self.core.A

    @property
    def B(self) -> np.ndarray:
        return self.core.B[:, : len(self.inputs)]

    @property
    def C(self) -> np.ndarray:
        return self.core.C

    @property
    def D(self) -> np.ndarray:
        return self.core.D[:, : len(self.inputs)]

    @property
    def Bq(self) -> np.ndarray:
        """Where the loop blocks' outputs ``q`` enter the state (nx, nl)."""
        return self.core.B[:, len(self.inputs) :]

    @property
    def Dq(self) -> np.ndarray:
        """Where the loop blocks' outputs ``q`` enter the core's output (ny, nl)."""
        return self.core.D[:, len(self.inputs) :]

    @property
    def loops(self) -> tuple[str, ...]:
        """Names of the loop channels, ``p1``, ``p2``, ..."""
        return tuple(f"p{i + 1}" for i in range(len(self.loop_blocks)))

    @property
    def state_bias(self) -> np.ndarray:
        return self.core.E[:, 0]

    @property
    def nx(self) -> int:
        return self.core.nx

    @property
    def max_lag(self) -> int:
        return self.nx

    @property
    def kind(self) -> str:
        """``hammerstein``, ``wiener``, ``hammerstein-wiener`` or ``linear`` (which
        sides carry blocks)."""
        left = any(b is not None for b in self.input_blocks)
        right = any(b is not None for b in self.output_blocks)
        kind = {(True, True): "hammerstein-wiener", (True, False): "hammerstein",
                (False, True): "wiener", (False, False): "linear"}[(left, right)]  # fmt: skip
        if self.loop_blocks:
            return "loop" if kind == "linear" else f"{kind}+loop"
        return kind

    def poles(self) -> np.ndarray:
        return self.core.poles()

    def linear_part(self) -> StateSpace:
        """The linear core from the blocks' outputs ``w`` to the output blocks'
        arguments ``z`` (normalised units; signals named ``w <input>``, ``z <output>``)."""
        return StateSpace(
            [f"w {c}" for c in self.inputs], [f"z {c}" for c in self.outputs], self.A, self.B,
            self.C, self.D, sampling_time=self.sampling_time,
        )  # fmt: skip

    def is_stable(self, margin: float = 0.0) -> bool:
        return self.core.is_stable(margin)

    # ------------------------------------------------------------------ parameters
    def _blocks(self) -> list[StaticBlock | None]:
        return [*self.input_blocks, *self.loop_blocks, *self.output_blocks]

    def free_parameters(self) -> np.ndarray:
        """``[A, B, C, D, e, 0 (ny, unused), Cp, Dp, input blocks, loop blocks, output
        blocks, h]``: the core's vector (:meth:`PolynomialStateSpace.free_parameters`,
        ``E = e``; with loop blocks its ``B`` and ``D`` are ``[B, Bq]`` and ``[D, Dq]``),
        the loop's argument maps, each block's
        :meth:`~blockid.blocks.base.Block.to_vector` in channel order, then ``h``."""
        parts = [self.core.free_parameters(), self.Cp.reshape(-1), self.Dp.reshape(-1)]
        parts += [b.to_vector() for b in self._blocks() if b is not None]
        return np.concatenate([*parts, self.output_bias])

    def parameter_mask(self, feedthrough: bool) -> np.ndarray:
        """Which entries of :meth:`free_parameters` a fit moves: not ``D`` without
        ``feedthrough``, not the state bias ``e`` (module docstring: the blocks carry the
        operating point, and a free ``e`` would make an output block's shape non-unique),
        not the unused column, not a block's entries its normalisation fixes."""
        nx, nu, ny, nl = self.nx, len(self.inputs), len(self.outputs), len(self.loop_blocks)
        core = np.zeros(self.core.free_parameters().size, dtype=bool)
        o_d = nx * nx + nx * (nu + nl) + ny * nx
        core[:o_d] = True
        d = np.ones((ny, nu + nl), dtype=bool)  # the loop's columns Dq are always free
        d[:, :nu] = feedthrough
        core[o_d : o_d + d.size] = d.reshape(-1)
        maps = np.r_[np.ones(nl * nx, dtype=bool), np.full(nl * nu, feedthrough)]
        parts = [core, maps]
        parts += [b.free_mask(after_linear=True) for b in self._blocks() if b is not None]
        return np.concatenate([*parts, np.ones(ny, dtype=bool)])

    def parameter_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Bounds of :meth:`free_parameters`: the blocks' own (positive slopes, ordered
        breakpoints, ..), none elsewhere."""
        nc = self.core.free_parameters().size + self.Cp.size + self.Dp.size
        ny = len(self.outputs)
        lows, highs = [np.full(nc, -np.inf)], [np.full(nc, np.inf)]
        for b in self._blocks():
            if b is not None:
                lo, hi = b.bounds()
                lows.append(np.asarray(lo, dtype=float))
                highs.append(np.asarray(hi, dtype=float))
        return np.concatenate([*lows, np.full(ny, -np.inf)]), np.concatenate(
            [*highs, np.full(ny, np.inf)]
        )

    @property
    def n_free_parameters(self) -> int:
        return int(self.parameter_mask(bool(np.any(self.D != 0.0))).sum())

    def free_parameter_names(self) -> list[str]:
        nu = len(self.inputs)

        def core_name(n: str) -> str:
            if n.startswith("E["):
                return f"e[{n[2:].split(',')[0]}]"
            if n[0] in "BD" and n[1] == "[":  # a loop column of the core: Bq, Dq
                r, c = (int(v) for v in n[2:-1].split(","))
                return n if c < nu else f"{n[0]}q[{r},{c - nu}]"
            return n

        names = [core_name(n) for n in self.core.free_parameter_names()]
        names += [f"Cp[{i},{j}]" for i in range(self.Cp.shape[0]) for j in range(self.nx)]
        names += [f"Dp[{i},{j}]" for i in range(self.Dp.shape[0]) for j in range(nu)]
        for side, channels, blocks in self._sides():
            for c, b in zip(channels, blocks, strict=True):
                if b is not None:
                    names += [f"{side} {c}: {v}" for v in b.vector_names()]
        return names + [f"h[{j}]" for j in range(len(self.outputs))]

    def _sides(self) -> tuple[tuple[str, tuple[str, ...], tuple[StaticBlock | None, ...]], ...]:
        return (
            ("input", self.inputs, self.input_blocks),
            ("loop", self.loops, self.loop_blocks),
            ("output", self.outputs, self.output_blocks),
        )

    def with_free_parameters(self, theta: Any) -> BlockStateSpace:
        theta = np.asarray(theta, dtype=float).reshape(-1)
        if theta.size != self.free_parameters().size:
            raise OrderError(
                f"the model takes {self.free_parameters().size} parameters, got {theta.size}"
            )
        nc = self.core.free_parameters().size
        core = self.core.with_free_parameters(theta[:nc])
        nl, nu = len(self.loop_blocks), len(self.inputs)
        Cp = theta[nc : nc + self.Cp.size].reshape(self.Cp.shape)
        k = nc + self.Cp.size
        Dp = theta[k : k + self.Dp.size].reshape(self.Dp.shape)
        k += self.Dp.size
        blocks: list[StaticBlock | None] = []
        for b in self._blocks():
            if b is None:
                blocks.append(None)
                continue
            n = b.to_vector().size
            blocks.append(b.with_vector(theta[k : k + n]))  # type: ignore[arg-type]
            k += n
        return self.replace(
            A=core.A, B=core.B[:, :nu], C=core.C, D=core.D[:, :nu], state_bias=core.E[:, 0],
            input_blocks=blocks[:nu], loop_blocks=blocks[nu : nu + nl],
            output_blocks=blocks[nu + nl :], output_bias=theta[k:], Cp=Cp, Dp=Dp,
            Bq=core.B[:, nu:], Dq=core.D[:, nu:],
        )  # fmt: skip

    def replace(self, **changes: Any) -> BlockStateSpace:
        """A copy with some constructor arguments changed."""
        kwargs: dict[str, Any] = dict(
            A=self.A, B=self.B, C=self.C, D=self.D, input_blocks=self.input_blocks,
            output_blocks=self.output_blocks, state_bias=self.state_bias,
            output_bias=self.output_bias, input_offset=self.input_offset,
            input_scale=self.input_scale, output_offset=self.output_offset,
            output_scale=self.output_scale, input_range=self.input_range,
            output_range=self.output_range, sampling_time=self.sampling_time,
            loop_blocks=self.loop_blocks, Cp=self.Cp, Dp=self.Dp, Bq=self.Bq, Dq=self.Dq,
            loop_range=self.loop_range,
        )  # fmt: skip
        kwargs.update(changes)
        return BlockStateSpace(self.inputs, self.outputs, **kwargs)

    @property
    def parameters(self) -> dict[str, Any]:
        out: dict[str, Any] = {k: getattr(self, k).tolist() for k in "ABCD"}
        if self.loop_blocks:
            out.update({k: getattr(self, k).tolist() for k in ("Bq", "Dq", "Cp", "Dp")})
        out["e"] = self.state_bias.tolist()
        out["h"] = self.output_bias.tolist()
        for side, channels, blocks in self._sides():
            for c, b in zip(channels, blocks, strict=True):
                if b is not None:
                    out[f"{side} block {c}"] = b.to_dict()
        return out

    def parameter_table(self) -> list[tuple[str, str]]:
        rows = []
        keys = ("A", "B", "C", "D") + (("Bq", "Dq", "Cp", "Dp") if self.loop_blocks else ())
        for key in keys:
            for i, row in enumerate(getattr(self, key)):
                if row.size:
                    rows.append((f"{key}[{i}]", ", ".join(f"{v:.6g}" for v in row)))
        rows.append(("e", ", ".join(f"{v:.6g}" for v in self.state_bias)))
        rows.append(("h", ", ".join(f"{v:.6g}" for v in self.output_bias)))
        for side, channels, blocks in self._sides():
            for c, b in zip(channels, blocks, strict=True):
                if b is None:
                    continue
                for name, value in b.parameters.items():
                    values = value if isinstance(value, list | tuple | np.ndarray) else [value]
                    text = ", ".join(
                        f"{v:.6g}" if isinstance(v, float | np.floating) else str(v) for v in values
                    )
                    rows.append((f"{side} {c}: {b.kind} {name}", text))
        return rows

    # ------------------------------------------------------------------ signals
    @staticmethod
    def _edge(block: StaticBlock, s: np.ndarray, seen: np.ndarray) -> np.ndarray | None:
        """``s`` clipped to the range ``seen`` for a block that extrapolates unreliably
        (``warn_extrapolation``: polynomials) when the range is recorded; else None."""
        if not block.warn_extrapolation or not np.all(np.isfinite(seen)):
            return None
        return np.clip(s, seen[0], seen[1])

    def _at(self, block: StaticBlock, s: np.ndarray, seen: np.ndarray) -> np.ndarray:
        """Where a block's slope and parameter effects are taken for the argument ``s``:
        ``s`` itself, or the end of the range ``seen`` beyond which it follows its
        tangent (:meth:`_edge`)."""
        edge = self._edge(block, s, seen)
        return s if edge is None else edge

    def _apply(self, block: StaticBlock, s: np.ndarray, seen: np.ndarray) -> np.ndarray:
        """``block`` on ``s``; beyond the range recorded in estimation a polynomial block
        continues along its tangent instead of running away, as the chains' blocks do."""
        out = block.run(s)
        edge = self._edge(block, s, seen)
        if edge is None or not (outside := edge != s).any():
            return out
        out = np.array(out, dtype=float, copy=True)
        e = edge[outside]
        out[outside] = np.asarray(block(e), dtype=float) + block.derivative(e) * (s[outside] - e)
        return out

    def block_inputs(self, un: np.ndarray) -> np.ndarray:
        """``w``: the core's input for the normalised input ``un`` (N, nu)."""
        w = np.array(un, dtype=float)
        for i, b in enumerate(self.input_blocks):
            if b is not None:
                w[:, i] = self._apply(b, un[:, i], self.input_range[i])
        return np.ascontiguousarray(w)

    def block_outputs(self, z: np.ndarray) -> np.ndarray:
        """``y_n`` for the core's output ``z`` (N, ny)."""
        y = np.array(z, dtype=float)
        for j, b in enumerate(self.output_blocks):
            if b is not None:
                y[:, j] = self._apply(b, z[:, j], self.output_range[j])
        return y + self.output_bias

    def run(
        self, un: np.ndarray, x0: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Free run on a normalised input from ``x0`` (default 0): normalised outputs,
        the core's outputs ``z`` and the state after the last sample."""
        if self.loop_blocks:
            _, _, _, z, x = self._loop_run(self.block_inputs(un), x0)
        else:
            z, x = self.core.run(self.block_inputs(un), x0)
        with np.errstate(all="ignore"):
            return self.block_outputs(z), z, x

    def _loop_limits(self) -> tuple[np.ndarray, np.ndarray]:
        """Where each loop block leaves itself for its tangent (a polynomial's recorded
        range; +-inf for the others and where no range is recorded)."""
        lo = np.full(len(self.loop_blocks), -np.inf)
        hi = np.full(len(self.loop_blocks), np.inf)
        for l, b in enumerate(self.loop_blocks):
            seen = self.loop_range[l]
            if b.warn_extrapolation and np.all(np.isfinite(seen)):
                lo[l], hi[l] = seen
        return lo, hi

    def _loop_run(
        self, w: np.ndarray, x0: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Free run of the core with its loop blocks on the core's input ``w`` from
        ``x0``: the states before each update, the loop blocks' arguments ``p`` and
        outputs ``q``, the core's outputs ``z`` and the final state. Compiled for the
        blocks :func:`_pack` takes; any other block is evaluated sample by sample in
        Python (correct, much slower)."""
        n, nx, nl, ny = w.shape[0], self.nx, len(self.loop_blocks), len(self.outputs)
        x = np.zeros(nx) if x0 is None else np.array(x0, dtype=float)
        X, P, Q, z = np.zeros((n, nx)), np.zeros((n, nl)), np.zeros((n, nl)), np.zeros((n, ny))
        core = self.core
        A, B, C, D = (writable(m, float) for m in (core.A, core.B, core.C, core.D))
        e, Cp, Dp = writable(core.E[:, 0], float), writable(self.Cp, float), writable(self.Dp)
        packed = _pack(self.loop_blocks)
        with np.errstate(all="ignore"):
            if packed is not None:
                lo, hi = self._loop_limits()
                loop_simulate(A, B, C, D, e, Cp, Dp, *packed, lo, hi, writable(w, float), x,
                              X, P, Q, z)  # fmt: skip
                return X, P, Q, z, x
            for k in range(n):
                X[k] = x
                P[k] = Cp @ x + Dp @ w[k]
                for l, b in enumerate(self.loop_blocks):
                    Q[k, l] = self._apply(b, P[k, l : l + 1], self.loop_range[l])[0]
                v = np.r_[w[k], Q[k]]
                z[k] = C @ x + D @ v
                x = A @ x + B @ v + e
        return X, P, Q, z, x

    def step(self, x: Any, un: Any) -> tuple[np.ndarray, np.ndarray]:
        """One sample on normalised signals: ``x(k+1)`` and ``y_n(k)`` from ``x(k)`` and
        ``u_n(k)`` (:meth:`run` over one sample)."""
        un = np.asarray(un, dtype=float).reshape(1, len(self.inputs))
        yn, _, x_next = self.run(un, np.asarray(x, dtype=float).reshape(self.nx))
        return x_next, yn[0]

    def _slopes(
        self, blocks: Sequence[StaticBlock | None], s: np.ndarray, seen: np.ndarray
    ) -> np.ndarray:
        """Each channel's slope at its argument ``s`` (1 without a block): the block's
        ``derivative``, at the end of the range ``seen`` beyond which it follows its
        tangent (:meth:`_apply`)."""
        out = np.ones(len(blocks))
        for i, b in enumerate(blocks):
            if b is not None:
                at = self._at(b, np.asarray(s[i : i + 1], dtype=float), seen[i])
                out[i] = float(np.asarray(b.derivative(at), dtype=float).reshape(-1)[0])
        return out

    def step_jacobians(self, x: Any, un: Any) -> tuple[np.ndarray, ...]:
        """The one-step map's derivatives at ``(x, u_n)`` (normalised signals) by the
        chain rule through the blocks' slopes ``N'`` (diagonal, :meth:`_slopes`):

        .. math::

            \\partial x^+/\\partial x = A + B_q N_q' C_p, \\quad
            \\partial x^+/\\partial u_n = (B + B_q N_q' D_p) N_u', \\quad
            \\partial y_n/\\partial x = N_y' (C + D_q N_q' C_p), \\quad
            \\partial y_n/\\partial u_n = N_y' (D + D_q N_q' D_p) N_u'

        (``p = C_p x + D_p w`` the loop blocks' arguments; no loop blocks: ``N_q' = 0``)."""
        x = np.asarray(x, dtype=float).reshape(self.nx)
        un = np.asarray(un, dtype=float).reshape(1, len(self.inputs))
        w = self.block_inputs(un)[0]
        slope_in = self._slopes(self.input_blocks, un[0], self.input_range)
        A, B, C, D = self.A, self.B, self.C, self.D
        if self.loop_blocks:
            p = self.Cp @ x + self.Dp @ w
            slope_q = self._slopes(self.loop_blocks, p, self.loop_range)
            A = A + self.Bq @ (slope_q[:, None] * self.Cp)
            B = B + self.Bq @ (slope_q[:, None] * self.Dp)
            C = C + self.Dq @ (slope_q[:, None] * self.Cp)
            D = D + self.Dq @ (slope_q[:, None] * self.Dp)
        _, z, _ = self.run(un, x)
        slope_out = self._slopes(self.output_blocks, z[0], self.output_range)
        B, D = B * slope_in[None, :], D * slope_in[None, :]
        return A, B, slope_out[:, None] * C, slope_out[:, None] * D

    # ------------------------------------------------------------------ derivatives
    def jacobian_piece(
        self, un: np.ndarray, x: np.ndarray, S: np.ndarray, X: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Normalised outputs and ``∂y_n/∂[θ, x(0)]`` over a piece of a record.

        ``θ`` is :meth:`free_parameters` (every entry; a fit keeps the columns of its
        mask). ``x`` (nx,), ``S`` (nx, Pc + nx: the core's parameters and ``x(0)``) and
        ``X`` (nx, p_in: the input blocks' parameters) carry the state and its
        sensitivities across pieces, updated in place; start with ``x = x(0)``, ``S =
        [0 | I]`` and ``X = 0`` (:meth:`_sensitivity_start`; with loop blocks ``S``
        carries every column the loop reaches and ``X`` is None). Row ``k * ny + j`` of
        the Jacobian is output ``j`` at sample ``k``; its columns are ``θ`` then
        ``x(0)``.
        """
        if self.loop_blocks:
            return self._loop_jacobian_piece(un, x, S)
        n, ny, nx = un.shape[0], len(self.outputs), self.nx
        w = self.block_inputs(un)
        G, chans = self._input_effects(un)
        p_in = len(chans)
        Pc = S.shape[1] - nx
        z = np.zeros((n, ny))
        Jc = np.zeros((n * ny, Pc + nx))
        core = self.core._arrays()
        pnlss_walk(*core, w, x, S, z, Jc)
        Jin = np.zeros((n, ny, p_in))
        if p_in:
            channel_response(core[0], core[1], core[2], core[3],
                             np.array(chans, dtype=np.int64), G, X, Jin)  # fmt: skip
        P = self.free_parameters().size
        J = np.zeros((n * ny, P + nx))
        J[:, : Pc - ny] = Jc[:, : Pc - ny]  # the core's F (last ny) is unused: zero
        J[:, Pc : Pc + p_in] = Jin.reshape(n * ny, p_in)
        J[:, P:] = Jc[:, Pc:]
        return self._through_output_blocks(z, J, Pc + p_in), J

    def _input_effects(self, un: np.ndarray) -> tuple[np.ndarray, list[int]]:
        """The input blocks' parameter effects on their outputs (N, p_in) and the
        channel of each column."""
        cols, chans = [np.zeros((un.shape[0], 0))], []
        for i, b in enumerate(self.input_blocks):
            if b is not None:
                # beyond a recorded range: the parameters' effect at the range's end
                G = b.jacobian(self._at(b, un[:, i], self.input_range[i]))
                cols.append(G)
                chans += [i] * G.shape[1]
        return np.ascontiguousarray(np.hstack(cols)), chans

    def _through_output_blocks(self, z: np.ndarray, J: np.ndarray, k: int) -> np.ndarray:
        """Normalised outputs for the core's outputs ``z``; ``J`` (the core's output
        sensitivities, output blocks' and ``h``'s columns from ``k`` still zero) turned
        in place into the outputs' by the chain rule."""
        ny = len(self.outputs)
        y = self.block_outputs(z) - self.output_bias
        p_out = sum(b.to_vector().size for b in self.output_blocks if b is not None)
        h = k + p_out
        for j, b in enumerate(self.output_blocks):
            rows = slice(j, None, ny)
            if b is not None:
                at = self._at(b, z[:, j], self.output_range[j])  # the tangent's beyond it
                J[rows, :] *= b.derivative(at)[:, None]
                n = b.to_vector().size
                J[rows, k : k + n] = b.jacobian(at)
                k += n
            J[rows, h + j] = 1.0
        return y + self.output_bias

    def _loop_offsets(self) -> np.ndarray:
        """Where each group of the loop kernel's columns starts
        (:func:`~blockid._kernels.loop.loop_sensitivity`), and its column count last."""
        nx, nu, ny, nl = self.nx, len(self.inputs), len(self.outputs), len(self.loop_blocks)
        p_in = sum(b.to_vector().size for b in self.input_blocks if b is not None)
        p_loop = sum(b.to_vector().size for b in self.loop_blocks)
        sizes = [nx * nx, nx * (nu + nl), ny * nx, ny * (nu + nl)]
        o_b, o_c, o_d, o_e = np.cumsum([0, *sizes])[1:]
        o_cp = o_e + nx + ny  # after e and the unused F
        o_dp = o_cp + nl * nx
        o_in = o_dp + nl * nu
        o_loop = o_in + p_in
        o_x0 = o_loop + p_loop
        return np.array([o_b, o_c, o_d, o_e, o_cp, o_dp, o_in, o_loop, o_x0, o_x0 + nx],
                        dtype=np.int64)  # fmt: skip

    def _loop_jacobian_piece(
        self, un: np.ndarray, x: np.ndarray, S: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`jacobian_piece` with loop blocks: the run fixes the trajectory, the
        blocks give their slopes and parameter effects on it, and the compiled walk
        (:func:`~blockid._kernels.loop.loop_sensitivity`) carries ``S`` (nx, columns
        of :meth:`_loop_offsets`) through the piece."""
        n, ny, nx = un.shape[0], len(self.outputs), self.nx
        w = self.block_inputs(un)
        Xs, P, Q, z, x_end = self._loop_run(w, x)
        x[:] = x_end
        Gin, chin = self._input_effects(un)
        slopes = np.zeros(P.shape)
        cols, chl = [np.zeros((n, 0))], []
        for l, b in enumerate(self.loop_blocks):
            at = self._at(b, P[:, l], self.loop_range[l])
            slopes[:, l] = b.derivative(at)
            G = b.jacobian(at)
            cols.append(G)
            chl += [l] * G.shape[1]
        offsets = self._loop_offsets()
        o_x0 = int(offsets[8])
        Js = np.zeros((n * ny, o_x0 + nx))
        core = self.core
        with np.errstate(all="ignore"):
            loop_sensitivity(
                *(writable(m, float) for m in (core.A, core.B, core.C, core.D, self.Cp, self.Dp)),
                Xs, np.ascontiguousarray(np.hstack((w, Q))), slopes, Gin,
                np.array(chin, dtype=np.int64), np.ascontiguousarray(np.hstack(cols)),
                np.array(chl, dtype=np.int64), offsets, S, Js,
            )  # fmt: skip
        P_all = self.free_parameters().size
        J = np.zeros((n * ny, P_all + nx))
        J[:, :o_x0] = Js[:, :o_x0]
        J[:, P_all:] = Js[:, o_x0:]
        return self._through_output_blocks(z, J, o_x0), J

    @property
    def linear_in_state(self) -> bool:
        """Whether the output is linear in ``x(0)`` (no output block, no loop block)."""
        return not self.loop_blocks and all(b is None for b in self.output_blocks)

    def _sensitivity_start(self, x0: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        nx = self.nx
        if self.loop_blocks:
            offsets = self._loop_offsets()
            S = np.zeros((nx, int(offsets[-1])))
            S[:, int(offsets[8]) :] = np.eye(nx)
            return np.array(x0, dtype=float), S, None  # type: ignore[return-value]
        Pc = self.core.free_parameters().size
        S = np.zeros((nx, Pc + nx))
        S[:, Pc:] = np.eye(nx)
        p_in = sum(b.to_vector().size for b in self.input_blocks if b is not None)
        return np.array(x0, dtype=float), S, np.zeros((nx, p_in))

    def shaped(self, values: Any) -> dict[str, Any]:
        """Numbers, one per entry of :meth:`free_parameters` (standard errors), shaped
        like :attr:`parameters`; the unused column is left out."""
        values = np.asarray(values, dtype=float).reshape(-1)
        nx, nu, ny, nl = self.nx, len(self.inputs), len(self.outputs), len(self.loop_blocks)
        nv = nu + nl
        sizes = [nx * nx, nx * nv, ny * nx, ny * nv, nx, ny, nl * nx, nl * nu]
        parts = np.split(values[: sum(sizes)], np.cumsum(sizes)[:-1])
        B, D = parts[1].reshape(nx, nv), parts[3].reshape(ny, nv)
        out: dict[str, Any] = {
            "A": parts[0].reshape(nx, nx).tolist(),
            "B": B[:, :nu].tolist(),
            "C": parts[2].reshape(ny, nx).tolist(),
            "D": D[:, :nu].tolist(),
        }
        if nl:
            out.update(Bq=B[:, nu:].tolist(), Dq=D[:, nu:].tolist(),
                       Cp=parts[6].reshape(nl, nx).tolist(),
                       Dp=parts[7].reshape(nl, nu).tolist())  # fmt: skip
        out["e"] = parts[4].tolist()
        out["h"] = values[-ny:].tolist()
        k = sum(sizes)
        for side, channels, blocks in self._sides():
            for c, b in zip(channels, blocks, strict=True):
                if b is not None:
                    n = b.to_vector().size
                    out[f"{side} block {c}"] = dict(
                        zip(b.vector_names(), values[k : k + n].tolist(), strict=True)
                    )
                    k += n
        return out

    # ------------------------------------------------------------------ simulation
    def simulate(self, u: Any, y_initial: Any = None) -> np.ndarray:
        """Free run; with measured outputs ``y_initial`` the initial state is estimated
        from all of them and the first ``min(n, max_lag)`` outputs are copied from them;
        without, the run starts at ``x(0) = 0``."""
        un = self.normalised_input(u)
        x0, n = None, 0
        if y_initial is not None and len(np.atleast_1d(y_initial)):
            y0 = np.asarray(y_initial, dtype=float).reshape(-1, len(self.outputs))
            n = min(y0.shape[0], un.shape[0])
            x0 = self.initial_state(u, y0[:n])
        yn, _, _ = self.run(un, x0)
        y = yn * self.output_scale + self.output_offset
        self._measured_head(y, y_initial, n)
        return y

    def predict(self, u: Any, y: Any) -> np.ndarray:
        """One step ahead: an output-error model has no noise model, so the prediction is
        the free run from the state estimated from the first ``max_lag`` outputs."""
        u, y = self._check_signals(u, y)
        return self.simulate(u, y[: self.max_lag])

    def range_excursion(self, u: Any) -> dict[str, float]:
        """How far input ``u`` and a free run on it from ``x(0) = 0`` drive the blocks'
        arguments beyond the ranges they covered in estimation (fractions of each
        range's width): ``"u"`` the inputs' own (the largest over the channels with a
        block), ``"z <output>"`` the argument of each output block."""
        un = self.normalised_input(u)
        _, z, _ = self.run(un)
        out: dict[str, float] = {}
        if self.loop_blocks:
            P = self._loop_run(self.block_inputs(un), None)[1]
            for l, name in enumerate(self.loops):
                if np.all(np.isfinite(self.loop_range[l])):
                    out[f"p {name}"] = excursion(tuple(self.loop_range[l]), P[:, l])
        for i, b in enumerate(self.input_blocks):
            if b is not None and np.all(np.isfinite(self.input_range[i])):
                value = excursion(tuple(self.input_range[i]), un[:, i])
                out["u"] = max(out.get("u", 0.0), value)
        for j, (c, b) in enumerate(zip(self.outputs, self.output_blocks, strict=True)):
            if b is not None and np.all(np.isfinite(self.output_range[j])):
                out[f"z {c}"] = excursion(tuple(self.output_range[j]), z[:, j])
        return out

    def block_ranges(self) -> list[tuple[str, Any, tuple[float, float]]]:
        """See :meth:`Model.block_ranges`: the input blocks on their normalised inputs,
        the loop blocks on their arguments ``p``, the output blocks on ``z`` (where the
        fit recorded those ranges)."""
        sides = (
            ("input block on", self.inputs, self.input_blocks, self.input_range),
            ("loop block", self.loops, self.loop_blocks, self.loop_range),
            ("output block on", self.outputs, self.output_blocks, self.output_range),
        )
        out = []
        for what, names, blocks, ranges in sides:
            for name, block, seen in zip(names, blocks, ranges, strict=True):
                if block is not None and np.all(np.isfinite(seen)):
                    out.append((f"{what} {name}", block, (float(seen[0]), float(seen[1]))))
        return out

    def block_curve(self, side: str, k: int, grid: Any) -> np.ndarray:
        """The ``k``-th ``side`` block (``"input"``, ``"loop"``, ``"output"``) on
        ``grid`` (its argument, normalised), on the axis :meth:`static_curves` draws it:
        an input or loop block's own output (normalised), an output block's with the
        bias ``h`` and in the output's units."""
        grid = np.asarray(grid, dtype=float)
        if side == "output":
            out = np.asarray(self.output_blocks[k](grid), dtype=float) + self.output_bias[k]
            return self.output_offset[k] + self.output_scale[k] * out
        blocks = self.input_blocks if side == "input" else self.loop_blocks
        return np.asarray(blocks[k](grid), dtype=float)

    def static_curves(self, u: Any = None, n_points: int = 400) -> list[dict[str, Any]]:
        """Each block's curve over the range its argument takes when input ``u`` is
        simulated from ``x(0) = 0`` (without ``u``: the range recorded in estimation,
        for the blocks that have one), in the signals' units where they have them: an
        input block against its input, an output block's output (with the offset and
        scale) against its argument ``z``. Dicts with ``title``, ``x``, ``y``,
        ``xlabel``, ``ylabel`` (the report draws one panel each), and ``side``, ``index``
        and ``grid`` (the argument, normalised) for :meth:`block_curve`."""

        def finite(columns: Any) -> list[np.ndarray | None]:
            return [c if np.all(np.isfinite(c)) else None for c in columns]

        spans = {"loop": finite(self.loop_range), "input": finite(self.input_range),
                 "output": finite(self.output_range)}  # fmt: skip
        if u is not None:
            un = self.normalised_input(u)
            spans["input"] = list(un.T)
            spans["output"] = finite(self.run(un)[1].T)
            if self.loop_blocks:
                spans["loop"] = finite(self._loop_run(self.block_inputs(un), None)[1].T)
        curves = []

        def add(side: str, k: int, title: str, x: Any, xlabel: str, ylabel: str) -> None:
            seen = spans[side][k]
            if seen is None:
                return
            grid = np.linspace(np.min(seen), np.max(seen), n_points)
            curves.append({
                "title": title, "x": x(grid), "y": self.block_curve(side, k, grid),
                "xlabel": xlabel, "ylabel": ylabel, "side": side, "index": k, "grid": grid,
            })  # fmt: skip

        for l, (name, b) in enumerate(zip(self.loops, self.loop_blocks, strict=True)):
            add("loop", l, f"loop block {name} ({b.kind})", lambda g: g,
                f"{name} (its argument Cp x + Dp w, normalised)",
                f"q{l + 1} (into the core, normalised)")  # fmt: skip
        for i, (c, b) in enumerate(zip(self.inputs, self.input_blocks, strict=True)):
            if b is not None:
                add("input", i, f"input block on {c} ({b.kind})",
                    lambda g, i=i: self.input_offset[i] + self.input_scale[i] * g,
                    c, f"w{i + 1} (core input, normalised)")  # fmt: skip
        for j, (c, b) in enumerate(zip(self.outputs, self.output_blocks, strict=True)):
            if b is not None:
                add("output", j, f"output block on {c} ({b.kind})", lambda g: g,
                    f"z{j + 1} (core output, normalised)", c)  # fmt: skip
        return curves

    # ------------------------------------------------------------------ files
    def to_dict(self) -> dict[str, Any]:
        def pair(row: np.ndarray) -> list[float | None]:
            return [float(v) if np.isfinite(v) else None for v in row]

        def blocks(bs: tuple[StaticBlock | None, ...]) -> list[dict[str, Any] | None]:
            return [None if b is None else b.to_dict() for b in bs]

        return {
            **self._file_header(),
            "nx": self.nx,
            "A": self.A.tolist(),
            "B": self.B.tolist(),
            "C": self.C.tolist(),
            "D": self.D.tolist(),
            "state_bias": self.state_bias.tolist(),
            "output_bias": self.output_bias.tolist(),
            "input_blocks": blocks(self.input_blocks),
            "output_blocks": blocks(self.output_blocks),
            "input_range": [pair(r) for r in self.input_range],
            "output_range": [pair(r) for r in self.output_range],
            **(
                {
                    "loop": {
                        "blocks": [b.to_dict() for b in self.loop_blocks],
                        "Cp": self.Cp.tolist(),
                        "Dp": self.Dp.tolist(),
                        "Bq": self.Bq.tolist(),
                        "Dq": self.Dq.tolist(),
                        "range": [pair(r) for r in self.loop_range],
                    }
                }
                if self.loop_blocks
                else {}
            ),  # fmt: skip
            "normalisation": {
                "input_offset": self.input_offset.tolist(),
                "input_scale": self.input_scale.tolist(),
                "output_offset": self.output_offset.tolist(),
                "output_scale": self.output_scale.tolist(),
            },
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> BlockStateSpace:
        norm = data.get("normalisation", {})

        def blocks(key: str) -> list[Any]:
            return [None if b is None else block_from_dict(b) for b in data.get(key) or []] or None

        loop = data.get("loop") or {}
        try:
            return cls(
                data["inputs"], data["outputs"], data["A"], data["B"], data["C"], data["D"],
                loop_blocks=[block_from_dict(b) for b in loop.get("blocks", [])] or None,
                Cp=loop.get("Cp"), Dp=loop.get("Dp"), Bq=loop.get("Bq"), Dq=loop.get("Dq"),
                loop_range=loop.get("range"),
                input_blocks=blocks("input_blocks"), output_blocks=blocks("output_blocks"),
                state_bias=data.get("state_bias"), output_bias=data.get("output_bias"),
                input_offset=norm.get("input_offset"), input_scale=norm.get("input_scale"),
                output_offset=norm.get("output_offset"), output_scale=norm.get("output_scale"),
                input_range=data.get("input_range"), output_range=data.get("output_range"),
                sampling_time=data.get("sampling_time"),
            )  # fmt: skip
        except OrderError as exc:
            raise ModelFileError(
                f"the block state-space model description is invalid: {exc}"
            ) from None
