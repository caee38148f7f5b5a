"""The classic figure of a measured best linear approximation (``blockid bla --plot``):
``|G|`` in dB against frequency with the levels of its total and noise variances, the
distortion (total less noise) and, for an odd multisine, the output at the even lines
and at the odd lines left out (Pintelon & Schoukens 2012, ch. 3). Welch's estimate gets
its coherence below. matplotlib is imported inside the functions."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["BLA_FIGURE", "bla_figure", "plot_bla"]

#: The file name of the figure.
BLA_FIGURE = "bla.png"

_LINES = {  # kind of non-excited line -> (label, marker, colour)
    "even": ("even lines (even distortion + noise)", "o", "tab:blue"),
    "odd": ("odd non-excited lines (odd distortion + noise)", "^", "tab:red"),
    "non-excited": ("non-excited lines (distortion + noise)", "s", "tab:purple"),
}


def _db(power: Any) -> np.ndarray:
    p = np.asarray(power, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(p > 0, 10 * np.log10(np.where(p > 0, p, 1.0)), np.nan)


def plot_bla(bla: Any) -> Any:
    """The figure of ``bla`` (a :class:`~blockid.evaluation.bla_result.BestLinearApproximation`):
    returns it."""
    import matplotlib.pyplot as plt

    welch = bla.method == "welch"
    rows = 2 if welch else 1
    fig, axes = plt.subplots(rows, 1, figsize=(9, 4.8 + 2.0 * (rows - 1)), squeeze=False,
                             sharex=True, height_ratios=[3, 1][:rows])  # fmt: skip
    ax = axes[0][0]
    f = bla.frequencies
    style = {"lw": 1.2} if welch else {"ls": "none", "marker": ".", "ms": 4}
    ax.plot(f, _db(np.abs(bla.g) ** 2), color="black", label="BLA |G|", **style)
    small = {"ls": "none", "marker": ".", "ms": 3} if not welch else {"lw": 1.0}
    if bla.var_total is not None:
        what = "std of G (noise + distortion)" if not welch else "std of G (1 - coherence)"
        ax.plot(f, _db(bla.var_total), color="tab:orange", label=what, **small)
    if bla.var_noise is not None:
        ax.plot(f, _db(bla.var_noise), color="tab:green", label="std of G from noise", **small)
    distortion = bla.var_distortion
    if distortion is not None:
        ax.plot(f, _db(distortion), color="tab:red", alpha=0.5, label="distortion (total - noise)",
                **small)  # fmt: skip
    ne = bla.nonexcited
    if ne is not None and ne.lines.size:
        for kind, (label, marker, colour) in _LINES.items():
            sel = ne.kind == kind
            if sel.any():
                ax.plot(ne.frequencies[sel], _db(ne.level[sel]), ls="none", marker=marker,
                        ms=3, mfc="none", color=colour, label=label)  # fmt: skip
        if ne.noise is not None:
            ax.plot(ne.frequencies, _db(ne.noise), ls="none", marker="_", ms=3, color="0.6",
                    label="noise at the non-excited lines")  # fmt: skip
    ax.set_ylabel("dB")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="best", ncol=2)
    ax.set_title(_wrapped(bla.describe()) + "\n" + _wrapped(bla.verdict, 130), fontsize=8)
    if welch:
        ax2 = axes[1][0]
        ax2.plot(f, bla.coherence, color="tab:blue", lw=1.0)
        ax2.set_ylim(0, 1.02)
        ax2.set_ylabel("coherence γ²")
        ax2.grid(alpha=0.3)
    axes[-1][0].set_xlabel(f"frequency ({bla.unit})")
    fig.tight_layout()
    return fig


def _wrapped(text: str, width: int = 110) -> str:
    import textwrap

    return "\n".join(textwrap.wrap(text, width))


def bla_figure(bla: Any, folder: str | Path, *, overwrite: bool = False) -> Path:
    """Write :func:`plot_bla` to ``folder/bla.png`` (the folder created if needed); an
    existing file is replaced only with ``overwrite``."""
    import matplotlib.pyplot as plt

    from blockid.plotting.figures import _save

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    fig = bla.plot()
    try:
        return _save(fig, folder / BLA_FIGURE, overwrite)
    finally:
        plt.close(fig)
