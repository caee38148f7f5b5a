"""Block-oriented models: Hammerstein, Wiener, Hammerstein-Wiener and backlash.

All four are one cascade with optional outer blocks (SISO):

.. math::

    w(k) = N_1(u(k)),\\qquad
    A(z^{-1})\\,x(k) = z^{-n_k} B(z^{-1})\\,w(k),\\qquad
    y(k) = N_2(x(k))

* :class:`Hammerstein` — ``N_1`` static (two-segment polynomial B1 by default),
  no ``N_2``;
* :class:`Wiener` — no ``N_1`` (``w = u``), ``N_2`` a polynomial without constant (B3);
* :class:`HammersteinWiener` — both (paper B, B1–B3);
* :class:`BacklashModel` — ``N_1`` the backlash of paper A (A3), no ``N_2``: the
  "pseudo-Hammerstein" of A4–A5.

The linear block follows the MATLAB convention of :class:`~blockid.models.ARX`
(``a = [a_1..a_na]``, ``b = [b_0..b_{nb-1}]``, ``b_0`` multiplies ``w(k - nk)``).

Normalisation (SPEC): the cascade is otherwise not identifiable, because a gain can
move between the blocks. With an input block ``b_0 = 1`` is fixed; with an output
block its linear coefficient ``q_1 = 1`` is fixed. Paper A's S2 (``v2(t) = x(t-1) +
... - a_1 v2(t-1) - a_2 v2(t-2)``) is ``na = 2, nb = 1, nk = 1`` with ``b_0 = 1``.

One-step-ahead prediction needs the unmeasured ``x`` in the past: it is recovered from
the measured output as ``x = N_2^{-1}(y)``, so a model with an output block predicts
one step ahead only where ``N_2`` is monotone over the measured range.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from blockid.blocks import Backlash, Polynomial
from blockid.blocks.base import Block, DynamicBlock, StaticBlock, block_from_dict
from blockid.errors import BlockidError, EstimationError, ModelFileError, OrderError
from blockid.models.arx import ARX
from blockid.models.base import Model

__all__ = [
    "BlockModel",
    "Hammerstein",
    "Wiener",
    "HammersteinWiener",
    "BacklashModel",
    "BLOCK_STRUCTURES",
]

#: Blocks whose extrapolation beyond the fitted range is unreliable.
_POLYNOMIAL_KINDS = ("polynomial", "two-segment-polynomial")

#: SPEC names of the input-block parameters, by block kind (others keep their own names).
_SPEC_NAMES = {"polynomial": {"coefficients": "f"}}


def _one_name(names: Any, what: str) -> tuple[str]:
    names = (names,) if isinstance(names, str) else tuple(names)
    if len(names) != 1:
        raise OrderError(
            f"block-oriented models have one {what}; got {len(names)} ({list(names)}). "
            "Use an ARX model or a network of blocks for several signals"
        )
    return names


class BlockModel(Model):
    """Generic ``N_1 - L - N_2`` cascade; use the named subclasses.

    Parameters
    ----------
    input, output : str
        Signal names.
    input_block : Block, optional
        Static block or backlash; ``None`` means ``w = u``.
    output_block : Polynomial, optional
        Polynomial without constant term, ``y = q_1 x + q_2 x^2 + ...``; ``None`` means
        ``y = x``.
    na, nb, nk : int
        Orders of the linear block (MATLAB convention).
    a, b : sequence of float, optional
        ``[a_1..a_na]`` and ``[b_0..b_{nb-1}]``; with an input block ``b_0`` must be 1.
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
        output_block: Polynomial | None = None,
        na: int = 1,
        nb: int = 1,
        nk: int = 1,
        a: Any = None,
        b: Any = None,
        sampling_time: float | None = None,
        input_offset: float = 0.0,
        output_offset: float = 0.0,
    ) -> None:
        self.inputs = _one_name(input, "input")
        self.outputs = _one_name(output, "output")
        for flag, block, what in (
            (self.requires_input_block, input_block, "an input block"),
            (self.requires_output_block, output_block, "an output block"),
        ):
            if flag is True and block is None:
                raise OrderError(f"a {self.structure} model needs {what}")
            if flag is False and block is not None:
                raise OrderError(f"a {self.structure} model has no {what[3:]}")
        if output_block is not None and (
            not isinstance(output_block, Polynomial) or output_block.constant
        ):
            raise OrderError("the output block must be a Polynomial without constant term (B3)")
        self.input_block = input_block
        self.output_block = output_block
        self.sampling_time = sampling_time
        self.input_offset = float(input_offset)
        self.output_offset = float(output_offset)
        #: Ranges of the block inputs seen in the estimation data, ``{"u": [lo, hi],
        #: "x": [lo, hi]}`` (relative to the offsets); set by :meth:`record_ranges`.
        self.ranges: dict[str, list[float]] = {}
        for name, value in (("na", na), ("nb", nb), ("nk", nk)):
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
                raise OrderError(
                    f"{name}={value!r}: a block-oriented (single-input single-output) model "
                    "takes one whole number >= 0 per order"
                )
        if nb < 1:
            raise OrderError(f"nb={nb}: a block-oriented model needs nb >= 1")
        if b is None:
            b = np.zeros(nb)
            if input_block is not None:
                b[0] = 1.0
        b = np.asarray(b, dtype=float).reshape(-1)
        if input_block is not None and b.size and b[0] != 1.0:
            raise OrderError(f"b_0 is fixed to 1 when there is an input block (got {b[0]})")
        if output_block is not None and output_block.coefficients[0] != 1.0:
            raise OrderError(
                f"q_1 is fixed to 1 (normalisation B3); got {output_block.coefficients[0]}"
            )
        self.linear = ARX(
            ["w"],
            ["x"],
            na,
            nb,
            nk,
            a={"x": {"x": np.zeros(na) if a is None else a}},
            b={"x": {"w": b}},
        )

    # ------------------------------------------------------------------ structure
    @property
    def na(self) -> int:
        return int(self.linear.na[0, 0])

    @property
    def nb(self) -> int:
        return int(self.linear.nb[0, 0])

    @property
    def nk(self) -> int:
        return int(self.linear.nk[0, 0])

    @property
    def a(self) -> np.ndarray:
        """``[a_1..a_na]`` of the linear block."""
        return self.linear.a["x"]["x"]

    @property
    def b(self) -> np.ndarray:
        """``[b_0..b_{nb-1}]`` of the linear block."""
        return self.linear.b["x"]["w"]

    @property
    def max_lag(self) -> int:
        return self.linear.max_lag

    @property
    def fixed_b0(self) -> bool:
        return self.input_block is not None

    def is_stable(self, margin: float = 0.0) -> bool:
        """True when the linear block's poles lie inside the circle of radius 1 - margin."""
        return self.linear.is_stable(margin)

    @property
    def parameters(self) -> dict[str, Any]:
        """Parameters under SPEC's names: ``f, p`` / backlash names, ``a, b``, ``q``."""
        out: dict[str, Any] = {}
        if self.input_block is not None:
            rename = _SPEC_NAMES.get(self.input_block.kind, {})
            for key, value in self.input_block.parameters.items():
                if key == "constant" and value is True:
                    continue  # the usual case; kept only when there is no constant term
                out[rename.get(key, key)] = value
        out["a"] = self.a.tolist()
        out["b"] = self.b.tolist()
        if self.output_block is not None:
            out["q"] = self.output_block.coefficients.tolist()
        return out

    # ------------------------------------------------------------------ dynamics
    def _u(self, u: Any) -> np.ndarray:
        u, _ = self._check_signals(u)
        return u[:, 0] - self.input_offset

    def internal(self, u: Any, x0: float | None = None) -> np.ndarray:
        """The linear block's input ``w = N_1(u)`` (``u`` itself without input block).

        A backlash starts from ``x0``; by default from the middle of its dead band at
        the first input, so that no start-up jump is simulated.
        """
        u = self._u(u)
        block = self.input_block
        if block is None:
            return u.copy()
        if isinstance(block, DynamicBlock):
            if x0 is None:
                x0 = self._backlash_rest(block, u[0]) if isinstance(block, Backlash) else 0.0
            return block.simulate(u, x0=x0)
        return np.asarray(block(u), dtype=float)

    @staticmethod
    def _backlash_rest(block: Backlash, u0: float) -> float:
        return 0.5 * (block.m_left * (u0 + block.c_left) + block.m_right * (u0 - block.c_right))

    def monotone_branch(self) -> tuple[float, float]:
        """The interval around ``x = 0`` on which the output polynomial is monotone.

        ``q_1 = 1`` makes it increasing at 0; the branch runs to the nearest stationary
        points on either side (infinite where there is none).
        """
        coeffs = np.concatenate(([0.0], self.output_block.coefficients))
        crit = np.polynomial.polynomial.polyroots(np.polynomial.polynomial.polyder(coeffs))
        real = crit[np.abs(crit.imag) < 1e-12].real if crit.size else np.zeros(0)
        lo = max((r for r in real if r < 0), default=-np.inf)
        hi = min((r for r in real if r > 0), default=np.inf)
        return float(lo), float(hi)

    def x_from_y(self, y: np.ndarray) -> np.ndarray:
        """``x = N_2^{-1}(y)`` (``y`` relative to the offset) on the monotone branch.

        The polynomial need only be monotone over the values the model works with: the
        branch around 0 must contain the range of ``x`` seen in estimation (when
        recorded). Outputs beyond the branch's reach map to its ends.
        """
        if self.output_block is None:
            return y
        lo, hi = self.monotone_branch()
        seen = self.ranges.get("x")
        if seen is not None and (seen[0] < lo or seen[1] > hi):
            raise EstimationError(
                f"the output block {self.output_block.coefficients.tolist()} is not monotone "
                f"over the range of x it was fitted on [{seen[0]:.4g}, {seen[1]:.4g}] (it turns "
                f"at {lo if seen[0] < lo else hi:.4g}), so past x cannot be recovered from the "
                "measured y; one-step prediction is not defined. Use free-run simulation"
            )
        scale = 1.0 + float(np.max(np.abs(y), initial=0.0))
        big = 1e6 * scale
        rng = (max(lo, -big), min(hi, big))
        try:
            return self.output_block.inverse(y, u_range=rng, clip=True)
        except BlockidError as exc:
            raise EstimationError(
                f"the output block {self.output_block.coefficients.tolist()} cannot be inverted "
                f"on its monotone branch {rng} ({exc}); one-step prediction is not defined"
            ) from None

    def simulate(self, u: Any, y_initial: Any = None) -> np.ndarray:
        """Free-run simulation from the input alone.

        Without ``y_initial`` the linear block starts at rest; with it, its first
        ``max_lag`` outputs are set from the measurement (through ``N_2^{-1}`` when the
        output block is monotone there; otherwise the block starts at rest).
        """
        w = self.internal(u)
        x_init = None
        if y_initial is not None:
            _, y0 = self._check_signals(np.zeros((len(np.atleast_1d(y_initial)), 1)), y_initial)
            y0 = y0[: self.max_lag, 0] - self.output_offset
            try:
                x_init = self.x_from_y(y0)[:, None]
            except BlockidError:
                x_init = None
        x = self.linear.simulate(w[:, None], x_init)[:, 0]
        y = x if self.output_block is None else self.output_block(x)
        return (y + self.output_offset)[:, None]

    def predict(self, u: Any, y: Any) -> np.ndarray:
        """One-step-ahead prediction: past ``x`` recovered from the measured ``y``."""
        u_arr, y_arr = self._check_signals(u, y)
        y_rel = y_arr[:, 0] - self.output_offset
        x_meas = self.x_from_y(y_rel)
        w = self.internal(u_arr)
        x_hat = self.linear.predict(w[:, None], x_meas[:, None])[:, 0]
        y_hat = x_hat if self.output_block is None else self.output_block(x_hat)
        out = y_hat + self.output_offset
        out[: self.max_lag] = y_arr[: self.max_lag, 0]
        return out[:, None]

    # ------------------------------------------------------------------ vectors
    def free_parameters(self) -> np.ndarray:
        """The identifiable parameters as one vector (fixed ``b_0``, ``q_1`` left out).

        Order: input block, ``a``, ``b`` (without ``b_0`` if fixed), ``q_2..``.
        """
        parts = []
        if self.input_block is not None:
            parts.append(_block_vector(self.input_block))
        parts.append(self.a)
        parts.append(self.b[1:] if self.fixed_b0 else self.b)
        if self.output_block is not None:
            parts.append(self.output_block.coefficients[1:])
        return np.concatenate(parts)

    def with_free_parameters(self, theta: Any) -> BlockModel:
        """A copy with :meth:`free_parameters` replaced by ``theta``."""
        theta = np.asarray(theta, dtype=float).reshape(-1)
        if theta.size != self.free_parameters().size:
            raise OrderError(
                f"expected {self.free_parameters().size} free parameters, got {theta.size}"
            )
        pos = 0
        input_block = None
        if self.input_block is not None:
            n = _block_vector(self.input_block).size
            input_block = _block_with_vector(self.input_block, theta[pos : pos + n])
            pos += n
        a = theta[pos : pos + self.na]
        pos += self.na
        nfree_b = self.nb - 1 if self.fixed_b0 else self.nb
        b = theta[pos : pos + nfree_b]
        pos += nfree_b
        if self.fixed_b0:
            b = np.concatenate(([1.0], b))
        output_block = None
        if self.output_block is not None:
            output_block = Polynomial(np.concatenate(([1.0], theta[pos:])), constant=False)
        return self._replace(input_block=input_block, output_block=output_block, a=a, b=b)

    def record_ranges(self, experiments: Any) -> None:
        """Remember the ranges of ``u`` and of the linear block's output ``x`` over
        estimation data (a sequence of ``(u, y)`` arrays), to flag extrapolation later."""
        us, xs = [], []
        for u, _ in experiments:
            us.append(self._u(u))
            xs.append(self.linear.simulate(self.internal(u)[:, None])[:, 0])
        u_all, x_all = np.concatenate(us), np.concatenate(xs)
        self.ranges = {"u": [float(u_all.min()), float(u_all.max())]}
        if self.output_block is not None and np.all(np.isfinite(x_all)):
            self.ranges["x"] = [float(x_all.min()), float(x_all.max())]

    def extrapolation(self, u: Any) -> list[str]:
        """Warnings when ``u`` (or the simulated ``x``) leaves the recorded ranges.

        A polynomial block fitted on a range says nothing outside it; a cubic output
        block can run away there.
        """
        notes = []
        if not self.ranges:
            return notes
        u_rel = self._u(u)
        checks = []
        kind = getattr(self.input_block, "kind", "")
        if kind in _POLYNOMIAL_KINDS:  # piecewise-linear blocks extrapolate by construction
            checks.append(("u", u_rel, f"input {self.inputs[0]!r}"))
        if "x" in self.ranges:
            x = self.linear.simulate(self.internal(u)[:, None])[:, 0]
            checks.append(("x", x, "the linear block's output x (input of the output block)"))
        for key, values, what in checks:
            lo, hi = self.ranges[key]
            if key == "u":  # report in the user's units, not relative to the offset
                lo, hi, values = (
                    lo + self.input_offset,
                    hi + self.input_offset,
                    (values + self.input_offset),
                )
            span = max(hi - lo, 1e-300)
            out = (values < lo - 0.02 * span) | (values > hi + 0.02 * span)
            if out.any():
                worst = float(max(lo - values.min(), values.max() - hi)) / span
                notes.append(
                    f"{what} leaves the range seen in estimation [{lo:.4g}, {hi:.4g}] in "
                    f"{int(out.sum())} of {values.size} samples (by up to {100 * worst:.0f} % "
                    "of that range): the model extrapolates there"
                )
        return notes

    def _replace(self, **changes: Any) -> BlockModel:
        kwargs = dict(
            input_block=self.input_block,
            output_block=self.output_block,
            na=self.na,
            nb=self.nb,
            nk=self.nk,
            a=self.a,
            b=self.b,
            sampling_time=self.sampling_time,
            input_offset=self.input_offset,
            output_offset=self.output_offset,
        )
        kwargs.update(changes)
        cls = type(self)
        new = cls(self.inputs[0], self.outputs[0], **_ctor_kwargs(cls, kwargs))
        if "input_offset" not in changes and "output_offset" not in changes:
            new.ranges = dict(self.ranges)
        return new

    # ------------------------------------------------------------------ files
    def to_dict(self) -> dict[str, Any]:
        return {
            "structure": self.structure,
            "inputs": list(self.inputs),
            "outputs": list(self.outputs),
            "sampling_time": self.sampling_time,
            "orders": {"na": self.na, "nb": self.nb, "nk": self.nk},
            "blocks": {
                "input": None if self.input_block is None else self.input_block.kind,
                "output": None if self.output_block is None else "polynomial",
            },
            "parameters": self.parameters,
            "offsets": {
                "inputs": {self.inputs[0]: self.input_offset},
                "outputs": {self.outputs[0]: self.output_offset},
            },
            "estimation_ranges": self.ranges,
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> BlockModel:
        params = dict(data["parameters"])
        kinds = data.get("blocks", {})
        input_block = None
        if kinds.get("input"):
            kind = kinds["input"]
            back = {v: k for k, v in _SPEC_NAMES.get(kind, {}).items()}
            block_params = {
                back.get(k, k): v for k, v in params.items() if k not in ("a", "b", "q")
            }
            if kind == "polynomial":
                block_params.setdefault("constant", True)
            input_block = block_from_dict({"kind": kind, **block_params})
        output_block = None
        if kinds.get("output"):
            if kinds["output"] != "polynomial" or "q" not in params:
                raise ModelFileError("the output block must be a polynomial with parameters 'q'")
            output_block = Polynomial(params["q"], constant=False)
        orders = data["orders"]
        offsets = data.get("offsets", {})
        kwargs = dict(
            input_block=input_block,
            output_block=output_block,
            na=int(orders["na"]),
            nb=int(orders["nb"]),
            nk=int(orders["nk"]),
            a=params["a"],
            b=params["b"],
            sampling_time=data.get("sampling_time"),
            input_offset=offsets.get("inputs", {}).get(data["inputs"][0], 0.0),
            output_offset=offsets.get("outputs", {}).get(data["outputs"][0], 0.0),
        )
        model = cls(data["inputs"][0], data["outputs"][0], **_ctor_kwargs(cls, kwargs))
        model.ranges = {
            k: [float(v[0]), float(v[1])] for k, v in data.get("estimation_ranges", {}).items()
        }
        return model


def _ctor_kwargs(cls: type, kwargs: dict[str, Any]) -> dict[str, Any]:
    """Drop the block arguments a subclass's constructor does not take."""
    if cls.requires_input_block is False:
        kwargs.pop("input_block", None)
    if cls.requires_output_block is False:
        kwargs.pop("output_block", None)
    return kwargs


def _block_vector(block: Block) -> np.ndarray:
    if hasattr(block, "to_vector"):
        return np.asarray(block.to_vector(), dtype=float)
    values = [v for k, v in block.parameters.items() if not isinstance(v, bool)]
    return np.concatenate([np.atleast_1d(np.asarray(v, dtype=float)) for v in values])


def _block_with_vector(block: Block, theta: np.ndarray) -> Block:
    if hasattr(block, "with_vector"):
        return block.with_vector(theta)
    if isinstance(block, Backlash):
        return Backlash(*theta)
    params, pos = {}, 0
    for key, value in block.parameters.items():
        if isinstance(value, bool):
            params[key] = value
            continue
        size = np.atleast_1d(np.asarray(value)).size
        chunk = theta[pos : pos + size]
        params[key] = chunk.tolist() if isinstance(value, list) else float(chunk[0])
        pos += size
    return type(block).from_dict({"kind": block.kind, **params})


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


class Wiener(BlockModel):
    """Linear block followed by a static output polynomial (``L - N_2``), ``q_1 = 1``.

    .. math:: A(z^{-1}) x(k) = z^{-n_k} B(z^{-1}) u(k),\\quad y(k) = \\sum_m q_m x(k)^m
    """

    structure = "wiener"
    requires_input_block = False
    requires_output_block = True

    def __init__(self, input: Any, output: Any, *, output_block: Polynomial, **kwargs: Any):
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
        output_block: Polynomial,
        **kwargs: Any,
    ):
        super().__init__(
            input, output, input_block=input_block, output_block=output_block, **kwargs
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
        if not isinstance(input_block, Backlash):
            raise OrderError("a backlash model's input block must be a Backlash")
        super().__init__(input, output, input_block=input_block, **kwargs)


#: Structure name -> class, for the command line and the fitting dispatcher.
BLOCK_STRUCTURES = {
    cls.structure: cls for cls in (Hammerstein, Wiener, HammersteinWiener, BacklashModel)
}
