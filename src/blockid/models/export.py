"""Take a model elsewhere: transfer functions for SciPy and python-control, and a
self-contained Python module.

* :func:`transfer_functions` — every linear block (or a SISO ARX model) as numerator
  and denominator in positive powers of ``z``, plain lists (no SciPy needed);
* :func:`to_scipy` / :func:`to_control` — the same as ``scipy.signal.dlti`` /
  ``control.TransferFunction`` (python-control is optional: a clear error when it is
  not installed);
* :func:`to_control` of a state-space model or a multivariable ARX model — one
  ``control.StateSpace`` from physical input deviations to physical output deviations
  (:func:`state_space_matrices`: the matrices and the operating point they deviate from);
  a polynomial or block state space linearised at its equilibrium for a constant input
  (:func:`linearise`, from :mod:`blockid.models.linearise`);
* :func:`to_python_module` — the source of a module that needs NumPy only, with the
  model's parameters embedded and ``simulate(u, y0=None)`` reproducing
  ``model.simulate(u, y_initial=y0[:max_lag])`` to rounding, for ARX (MIMO), every chain of
  blocks (Hammerstein, Wiener, Hammerstein-Wiener, backlash, Wiener-Hammerstein, output
  error), the feedback model, linear and polynomial state-space models and block
  state-space models (MIMO; their initial state estimated from all of ``y0``, by the
  same Gauss-Newton iteration).

The linear block ``x = z^-nk B(z^-1)/A(z^-1) w`` (MATLAB convention) is, in positive
powers with ``n = max(na, nk + nb - 1)``,

.. math::

    \\frac{X(z)}{W(z)} = \\frac{0\\,z^n + \\dots + b_0 z^{n - n_k} + \\dots
        + b_{n_b-1} z^{n - n_k - n_b + 1}}{z^n + a_1 z^{n-1} + \\dots + a_{n_a} z^{n - n_a}}

Offsets (the operating point) are not part of a transfer function; the exported module
keeps them.

The module interprets the model description it embeds (the model file's ``"model"``
entry). It is three texts: the header (``export_header.txt``, a template), the rules of
the block kinds the model holds, each copied from its block's class
(:attr:`~blockid.blocks.base.Block.export_source`: ``evaluate`` and ``slope`` of a
static block, ``run`` of a dynamic one) into a table ``_BLOCKS`` by kind, and the runtime
(``_export_runtime.py`` below its marker), which runs the structures and the linear block
and knows no other block kind. So a block family written in one file (or a test) is
exported as it is; a block whose class gives no rule, or not the slope the model needs,
is refused at export with one line naming its kind and what is missing, so a module is
never written that would simulate something else. Starting from measured outputs
follows :meth:`~blockid.models.ChainModel.simulate` given the first ``max_lag`` of them:
the last linear block starts from ``N^{-1}`` of the first outputs where the blocks after
it are invertible over their estimation range (decided here, at export, with the blocks'
own ``invert``), solved in the module by bisection to machine precision on the same
interval. A longer ``y0`` is cut to its first ``max_lag`` outputs: the start a chain
estimates from more (:mod:`blockid.models.initial_state`) is not exported.
"""

from __future__ import annotations

import ast
import json
import re
import textwrap
from importlib.resources import files
from typing import Any

import numpy as np

from blockid.blocks.base import Block, StaticBlock
from blockid.blocks.polynomial import Polynomial
from blockid.errors import BlockidError, ParameterError
from blockid.models.linearise import linearise

__all__ = [
    "FORMATS",
    "export_text",
    "linearise",
    "state_space_matrices",
    "to_control",
    "to_python_module",
    "to_scipy",
    "transfer_functions",
]


# ----------------------------------------------------------------------------- transfer functions
def _tf(block: Any, dt: float | None) -> dict[str, Any]:
    n = max(block.na, block.nk + block.nb - 1)
    den = np.zeros(n + 1)
    den[0] = 1.0
    den[1 : block.na + 1] = block.a
    num = np.zeros(n + 1)
    num[block.nk : block.nk + block.nb] = block.b
    nonzero = np.flatnonzero(num)
    num = num[nonzero[0] :] if nonzero.size else num[-1:]  # no leading zeros (SciPy warns)
    return {"num": num.tolist(), "den": den.tolist(), "dt": dt}


