"""The linear dynamics of a model: poles and zeros, step response and frequency response.

Every model kind gives its linear part through
:func:`blockid.models.export.transfer_functions` (numerator and denominator in positive
powers of ``z``): each linear block of a chain, the forward path ``B/A`` of the feedback
model, a single-input single-output ARX model, and the linear part ``A, B, C, D`` of a
state-space model for every input-output pair.

.. math::

    G(z) = \\frac{N(z)}{D(z)}, \\qquad g_\\infty = G(1) = \\frac{N(1)}{D(1)}, \\qquad
    G(e^{j\\omega}),\\ 0 < \\omega \\le \\pi

With the sampling time ``T`` known, time is in seconds (``t = k T``) and frequency in
hertz (``f = \\omega / (2 \\pi T)``, up to the Nyquist frequency ``1 / (2T)``); without it,
in samples and rad/sample. matplotlib is imported inside the functions.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "NEAR_NYQUIST",
    "PZ_REACH",
    "LinearDynamics",
    "at_nyquist",
    "describe_dynamics",
    "linear_dynamics",
    "linear_figure",
    "oscillation",
    "pole_rows",
    "time_constant",
]

#: Frequencies of the Bode plot: this many, log-spaced from PI * 1e-3 to PI rad/sample.
N_FREQUENCIES = 400
#: A complex pole whose angle is within this of pi (a period under 2.22 samples) is named
#: a mode near the Nyquist frequency; a negative real pole is one at it.
NEAR_NYQUIST = 0.1 * np.pi
#: The pole-zero plot reaches this far from 0 at most (1.1 times the largest pole or
#: zero, at least 1.1): a zero at -7.8 would otherwise shrink the unit circle to a dot.
PZ_REACH = 1.5


@dataclass(frozen=True)
class LinearDynamics:
    """One linear transfer function ``G(z) = num(z) / den(z)`` of a model.

    Attributes
    ----------
    name : str
        What it is in the model ("linear block", "linear block 1 of 2 (input side)",
        "linear part: velocity / current").
    num, den : ndarray
        Coefficients in positive powers of ``z``, highest first (``den[0] = 1``).
    dt : float or None
        Sampling time in seconds (None: unknown; samples and rad/sample).
    input, output : str
        What the block's input and output are (for axis labels).

    Examples
    --------
    >>> g = LinearDynamics("g", np.array([0.5]), np.array([1.0, -0.5]), None)
    >>> g.static_gain(), g.poles().tolist(), g.delay()
    (1.0, [0.5], 1)
    >>> g.step(4).tolist()
    [0.0, 0.5, 0.75, 0.875]
    """

    name: str
    num: np.ndarray
    den: np.ndarray
    dt: float | None
    input: str = "input"
    output: str = "output"

    def poles(self) -> np.ndarray:
        """Roots of ``den`` (a pole at ``z = 0`` is a delay)."""
        return np.roots(self.den) if len(self.den) > 1 else np.zeros(0)

    def zeros(self) -> np.ndarray:
        """Roots of ``num`` (the finite zeros, those at ``z = 0`` included)."""
        num = np.trim_zeros(np.asarray(self.num, float), "f")
        return np.roots(num) if num.size > 1 else np.zeros(0)

    def static_gain(self) -> float:
        """``G(1)``: the gain to a constant input (infinite for a pole at 1)."""
        den = float(np.polyval(self.den, 1.0))
        num = float(np.polyval(self.num, 1.0))
        if den == 0.0:
            return float("inf") if num != 0.0 else float("nan")
        return num / den

    def delay(self) -> int:
        """Samples before the input acts: the relative degree ``deg D - deg N``."""
        num = np.trim_zeros(np.asarray(self.num, float), "f")
        return int(len(self.den) - max(num.size, 1))

    def describe_delay(self) -> str:
        """The delay in words: ``"8 samples (0.4 s)"``, ``"1 sample"``."""
        d = self.delay()
        samples = f"{d} sample{'' if d == 1 else 's'}"
        return f"{samples} ({d * self.dt:.4g} s)" if self.dt else samples

    def stable(self) -> bool:
        p = self.poles()
        return bool(p.size == 0 or np.max(np.abs(p)) < 1.0)

    def frequency_response(self, w: Any) -> np.ndarray:
        """``G(e^{jw})`` at ``w`` rad/sample (``w = 0`` gives the static gain)."""
        z = np.exp(1j * np.asarray(w, float))
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.polyval(self.num, z) / np.polyval(self.den, z)

    def step(self, n: int) -> np.ndarray:
        """Response to a unit step applied at sample 0, from rest, ``n`` samples."""
        from scipy.signal import lfilter

        den = np.asarray(self.den, float)
        num = np.asarray(self.num, float)
        b = np.concatenate([np.zeros(den.size - num.size), num])  # powers of z^-1
        return lfilter(b, den, np.ones(int(n)))

    def step_length(self) -> int:
        """Samples that show the step response settle: 1.5 times the time the slowest
        pole takes to decay to 1 %, plus the delay (30 to 3000; 100 when a pole lies on
        or outside the unit circle)."""
        p = self.poles()
        r = float(np.max(np.abs(p))) if p.size else 0.0
        delay = int(np.sum(np.abs(p) < 1e-12))
        if r >= 1.0:
            return 100
        settle = np.log(0.01) / np.log(r) if r > 1e-12 else 1.0
        return int(np.clip(np.ceil(1.5 * settle) + delay + 2, 30, 3000))

    def frequencies(self) -> np.ndarray:
        """The Bode plot's frequencies in rad/sample."""
        return np.pi * np.logspace(-3.0, 0.0, N_FREQUENCIES)


