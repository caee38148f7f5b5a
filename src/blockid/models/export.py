"""Take a model elsewhere: transfer functions for SciPy and python-control, and a
self-contained Python module.

* :func:`transfer_functions` — every linear block (or a SISO ARX model) as numerator
  and denominator in positive powers of ``z``, plain lists (no SciPy needed);
* :func:`to_scipy` / :func:`to_control` — the same as ``scipy.signal.dlti`` /
  ``control.TransferFunction`` (python-control is optional: a clear error when it is
  not installed);
* :func:`to_python_module` — the source of a module that needs NumPy only, with the
  model's parameters embedded and ``simulate(u, y0=None)`` reproducing
  ``model.simulate(u, y_initial=y0[:max_lag])`` to rounding, for ARX (MIMO), every chain of
  blocks (Hammerstein, Wiener, Hammerstein-Wiener, backlash, Wiener-Hammerstein, output
  error), the feedback model, and linear and polynomial state-space models (MIMO; their
  initial state estimated from all of ``y0``, by the same Gauss-Newton iteration).

The linear block ``x = z^-nk B(z^-1)/A(z^-1) w`` (MATLAB convention) is, in positive
powers with ``n = max(na, nk + nb - 1)``,

.. math::

    \\frac{X(z)}{W(z)} = \\frac{0\\,z^n + \\dots + b_0 z^{n - n_k} + \\dots
        + b_{n_b-1} z^{n - n_k - n_b + 1}}{z^n + a_1 z^{n-1} + \\dots + a_{n_a} z^{n - n_a}}

Offsets (the operating point) are not part of a transfer function; the exported module
keeps them.

The module interprets the model description it embeds (the model file's ``"model"``
entry): it holds one evaluation rule per block kind, copied from the blocks, which is
knowledge of the blocks outside them, the price of a file that needs nothing but NumPy.
A block kind it does not know (a user-defined block) is refused at export, so a module
is never written that would simulate something else. Starting from measured outputs
follows :meth:`~blockid.models.ChainModel.simulate` given the first ``max_lag`` of them:
the last linear block starts from ``N^{-1}`` of the first outputs where the blocks after
it are invertible over their estimation range (decided here, at export, with the blocks'
own ``invert``), solved in the module by bisection to machine precision on the same
interval. A longer ``y0`` is cut to its first ``max_lag`` outputs: the start a chain
estimates from more (:mod:`blockid.models.initial_state`) is not exported.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np

from blockid.blocks.base import StaticBlock
from blockid.errors import BlockidError, ParameterError

__all__ = [
    "EXPORTABLE_KINDS",
    "FORMATS",
    "export_text",
    "to_control",
    "to_python_module",
    "to_scipy",
    "transfer_functions",
]

#: Block kinds whose derivative the exported module knows (for tangent extrapolation).
_SLOPES = ("polynomial", "two-segment-polynomial")

#: Block kinds the exported module can evaluate.
EXPORTABLE_KINDS = (
    "linear",
    "polynomial",
    "two-segment-polynomial",
    "dead-zone",
    "saturation",
    "piecewise-linear",
    "piecewise-linear-free",
    "backlash",
)


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
    from blockid.models.state_space import PolynomialStateSpace

    if getattr(model, "role", None) == "linear":
        return [_tf(model, None)]
    dt = getattr(model, "sampling_time", None)
    if isinstance(model, PolynomialStateSpace):  # every input-output pair of A, B, C, D
        linear = model.linear_part()
        out = []
        for i, name_y in enumerate(model.outputs):
            for j, name_u in enumerate(model.inputs):
                num, den = linear.transfer_function(i, j)
                out.append({"num": num.tolist(), "den": den.tolist(), "dt": dt,
                            "input": name_u, "output": name_y})  # fmt: skip
        return out
    if hasattr(model, "lag_arrays"):  # ARX
        if len(model.inputs) != 1 or len(model.outputs) != 1:
            raise ParameterError(
                f"a transfer function here is single-input single-output; the ARX model has "
                f"{len(model.inputs)} input(s) and {len(model.outputs)} output(s): export it "
                "as a Python module instead"
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


def to_control(model: Any, index: int | None = None) -> Any:
    """A linear block as ``control.TransferFunction`` (python-control, optional)."""
    try:
        import control
    except ImportError:
        raise ParameterError(
            "python-control is not installed; install it (pip install control) to export "
            "to python-control, or use to_scipy / the transfer_functions lists"
        ) from None
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
    if block.kind == "polynomial" and hasattr(block, "monotone_branch"):
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
    if seen is None:
        return None
    if block.kind not in _SLOPES:
        raise ParameterError(
            f"the exported module has no derivative of a {block.kind} block, which the model "
            "continues along its tangent outside its estimation range"
        )
    return [float(seen[0]), float(seen[1])]


def _check_kinds(blocks: Any) -> None:
    for block in blocks:
        if block.kind not in EXPORTABLE_KINDS:
            raise ParameterError(
                f"cannot export a {block.kind!r} block (a user-defined block?): the module "
                f"evaluates {', '.join(EXPORTABLE_KINDS)}"
            )


def _spec(model: Any) -> dict[str, Any]:
    """What the module's ``simulate`` needs beyond the model description."""
    from blockid.models.state_space import INITIAL_ITERATIONS, PolynomialStateSpace

    if isinstance(model, PolynomialStateSpace):
        return {"form": "state-space", "max_lag": model.max_lag, "iterations": INITIAL_ITERATIONS}
    if hasattr(model, "lag_arrays"):  # ARX
        A, B = model.lag_arrays()
        return {"form": "arx", "A": A.tolist(), "B": B.tolist(), "max_lag": model.max_lag}
    if hasattr(model, "feedback") and hasattr(model, "linear"):
        _check_kinds([model.linear, model.feedback])
        return {"form": "feedback", "max_lag": model.max_lag}
    if hasattr(model, "last_linear_index"):
        _check_kinds(model.blocks)
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