def transfer_functions(model: Any) -> list[dict[str, Any]]:
    """The linear blocks as ``{"num", "den", "dt"}`` (positive powers of ``z``).

    Parameters
    ----------
    model : LinearBlock, ARX (one input, one output), ChainModel or LinearFeedback
        A chain gives one entry per linear block, input side first (the feedback
        model's loop is not a transfer function of ``u``: its ``B/A`` is given).

    Examples
    --------
    >>> from blockid.blocks import LinearBlock
    >>> transfer_functions(LinearBlock(2, 1, 1, a=[-1.2, 0.35], b=[0.5]))
    [{'num': [0.5, 0.0], 'den': [1.0, -1.2, 0.35], 'dt': None}]
    """
    from blockid.models.block_state_space import BlockStateSpace
    from blockid.models.state_space import PolynomialStateSpace

    if getattr(model, "role", None) == "linear":
        return [_tf(model, None)]
    dt = getattr(model, "sampling_time", None)
    if isinstance(model, PolynomialStateSpace | BlockStateSpace):
        # every input-output pair of A, B, C, D (a block model's: of its linear core)
        linear = model.linear_part()
        out = []
        for i, name_y in enumerate(linear.outputs):
            for j, name_u in enumerate(linear.inputs):
                num, den = linear.transfer_function(i, j)
                out.append({"num": num.tolist(), "den": den.tolist(), "dt": dt,
                            "input": name_u, "output": name_y})  # fmt: skip
        return out
    if hasattr(model, "lag_arrays"):  # ARX
        if len(model.inputs) != 1 or len(model.outputs) != 1:
            raise ParameterError(
                f"a transfer function here is single-input single-output; the ARX model has "
                f"{len(model.inputs)} input(s) and {len(model.outputs)} output(s): export it "
                "as a Python module, or as one state space with to_control(model)"
            )
        yi, ui = model.outputs[0], model.inputs[0]
        from blockid.blocks.linear import LinearBlock

        block = LinearBlock(
            int(model.na[0, 0]),
            max(int(model.nb[0, 0]), 1),
            int(model.nk[0, 0]),
            model.a[yi][yi],
            model.b[yi][ui] if model.nb[0, 0] else [0.0],
        )
        return [_tf(block, dt)]
    if hasattr(model, "linear_blocks"):
        return [_tf(g, dt) for g in model.linear_blocks]
    raise ParameterError(f"{type(model).__name__} has no linear block to export")


def _one(model: Any, index: int | None) -> dict[str, Any]:
    tfs = transfer_functions(model)
    if index is None:
        if len(tfs) != 1:
            raise ParameterError(
                f"the model has {len(tfs)} linear blocks; choose one with index=0..{len(tfs) - 1}",
                parameter="index",
            )
        return tfs[0]
    if not -len(tfs) <= index < len(tfs):
        raise ParameterError(
            f"index={index} but the model has {len(tfs)} linear block(s)", parameter="index"
        )
    return tfs[index]


def to_scipy(model: Any, index: int | None = None) -> Any:
    """A linear block as ``scipy.signal.dlti`` (``dt=True`` without a sampling time).

    ``index`` chooses among several linear blocks (a Wiener-Hammerstein chain).

    Examples
    --------
    >>> from blockid.blocks import LinearBlock
    >>> g = to_scipy(LinearBlock(1, 1, 1, a=[-0.5], b=[1.0]))
    >>> g.poles.tolist()
    [0.5]
    """
    from scipy import signal

    tf = _one(model, index)
    return signal.dlti(tf["num"], tf["den"], dt=tf["dt"] if tf["dt"] else True)