def _num(block_count: int, k: int) -> str:
    if block_count == 1:
        return "linear block"
    side = " (input side)" if k == 0 else " (output side)" if k == block_count - 1 else ""
    return f"linear block {k + 1} of {block_count}{side}"


def linear_dynamics(model: Any) -> list[LinearDynamics]:
    """Every linear transfer function of ``model`` (module docstring), input side first.

    A model without a single-input single-output linear part (a MIMO ARX model, a
    network) gives an empty list.

    >>> from blockid.blocks import LinearBlock
    >>> [g.name for g in linear_dynamics(LinearBlock(1, 1, 1, a=[-0.5], b=[1.0]))]
    ['linear block']
    """
    from blockid.errors import BlockidError
    from blockid.models.export import transfer_functions

    try:
        tfs = transfer_functions(model)
    except (BlockidError, ImportError):
        return []
    dt = getattr(model, "sampling_time", None) or None
    inputs = tuple(getattr(model, "inputs", ("input",)))
    outputs = tuple(getattr(model, "outputs", ("output",)))
    feedback = getattr(model, "feedback", None) is not None
    out = []
    for k, tf in enumerate(tfs):
        if "input" in tf:  # a state-space model: one entry per input-output pair
            name = f"linear part: {tf['output']} / {tf['input']}"
            u, y = tf["input"], tf["output"]
        elif feedback:
            name = "forward path B/A (the fed-back block closes the loop around it)"
            u, y = f"{inputs[0]} - N({outputs[0]})", outputs[0]
        elif not hasattr(model, "blocks"):  # a linear block, or a SISO ARX model
            linear = getattr(model, "role", None) == "linear"
            name = "linear block" if linear else f"{outputs[0]} / {inputs[0]}"
            u, y = inputs[0], outputs[0]
        else:
            name = _num(len(tfs), k)
            u, y = "block input", "block output"
        num = np.asarray(tf["num"], float)
        den = np.asarray(tf["den"], float)
        out.append(LinearDynamics(name, num, den, dt, u, y))
    return out


def _complex(z: complex) -> str:
    if abs(z.imag) < 1e-12:
        return f"{z.real:.5g}"
    return f"{z.real:.5g} {'+' if z.imag > 0 else '-'} {abs(z.imag):.5g}j"


def time_constant(p: complex, dt: float | None) -> float:
    """``-T / ln|p|``: the time in which the envelope ``|p|^k`` of the pole's mode falls
    by the factor e (in samples without ``T``); infinite on or outside the unit circle.

    >>> round(time_constant(-0.999, None), 1), round(time_constant(0.5j, 0.1), 4)
    (999.5, 0.1443)
    """
    r = abs(p)
    return float(-(dt or 1.0) / np.log(r)) if 0.0 < r < 1.0 else float("inf")


