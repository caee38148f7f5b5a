"""The outlier guard of a stream: a robust RLS that a single bad sample cannot ruin.

A live plant sends glitches: one output sample of 1e8, one input sample of 1e12. Plain
RLS learns from it, and the estimate (and ``P``) is ruined for good. The guard of
:class:`StreamGuard` sits between the stream and its online learner
(:mod:`blockid.fitting.online`) and decides, row by row, whether the learner learns
from a sample or only takes it into its memory (``update(.., learn=False)``: its
regressors keep the true lags).

The rule, with ``T`` the threshold (:data:`THRESHOLD`, 10) and ``W`` the warm-up
(:func:`warmup`, at least 20 samples):

* **Scale.** Per output, ``s`` is a running 99th percentile of ``|e|``, the one-step
  prediction error: 4 times the median of the first ``W`` non-zero errors (the 99th
  percentile of a normal ``|e|`` is 3.8 times its median), then, over the samples
  the guard accepts, ``s <- 1.2 s`` when ``|e| > s`` and ``s <- 1.2^(-1/99) s``
  otherwise, which settles where 1 % of the errors lie above ``s``. A percentile,
  not a mean: the errors of a nonlinear model learning online have heavy tails (the
  largest of 50 000 clean Hammerstein-Wiener errors is 17 times their running mean
  absolute value, but 3.5 times this scale), and no single sample moves it by more
  than 20 %.
* **Outlier.** A sample whose error exceeds ``T max(s, 1e-6 w)`` (``w`` the width of
  the output's range so far: the floor that keeps a noise-free record, whose errors
  end at rounding level, from rejecting its own rounding) is not learned from:
  :meth:`~blockid.fitting.online.OnlineEstimator.revert` takes the update back.
* **Out of range.** A sample with a value (input or output) beyond the range of that
  signal so far by more than ``T`` times the range's width is not learned from. This
  catches an input glitch at its own row (the prediction error sees it only at the
  rows whose regressors hold it). It starts with the outlier test, and not before
  ``2 max_lag`` samples learned: the outputs of a plant with a dead time are noise
  until its inputs reach them.
* **Held.** A rejected value sits in the regressors of the ``max_lag`` samples after
  it (``na`` for an output, ``nk + nb - 1`` for an input): those are not learned from
  either.
* **A glitch in the warm-up.** At its end, an error past the recursion's transient
  (its first ``n + max_lag`` errors) beyond ``T s`` means a glitch was learned: the
  last good estimate comes back and the warm-up starts again (``restarted``).
* **A change that lasts is the plant, not a glitch.** After ``W`` rows in a row not
  learned from, the guard steps aside: the last good estimate (below) comes back and
  the guard warms up again on the plant as it is now.

Before the warm-up is complete every sample is learned, as without a guard. Below the
threshold a sample is learned exactly as without a guard, so a clean record ends with
the estimate of the one-pass offline fit, bit for bit (the equivalence contract of
:mod:`blockid.workflows.stream`).

Why reject, not down-weight (Huber). A Huber weight shrinks a large residual's pull,
but the sample still updates ``P`` with its regressor: a regressor holding 1e12
collapses ``P`` along it, and the recursion stops learning in that direction long
after the glitch. Down-weighting also changes every moderately large residual of a
clean record, which would break the equivalence with the offline fit. Rejection
leaves clean samples untouched and a glitch with no trace.

Recovery. The guard also keeps the last *good* estimate: a snapshot of ``theta`` and
``P`` (the estimate alone; the memory stays current) promoted to good once the ``W``
samples learned after it were predicted within the threshold. When the recursion
diverges anyway (the guard off, a glitch during the warm-up), :meth:`diverged` puts
the last good estimate back and holds the rows whose regressors reach back to the
diverging one; learning goes on after them. A stream is *recovered* once a good
estimate was confirmed after its last divergence.
"""

from __future__ import annotations

import math
from typing import Any

from blockid.errors import ParameterError

__all__ = ["THRESHOLD", "StreamGuard", "guard_note", "warmup"]

#: Default threshold: a prediction error ``THRESHOLD`` times the running scale of the
#: errors, or a value that far beyond a signal's range (in widths of the range).
THRESHOLD = 10.0

#: Fewest samples of the warm-up (and of a good estimate's confirmation).
_MIN_WARMUP = 20

#: Relative floor of the scale, in widths of the output's range.
_FLOOR = 1e-6

#: Steps of the running 99th percentile: up for an error above it, down for one below
#: (a 99th of the step up: it settles where 1 % of the errors lie above).
_UP = 1.2
_DOWN = _UP ** (-1 / 99)