def _arx_matrices(model: Any) -> tuple[np.ndarray, ...]:
    """A non-minimal realisation of an ARX model (:func:`state_space_matrices`): the state
    ``x(k) = [y(k-1); ..; y(k-La); u(k-1); ..; u(k-Lb)]`` (deviations from the offsets),
    ``y(k) = -sum_l A_l y(k-l) + B_0 u(k) + sum_l B_l u(k-l) = C x(k) + D u(k)``."""
    lags_a, lags_b = model.lag_arrays()
    ny, nu = lags_b.shape[:2]
    nonzero_a = np.flatnonzero(np.any(lags_a, axis=(0, 1)))
    nonzero_b = np.flatnonzero(np.any(lags_b, axis=(0, 1)))
    La = int(nonzero_a[-1]) if nonzero_a.size else 0
    Lb = int(nonzero_b[-1]) if nonzero_b.size else 0
    n = ny * La + nu * Lb
    C = np.zeros((ny, n))
    for lag in range(1, La + 1):
        C[:, (lag - 1) * ny : lag * ny] = -lags_a[:, :, lag]
    for lag in range(1, Lb + 1):
        C[:, ny * La + (lag - 1) * nu : ny * La + lag * nu] = lags_b[:, :, lag]
    D = lags_b[:, :, 0].copy()
    A, B = np.zeros((n, n)), np.zeros((n, nu))
    if La:  # y(k) enters the first block of past outputs, the others move one lag on
        A[:ny] = C
        B[:ny] = D
        A[ny : ny * La, : ny * (La - 1)] = np.eye(ny * (La - 1))
    if Lb:  # the same for the past inputs
        B[ny * La : ny * La + nu] = np.eye(nu)
        start = ny * La
        A[start + nu :, start : start + nu * (Lb - 1)] = np.eye(nu * (Lb - 1))
    states = [f"{y}(k-{lag})" for lag in range(1, La + 1) for y in model.outputs]
    states += [f"{u}(k-{lag})" for lag in range(1, Lb + 1) for u in model.inputs]
    return A, B, C, D, states


def state_space_matrices(model: Any, operating_point: Any = None) -> dict[str, Any]:
    """``A, B, C, D`` from physical input deviations to physical output deviations, and
    the operating point they deviate from (what :func:`to_control` exports).

    .. math::

        x(k+1) = A x(k) + B (u(k) - u_0), \\qquad y(k) = y_0 + C x(k) + D (u(k) - u_0)

    * A linear state-space model (normalised signals,
      :mod:`blockid.models.state_space`): ``A``, ``B S_u^{-1}``, ``S_y C``,
      ``S_y D S_u^{-1}`` with ``S_u``, ``S_y`` the diagonal input and output scales and
      ``u_0``, ``y_0`` the offsets. The state is the model's own, so ``x(0)`` from
      :meth:`~blockid.models.state_space.PolynomialStateSpace.initial_state` carries
      over. The predictor gain ``K`` is left out: this is the simulation model. With an
      ``operating_point`` the same matrices about the equilibrium there (as below).
    * A polynomial or block state-space model: the model linearised at its equilibrium
      for the constant input ``u_0 = operating_point`` (default the input offset, the
      middle of the estimation data), :func:`linearise`; ``y_0``
      is the equilibrium's output and the state the deviation ``x - x^*`` from the
      equilibrium state (``"equilibrium_state"``). Refused, naming why, where there is no
      stable equilibrium or the monomials' arguments are clipped there.
    * An ARX model (any number of inputs and outputs): a non-minimal realisation whose
      state holds the past outputs and inputs (deviations), ``y(k-1) .. y(k-n_a)``,
      ``u(k-1) .. u(k-n_b)``; the state 0 is the model at rest at its operating point,
      where its simulation without ``y_initial`` starts (no ``operating_point``: an ARX
      model's matrices are the same at every point).

    Returns ``{"A", "B", "C", "D", "states", "input_offset", "output_offset",
    "equilibrium_state"}`` (arrays; ``states``: names; a linearisation adds
    ``"spectral_radius"``).

    Examples
    --------
    >>> from blockid.models import StateSpace
    >>> m = StateSpace(["u"], ["y"], A=[[0.5]], B=[[1.0]], C=[[1.0]], D=[[0.0]],
    ...                input_scale=2.0, output_offset=10.0, output_scale=3.0)
    >>> ss = state_space_matrices(m)
    >>> ss["B"].tolist(), ss["C"].tolist(), ss["output_offset"].tolist()
    ([[0.5]], [[3.0]], [10.0])
    """
    from blockid.models.block_state_space import BlockStateSpace
    from blockid.models.state_space import PolynomialStateSpace

    if isinstance(model, BlockStateSpace) or (
        isinstance(model, PolynomialStateSpace)
        and (model.n_monomials or operating_point is not None)
    ):
        return linearise(model, operating_point)
    if operating_point is not None:
        raise ParameterError(
            f"a {type(model).__name__} is linear in deviations from its offsets: its "
            "matrices do not depend on an operating point; leave operating_point out",
            parameter="operating_point",
        )
    if isinstance(model, PolynomialStateSpace):
        su, sy = model.input_scale, model.output_scale
        A, B = model.A.copy(), model.B / su[None, :]
        C, D = sy[:, None] * model.C, sy[:, None] * model.D / su[None, :]
        states = [f"x{i + 1}" for i in range(model.nx)]
    elif hasattr(model, "lag_arrays"):  # ARX
        A, B, C, D, states = _arx_matrices(model)
    else:
        raise ParameterError(
            f"a {type(model).__name__} has no state-space export; use to_control(model) for "
            "its linear block's transfer function, or to_python_module"
        )
    return {
        "A": A, "B": B, "C": C, "D": D, "states": states,
        "input_offset": np.asarray(model.input_offset, dtype=float).copy(),
        "output_offset": np.asarray(model.output_offset, dtype=float).copy(),
        "equilibrium_state": np.zeros(A.shape[0]),
    }  # fmt: skip


