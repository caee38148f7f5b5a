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

**Orders.** With the delays found, :func:`channel_orders` gives each pair its own
number of input coefficients ``nb``: for each output, each input's ``nb`` in ``0 ..
nb_max`` (the other inputs at theirs, in turn) minimises Rissanen's minimum description
length of the least-squares residual, ``V (1 + nb log N / N)`` (MATLAB's
``selstruc(V, 'mdl')`` for ``arxstruc`` losses); 0 drops a pair whose input does not
act on the output (an output whose every pair would drop keeps its best one). A
chi-square test of the dropped coefficients at 95 % kept 1-3
coefficients too many on a plant with output noise (which an equation-error model
fits with extra input lags); MDL's ``log N`` per coefficient keeps fewer, and the
search's cross-validation judges the result. The false-nearest-neighbour test
(:mod:`blockid.fitting.orders`) cannot choose orders per pair: with one input of
several the output is not a function of that pair's regressor (the other inputs move
it).

Every delay of a pair is scored on the same samples (those that the longest delay
leaves), regressors never straddle two experiments, and the signals are divided by
their spread. The result is evidence for a search to weigh (``identify`` scores the
per-pair delays by cross-validation beside one common delay), not a decision.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from blockid.errors import DataError, ParameterError

if TYPE_CHECKING:  # pragma: no cover
    from blockid.data import Dataset

__all__ = ["ChannelDelays", "ChannelOrders", "channel_delays", "channel_orders"]


class _PerPair:
    """A result of one number per input-output pair: the matrix the attribute ``_matrix``
    names (``nk`` or ``nb``), which is also ``fit``'s option of that name."""

    _matrix: ClassVar[str]

    @property
    def common(self) -> bool:
        """True when every pair has the same value."""
        return isinstance(self.as_option(), int)

    def as_option(self) -> int | tuple[tuple[int, ...], ...]:
        """The matrix as ``fit``'s option of that name: one number when every pair
        agrees, else nested tuples (rows: outputs)."""
        return _option(getattr(self, self._matrix))


@dataclass(frozen=True)
class ChannelDelays(_PerPair):
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
    _matrix: ClassVar[str] = "nk"


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
    _whole_numbers(("max_delay", max_delay, 0), ("na", na, 0), ("nb", nb, 1))
    start = max(na, max_delay + nb - 1)
    if all(e.n_samples <= start + 1 for e in data.experiments):
        raise DataError(
            f"every experiment is too short to scan delays up to {max_delay} "
            f"({start + 2} samples needed); give a smaller max_delay"
        )
    signals = _signals(data, start, na + nb * data.n_inputs, f"delays up to {max_delay}",
                       "a smaller max_delay")  # fmt: skip
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


@dataclass(frozen=True)
class ChannelOrders(_PerPair):
    """Per-pair numbers of input coefficients and the losses they were chosen on.

    Attributes
    ----------
    nb : numpy.ndarray
        ``(n_outputs, n_inputs)``, MATLAB's ``nb`` matrix (0: the input does not enter
        that output).
    loss : numpy.ndarray
        ``(n_outputs, n_inputs, nb_max + 1)`` mean squared residual (normalised signals)
        of each ``nb`` of each pair, the other inputs at theirs.
    outputs, inputs : tuple of str
    """

    nb: np.ndarray
    loss: np.ndarray
    outputs: tuple[str, ...]
    inputs: tuple[str, ...]
    _matrix: ClassVar[str] = "nb"


