"""The runtime of a model exported by :func:`blockid.models.export.to_python_module`.

Everything below the marker line is copied, as text, at the end of every exported
module, after its header (``export_header.txt``: ``MODEL``, ``SPEC``, ``INPUTS``,
``OUTPUTS`` and ``SAMPLING_TIME``, ``json`` and NumPy) and the rules of the blocks the
model holds (``_BLOCKS``). It runs the structures (chains, the feedback loop, ARX, state
spaces) and the linear block, copied from blockid operation by operation so that results
agree to rounding; it knows no block kind: a static block is evaluated by its own rule,
``_BLOCKS[kind]["evaluate"]`` (and ``["slope"]``), which the exporter copies from the
block's class (:attr:`blockid.blocks.base.Block.export_source`). ``_polyval`` and
``_derivative`` are helpers those rules may use. It is a real module so that the linter,
the coverage and the mutation tools read it; it needs NumPy only, and nothing of
blockid. The names above the marker stand for the header's and the blocks';
``tests/test_export.py`` also runs this file's functions here.
"""

import numpy as np

MODEL: dict = {}
SPEC: dict = {}
INPUTS: list = []
OUTPUTS: list = []
_BLOCKS: dict = {}

__all__ = ["simulate"]  # the exported module's header declares its own


# --- runtime: copied from here ---
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


def _derivative(c):
    """Coefficients of the derivative (numpy.polynomial.polynomial.polyder)."""
    c = np.asarray(c, dtype=float)
    if c.size <= 1:
        return np.zeros(1)
    return np.array([j * c[j] for j in range(1, c.size)])


def _static(p, s):
    """A memoryless block on the signal ``s``: its own rule."""
    return _BLOCKS[p["kind"]]["evaluate"](p, s)


def _slope(p, s):
    """dN/ds of a static block: its own rule, else central differences as blockid's
    default ``StaticBlock.derivative`` takes them."""
    slope = _BLOCKS[p["kind"]].get("slope")
    if slope is not None:
        return slope(p, s)
    h = 1e-6 * np.maximum(1.0, np.abs(s))
    up, down = _static(p, s + h), _static(p, s - h)
    return (np.asarray(up, dtype=float) - np.asarray(down, dtype=float)) / (2.0 * h)


def _apply(i, p, s):
    """Block ``i`` of the chain on ``s``, from rest; a block that extrapolates unreliably
    (a polynomial) continues along its tangent beyond the input range recorded in
    estimation (``SPEC["tangents"]``)."""
    if p["kind"] == "linear":
        return _linear(p, s)
    block = _BLOCKS[p["kind"]]
    if "run" in block:  # a block with memory (backlash), from rest
        return block["run"](p, s)
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
    # "branch": on the block's monotone branch around 0 (a polynomial's), clipped to the
    # branch's image
    big = 1e6 * (1.0 + float(np.max(np.abs(w), initial=0.0)))
    lo, hi = max(spec["range"][0], -big), min(spec["range"][1], big)
    at_lo, at_hi = _static(p, lo), _static(p, hi)
    ends = sorted((float(at_lo), float(at_hi)))
    sign = 1.0 if at_hi > at_lo else -1.0
    target = sign * np.clip(w, ends[0], ends[1])
    return _bisect(lambda s: _static(p, s), target, lo, hi, sign, 200)


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
        for p, spec in zip(blocks[:last:-1], SPEC["inverses"], strict=False):
            if spec is None:
                x0 = None
                break
            x0 = _invert(p, spec, x0)
    x = _linear(blocks[last], s, x0)
    for i in range(last + 1, len(blocks)):
        x = _apply(i, blocks[i], x)
    return (x + _offsets("outputs")[0])[:, None]