def to_control(model: Any, index: int | None = None, operating_point: Any = None) -> Any:
    """The model's linear dynamics in python-control (optional).

    * A state-space model or an ARX model of several inputs or outputs, without
      ``index``: one ``control.StateSpace`` from the physical input deviations
      ``u - u_0`` to the physical output deviations ``y - y_0``
      (:func:`state_space_matrices`), with ``dt`` the sampling time (``True`` without
      one) and the model's signal names. For a linear model ``u_0``, ``y_0`` are
      ``model.input_offset``, ``model.output_offset``:
      ``y_0 + control.forced_response(sys, inputs=(u - u_0).T).outputs.T`` equals
      ``model.simulate(u)``; with ``initial_state=model.initial_state(u, y_meas)`` it
      equals ``model.simulate(u, y_meas)`` beyond the ``max_lag`` outputs that copies.
      A polynomial or block state space is linearised at its equilibrium for the
      constant input ``u_0 = operating_point`` (one value, or one per input; default
      the input offset) and ``y_0`` is the output there: the small-signal model
      (:func:`linearise`).
    * A linear block, a chain, a feedback model, a single-input single-output ARX
      model, or a state-space model's input-output pair ``index`` (the order of
      :func:`transfer_functions`): ``control.TransferFunction`` (no ``operating_point``).

    Examples
    --------
    >>> from blockid.models import StateSpace
    >>> m = StateSpace(["u"], ["y"], A=[[0.5]], B=[[1.0]], C=[[1.0]], D=[[0.0]],
    ...                output_offset=10.0, sampling_time=0.1)
    >>> sys = to_control(m)
    >>> sys.input_labels, sys.output_labels, sys.dt
    (['u'], ['y'], 0.1)
    """
    try:
        import control
    except ImportError:
        raise ParameterError(
            "python-control is not installed; install it (pip install control) to export "
            "to python-control, or use to_scipy / the transfer_functions lists"
        ) from None
    from blockid.models.block_state_space import BlockStateSpace
    from blockid.models.state_space import PolynomialStateSpace

    multivariable = len(getattr(model, "inputs", ())) > 1 or len(getattr(model, "outputs", ())) > 1
    if index is None and (
        isinstance(model, PolynomialStateSpace | BlockStateSpace)
        or (hasattr(model, "lag_arrays") and multivariable)
    ):
        ss = state_space_matrices(model, operating_point)
        dt = getattr(model, "sampling_time", None)
        return control.ss(
            ss["A"], ss["B"], ss["C"], ss["D"], dt if dt else True,
            inputs=list(model.inputs), outputs=list(model.outputs), states=ss["states"],
            name=model.structure,
        )  # fmt: skip
    if operating_point is not None:
        raise ParameterError(
            "a transfer function holds the linear dynamics only, with no operating point; "
            "leave operating_point out, or export a state-space model whole (index=None)",
            parameter="operating_point",
        )
    tf = _one(model, index)
    return control.tf(tf["num"], tf["den"], tf["dt"] if tf["dt"] else True)


