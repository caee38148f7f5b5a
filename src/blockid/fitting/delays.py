"""The input delay of every input-output pair of a multivariable record.

One delay for all channels is a poor guess where the inputs act through different
paths (a valve two samples away, a heater ten). For each output, the delay of each
input is chosen by least squares on a small equation-error model, as MATLAB's
``delayest`` does for one pair: the output's ``na`` past values and ``nb`` samples of
each input from its delay on, with an intercept. The delay of one input is scanned
over ``0 .. max_delay`` first with that input alone, then once more with every other
input at the delay found for it (an input that explains part of the output would
otherwise pull the others' losses). The delay is the longest whose residual is within
chance of the smallest: a window that starts a sample early still holds the true first
lag, and each of a window's ``nb`` coefficients that fits only noise lowers the
residual by a chi-square share of one degree of freedom, so within ``4 nb / N``
(relative; 3.84 is the 95 % point of one degree of freedom) of the smallest, the longer
delay is taken.

**Evidence.** A pair whose input does not act on the output has a flat scan, whose
longest "best" delay means nothing. So the best delay's residual is tested against the
residual without that input (the others at their delays): the reduction, ``N`` times
its relative size, must exceed the chi-square 99.9 % point of ``nb`` degrees of freedom
(strict, as the smallest of ``max_delay + 1`` residuals is taken). A pair that fails has
no evidence (``ChannelDelays.evidence``): its delay is the median of the pairs that
have it (0 if none does), so it does not make a per-pair candidate on its own. Records
with fewer than five rows per regression coefficient are refused.

Every delay of a pair is scored on the same samples (those that the longest delay
leaves), regressors never straddle two experiments, and the signals are divided by
their spread. The result is evidence for a search to weigh (``identify`` scores the
per-pair delays by cross-validation beside one common delay), not a decision.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from blockid.errors import DataError, ParameterError

if TYPE_CHECKING:  # pragma: no cover
    from blockid.data import Dataset

__all__ = ["ChannelDelays", "channel_delays"]


@dataclass(frozen=True)
class ChannelDelays:
    """Per-pair delays and the losses they were chosen on.

    Attributes
    ----------
    nk : numpy.ndarray
        ``(n_outputs, n_inputs)`` delays, MATLAB's ``nk`` matrix.
    loss : numpy.ndarray
        ``(n_outputs, n_inputs, max_delay + 1)`` mean squared residual (normalised
        signals) of each delay of each pair in the last scan of that pair (the other
        inputs at the delays found for them by then).
    evidence : numpy.ndarray of bool
        ``(n_outputs, n_inputs)``: the pair's input lowers the residual beyond chance
        (module docstring); where not, ``nk`` holds the median of the pairs that do.
    outputs, inputs : tuple of str
    """

    nk: np.ndarray
    loss: np.ndarray
    evidence: np.ndarray
    outputs: tuple[str, ...]
    inputs: tuple[str, ...]

    @property
    def common(self) -> bool:
        """True when every pair has the same delay."""
        return bool(np.all(self.nk == self.nk.flat[0]))

    def as_option(self) -> int | tuple[tuple[int, ...], ...]:
        """The delays as ``fit``'s ``nk`` option: one number when they agree."""
        if self.common:
            return int(self.nk.flat[0])
        return tuple(tuple(int(v) for v in row) for row in self.nk)


