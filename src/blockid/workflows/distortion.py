"""What ``identify`` records of the plant's nonlinear distortion when its data are
periodic (issue 34 item 3): the best linear approximation measured once on the
estimation data (:func:`~blockid.evaluation.best_linear_approximation`), its per-band
summary in the search record, and a note when no band shows nonlinear distortion above
the noise.

The note never changes what is searched: a nonlinear structure may still win on data
whose distortion sits below the noise (its gain is then within the noise too), and the
user asked for the search. It says that the data cannot justify one, so that a reader
weighs the choice. Non-periodic data tell noise and distortion apart nowhere (Welch's
coherence counts both), and several inputs or outputs are not measured: nothing is
recorded for them.
"""

from __future__ import annotations

from typing import Any

from blockid.data.dataset import Dataset
from blockid.errors import BlockidError

__all__ = ["distortion_record"]


def _any_detected(band: Any) -> bool:
    """Whether the band shows distortion at its excited lines or at the empty ones."""
    return bool(band.detected) or any(
        bool(part.get("detected")) for part in band.nonexcited.values()
    )


def distortion_record(data: Dataset, notes: list[str]) -> dict[str, Any] | None:
    """The distortion measured on ``data`` for ``identify``'s search record (None: data
    that are not periodic, of several inputs or outputs, or that the measurement
    refuses, e.g. no whole number of periods); appends the note to ``notes`` when no
    band shows nonlinear distortion above the noise.

    Returns
    -------
    dict or None
        ``{"method", "realisations", "periods", "verdict", "detected", "bands"}``:
        ``detected`` whether any band shows distortion, ``bands`` each band's summary
        (:meth:`~blockid.evaluation.bla_result.BandSummary.to_dict`).
    """
    if data.n_inputs != 1 or data.n_outputs != 1:
        return None
    from blockid.evaluation.bla import best_linear_approximation
    from blockid.evaluation.periods import find_period

    try:
        if any(find_period(e.u[:, 0]) is None for e in data.experiments):
            return None  # not periodic: Welch's coherence cannot tell distortion from noise
        bla = best_linear_approximation(data, method="robust")
    except BlockidError:
        return None
    detected = any(_any_detected(b) for b in bla.bands)
    record = {
        "method": bla.method,
        "realisations": bla.realisations,
        "periods": bla.periods,
        "verdict": bla.verdict,
        "detected": detected,
        "bands": [b.to_dict() for b in bla.bands],
    }
    if not detected:
        notes.append(
            "nonlinear candidates cannot be justified by the data: the best linear "
            "approximation measured on the periodic estimation data shows no nonlinear "
            f"distortion above the noise in any band ({bla.verdict}); the nonlinear "
            "structures were searched as asked, and a nonlinear choice gains no more than "
            "the noise (search.distortion in the JSON)"
        )
    return record