# ----------------------------------------------------------------------------- python module
def _inverse_spec(model: Any, i: int) -> dict[str, Any] | None:
    """How the module inverts tail block ``i`` (None: the model would not, so the last
    linear block starts from rest)."""
    block = model.blocks[i]
    seen = model.ranges.get(model._range_key(i))
    seen = None if seen is None else (float(seen[0]), float(seen[1]))
    try:
        block.invert(np.zeros(1), seen)
    except BlockidError:
        return None
    own = type(block)
    if own.invert is StaticBlock.invert and own.inverse_on is StaticBlock.inverse_on:
        lo, hi = seen  # the default invert needs the range (checked above)
        pad = 0.5 * (hi - lo) + 1e-12
        lo, hi = lo - pad, hi + pad
        values = np.asarray(block(np.linspace(lo, hi, 513)), dtype=float)
        return {
            "method": "bisect",
            "range": [lo, hi],
            "sign": 1.0 if values[1] > values[0] else -1.0,
            "clip": [float(values.min()), float(values.max())],
        }
    if own.invert is Polynomial.invert:  # on its monotone branch around 0
        lo, hi = block.monotone_branch()
        return {"method": "branch", "range": [float(lo), float(hi)]}
    raise ParameterError(
        f"the {block.kind} output block inverts itself in a way the exported module does "
        "not copy; simulate from rest (y0=None) or keep the model in blockid"
    )


def _tangent_range(model: Any, i: int) -> list[float] | None:
    """The input range beyond which block ``i`` continues along its tangent (the
    chain's rule for blocks that extrapolate unreliably), or None."""
    block = model.blocks[i]
    if not (block.warn_extrapolation and block.role == "static"):
        return None
    seen = model.ranges.get(model._range_key(i))
    return None if seen is None else [float(seen[0]), float(seen[1])]


def _spec(model: Any) -> dict[str, Any]:
    """What the module's ``simulate`` needs beyond the model description."""
    from blockid.models.block_state_space import BlockStateSpace
    from blockid.models.state_space import INITIAL_ITERATIONS, PolynomialStateSpace

    if isinstance(model, PolynomialStateSpace):
        return {"form": "state-space", "max_lag": model.max_lag, "iterations": INITIAL_ITERATIONS}
    if isinstance(model, BlockStateSpace):
        return {
            "form": "block-state-space",
            "max_lag": model.max_lag,
            "iterations": INITIAL_ITERATIONS,
        }
    if hasattr(model, "lag_arrays"):  # ARX
        A, B = model.lag_arrays()
        return {"form": "arx", "A": A.tolist(), "B": B.tolist(), "max_lag": model.max_lag}
    if hasattr(model, "feedback") and hasattr(model, "linear"):
        return {"form": "feedback", "max_lag": model.max_lag}
    if hasattr(model, "last_linear_index"):
        last = model.last_linear_index
        tail = range(len(model.blocks) - 1, last, -1)
        return {
            "form": "chain",
            "last_linear": last,
            "max_lag": model.max_lag,
            "tangents": [_tangent_range(model, i) for i in range(len(model.blocks))],
            "inverses": [_inverse_spec(model, i) for i in tail],
        }
    raise ParameterError(
        f"cannot export a {type(model).__name__} (a network?); export each subsystem"
    )


# ----------------------------------------------------------------------------- block rules
#: What the module calls in a block's export_source, by the block's role: the first is
#: required (a static block's ``scalar(p)``, a plain-Python function of one float equal
#: to ``evaluate`` bit for bit, serves a feedback loop sample by sample).
_CALLS = {"static": ("evaluate", "slope", "scalar"), "dynamic": ("run",)}

#: The block's methods its export_source copies, by role: a subclass that changes one
#: of them must give its own export_source (an inherited one would simulate its parent).
#: A static block's derivative counts where the module takes its slope.
_COPIED = {"static": ("__call__",), "dynamic": ("run", "simulate", "rest_state")}