_HEADER = '''"""{title}

Exported by blockid {version} ({what}). Self-contained: needs NumPy only.

    simulate(u, y0=None) -> array (N, {ny})

is the free-run simulation of blockid's ``simulate``: ``u`` has shape (N,) or (N, {nu})
(inputs {inputs}); without ``y0`` the model starts at rest at its operating point, with
``y0`` (the first measured outputs, at least {max_lag} of them; later ones are not
used) it starts from them as blockid does. ``MODEL`` is the model file's description;
``SPEC`` what simulation needs.
"""

import json

import numpy as np

__all__ = ["INPUTS", "MODEL", "OUTPUTS", "SAMPLING_TIME", "simulate"]

MODEL = json.loads(
    r"""
{model}
"""
)
SPEC = json.loads(
    r"""
{spec}
"""
)
INPUTS = MODEL["inputs"]
OUTPUTS = MODEL["outputs"]
SAMPLING_TIME = MODEL.get("sampling_time")
'''

#: The interpreter of the module: one rule per block kind, copied from blockid's blocks
#: (and kernels) operation by operation, so results agree to rounding.
_RUNTIME = '''

def _offsets(kind):
    names = MODEL[kind]
    table = MODEL.get("offsets", {}).get(kind, {})
    return np.array([float(table.get(n, 0.0)) for n in names])


def _polyval(x, c):
    """Horner's rule, lowest power first (numpy.polynomial.polynomial.polyval)."""
    c = np.asarray(c, dtype=float)
    value = c[-1] + x * 0
    for i in range(2, len(c) + 1):
        value = c[-i] + value * x
    return value


def _powers(p):
    c = [float(v) for v in p["coefficients"]]
    return np.array(c if p.get("constant", True) else [0.0] + c)


def _static(p, s):
    """A memoryless block on the signal ``s``."""
    kind = p["kind"]
    if kind == "polynomial":
        return _polyval(s, _powers(p))
    if kind == "two-segment-polynomial":
        return _polyval(s, np.array(p["f"])) + (s < 0) * _polyval(s, np.array(p["p"]))
    if kind == "dead-zone":
        return p["slope_left"] * np.minimum(s - p["lower"], 0.0) + p["slope_right"] * np.maximum(
            s - p["upper"], 0.0
        )
    if kind == "saturation":
        return np.clip(p["slope"] * s, p["lower"], p["upper"])
    if kind in ("piecewise-linear", "piecewise-linear-free"):
        bp, v = np.array(p["breakpoints"]), np.array(p["values"])
        j = np.clip(np.searchsorted(bp, s, side="right") - 1, 0, bp.size - 2)
        t = (s - bp[j]) / (bp[j + 1] - bp[j])
        return v[j] + t * (v[j + 1] - v[j])
    raise ValueError("unknown block kind " + repr(kind))


def _derivative(c):
    """Coefficients of the derivative (numpy.polynomial.polynomial.polyder)."""
    c = np.asarray(c, dtype=float)
    if c.size <= 1:
        return np.zeros(1)
    return np.array([j * c[j] for j in range(1, c.size)])


def _slope(p, s):
    """dN/du of the blocks that continue along their tangent."""
    if p["kind"] == "polynomial":
        return _polyval(s, _derivative(_powers(p)))
    return _polyval(s, _derivative(p["f"])) + (s < 0) * _polyval(s, _derivative(p["p"]))


def _apply(i, p, s):
    """Block ``i`` of the chain on ``s``, from rest; a polynomial block continues along
    its tangent beyond the input range recorded in estimation (``SPEC["tangents"]``)."""
    if p["kind"] == "linear":
        return _linear(p, s)
    if p["kind"] == "backlash":
        return _backlash(p, s)
    out = _static(p, s)
    seen = SPEC["tangents"][i]
    if seen is None:
        return out
    edge = np.clip(s, seen[0], seen[1])
    outside = edge != s
    if not outside.any():
        return out
    out = np.array(out, dtype=float, copy=True)
    out[outside] = _static(p, edge[outside]) + _slope(p, edge[outside]) * (
        s[outside] - edge[outside]
    )
    return out


def _backlash(p, u):
    """Backlash from the middle of its dead band at the first input."""
    m_left, c_left, m_right, c_right = p["m_left"], p["c_left"], p["m_right"], p["c_right"]
    x = np.empty(len(u))
    if len(u) == 0:
        return x
    u0 = float(u[0])
    prev = 0.5 * (m_left * (u0 + c_left) + m_right * (u0 - c_right))
    for t, ut in enumerate(u.tolist()):
        if ut < prev / m_left - c_left:
            prev = m_left * (ut + c_left)
        elif ut > prev / m_right + c_right:
            prev = m_right * (ut - c_right)
        x[t] = prev
    return x


def _arx(A, B, u, y, n0):
    """In place: y[t, i] = -sum A[i][j][k] y[t-k, j] + sum B[i][m][l] u[t-l, m], t >= n0."""
    N, ny = y.shape
    nu = u.shape[1]
    La, Lb = len(A[0][0]), len(B[0][0])
    uu, yy = u.tolist(), y.tolist()
    for t in range(n0, N):
        for i in range(ny):
            acc = 0.0
            for j in range(ny):
                for k in range(1, min(La, t + 1)):
                    acc -= A[i][j][k] * yy[t - k][j]
            for m in range(nu):
                for lag in range(Lb):
                    if t - lag >= 0:
                        acc += B[i][m][lag] * uu[t - lag][m]
            yy[t][i] = acc
    y[:] = np.array(yy, dtype=float).reshape(y.shape)


def _linear_lags(p):
    na, nb, nk = int(p["na"]), int(p["nb"]), int(p["nk"])
    lag = max(na, nk + nb - 1, 1)
    A = [[[0.0] + [float(v) for v in p["a"]]]]
    b = [0.0] * (lag + 1)
    b[nk : nk + nb] = [float(v) for v in p["b"]]
    return A, [[b]], lag


def _linear(p, w, x0=None):
    """The linear block; its first outputs set from ``x0`` when given."""
    A, B, lag = _linear_lags(p)
    N = w.shape[0]
    x = np.zeros((N, 1))
    n0 = 0
    if x0 is not None:
        n0 = min(lag, N)
        k = min(n0, x0.size)
        x[:k, 0] = x0[:k]
    _arx(A, B, np.ascontiguousarray(w, dtype=float).reshape(-1, 1), x, n0)
    return x[:, 0]


def _bisect(f, w, lo, hi, sign, iterations):
    a = np.full(w.shape, lo)
    b = np.full(w.shape, hi)
    for _ in range(iterations):
        mid = 0.5 * (a + b)
        below = sign * f(mid) < w
        a = np.where(below, mid, a)
        b = np.where(below, b, mid)
    return 0.5 * (a + b)


def _invert(p, spec, w):
    """The block's input for its output ``w``, as blockid's ``invert`` finds it."""
    if spec["method"] == "bisect":
        lo, hi = spec["range"]
        target = spec["sign"] * np.clip(w, *spec["clip"])
        return _bisect(lambda s: _static(p, s), target, lo, hi, spec["sign"], 80)
    # a polynomial on its monotone branch around 0, clipped to the branch's image
    big = 1e6 * (1.0 + float(np.max(np.abs(w), initial=0.0)))
    lo, hi = max(spec["range"][0], -big), min(spec["range"][1], big)
    powers = _powers(p)
    ends = sorted((float(_polyval(lo, powers)), float(_polyval(hi, powers))))
    sign = 1.0 if _polyval(hi, powers) > _polyval(lo, powers) else -1.0
    target = sign * np.clip(w, ends[0], ends[1])
    return _bisect(lambda s: _polyval(s, powers), target, lo, hi, sign, 200)


def _rows(y0):
    y0 = np.asarray(y0, dtype=float)
    return y0[:, None] if y0.ndim == 1 else y0


def _chain(u, y0):
    blocks, last = MODEL["chain"], SPEC["last_linear"]
    s = u[:, 0] - _offsets("inputs")[0]
    for i in range(last):
        s = _apply(i, blocks[i], s)
    x0 = None
    if y0 is not None:
        x0 = _rows(y0)[: SPEC["max_lag"], 0] - _offsets("outputs")[0]
        for p, spec in zip(blocks[:last:-1], SPEC["inverses"]):
            if spec is None:
                x0 = None
                break
            x0 = _invert(p, spec, x0)
    x = _linear(blocks[last], s, x0)
    for i in range(last + 1, len(blocks)):
        x = _apply(i, blocks[i], x)
    return (x + _offsets("outputs")[0])[:, None]


def _feedback(u, y0):
    """y = z^-nk B/A [u - N(y)], N(y) = sum c_m y^m or another static block (Lur'e form)."""
    lin, fb = MODEL["linear"], MODEL["feedback"]
    a, b = [float(v) for v in lin["a"]], [float(v) for v in lin["b"]]
    c = [float(v) for v in fb["coefficients"]] if fb["kind"] == "polynomial" else None
    nk = int(lin["nk"])
    s = (u[:, 0] - _offsets("inputs")[0]).tolist()
    N = len(s)
    y, v = [0.0] * N, [0.0] * N
    n0 = 0
    if y0 is not None:
        y0 = _rows(y0)
        n0 = min(SPEC["max_lag"], N)
        for t in range(min(n0, y0.shape[0])):
            y[t] = float(y0[t, 0]) - float(_offsets("outputs")[0])
    for t in range(N):
        if t >= n0:
            acc = 0.0
            for j in range(1, min(len(a), t) + 1):
                acc -= a[j - 1] * y[t - j]
            for i in range(len(b)):
                if t - nk - i < 0:
                    break
                acc += b[i] * v[t - nk - i]
            y[t] = acc
        if c is None:
            v[t] = s[t] - float(_static(fb, np.array([y[t]]))[0])
            continue
        p = 0.0
        for m in range(len(c) - 1, -1, -1):
            p = p * y[t] + c[m]
        v[t] = s[t] - y[t] * p
    return (np.array(y) + _offsets("outputs")[0])[:, None]


def _arx_model(u, y0):
    N, ny = u.shape[0], len(OUTPUTS)
    y = np.zeros((N, ny))
    n0 = 0 if y0 is None else SPEC["max_lag"]
    if y0 is not None:
        y0 = _rows(y0)
        k = min(n0, y0.shape[0], N)
        y[:k] = y0[:k] - _offsets("outputs")
    _arx(SPEC["A"], SPEC["B"], u - _offsets("inputs"), y, min(n0, N))
    return y + _offsets("outputs")


def _ss_matrices():
    m = MODEL
    nx, nu, ny = int(m["nx"]), len(INPUTS), len(OUTPUTS)
    out = {k: np.asarray(m[k], dtype=float).reshape(s) for k, s in
           (("A", (nx, nx)), ("B", (nx, nu)), ("C", (ny, nx)), ("D", (ny, nu)))}
    expo = np.asarray(m.get("exponents", []), dtype=np.int64).reshape(-1, nx + nu)
    nm = expo.shape[0]
    out["E"] = np.asarray(m.get("E", []), dtype=float).reshape(nx, nm)
    out["F"] = np.asarray(m.get("F", []), dtype=float).reshape(ny, nm)
    out["expo"] = expo
    lo = m.get("lower") or [None] * (nx + nu)
    hi = m.get("upper") or [None] * (nx + nu)
    out["lo"] = np.array([-np.inf if v is None else v for v in lo], dtype=float)
    out["hi"] = np.array([np.inf if v is None else v for v in hi], dtype=float)
    return out


def _ss_run(M, un, x, sens=False):
    """Normalised outputs of a free run from ``x`` and, with ``sens``, their derivative
    with respect to the initial state (rows k * ny + i)."""
    A, B, C, D, E, F, expo = M["A"], M["B"], M["C"], M["D"], M["E"], M["F"], M["expo"]
    lo, hi = M["lo"], M["hi"]
    nx, ny, N = A.shape[0], C.shape[0], un.shape[0]
    y = np.zeros((N, ny))
    J = np.zeros((N * ny, nx)) if sens else None
    S = np.eye(nx)
    x = np.array(x, dtype=float)
    for k in range(N):
        z = np.concatenate((x, un[k]))
        zc = np.minimum(np.maximum(z, lo), hi)
        zeta = np.prod(zc[None, :] ** expo, axis=1) if expo.size else np.zeros(0)
        y[k] = C @ x + D @ un[k] + F @ zeta
        if sens:
            dz = np.zeros((expo.shape[0], nx))
            for j in range(expo.shape[0]):
                for i in range(nx):
                    p = expo[j, i]
                    if p and lo[i] < z[i] < hi[i]:
                        d = expo[j].copy()
                        d[i] -= 1
                        dz[j, i] = p * np.prod(zc ** d)
            J[k * ny : (k + 1) * ny] = (C + F @ dz) @ S
            S = (A + E @ dz) @ S
        x = A @ x + B @ un[k] + E @ zeta
    return y, J


def _state_space(u, y0):
    m, M = MODEL["normalisation"], _ss_matrices()
    un = (u - np.asarray(m["input_offset"])) / np.asarray(m["input_scale"])
    y_off, y_scale = np.asarray(m["output_offset"]), np.asarray(m["output_scale"])
    nx = M["A"].shape[0]
    x0 = np.zeros(nx)
    n = 0
    if y0 is not None and len(np.atleast_1d(y0)):
        y0 = _rows(y0)
        n = min(y0.shape[0], u.shape[0])
        yn = (y0[:n] - y_off) / y_scale
        best = np.inf
        for _ in range(SPEC["iterations"]):
            out, J = _ss_run(M, un[:n], x0, sens=True)
            r = (yn - out).reshape(-1)
            cost = float(r @ r)
            if not np.isfinite(cost) or cost >= best * (1 - 1e-12):
                break
            best = cost
            x0 = x0 + np.linalg.lstsq(J, r, rcond=None)[0]
            if not M["expo"].size:
                break
    y, _ = _ss_run(M, un, x0)
    y = y * y_scale + y_off
    k = min(n, SPEC["max_lag"])
    if k:
        y[:k] = y0[:k]
    return y


def simulate(u, y0=None):
    """Free-run simulation: outputs (N, len(OUTPUTS)) for inputs ``u``; ``y0`` holds the
    first measured outputs to start from (None: from rest)."""
    u = np.asarray(u, dtype=float)
    if u.ndim == 1:
        u = u[:, None]
    if u.ndim != 2 or u.shape[1] != len(INPUTS):
        raise ValueError(
            "the model has %d input(s) %s but got an input array of shape %s"
            % (len(INPUTS), INPUTS, u.shape)
        )
    form = SPEC["form"]
    if form == "state-space":
        return _state_space(u, y0)
    if form == "arx":
        return _arx_model(u, y0)
    if form == "feedback":
        return _feedback(u, y0)
    return _chain(u, y0)
'''


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
    header = _HEADER.format(
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
    return header + _RUNTIME


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