def oscillation(p: complex, dt: float | None) -> str:
    """How the mode ``p^k`` of a pole turns, in words (module docstring: ``angle(p) / (2
    pi T)`` hertz, or cycles/sample without ``T``): ``""`` for a positive real pole (it
    does not oscillate), the Nyquist frequency for a negative real pole (its sign
    alternates every sample: a period of 2 samples), and ``near the Nyquist frequency``
    for a complex pole within :data:`NEAR_NYQUIST` of ``z = -1``'s angle.

    >>> oscillation(-0.999, None)
    '0.5 cycles/sample: the Nyquist frequency, period 2 samples'
    >>> oscillation(0.9j, 0.1), oscillation(0.5, 0.1)
    ('2.5 Hz', '')
    """
    unit = "Hz" if dt else "cycles/sample"
    angle = abs(float(np.angle(p)))
    cycles = angle / (2 * np.pi) / (dt or 1.0)
    if _is_real(p):
        if p.real >= 0:
            return ""
        return f"{0.5 / (dt or 1.0):.4g} {unit}: the Nyquist frequency, period 2 samples"
    if angle >= np.pi - NEAR_NYQUIST:
        period = 2 * np.pi / angle
        return f"{cycles:.4g} {unit}: near the Nyquist frequency, period {period:.3g} samples"
    return f"{cycles:.4g} {unit}"


def at_nyquist(p: complex) -> bool:
    """Whether the mode of ``p`` oscillates at or near the Nyquist frequency (a negative
    real pole, or a complex one within :data:`NEAR_NYQUIST` of ``z = -1``'s angle)."""
    return abs(p) > 1e-12 and abs(float(np.angle(p))) >= np.pi - NEAR_NYQUIST


def pole_rows(system: LinearDynamics) -> list[list[Any]]:
    """Rows ``[what, value, |z|, time constant, oscillation]`` for a table of the poles
    and zeros: each conjugate pair once (``a ± bj``); for a pole the time constant of
    its envelope (:func:`time_constant`) and how it oscillates (:func:`oscillation`: a
    negative real pole at the Nyquist frequency), in seconds and hertz when the sampling
    time ``T`` is known, in samples and cycles/sample otherwise; for a complex zero the
    frequency its angle stands for."""
    ts = system.dt
    unit_t, unit_f = ("s", "Hz") if ts else ("samples", "cycles/sample")
    rows: list[list[Any]] = []
    for what, roots in (("pole", system.poles()), ("zero", system.zeros())):
        at_zero = int(np.sum(np.abs(roots) < 1e-12))
        for z in sorted(roots, key=lambda z: (-abs(z), -z.imag)):
            r = abs(z)
            if z.imag < -1e-12 or r < 1e-12:
                continue  # its conjugate is listed; those at 0 are counted below
            value = _complex(z) if abs(z.imag) < 1e-12 else _complex(z).replace("+", "±")
            tau, osc = "", ""
            if what == "pole":
                tau = (
                    f"{time_constant(z, ts):.4g} {unit_t}"
                    if r < 1.0
                    else "none (on or outside the unit circle)"
                )
                osc = oscillation(z, ts) or "none"
            elif abs(z.imag) > 1e-12:
                osc = f"{abs(np.angle(z)) / (2 * np.pi) / (ts or 1.0):.4g} {unit_f}"
            rows.append([what, value, float(r), tau, osc])
        if at_zero:
            note = "(delay)" if what == "pole" else ""
            rows.append([what if at_zero == 1 else f"{at_zero} {what}s", "0", 0.0, note, ""])
    return rows