def channel_orders(data: Dataset, nk: object, na: int, nb_max: int) -> ChannelOrders:
    """The number of input coefficients of every input-output pair (module docstring),
    at the delays ``nk`` (one number, or an ``(n_outputs, n_inputs)`` matrix) and ``na``
    past outputs.

    >>> import numpy as np
    >>> from blockid.data import Dataset
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal((3000, 2))
    >>> y = np.zeros(3000)
    >>> for t in range(3, 3000):
    ...     y[t] = 0.6 * y[t - 1] + u[t - 1, 0] + 0.5 * u[t - 2, 0] + 0.8 * u[t - 1, 1]
    >>> channel_orders(Dataset.from_arrays(u, y, ["a", "b"], ["y"]), 1, 1, 3).nb.tolist()
    [[2, 1]]
    """
    _whole_numbers(("na", na, 0), ("nb_max", nb_max, 1))
    ny, nu = data.n_outputs, data.n_inputs
    delays = np.broadcast_to(np.asarray(nk, dtype=int), (ny, nu))
    if np.any(delays < 0):
        raise ParameterError(f"nk must hold delays >= 0, got {np.asarray(nk).tolist()}")
    start = max(na, int(delays.max()) + nb_max - 1)
    signals = _signals(data, start, na + nb_max * nu, "the pairs' orders", "smaller orders")
    nb = np.full((ny, nu), nb_max, dtype=int)
    loss = np.full((ny, nu, nb_max + 1), np.inf)
    for j in range(ny):
        scan = _Scan(signals, j, start, na, nb_max)
        for i in range(nu):
            fixed = [scan.lagged(m, int(delays[j, m]), int(nb[j, m])) for m in range(nu) if m != i]
            for b in range(nb_max + 1):
                loss[j, i, b] = scan.residual([*fixed, scan.lagged(i, int(delays[j, i]), b)])
            nb[j, i] = int(np.argmin(_mdl(loss[j, i], scan.target.size)))  # ties: smaller
        if not nb[j].any():  # an output fed by no input is no model: keep its best pair
            best = [float(np.min(_mdl(loss[j, i], scan.target.size)[1:])) for i in range(nu)]
            i = int(np.argmin(best))
            nb[j, i] = 1 + int(np.argmin(_mdl(loss[j, i], scan.target.size)[1:]))
    return ChannelOrders(nb, loss, tuple(data.outputs), tuple(data.inputs))


def _whole_numbers(*checks: tuple[str, object, int]) -> None:
    """Refuse, by name, a value of ``(name, value, low)`` that is not a whole number
    ``>= low``."""
    for name, value, low in checks:
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < low:
            raise ParameterError(
                f"{name} must be a whole number >= {low}, got {value!r}", parameter=name
            )


def _option(matrix: np.ndarray) -> int | tuple[tuple[int, ...], ...]:
    """A per-pair order matrix as ``fit``'s option: one number when every pair agrees,
    else nested tuples (rows: outputs)."""
    if np.all(matrix == matrix.flat[0]):
        return int(matrix.flat[0])
    return tuple(tuple(int(v) for v in row) for row in matrix)


def _mdl(loss: np.ndarray, n: int) -> np.ndarray:
    """Rissanen's description length of each ``nb`` (the index) from its residual,
    ``V (1 + nb log N / N)``: MATLAB's ``selstruc(V, 'mdl')``, counting the pair's own
    coefficients (the others are the same for every ``nb`` of the pair)."""
    return loss * (1.0 + np.arange(loss.size) * np.log(n) / n)


def _signals(
    data: Dataset, start: int, columns: int, what: str, smaller: str
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Every experiment's signals that reach past ``start`` (the first sample every
    regression row can use), centred and divided by their spread; refuses fewer than
    five rows per coefficient (``columns`` and the intercept), naming ``what`` was to be
    scanned and the ``smaller`` setting that would help."""
    experiments = [e for e in data.experiments if e.n_samples > start + 1]
    rows = sum(e.n_samples - start for e in experiments)
    columns += 1
    if rows < 5 * columns:
        raise DataError(
            f"{rows} regression rows for {columns} coefficients: too few to scan {what} "
            f"(at least {5 * columns} needed); give more data or {smaller}"
        )
    u_all = np.vstack([e.u for e in experiments])
    y_all = np.vstack([e.y for e in experiments])
    u_scale = np.where(u_all.std(axis=0) > 0, u_all.std(axis=0), 1.0)
    y_scale = np.where(y_all.std(axis=0) > 0, y_all.std(axis=0), 1.0)
    return [
        ((e.u - u_all.mean(axis=0)) / u_scale, (e.y - y_all.mean(axis=0)) / y_scale)
        for e in experiments
    ]


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

    def lagged(self, i: int, d: int, nb: int | None = None) -> np.ndarray:
        """Input ``i`` from delay ``d`` on, ``nb`` samples (default the scan's)."""
        s, nb = self.start, self.nb if nb is None else nb
        return np.vstack(
            [
                np.column_stack([u[s - d - m : len(u) - d - m, i] for m in range(nb)])
                if nb
                else np.empty((len(u) - s, 0))
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
