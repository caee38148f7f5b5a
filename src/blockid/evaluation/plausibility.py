"""Warnings before a model misleads: an output far outside the measured one, poles on
or near the unit circle, or at the Nyquist frequency.

A model can run on new data and print an RMSE without saying that its output left the
measured one's range five times over (a linear state space fitted on a 0-10 V record
simulating its test record at 5.2 V RMSE, 22.6 V at worst: poles at 0.9923 +- 0.106j
rang from the initial state), or that its linear part is unstable (a model file with a
pole outside the unit circle simulated to an RMSE of 3.9e67). These checks need only
the model and the data; :func:`~blockid.evaluation.validate.evaluate` (``simulate``,
``predict``, ``compare``, ``identify``'s scores) and the fits' own checks
(:mod:`blockid.fitting.checks`) run them. The limits (module constants, documented in
``docs/cli.md``, "Warnings"):

* **output range** -- how far the model's output goes beyond the range the measured
  output covers on the same data, as a multiple of that range's width
  (:func:`output_excursion`). Warned above :data:`MAX_OUTPUT_EXCURSION` (0.5: half
  the measured range beyond either end). A model that extrapolates or rings can still
  score a modest RMSE; one whose output leaves the measured range by half its width
  is not describing these data. A constant measured output has no range to compare
  with and is not checked.
* **diverged** -- a model output that is not finite, or beyond the measured range by
  more than :data:`DIVERGED_EXCURSION` (10^6) widths (:func:`divergence`): no metric
  of it means anything, and ``simulate``/``predict`` stop with an error instead of
  printing one.
* **poles** (:func:`pole_notes`) -- a pole on or outside the unit circle (the free
  run grows without bound whatever the data), within :data:`POLE_MARGIN` (10^-3) of
  it (a time constant of 1 000 samples or more: it drifts or rings on other data), or
  within :data:`NYQUIST_MARGIN` (0.05) of -1 (a mode at the Nyquist frequency that
  flips sign every sample; sampled plants rarely have one).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from blockid.models.base import excursion

__all__ = [
    "DIVERGED_EXCURSION",
    "MAX_OUTPUT_EXCURSION",
    "NYQUIST_MARGIN",
    "POLE_MARGIN",
    "UNSTABLE_ADVICE",
    "divergence",
    "output_excursion",
    "output_range_notes",
    "pole_notes",
]

#: A model output beyond the measured output's range by more than this fraction of the
#: range's width (at either end) is warned about.
MAX_OUTPUT_EXCURSION = 0.5
#: A model output beyond the measured output's range by more than this many widths has
#: diverged (as has one that is not finite).
DIVERGED_EXCURSION = 1e6
#: A pole within this distance of the unit circle (``|p| > 1 - POLE_MARGIN``) is warned
#: about: a time constant of 1 000 samples or more.
POLE_MARGIN = 1e-3
#: A pole within this distance of -1 is a mode at the Nyquist frequency.
NYQUIST_MARGIN = 0.05


def output_excursion(y: np.ndarray, y_hat: np.ndarray) -> np.ndarray:
    """Per output (columns of the ``(N, ny)`` arrays), how far the model output
    ``y_hat`` goes beyond the range of the measured ``y``, in widths of that range: 0
    inside, infinite when ``y_hat`` is not finite, NaN for a constant measured output.

    >>> y = np.array([[0.0], [10.0]])
    >>> output_excursion(y, np.array([[-2.0], [25.0]])).tolist()
    [1.5]
    """
    y, y_hat = np.atleast_2d(y), np.atleast_2d(y_hat)
    out = np.full(y.shape[1], np.nan)
    for j in range(y.shape[1]):
        lo, hi = float(np.min(y[:, j], initial=np.inf)), float(np.max(y[:, j], initial=-np.inf))
        if hi > lo:
            out[j] = excursion((lo, hi), y_hat[:, j])
        elif not np.all(np.isfinite(y_hat[:, j])):
            out[j] = np.inf
    return out


def output_range_notes(
    y: np.ndarray,
    y_hat: np.ndarray,
    names: Sequence[str],
    what: str = "output",
    where: str = "on these data",
) -> list[str]:
    """A warning per output whose model ``what`` (``"output"``, ``"free run"``, ...)
    leaves the measured output's range ``where`` by more than
    :data:`MAX_OUTPUT_EXCURSION` of its width (:func:`output_excursion`), naming how
    far and what to do."""
    notes = []
    for j, value in enumerate(output_excursion(y, y_hat)):
        if not value > MAX_OUTPUT_EXCURSION:
            continue
        lo, hi = float(np.min(y[:, j])), float(np.max(y[:, j]))
        column = y_hat[:, j]
        finite = column[np.isfinite(column)]
        if np.isfinite(value):
            reach = f"reaches [{finite.min():.4g}, {finite.max():.4g}]"
            how = f"leaves it by {value:.3g} times its width"
        else:
            reach, how = "is not finite", "diverges"
        notes.append(
            f"the model's {what} of {names[j]!r} {reach} against the measured range "
            f"[{lo:.4g}, {hi:.4g}] {where}: it {how} (warned above "
            f"{MAX_OUTPUT_EXCURSION:g}), so it extrapolates or drifts and its metrics "
            "describe that, not the plant; check that the input stays within the range "
            "the model was fitted on, start from more measured outputs (--initial-samples "
            "N), or fit on data that cover these conditions"
        )
    return notes


def divergence(
    y: np.ndarray, y_hat: np.ndarray, names: Sequence[str], poles: np.ndarray | None = None
) -> str | None:
    """Why the model output ``y_hat`` has diverged on data with measured output ``y``
    (not finite, or more than :data:`DIVERGED_EXCURSION` widths beyond the measured
    range), naming a pole of the model's linear part (``poles``) outside the unit
    circle when there is one; None when it has not diverged."""
    reason = None
    for j, value in enumerate(output_excursion(y, y_hat)):
        column = y_hat[:, j]
        bad = ~np.isfinite(column)
        if bad.any():
            reason = f"output {names[j]!r} is not finite in {int(bad.sum())} of {bad.size} samples"
        elif value > DIVERGED_EXCURSION:
            peak = float(column[np.argmax(np.abs(column))])
            lo, hi = float(np.min(y[:, j])), float(np.max(y[:, j]))
            reason = (
                f"output {names[j]!r} reaches {peak:.3g}, {value:.3g} widths beyond the "
                f"measured range [{lo:.4g}, {hi:.4g}]"
            )
        if reason is not None:
            break
    if reason is None:
        return None
    poles = np.asarray([] if poles is None else poles, dtype=complex).ravel()
    if poles.size and np.max(np.abs(poles)) > 1.0:
        worst = complex(poles[np.argmax(np.abs(poles))])
        reason += (
            f"; its linear part is unstable (a pole at {_shown(worst)}, magnitude "
            f"{abs(worst):.6g}, outside the unit circle)"
        )
    return reason


def _shown(p: complex) -> str:
    return f"{p.real:.6g}" if abs(p.imag) < 1e-12 else f"{p.real:.6g}{p.imag:+.4g}j"


#: What to do with a model whose linear part is unstable, when it is run on data.
UNSTABLE_ADVICE = (
    "refit it (the fits keep every pole inside the unit circle), and check the model file"
)


def pole_notes(
    poles: np.ndarray,
    margin: float = POLE_MARGIN,
    *,
    near_noted: bool = False,
    unstable_advice: str = UNSTABLE_ADVICE,
) -> list[str]:
    """Warnings for poles (of a model's fitted linear part, :meth:`Model.fitted_poles`)
    on or outside the unit circle (with ``unstable_advice``), within ``margin`` of it
    (``near_noted``: noted elsewhere already, as a fit notes the poles on its stability
    margin, so not repeated), and within :data:`NYQUIST_MARGIN` of -1 (unless named
    already): at most one of each, naming the worst pole and what to do.

    >>> pole_notes(np.array([0.5, 1.02]))[0][:60]
    'the model is unstable: its linear part has a pole at 1.02 (m'
    """
    poles = np.asarray(poles, dtype=complex).ravel()
    poles = poles[np.isfinite(poles)]
    if poles.size == 0:
        return []
    notes, named = [], np.zeros(poles.size, dtype=bool)
    size = np.abs(poles)
    k = int(np.argmax(size))
    worst = complex(poles[k])
    if size[k] >= 1.0:
        where = "outside" if size[k] > 1.0 else "on"
        grows = (
            f"grows by a factor {size[k]:.4g} per sample (doubling every "
            f"{np.log(2.0) / np.log(size[k]):.3g} samples)"
            if size[k] > 1.0
            else "never settles"
        )
        notes.append(
            f"the model is unstable: its linear part has a pole at {_shown(worst)} (magnitude "
            f"{size[k]:.6g}), {where} the unit circle, so its free run {grows} whatever the "
            f"data; do not trust its simulations: {unstable_advice}"
        )
        named[size >= 1.0] = True
    elif size[k] > 1.0 - margin:
        # a pole by -1 is named below as the Nyquist mode it is: it neither drifts nor
        # calls for an integrator
        slow = (size > 1.0 - margin) & (np.abs(poles + 1.0) >= NYQUIST_MARGIN)
        named[slow | ((size > 1.0 - margin) & near_noted)] = True
        if slow.any():
            k = int(np.argmax(np.where(slow, size, -np.inf)))
            worst = complex(poles[k])
        if slow.any() and not near_noted:
            notes.append(
                f"the model's linear part has a pole at {_shown(worst)} (magnitude "
                f"{size[k]:.6g}), within {margin:g} of the unit circle: a mode with a time "
                f"constant of {-1.0 / np.log(size[k]):.4g} samples that its free run barely "
                "damps, so it drifts or rings on data other than those it was fitted on; "
                "check it on validation data, and for a plant that integrates use an "
                "explicit integrator (--integrator 1)"
            )
    nyquist = (np.abs(poles + 1.0) < NYQUIST_MARGIN) & ~named
    if nyquist.any():
        j = int(np.argmax(np.where(nyquist, size, -np.inf)))
        p = complex(poles[j])
        decay = -1.0 / np.log(size[j]) if 0.0 < size[j] < 1.0 else np.inf
        notes.append(
            f"the model's linear part has a pole at {_shown(p)}, within {NYQUIST_MARGIN:g} of "
            f"-1: a mode at the Nyquist frequency that flips sign every sample and decays "
            f"over {decay:.3g} samples; sampled plants rarely have one (it is usually fitted "
            "noise or orders higher than the data support), and it makes simulated outputs "
            "and step responses alternate sample by sample; try lower orders, or filter or "
            "decimate the data"
        )
    return notes