def channel_delays(data: Dataset, max_delay: int = 10, na: int = 2, nb: int = 2) -> ChannelDelays:
    """The delay of every input-output pair of ``data`` (module docstring).

    >>> import numpy as np
    >>> from blockid.data import Dataset
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((3000, 2))
    >>> y = np.zeros(3000)
    >>> for t in range(6, 3000):
    ...     y[t] = 0.6 * y[t - 1] + u[t - 1, 0] + 0.5 * u[t - 5, 1]
    >>> channel_delays(Dataset.from_arrays(u, y, ["a", "b"], ["y"])).nk.tolist()
    [[1, 5]]
    """
    for name, value, low in (("max_delay", max_delay, 0), ("na", na, 0), ("nb", nb, 1)):
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < low:
            raise ParameterError(
                f"{name} must be a whole number >= {low}, got {value!r}", parameter=name
            )
    start = max(na, max_delay + nb - 1)
    experiments = [e for e in data.experiments if e.n_samples > start + 1]
    if not experiments:
        raise DataError(
            f"every experiment is too short to scan delays up to {max_delay} "
            f"({start + 2} samples needed); give a smaller max_delay"
        )
    rows = sum(e.n_samples - start for e in experiments)
    columns = na + nb * data.n_inputs + 1
    if rows < 5 * columns:
        raise DataError(
            f"{rows} regression rows for {columns} coefficients: too few to scan delays up "
            f"to {max_delay} (at least {5 * columns} needed); give more data or a smaller "
            "max_delay"
        )
    u_all = np.vstack([e.u for e in experiments])
    y_all = np.vstack([e.y for e in experiments])
    u_scale = np.where(u_all.std(axis=0) > 0, u_all.std(axis=0), 1.0)
    y_scale = np.where(y_all.std(axis=0) > 0, y_all.std(axis=0), 1.0)
    signals = [
        ((e.u - u_all.mean(axis=0)) / u_scale, (e.y - y_all.mean(axis=0)) / y_scale)
        for e in experiments
    ]
    ny, nu = data.n_outputs, data.n_inputs
    nk = np.zeros((ny, nu), dtype=int)
    loss = np.full((ny, nu, max_delay + 1), np.inf)
    evidence = np.zeros((ny, nu), dtype=bool)
    from scipy.stats import chi2

    bound = float(chi2.ppf(0.999, nb))
    for j in range(ny):
        scan = _Scan(signals, j, start, na, nb)
        for i in range(nu):
            nk[j, i] = scan.best(i, {}, loss[j, i])
        for i in range(nu):
            others = {m: int(nk[j, m]) for m in range(nu) if m != i}
            if nu > 1:
                nk[j, i] = scan.best(i, others, loss[j, i])
            without = scan.residual([scan.lagged(m, d) for m, d in others.items()])
            best = float(loss[j, i, nk[j, i]])
            evidence[j, i] = scan.target.size * (without - best) / max(best, 1e-300) > bound
    if evidence.any():
        nk[~evidence] = int(np.round(np.median(nk[evidence])))
    else:
        nk[:] = 0
    return ChannelDelays(nk, loss, evidence, tuple(data.outputs), tuple(data.inputs))


class _Scan:
    """The least-squares residuals of one output's delay scans (module docstring)."""

    def __init__(
        self, signals: list[tuple[np.ndarray, np.ndarray]], j: int, start: int, na: int, nb: int
    ) -> None:
        self.signals, self.start, self.nb = signals, start, nb
        self.target = np.concatenate([y[start:, j] for _, y in signals])
        self.past = np.vstack(
            [
                np.column_stack([y[start - lag : len(y) - lag, j] for lag in range(1, na + 1)])
                if na
                else np.empty((len(y) - start, 0))
                for _, y in signals
            ]
        )

    def lagged(self, i: int, d: int) -> np.ndarray:
        """Input ``i`` from delay ``d`` on, ``nb`` samples."""
        s = self.start
        return np.vstack(
            [
                np.column_stack([u[s - d - m : len(u) - d - m, i] for m in range(self.nb)])
                for u, _ in self.signals
            ]
        )

    def residual(self, columns: list[np.ndarray]) -> float:
        X = np.column_stack([self.past, *columns, np.ones(self.target.size)])
        theta, *_ = np.linalg.lstsq(X, self.target, rcond=None)
        return float(np.mean((self.target - X @ theta) ** 2))

    def best(self, i: int, others: dict[int, int], losses: np.ndarray) -> int:
        """The delay of input ``i`` with the ``others`` at theirs; ``losses`` filled."""
        fixed = [self.lagged(m, d) for m, d in others.items()]
        for d in range(losses.size):
            losses[d] = self.residual([*fixed, self.lagged(i, d)])
        within = float(losses.min()) * (1.0 + 4.0 * self.nb / self.target.size)
        return int(np.flatnonzero(losses <= within)[-1])