#: Why the module needs a static block's slope, by form (None: it does not).
_SLOPE_USE = {
    "chain": "the model continues it along its tangent outside its estimation range",
    "block-state-space": "a block state-space model takes its slope (tangent and start)",
}


def _blocks(model: Any, spec: dict[str, Any]) -> list[tuple[Block, str | None]]:
    """The blocks of the model, each with why the module needs its slope (or None)."""
    form = spec["form"]
    if form == "chain":
        return [
            (b, None if seen is None else _SLOPE_USE["chain"])
            for b, seen in zip(model.blocks, spec["tangents"], strict=True)
        ]
    if form == "feedback":
        return [(model.linear, None), (model.feedback, None)]
    if form == "block-state-space":
        every = (*model.input_blocks, *model.loop_blocks, *model.output_blocks)
        return [(b, _SLOPE_USE[form]) for b in every if b is not None]
    return []


def _refused(block: Block, why: str) -> ParameterError:
    return ParameterError(f"cannot export the {block.kind!r} block ({type(block).__name__}): {why}")


def _rule(block: Block, slope_use: str | None) -> tuple[str, tuple[str, ...]]:
    """The block's export_source, checked, and the functions of it the module calls."""
    cls = type(block)
    source = cls.export_source
    if source is None:
        raise _refused(
            block,
            "its class gives no export_source, the NumPy source of its evaluation that the "
            "module copies (docs/extending.md)",
        )
    owner = next(c for c in cls.__mro__ if "export_source" in c.__dict__)
    for method in _COPIED.get(block.role, ()) + (("derivative",) if slope_use else ()):
        changed = next((c for c in cls.__mro__ if method in c.__dict__), owner)
        if changed is not owner and issubclass(changed, owner):
            raise _refused(
                block,
                f"{changed.__name__} changes {method} and inherits the export_source of "
                f"{owner.__name__}, which would simulate the parent: give {changed.__name__} "
                "its own",
            )
    source = textwrap.dedent(source).strip("\n") + "\n"
    try:
        defined = {n.name for n in ast.parse(source).body if isinstance(n, ast.FunctionDef)}
    except SyntaxError as exc:
        raise _refused(
            block, f"its export_source is not Python ({exc.msg}, line {exc.lineno})"
        ) from None
    calls = _CALLS.get(block.role, ("evaluate",))
    if calls[0] not in defined:
        raise _refused(block, f"its export_source defines no {calls[0]}(p, ...)")
    own_slope = getattr(cls, "derivative", None) is not StaticBlock.derivative
    if slope_use and own_slope and "slope" not in defined:
        raise _refused(
            block,
            f"{slope_use}, and its export_source defines no slope(p, s) for its own derivative",
        )
    return source, tuple(name for name in calls if name in defined)


def _blocks_text(pairs: list[tuple[Block, str | None]]) -> str:
    """The module's ``_BLOCKS``: the rule of each block kind the model holds, copied from
    its class into a function of its own (so that its names stay its own)."""
    kinds: dict[str, list[tuple[Block, str | None]]] = {}
    for block, slope_use in pairs:
        if block.role == "linear":  # the runtime's own, when it is the plain linear block
            if block.kind != "linear":
                raise _refused(
                    block, "the module runs the linear block of kind 'linear' (a, b, nk) only"
                )
            continue
        if not block.kind:
            raise ParameterError(
                f"cannot export a {type(block).__name__} block: it has no kind, the name the "
                "module would find its rule by"
            )
        kinds.setdefault(block.kind, []).append((block, slope_use))
    parts, table = [], []
    for kind, uses in kinds.items():
        rules = {_rule(block, slope_use) for block, slope_use in uses}
        block = uses[-1][0]
        if len(rules) > 1:
            raise _refused(block, "another block of the model has its kind and another rule")
        ((source, calls),) = rules
        name = "_block_" + re.sub(r"\W+", "_", kind).strip("_")
        while any(line.startswith(f"def {name}():") for line in parts):
            name += "_"
        owner = next(c for c in type(block).__mro__ if "export_source" in c.__dict__)
        tangent = bool(block.warn_extrapolation and block.role == "static")
        returned = "".join(f'"{c}": {c}, ' for c in calls)
        parts.append(
            f"def {name}():\n"
            f"    # {kind!r}: {owner.__module__}.{owner.__qualname__}.export_source\n"
            f"{textwrap.indent(source, '    ')}\n"
            f'    return {{{returned}"tangent": {tangent}}}\n'
        )
        table.append(f"    {json.dumps(kind)}: {name}(),\n")
    head = "# --- blocks: the rule of each block kind in MODEL, copied from its class ---\n"
    body = "{\n" + "".join(table) + "}" if table else "{}"
    return head + "".join(p + "\n\n" for p in parts) + f"_BLOCKS = {body}\n"