def describe_dynamics(system: LinearDynamics) -> str:
    """One sentence: static gain, delay, stability and the least damped mode (its pole,
    the time constant of its envelope, how it oscillates: a negative real pole is named a
    mode at the Nyquist frequency, not a slow pole), and, for a mode at or near the
    Nyquist frequency that decays slowly (``|p| >= 0.9``), the gain there against the
    static gain.

    >>> g = LinearDynamics("g", np.array([1.0]), np.array([1.0, 0.999]), None)
    >>> describe_dynamics(g)  # doctest: +NORMALIZE_WHITESPACE
    'g: static gain 0.5003, delay 1 sample, stable; its least damped pole p = -0.999 is
    a mode at the Nyquist frequency: its sign alternates every sample (period 2
    samples), its envelope decays with time constant 999.5 samples; gain at the Nyquist
    frequency |G(-1)| = 1000 (60 dB), against the static gain 0.5003 (-6.02 dB).'
    """
    head = system.name
    text = f"{head}: static gain {system.static_gain():.4g}, delay {system.describe_delay()}"
    p = system.poles()
    moving = p[np.abs(p) > 1e-12]
    if not moving.size:
        return text + "."
    slow = complex(moving[np.argmax(np.abs(moving))])
    slow = slow.conjugate() if slow.imag < 0 else slow  # a pair is written a ± bj
    r = float(abs(slow))
    if r >= 1.0:
        return text + f", NOT stable: a pole at |p| = {r:.4g}."
    unit = "s" if system.dt else "samples"
    tau = f"time constant {time_constant(slow, system.dt):.4g} {unit}"
    turns = oscillation(slow, system.dt)
    if _is_real(slow) and slow.real < 0:
        text += (
            f", stable; its least damped pole p = {slow.real:.4g} is a mode at the Nyquist "
            "frequency: its sign alternates every sample (period 2 samples), its envelope "
            f"decays with {tau}"
        )
    elif _is_real(slow):
        text += f", stable, slowest pole p = {slow.real:.4g} ({tau})"
    else:
        pair = _complex(slow).replace("+", "±")
        kind = "least damped" if at_nyquist(slow) else "slowest"
        text += f", stable, {kind} poles {pair}, |p| = {r:.4g} ({tau}), oscillating at {turns}"
    if at_nyquist(slow) and r >= 0.9:
        high = abs(complex(system.frequency_response(np.pi)))
        gain = system.static_gain()
        with np.errstate(divide="ignore"):
            text += (
                f"; gain at the Nyquist frequency |G(-1)| = {high:.4g} "
                f"({20 * np.log10(high):.3g} dB), against the static gain {gain:.4g} "
                f"({20 * np.log10(abs(gain)):.3g} dB)"
            )
    return text + "."


def _is_real(p: complex) -> bool:
    return abs(p.imag) < 1e-12 * max(abs(p), 1.0)


def _time_axis(system: LinearDynamics, n: int) -> tuple[np.ndarray, str]:
    k = np.arange(n)
    return (k * system.dt, "time [s]") if system.dt else (k.astype(float), "sample")


def _frequency_axis(system: LinearDynamics, w: np.ndarray) -> tuple[np.ndarray, str]:
    if system.dt:
        return w / (2 * np.pi * system.dt), "frequency [Hz]"
    return w, "frequency [rad/sample]"


def _mark_beyond(ax: Any, roots: dict[str, np.ndarray], reach: float) -> None:
    """An arrow at the border of a z-plane of half-width ``reach`` towards every pole or
    zero beyond it, labelled with its value (those in one direction share an arrow)."""
    arrows: dict[tuple[float, float], tuple[complex, list[str]]] = {}
    for what, values in roots.items():
        for v in values:
            far = max(abs(v.real), abs(v.imag))
            if far <= reach:
                continue
            tip = complex(v) * (0.92 * reach / far)
            key = (round(tip.real, 1), round(tip.imag, 1))  # one arrow per direction
            arrows.setdefault(key, (tip, []))[1].append(f"{what} {_complex(complex(v))}")
    for tip, labels in arrows.values():
        x, y = tip.real, tip.imag
        ax.annotate(
            "",
            (x, y),
            (0.84 * x, 0.84 * y),
            arrowprops={"arrowstyle": "->", "color": "0.3", "lw": 0.9},
        )
        beside = abs(x) >= abs(y)  # on the left or right border: the text above the arrow
        ax.annotate(
            "\n".join(dict.fromkeys(labels)),
            (x, y),
            (0, 5) if beside else (5, 0),
            textcoords="offset points",
            ha=("left" if x < 0 else "right") if beside else "left",
            va="bottom" if beside or y < 0 else "top",
            fontsize=7,
            color="C0" if labels[0].startswith("zero") else "C3",
        )