def _feedback(u, y0):
    """y = z^-nk B/A [u - N(y)], N a static block (Lur'e form)."""
    lin, fb = MODEL["linear"], MODEL["feedback"]
    a, b = [float(v) for v in lin["a"]], [float(v) for v in lin["b"]]
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
    rule = _BLOCKS[fb["kind"]]
    if "scalar" in rule:  # the block's own rule for one float (no array per sample)
        one = rule["scalar"](fb)
    else:

        def one(x):
            return float(_static(fb, np.array([x]))[0])

    with np.errstate(all="ignore"):  # a loop that diverges runs to inf and nan silently
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
            v[t] = s[t] - float(one(y[t]))
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
    out = {
        k: np.asarray(m[k], dtype=float).reshape(s)
        for k, s in (("A", (nx, nx)), ("B", (nx, nu)), ("C", (ny, nx)), ("D", (ny, nu)))
    }
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
                        dz[j, i] = p * np.prod(zc**d)
            J[k * ny : (k + 1) * ny] = (C + F @ dz) @ S
            S = (A + E @ dz) @ S
        x = A @ x + B @ un[k] + E @ zeta
    return y, J


def _state_space(u, y0):
    m, M = MODEL["normalisation"], _ss_matrices()
    un = (u - np.asarray(m["input_offset"])) / np.asarray(m["input_scale"])
    y0, n, yn = _measured_start(y0, u.shape[0], m)
    x0 = np.zeros(M["A"].shape[0])
    if yn is not None:
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
    return _in_units(_ss_run(M, un, x0)[0], m, y0, n)


def _measured_start(y0, N, norm):
    """The measured outputs ``y0`` a state-space run of ``N`` samples starts from (as
    rows), how many of them count and their normalised values (``None``, 0, ``None``
    without ``y0``): the state is fitted to them."""
    if y0 is None or not len(np.atleast_1d(y0)):
        return y0, 0, None
    y0 = _rows(y0)
    n = min(y0.shape[0], N)
    return y0, n, (y0[:n] - np.asarray(norm["output_offset"])) / np.asarray(norm["output_scale"])


def _in_units(y, norm, y0, n):
    """A state-space run's normalised outputs ``y`` in the data's units, the first
    ``min(n, max_lag)`` samples the measured ``y0`` it started from."""
    y = y * np.asarray(norm["output_scale"]) + np.asarray(norm["output_offset"])
    k = min(n, SPEC["max_lag"])
    if k:
        y[:k] = y0[:k]
    return y


def _bss_block(p, s, seen):
    """A block of a block state-space model on ``s`` and its slope; a block that
    extrapolates unreliably (a polynomial) continues along its tangent beyond its
    recorded range ``seen``."""
    edge = s
    if _BLOCKS[p["kind"]]["tangent"] and None not in seen:
        edge = np.clip(s, seen[0], seen[1])
    out, slope = _static(p, edge), _slope(p, edge)
    return out + slope * (s - edge) * (edge != s), slope


def _bss_run(M, w, x, sens=False):
    """Normalised outputs of a block state-space model's free run on the core's input
    ``w`` from ``x`` and, with ``sens``, their derivative to the initial state."""
    A, B, C, D, e = M["A"], M["B"], M["C"], M["D"], M["e"]
    nx, ny, N = A.shape[0], C.shape[0], w.shape[0]
    z = np.zeros((N, ny))
    J = np.zeros((N * ny, nx)) if sens else None
    S = np.eye(nx)
    x = np.array(x, dtype=float)
    loop = M.get("loop")
    for k in range(N):
        if loop is not None:  # p = Cp x + Dp w, q = phi(p) into the state and the output
            p = loop["Cp"] @ x + loop["Dp"] @ w[k]
            q, slope = np.zeros(p.size), np.zeros(p.size)
            for i, spec in enumerate(loop["blocks"]):
                value, d = _bss_block(spec, p[i : i + 1], loop["range"][i])
                q[i], slope[i] = value[0], d[0]
            z[k] = C @ x + D @ w[k] + loop["Dq"] @ q
            if sens:
                Sq = slope[:, None] * (loop["Cp"] @ S)
                J[k * ny : (k + 1) * ny] = C @ S + loop["Dq"] @ Sq
                S = A @ S + loop["Bq"] @ Sq
            x = A @ x + B @ w[k] + loop["Bq"] @ q + e
            continue
        z[k] = C @ x + D @ w[k]
        if sens:
            J[k * ny : (k + 1) * ny] = C @ S
            S = A @ S
        x = A @ x + B @ w[k] + e
    y = z.copy()
    for j, p in enumerate(MODEL["output_blocks"]):
        if p is not None:
            y[:, j], slope = _bss_block(p, z[:, j], MODEL["output_range"][j])
            if sens:
                J[j::ny] *= slope[:, None]
    return y + M["h"], J