# ----------------------------------------------------------------------------- the module
#: The module's header, a template filled by :func:`to_python_module` (``str.format``).
_HEADER_FILE = "export_header.txt"

#: The line after which ``_export_runtime.py`` is the module's runtime.
_MARKER = "# --- runtime: copied from here ---\n"


def _resource(name: str) -> str:
    return files("blockid.models").joinpath(name).read_text(encoding="utf-8")


def _runtime() -> str:
    """The interpreter of the module (``_export_runtime.py`` below its marker)."""
    text = _resource("_export_runtime.py")
    return text[text.index(_MARKER) + len(_MARKER) :]


def to_python_module(model: Any) -> str:
    """Source of a self-contained NumPy-only module that simulates ``model``.

    The module's ``simulate(u, y0=None)`` equals ``model.simulate(u, y_initial=y0)`` to
    rounding for ``y0`` of at most ``max_lag`` outputs (a longer one is cut to them:
    module docstring). Raises :class:`~blockid.errors.ParameterError` for a
    model it cannot copy (a network, a user-defined block).

    Examples
    --------
    >>> from blockid.blocks import LinearBlock, Polynomial
    >>> from blockid.models import Wiener
    >>> m = Wiener("u", "y", output_block=Polynomial([1.0, 0.2], constant=False),
    ...            na=1, nb=1, nk=1, a=[-0.5], b=[1.0])
    >>> namespace = {}
    >>> exec(to_python_module(m), namespace)
    >>> u = [1.0, 1.0, -1.0]
    >>> namespace["simulate"](u)[:, 0].tolist() == m.simulate(u)[:, 0].tolist()
    True
    """
    from blockid import __version__

    spec = _spec(model)
    description = model.to_dict()
    ny, nu = len(model.outputs), len(model.inputs)
    title = (
        f"{description['structure']} model from {', '.join(model.inputs)} to "
        f"{', '.join(model.outputs)}."
    )
    header = _resource(_HEADER_FILE).format(
        title=title[0].upper() + title[1:],
        version=__version__,
        what="blockid export",
        ny=ny,
        nu=nu,
        inputs=", ".join(model.inputs),
        max_lag=model.max_lag,
        model=json.dumps(description, indent=1),
        spec=json.dumps(spec, indent=1),
    )
    return "\n\n".join((header, _blocks_text(_blocks(model, spec)), _runtime()))


def _scipy_json(model: Any) -> str:
    doc = {
        "format": "blockid-transfer-functions",
        "structure": model.structure,
        "inputs": list(model.inputs),
        "outputs": list(model.outputs),
        "note": "scipy.signal.dlti(num, den, dt=dt or True) per linear block, input side "
        "first; positive powers of z; the model's offsets and nonlinear blocks are not "
        "included",
        "transfer_functions": transfer_functions(model),
    }
    return json.dumps(doc, indent=2, allow_nan=False) + "\n"


#: ``blockid export --to`` formats: name -> function from a model to the file's text.
FORMATS = {"python": to_python_module, "scipy-json": _scipy_json}


def export_text(model: Any, to: str) -> str:
    """The text of an export of ``model`` in format ``to`` (one of :data:`FORMATS`)."""
    if to not in FORMATS:
        raise ParameterError(
            f"unknown export format {to!r}; choose one of {', '.join(FORMATS)}", parameter="to"
        )
    return FORMATS[to](model)