def draw_pole_zero(ax: Any, system: LinearDynamics) -> None:
    """The z-plane: unit circle, poles (x) and zeros (o), at most :data:`PZ_REACH` out
    (so the unit circle stays readable); a pole or zero beyond is marked by an arrow at
    the border, labelled with its value."""
    theta = np.linspace(0.0, 2 * np.pi, 361)
    ax.plot(np.cos(theta), np.sin(theta), color="0.6", lw=0.8, label="unit circle")
    ax.axhline(0.0, color="0.85", lw=0.6)
    ax.axvline(0.0, color="0.85", lw=0.6)
    p, z = system.poles(), system.zeros()
    if z.size:
        ax.plot(z.real, z.imag, "o", mfc="none", color="C0", ms=6, label="zeros")
    if p.size:
        ax.plot(p.real, p.imag, "x", color="C3", ms=7, mew=1.5, label="poles")
    at_zero = int(np.sum(np.abs(p) < 1e-12))
    if at_zero > 1:
        ax.annotate(
            f"{at_zero} poles at 0",
            (0.0, 0.0),
            (4, -12),
            textcoords="offset points",
            fontsize=7,
            color="C3",
        )
    reach = min(PZ_REACH, max(1.1, 1.1 * float(np.max(np.abs(np.r_[p, z, 0.0])))))
    _mark_beyond(ax, {"pole": p, "zero": z}, reach)
    ax.set_xlim(-reach, reach)
    ax.set_ylim(-reach, reach)
    ax.set_aspect("equal")
    ax.set_xlabel("Re z", fontsize=8)
    ax.set_ylabel("Im z", fontsize=8)
    ax.set_title("poles and zeros", fontsize=9)


def draw_step(ax: Any, system: LinearDynamics, n: int | None = None) -> None:
    """The unit step response from rest, the static gain dashed (when stable)."""
    n = n or system.step_length()
    t, label = _time_axis(system, n)
    ax.step(t, system.step(n), where="post", color="C0", lw=1.0, label="step response")
    gain = system.static_gain()
    if system.stable() and np.isfinite(gain):
        ax.axhline(gain, color="C1", ls="--", lw=0.8, label="static gain G(1)")
        ax.annotate(
            f"G(1) = {gain:.4g}",
            (1.0, gain),
            (-4, 4),
            xycoords=("axes fraction", "data"),
            textcoords="offset points",
            ha="right",
            fontsize=7,
            color="C1",
        )
    ax.set_xlabel(label, fontsize=8)
    ax.set_ylabel(system.output, fontsize=8)
    ax.set_title(f"unit step in {system.input}, from rest", fontsize=9)


def draw_bode(ax_mag: Any, ax_phase: Any, system: LinearDynamics) -> None:
    """Magnitude (dB) and phase (degrees) of ``G(e^{jw})``, the static gain dashed."""
    w = system.frequencies()
    h = system.frequency_response(w)
    f, label = _frequency_axis(system, w)
    with np.errstate(divide="ignore"):
        ax_mag.semilogx(f, 20 * np.log10(np.abs(h)), color="C0", lw=1.0, label="|G|")
        gain = system.static_gain()
        if np.isfinite(gain) and gain != 0.0:
            ax_mag.axhline(
                20 * np.log10(abs(gain)), color="C1", ls="--", lw=0.8, label="static gain G(1)"
            )
    ax_phase.semilogx(f, np.degrees(np.unwrap(np.angle(h))), color="C0", lw=1.0)
    ax_mag.set_ylabel("magnitude [dB]", fontsize=8)
    ax_phase.set_ylabel("phase [deg]", fontsize=8)
    ax_phase.set_xlabel(label, fontsize=8)
    ax_mag.set_title("frequency response (Bode)", fontsize=9)
    ax_mag.tick_params(labelbottom=False)


def linear_figure(systems: Sequence[LinearDynamics], width: float = 9.0) -> Any:
    """One row per linear transfer function: the z-plane, the step response and the
    Bode plot (magnitude above phase). A :class:`matplotlib.figure.Figure` (no pyplot)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, 0.3 + 3.0 * len(systems)), layout="constrained")
    rows = fig.subfigures(len(systems), 1, squeeze=False)[:, 0]
    for sub, system in zip(rows, systems, strict=True):
        grid = sub.add_gridspec(2, 3, width_ratios=(1.0, 1.25, 1.25))
        pz = sub.add_subplot(grid[:, 0])
        step = sub.add_subplot(grid[:, 1])
        mag = sub.add_subplot(grid[0, 2])
        phase = sub.add_subplot(grid[1, 2], sharex=mag)
        draw_pole_zero(pz, system)
        draw_step(step, system)
        draw_bode(mag, phase, system)
        for ax in (pz, step, mag, phase):
            ax.tick_params(labelsize=7)
        handles = {}
        for ax in (pz, step, mag):
            for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
                handles.setdefault(lab, h)
        sub.legend(
            handles.values(),
            handles.keys(),
            loc="outside lower center",
            ncol=min(len(handles), 6),
            fontsize=7,
            frameon=False,
        )
        sub.suptitle(system.name, fontsize=9)
    return fig