def _block_state_space(u, y0):
    """w = f(u_n) per input, x(k+1) = A x + B w + Bq q + e, z = C x + D w + Dq q,
    y_n = g(z) + h, with loop blocks q = phi(p), p = Cp x + Dp w (when the model has them)."""
    m, norm = MODEL, MODEL["normalisation"]
    nx, nu, ny = int(m["nx"]), len(INPUTS), len(OUTPUTS)
    M = {
        k: np.asarray(m[k], dtype=float).reshape(s)
        for k, s in (("A", (nx, nx)), ("B", (nx, nu)), ("C", (ny, nx)), ("D", (ny, nu)))
    }
    M["e"] = np.asarray(m["state_bias"], dtype=float)
    M["h"] = np.asarray(m["output_bias"], dtype=float)
    if m.get("loop"):
        loop = m["loop"]
        nl = len(loop["blocks"])
        M["loop"] = {
            "blocks": loop["blocks"],
            "range": loop["range"],
            **{k: np.asarray(loop[k], dtype=float).reshape(s)
               for k, s in (("Cp", (nl, nx)), ("Dp", (nl, nu)), ("Bq", (nx, nl)),
                            ("Dq", (ny, nl)))},
        }  # fmt: skip
    un = (u - np.asarray(norm["input_offset"])) / np.asarray(norm["input_scale"])
    w = un.copy()
    for i, p in enumerate(m["input_blocks"]):
        if p is not None:
            w[:, i] = _bss_block(p, un[:, i], m["input_range"][i])[0]
    y0, n, yn = _measured_start(y0, u.shape[0], norm)
    x0 = np.zeros(nx)
    if yn is not None:

        def linearised(x):
            out, J = _bss_run(M, w[:n], x, sens=True)
            r = (yn - out).reshape(-1)
            return float(r @ r), r, J

        best, r, J = linearised(x0)
        for _ in range(SPEC["iterations"] if np.isfinite(best) else 0):
            if not np.all(np.isfinite(J)):
                break
            step = np.linalg.lstsq(J, r, rcond=None)[0]
            for _halving in range(10):  # Gauss-Newton, the step halved until it helps
                trial = x0 + step
                cost, r_new, J_new = linearised(trial)
                if np.isfinite(cost) and cost < best:
                    break
                step = step / 2
            else:
                break
            gain = (best - cost) / max(best, 1e-300)
            x0, best, r, J = trial, cost, r_new, J_new
            if gain < 1e-12:
                break
    return _in_units(_bss_run(M, w, x0)[0], norm, y0, n)


def simulate(u, y0=None):
    """Free-run simulation: outputs (N, len(OUTPUTS)) for inputs ``u``; ``y0`` holds the
    first measured outputs to start from (None: from rest)."""
    u = np.asarray(u, dtype=float)
    if u.ndim == 1:
        u = u[:, None]
    if u.ndim != 2 or u.shape[1] != len(INPUTS):
        raise ValueError(
            f"the model has {len(INPUTS)} input(s) {INPUTS} but got an input array of "
            f"shape {u.shape}"
        )
    form = SPEC["form"]
    if form == "state-space":
        return _state_space(u, y0)
    if form == "block-state-space":
        return _block_state_space(u, y0)
    if form == "arx":
        return _arx_model(u, y0)
    if form == "feedback":
        return _feedback(u, y0)
    return _chain(u, y0)
