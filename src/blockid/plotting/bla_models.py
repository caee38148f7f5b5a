"""Models checked against the measured best linear approximation: each model's linear
frequency response overlaid on the BLA with its confidence bound (issue 34 item 3).

A linear model (ARX, output error, a linear state space; a polynomial state space's
linear part) is drawn as it is: its response should lie within the BLA's bound where
the BLA is measured. A block-oriented model's linear blocks (their product, for a
Wiener-Hammerstein model) hold its dynamics only up to a gain: the static blocks' gain
cannot be told from the linear block's, and a nonlinearity's BLA is its linear part
times the static block's equivalent gain for that input (Bussgang). Such a response is
scaled by the real gain ``c`` that fits it best to the BLA, ``c = Re Σ H* G / σ² / Σ |H|²
/ σ²`` (``σ²`` the variance of ``G``), and the gain is said. A feedback model's forward
path, a network, a model of several inputs or outputs are not compared (no one linear
response from the input to the output). matplotlib is imported inside the functions.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from blockid.plotting.linear import linear_dynamics

__all__ = ["ModelResponse", "model_response", "plot_bla_models"]


@dataclass(frozen=True)
class ModelResponse:
    """One model's linear response at the BLA's lines.

    Attributes
    ----------
    label : str
    response : ndarray of complex
        ``c H`` at the BLA's frequencies.
    gain : float or None
        ``c`` for a block-oriented model (None: drawn unscaled).
    within : float or None
        Fraction of the lines where ``|G - c H|`` is within the BLA's bound (None
        without a bound).
    ratio : float or None
        Mean ``|G - c H|² / σ²``: about 1 when the model's linear response is the BLA
        within the BLA's uncertainty.
    """

    label: str
    response: np.ndarray
    gain: float | None
    within: float | None
    ratio: float | None


def _has_static_blocks(model: Any) -> bool:
    return any(getattr(b, "role", "") != "linear" for b in getattr(model, "blocks", ()))


def model_response(label: str, model: Any, bla: Any) -> ModelResponse | str:
    """``model``'s :class:`ModelResponse` at ``bla``'s lines, or why there is none."""
    inputs, outputs = tuple(getattr(model, "inputs", ())), tuple(getattr(model, "outputs", ()))
    if inputs != (bla.input_name,) or outputs != (bla.output_name,):
        return f"{label}: not one input to one output ({', '.join(inputs)} to {', '.join(outputs)})"
    if getattr(model, "feedback", None) is not None:
        return f"{label}: a feedback model; its forward path is not its response"
    systems = linear_dynamics(model)
    if not systems:
        return f"{label}: no linear transfer function"
    w = 2.0 * np.pi * np.asarray(bla.frequencies, float) * float(bla.sampling_time)
    h = np.ones(w.shape, complex)
    for system in systems:
        h = h * system.frequency_response(w)
    var = np.asarray(bla.std, float) ** 2
    use = np.isfinite(var) & (var > 0) & np.isfinite(h)
    gain = None
    if _has_static_blocks(model):
        weight = (
            np.where(use, 1.0 / np.where(use, var, 1.0), 0.0) if use.any() else np.ones(w.shape)
        )
        fin = np.isfinite(h)
        denom = float(np.sum(weight[fin] * np.abs(h[fin]) ** 2))
        gain = (
            float(np.real(np.sum(weight[fin] * np.conj(h[fin]) * bla.g[fin])) / denom)
            if denom > 0
            else 1.0
        )
        h = gain * h
    error = np.abs(bla.g - h)
    within = ratio = None
    if bla.bound is not None and np.any(np.isfinite(bla.bound)):
        ok = np.isfinite(bla.bound) & np.isfinite(error)
        within = float(np.mean(error[ok] <= bla.bound[ok]))
    if use.any():
        ratio = float(np.mean(error[use] ** 2 / var[use]))
    return ModelResponse(label, h, gain, within, ratio)


def plot_bla_models(bla: Any, responses: list[ModelResponse]) -> Any:
    """The BLA's magnitude with its bound shaded and each model's response (top), and
    each model's distance from the BLA against the bound (bottom), in dB."""
    import matplotlib.pyplot as plt

    f = np.asarray(bla.frequencies, float)
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 6), sharex=True, height_ratios=[3, 2])
    with np.errstate(divide="ignore", invalid="ignore"):
        mag = np.abs(bla.g)
        top.plot(f, 20 * np.log10(mag), ls="none", marker=".", ms=3, color="black",
                 label="BLA |G| (measured)")  # fmt: skip
        if bla.bound is not None:
            low = 20 * np.log10(np.maximum(mag - bla.bound, mag * 1e-3))
            high = 20 * np.log10(mag + bla.bound)
            level = f"{bla.confidence:.0%}"
            top.fill_between(f, low, high, color="0.8", label=f"BLA's {level} bound")
            bottom.plot(f, 20 * np.log10(bla.bound), color="0.5", lw=1.0,
                        label=f"BLA's {level} bound")  # fmt: skip
        for k, r in enumerate(responses):
            scaled = "" if r.gain is None else f" x {r.gain:.4g}"
            top.plot(f, 20 * np.log10(np.abs(r.response)), color=f"C{k}", lw=1.2,
                     label=f"{r.label}{scaled}")  # fmt: skip
            bottom.plot(f, 20 * np.log10(np.abs(bla.g - r.response)), color=f"C{k}", lw=0.8,
                        ls="none", marker=".", ms=2, label=f"|G - model|: {r.label}")  # fmt: skip
    finite = 20 * np.log10(mag[mag > 0])
    if finite.size:  # a bound wider than |G| reaches -inf dB: keep |G| readable
        top.set_ylim(bottom=float(np.min(finite)) - 20.0)
    top.set_ylabel("magnitude (dB)")
    bottom.set_ylabel("distance from the BLA (dB)")
    bottom.set_xlabel("frequency (Hz)")
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    top.set_title("each model's linear response against the measured BLA", fontsize=9)
    fig.tight_layout()
    return fig