#: The scale at the end of the warm-up, in medians of its errors.
_START = 4.0


def warmup(n_parameters: int) -> int:
    """Samples of the warm-up: ``max(20, 2 n)`` for a recursion of ``n`` coefficients
    (its first errors, while the estimate converges, are the largest: a scale taken
    from them is lenient, never strict)."""
    return max(_MIN_WARMUP, 2 * int(n_parameters))


def _median(values: list[float]) -> float:
    ordered = sorted(values)
    mid = len(ordered) // 2
    return ordered[mid] if len(ordered) % 2 else 0.5 * (ordered[mid - 1] + ordered[mid])


class StreamGuard:
    """Outlier guard and divergence recovery of one online learner (module docstring).

    Parameters
    ----------
    learner : OnlineEstimator
        The learner it guards (:func:`~blockid.fitting.online.online_estimator`).
    threshold : float or None
        ``T``; None switches rejection off (the statistics, the recovery after a
        divergence and the holding of the rows after it stay).

    Per row the stream calls :meth:`before` (a reason not to learn, or None), then the
    learner's ``update`` (``learn=False`` when there is a reason), then :meth:`after`
    with the prediction errors of a learned sample (a reason the update was taken
    back, or None), or :meth:`diverged` when the update raised.
    """

    def __init__(self, learner: Any, threshold: float | None = THRESHOLD) -> None:
        if threshold is not None and not (threshold > 1.0 and math.isfinite(threshold)):
            raise ParameterError(
                f"the outlier threshold must be a number above 1 (the multiple of the running "
                f"error scale beyond which a sample is not learned from), got {threshold!r}",
                parameter="guard",
            )
        self.learner = learner
        self.names = (*learner.names.inputs, *learner.names.outputs)  # values of a row
        self.nu = len(learner.names.inputs)
        self.threshold = threshold  # T, or None: rejection off
        self.limit = THRESHOLD if threshold is None else threshold  # T of the statistics
        self.lag = learner.max_lag  # rows after a rejected one that are held
        self.window = warmup(learner.n_parameters)  # W: warm-up, confirmation, patience
        n, ny = len(self.names), len(learner.names.outputs)
        self.low = [math.inf] * n  # range of every signal over the samples learned
        self.high = [-math.inf] * n
        self.lower = [-math.inf] * n  # beyond these a value is out of range
        self.upper = [math.inf] * n
        self.scale = [0.0] * ny  # s of every output, a running 99th percentile of |e|
        self.warming: list[list[float]] = []  # |e| of the warm-up samples
        self.warm = False  # the warm-up is complete: the tests apply
        self.hold = 0  # rows still to hold
        self.held_reason = ""  # why they are held
        self.run = 0  # rows in a row not learned from
        self.learned = 0  # samples learned from
        # the range test waits, beyond the warm-up, for the outputs to show the inputs'
        # effect: twice the regressors' reach (a dead time nk of the plant)
        self.range_start = 2 * self.lag
        self.good = learner.snapshot()  # the last confirmed estimate
        self.good_row: int | None = None  # its row (None: the start)
        self.candidate: dict[str, Any] | None = self.good  # the next one, being confirmed
        self.candidate_row: int | None = None
        self.since = 0  # samples learned and predicted well since the candidate
        self.diverged_at: int | None = None  # row of the last divergence not recovered
        self.outlier_at: int | None = None  # row of the last outlier learned, not recovered
        self.counts = dict.fromkeys(
            ("rejected", "held", "diverged", "relented", "restarted", "outliers"), 0
        )

    # ------------------------------------------------------------------ per row
    def before(self, k: int, values: tuple[float, ...]) -> str | None:
        """Why row ``k`` (its inputs then outputs) is not to be learned from, or None."""
        if self.run >= self.window and self.threshold is not None:
            # a change that lasts is the plant: step aside, warm up again on it, from
            # the last good estimate (the estimate since may have learned a glitch of
            # the warm-up: it predicted none of these rows)
            self.counts["relented"] += 1
            self.hold, self.run = 0, 0
            self.warm, self.warming = False, []
            self.learner.rewind(self.good)
            self.candidate, self.candidate_row, self.since = self.good, self.good_row, 0
            return None
        if self.hold:
            self.hold -= 1
            self.run += 1
            self.counts["held"] += 1
            return self.held_reason
        if self.warm and self.learned >= self.range_start and self.threshold is not None:
            lower, upper = self.lower, self.upper
            for j, v in enumerate(values):
                if v > upper[j] or v < lower[j]:
                    return self._reject(k, self._out_of_range(j, v))
        return None

    def after(self, k: int, values: tuple[float, ...], errors: list[float]) -> str | None:
        """The learned row ``k`` judged by its prediction errors: the reason its update
        was taken back (an outlier), or None (the statistics updated)."""
        limit = self.limit
        outlier = False
        if self.warm:
            low, high, scale, nu = self.low, self.high, self.scale, self.nu
            for i, e in enumerate(errors):
                a = -e if e < 0.0 else e
                s = scale[i]
                floor = _FLOOR * (high[nu + i] - low[nu + i])
                if a > limit * (s if s > floor else floor):
                    if self.threshold is not None:
                        self.learner.revert()
                        return self._reject(k, self._outlier(i, e))
                    self.counts["outliers"] += 1  # learned all the same: no confirmation
                    self.candidate, self.since, outlier = None, 0, True
                    self.outlier_at = k
                    break
            if not outlier:  # the scale follows the samples the guard accepts
                for i, e in enumerate(errors):
                    a = -e if e < 0.0 else e
                    if a < math.inf:  # NaN: no prediction
                        scale[i] *= _UP if a > scale[i] else _DOWN
        else:
            self._warm_up(k, errors)
        self.run = 0
        self.learned += 1
        low, high = self.low, self.high
        for j, v in enumerate(values):
            if v > high[j] or v < low[j]:
                self._widen(j, v)
        if outlier:
            return None
        if self.candidate is None:
            self.candidate, self.candidate_row, self.since = self.learner.snapshot(), k, 0
            return None
        self.since += 1
        if self.since >= self.window:  # the candidate predicted W samples well: good
            self.good, self.good_row = self.candidate, self.candidate_row
            self.candidate, self.candidate_row, self.since = self.learner.snapshot(), k, 0
            self.diverged_at = self.outlier_at = None  # recovered
        return None

    def diverged(self, k: int, summary: str) -> str:
        """The update of row ``k`` raised: the last good estimate put back, the rows
        whose regressors reach back to ``k`` held. Returns the message of the row."""
        self.learner.rewind(self.good)
        self.candidate, self.candidate_row, self.since = self.good, self.good_row, 0
        self.diverged_at = k
        self.counts["diverged"] += 1
        self.run += 1
        self._hold_after(k, "diverged")
        start = "the start" if self.good_row is None else f"row {self.good_row}"
        held = f"; the {self.lag} rows after it are not learned from" if self.lag else ""
        return (
            f"{summary}. The last good estimate (of {start}) is restored and learning goes on{held}"
        )

    # ------------------------------------------------------------------ the end
    def summary(self) -> dict[str, Any]:
        """What the guard did: its threshold (None: off), the rows rejected, held,
        recovered from (``diverged``), the times it stepped aside (``relented``) or
        started its warm-up again (``restarted``) and, with rejection off, the outliers
        learned from all the same."""
        return {"threshold": self.threshold, **self.counts}

    def unrecovered(self) -> str | None:
        """Why the estimate is not to be trusted after a divergence, or after an outlier
        it learned from (rejection off), or None: it has not predicted ``W`` samples in
        a row within the threshold since."""
        start = "the start" if self.good_row is None else f"row {self.good_row}"
        since = (
            f"fewer than {self.window} samples in a row after it were learned and predicted "
            f"within the outlier threshold (the last good estimate is that of {start})"
        )
        if self.diverged_at is not None:
            return (
                f"the estimate diverged at row {self.diverged_at} and did not recover: "
                f"{since}; send more samples of the running plant, or check its signals "
                "at that row"
            )
        if self.outlier_at is not None:
            return (
                f"the estimate learned from {self.counts['outliers']} outlier(s) (the last "
                f"at row {self.outlier_at}; the guard is off) and did not recover: {since}; "
                "stream with the guard on (it does not learn from them)"
            )
        return None

    def constant(self) -> str | None:
        """The signals that did not vary over the samples learned, named, or None."""
        found = []
        for j, name in enumerate(self.names):
            if self.low[j] == self.high[j]:
                kind = "input" if j < self.nu else "output"
                found.append(f"{kind} {name!r} is constant over the stream ({self.low[j]:.6g} "
                             "at every sample learned from)")  # fmt: skip
        if not found:
            return None
        return (
            "; ".join(found) + ": a constant signal tells nothing about the dynamics and its "
            "lags repeat one another; stream data in which it varies"
        )

    # ------------------------------------------------------------------ checkpoints
    def state(self) -> dict[str, Any]:
        """Everything the guard carries from row to row, JSON-ready (infinite bounds as
        None), for :meth:`restore`."""
        out = {name: getattr(self, name) for name in _STATE}
        out["scale"], out["counts"] = list(self.scale), dict(self.counts)
        out["warming"] = [list(m) for m in self.warming]
        for name in ("low", "high", "lower", "upper"):
            out[name] = [v if math.isfinite(v) else None for v in out[name]]
        return out

    def restore(self, state: dict[str, Any]) -> StreamGuard:
        """Take the state of :meth:`state` (of a guard of the same learner)."""
        for name in _STATE:
            setattr(self, name, state[name])
        for name, missing in (("low", math.inf), ("high", -math.inf), ("lower", -math.inf),
                              ("upper", math.inf)):  # fmt: skip
            setattr(self, name, [missing if v is None else float(v) for v in state[name]])
        self.counts = dict(self.counts)
        return self

    # ------------------------------------------------------------------ helpers
    def _reject(self, k: int, reason: str) -> str:
        self.counts["rejected"] += 1
        self.run += 1
        self._hold_after(k, "rejected")
        return reason

    def _hold_after(self, k: int, what: str) -> None:
        self.hold = self.lag
        self.held_reason = f"held: its regressors reach back to row {k}, which was {what}"

    def _out_of_range(self, j: int, v: float) -> str:
        return (
            f"out of range: {self.names[j]} = {v:.6g} lies beyond its range so far "
            f"[{self.low[j]:.6g}, {self.high[j]:.6g}] by more than {self.limit:g} times its "
            "width"
        )

    def _outlier(self, i: int, e: float) -> str:
        name = self.names[self.nu + i]
        s = self.scale[i]
        return (
            f"outlier: the prediction error of {name}, {e:.6g}, is {abs(e) / s:.3g} times "
            f"its running scale {s:.3g} (threshold {self.limit:g})"
        )

    def _warm_up(self, k: int, errors: list[float]) -> None:
        """Collect the errors of row ``k``; at ``W`` of them, the scale, unless a late one
        was an outlier: then a glitch of the warm-up was learned, and the warm-up starts
        again from the last good estimate (the rows that hold the glitch held)."""
        magnitudes = [abs(e) for e in errors]
        if all(0.0 < a < math.inf for a in magnitudes):  # a plant at rest does not count
            self.warming.append([k, *magnitudes])
        if len(self.warming) < self.window:
            return
        ny = len(errors)
        scale = [_START * _median([m[1 + i] for m in self.warming]) for i in range(ny)]
        # past the recursion's transient (its first n + max_lag errors are large anyway)
        late = self.warming[self.learner.n_parameters + self.lag :]
        glitch = [m[0] for m in late if any(m[1 + i] > self.limit * scale[i] for i in range(ny))]
        self.warming = []
        if glitch and self.threshold is not None:
            self.counts["restarted"] += 1
            self.learner.rewind(self.good)
            self.candidate, self.candidate_row, self.since = self.good, self.good_row, 0
            self.hold = max(0, glitch[-1] + self.lag - k)
            self.held_reason = (
                f"held: its regressors reach back to row {glitch[-1]}, an outlier learned "
                "during the warm-up (the warm-up starts again)"
            )
            return
        self.scale, self.warm = scale, True

    def _widen(self, j: int, v: float) -> None:
        """Signal ``j``'s range to include ``v``, and the bounds beyond it."""
        low, high = self.low, self.high
        low[j], high[j] = min(low[j], v), max(high[j], v)
        width = high[j] - low[j]
        if width > 0.0:
            self.lower[j] = low[j] - self.limit * width
            self.upper[j] = high[j] + self.limit * width


#: Attributes of :meth:`StreamGuard.state`.
_STATE = (
    "low", "high", "lower", "upper", "scale", "warming", "warm", "hold", "held_reason",
    "run", "learned", "good", "good_row", "candidate", "candidate_row", "since", "diverged_at",
    "outlier_at", "counts",
)  # fmt: skip


def guard_note(summary: dict[str, Any] | None) -> str | None:
    """The line ``blockid stream`` prints on standard error when the guard kept samples
    from the estimator (``summary``: the final event's ``guard`` counts); None if none."""
    if not summary:
        return None
    parts = [
        f"{summary[key]} {what}"
        for key, what in (
            ("rejected", "rejected (an outlier, or a value out of range)"),
            ("held", "held (their regressors reach back to a rejected or diverged row)"),
            ("diverged", "diverged (the last good estimate restored)"),
            ("outliers", "outliers learned from (--no-guard)"),
            ("relented", "time(s) stepped aside for a change that lasted"),
            ("restarted", "warm-up(s) started again after a glitch learned in it"),
        )
        if summary.get(key)
    ]
    if not parts:
        return None
    return f"guard: {', '.join(parts)}; see the lines with not_learned or error_message"
