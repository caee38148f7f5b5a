"""What the BLA's two estimates share: the signals picked, the confidence checked, the
excited lines found, levels in dB.

The robust method (:mod:`blockid.evaluation.bla`) and Welch's estimate
(:mod:`blockid.evaluation.frf`) read the same data the same way; their results and
summaries are in :mod:`blockid.evaluation.bla_result` and
:mod:`blockid.evaluation.bla_bands`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from blockid.data.dataset import Dataset
from blockid.errors import DataError, ParameterError

__all__ = [
    "CONFIDENCE",
    "EXCITED_FLOOR",
    "check_confidence",
    "check_finite",
    "db",
    "frequency_unit",
    "powered",
    "signal_columns",
]

#: Confidence of the bounds and of the bands' tests (as ``blockid residuals``).
CONFIDENCE = 0.99


def check_confidence(confidence: float) -> float:
    """``confidence`` as a float in (0, 1), or a :class:`ParameterError`."""
    if not 0.0 < float(confidence) < 1.0:
        raise ParameterError(f"confidence must lie between 0 and 1 (e.g. 0.99), got "
                             f"{confidence!r}", parameter="confidence")  # fmt: skip
    return float(confidence)


def check_finite(data: Dataset, input_column: int, output_column: int) -> None:
    """Refuse a NaN or infinite sample of the BLA's input or output, naming where."""
    for exp in data.experiments:
        for what, x in (("input", exp.u[:, input_column]), ("output", exp.y[:, output_column])):
            bad = np.flatnonzero(~np.isfinite(x))
            if bad.size:
                raise DataError(
                    f"experiment '{exp.name}': the {what} is {x[bad[0]]} at sample {bad[0]} "
                    "(0-based); a frequency response needs every sample: remove or fill the gap"
                )


def signal_columns(data: Dataset, input: str | None, output: str | None) -> tuple[int, int]:
    """The columns of the input and output of the BLA (one each; a data set with one
    input and one output needs no names)."""
    picked = []
    for what, name, names in (("input", input, data.inputs), ("output", output, data.outputs)):
        if name is None:
            if len(names) != 1:
                raise ParameterError(f"the data have {len(names)} {what}s ({', '.join(names)}); "
                                     f"name the {what} of the BLA", parameter=what)  # fmt: skip
            picked.append(0)
        elif name not in names:
            raise ParameterError(f"no {what} named {name!r} (the data have {', '.join(names)})",
                                 parameter=what)  # fmt: skip
        else:
            picked.append(names.index(name))
    return picked[0], picked[1]


def db(power: Any) -> Any:
    """``10 log10`` of a power (a variance, ``|G|²``); None (scalars) or NaN (arrays)
    where it is not positive.

    >>> db(100.0), db(0.0)
    (20.0, None)
    """
    p = np.asarray(power, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(p > 0, 10.0 * np.log10(np.where(p > 0, p, 1.0)), np.nan)
    if out.ndim == 0:
        return None if np.isnan(out) else float(out)
    return out


#: A line is taken as excited when the input's power there is at least this share of
#: its typical power on the excited lines (-20 dB): a multisine's empty lines hold its
#: noise, many tens of dB lower; a coloured noise input's weak lines are left out,
#: where ``G`` would be measured with little power behind it.
EXCITED_FLOOR = 1e-2


def powered(power: np.ndarray, floor: float = EXCITED_FLOOR) -> np.ndarray:
    """Which lines of the input's ``power`` spectrum are excited: those at or above
    ``floor`` times the median power of the lines within 20 dB of the strongest.

    >>> powered(np.array([0.0, 1.0, 1e-9, 0.9, 0.005])).tolist()
    [False, True, False, True, False]
    """
    power = np.asarray(power, dtype=float)
    top = power.max() if power.size else 0.0
    if not top > 0:
        return np.zeros(power.shape, bool)
    typical = np.median(power[power >= top / 100])
    return power >= floor * typical


def frequency_unit(sampling_time: float | None) -> str:
    """The unit of the frequencies a record gives: Hz with a sampling time, cycles per
    sample without one (the frequencies are then computed with a sampling time of 1)."""
    return "Hz" if sampling_time else "cycles/sample"
