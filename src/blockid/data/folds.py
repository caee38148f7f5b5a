"""Blocked cross-validation folds over a data set's experiments.

A fold holds back one contiguous block of the record (or one group of experiments) and
trains on the rest; on time series the blocks must be contiguous, not shuffled samples,
or every held-back sample has its neighbours in the training set (Bergmeir & Benítez,
Information Sciences 191, 2012; Arlot & Celisse, Statistics Surveys 4, 2010).

:func:`fold_plan` chooses the folds from the data alone:

* **three or more experiments**: leave one group of consecutive experiments out, with
  as many groups as there are experiments up to ``max_folds``;
* **one or two experiments**: ``max_folds`` contiguous blocks, spread over the
  experiments in proportion to their lengths (at least one block each), every block of
  an experiment of equal length.

The plan holds sample ranges only (:class:`Segment`); :func:`materialise` turns them into
a :class:`~blockid.data.dataset.Dataset` of views, so a worker process holding the
record once can build any fold without a copy. Training segments that touch in the same
experiment are merged (a fold that holds back the middle of a record trains on the two
pieces around it, as two experiments).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from blockid.data.dataset import Dataset, Experiment
from blockid.errors import DataError

__all__ = ["Fold", "FoldPlan", "Segment", "fold_plan", "materialise"]


@dataclass(frozen=True)
class Segment:
    """Samples ``start:stop`` of experiment number ``experiment``."""

    experiment: int
    start: int
    stop: int

    @property
    def n_samples(self) -> int:
        return self.stop - self.start


@dataclass(frozen=True)
class Fold:
    """One split: train on ``train``, score on ``test``."""

    name: str
    train: tuple[Segment, ...]
    test: tuple[Segment, ...]


@dataclass(frozen=True)
class FoldPlan:
    """The folds of a search and how they were chosen (``text``)."""

    folds: tuple[Fold, ...]
    text: str

    def __len__(self) -> int:
        return len(self.folds)

    def to_dict(self, data: Dataset) -> list[dict[str, object]]:
        """Each fold's held-back samples, named by experiment."""
        names = [e.name for e in data.experiments]
        return [
            {
                "name": f.name,
                "held_back": [
                    {"experiment": names[s.experiment], "start": s.start, "stop": s.stop}
                    for s in f.test
                ],
            }
            for f in self.folds
        ]


def _merged(segments: Sequence[Segment]) -> tuple[Segment, ...]:
    out: list[Segment] = []
    for s in sorted(segments, key=lambda s: (s.experiment, s.start)):
        if out and out[-1].experiment == s.experiment and out[-1].stop == s.start:
            out[-1] = Segment(s.experiment, out[-1].start, s.stop)
        else:
            out.append(s)
    return tuple(out)


def _blocks(lengths: Sequence[int], n_blocks: int) -> list[Segment]:
    """``n_blocks`` contiguous blocks over experiments of ``lengths`` (module notes)."""
    total = sum(lengths)
    counts = [max(1, round(n_blocks * n / total)) for n in lengths]
    while sum(counts) > n_blocks and max(counts) > 1:  # rounding up on every record
        counts[counts.index(max(counts))] -= 1
    while sum(counts) < n_blocks:
        share = [n / c for n, c in zip(lengths, counts, strict=True)]
        counts[share.index(max(share))] += 1
    out = []
    for e, (n, c) in enumerate(zip(lengths, counts, strict=True)):
        edges = [round(i * n / c) for i in range(c + 1)]
        out += [Segment(e, edges[i], edges[i + 1]) for i in range(c)]
    return out


def fold_plan(data: Dataset, max_folds: int, min_samples: int = 30) -> FoldPlan:
    """The folds of ``data`` (module docstring): at most ``max_folds`` (at least 2), each
    held-back block at least ``min_samples`` long (fewer folds when the record is short).

    >>> import numpy as np
    >>> d = Dataset.from_arrays(np.zeros(400), np.arange(400.0))
    >>> plan = fold_plan(d, 4)
    >>> [(f.test[0].start, f.test[0].stop) for f in plan.folds]
    [(0, 100), (100, 200), (200, 300), (300, 400)]
    >>> [(s.start, s.stop) for s in plan.folds[1].train]
    [(0, 100), (200, 400)]
    """
    if max_folds < 2:
        raise DataError(f"cross-validation needs at least 2 folds, got {max_folds}")
    lengths = [e.n_samples for e in data.experiments]
    n_exp = len(lengths)
    if n_exp >= 3:
        k = min(n_exp, max_folds)
        edges = [round(i * n_exp / k) for i in range(k + 1)]
        groups = [list(range(edges[i], edges[i + 1])) for i in range(k)]
        folds = []
        for i, group in enumerate(groups):
            test = tuple(Segment(e, 0, lengths[e]) for e in group)
            train = tuple(Segment(e, 0, lengths[e]) for e in range(n_exp) if e not in group)
            names = ", ".join(data.experiments[e].name for e in group)
            folds.append(Fold(f"fold {i + 1} (experiment {names})", train, test))
        text = f"{k} folds: leave {'one experiment' if k == n_exp else 'a group'} out"
        return FoldPlan(tuple(folds), text)
    k = max(max_folds, n_exp)
    blocks = _blocks(lengths, k)
    while k > max(2, n_exp) and min(b.n_samples for b in blocks) < min_samples:
        k -= 1  # short records: fewer, longer folds
        blocks = _blocks(lengths, k)
    if min(b.n_samples for b in blocks) < min_samples:
        raise DataError(
            f"the estimation data are too short to hold back {k} blocks of at least "
            f"{min_samples} samples for cross-validation ({sum(lengths)} samples); give "
            "more data"
        )
    folds = []
    for i, held in enumerate(blocks):
        train = _merged([b for b in blocks if b is not held])
        where = f"{data.experiments[held.experiment].name!r} {held.start}:{held.stop}"
        folds.append(Fold(f"fold {i + 1} ({where})", train, (held,)))
    return FoldPlan(tuple(folds), f"{k} contiguous folds (blocked cross-validation)")


def materialise(data: Dataset, segments: Sequence[Segment], limit: int | None = None) -> Dataset:
    """The samples of ``segments`` as a data set of views (one experiment per segment);
    with ``limit``, only the first ``limit`` samples of them (the last segment cut)."""
    exps = []
    left = limit
    for s in segments:
        if left is not None and left <= 0:
            break
        stop = s.stop if left is None else min(s.stop, s.start + left)
        e = data.experiments[s.experiment]
        name = e.name if (s.start, stop) == (0, e.n_samples) else f"{e.name}[{s.start}:{stop}]"
        exps.append(Experiment(name, e.u[s.start : stop], e.y[s.start : stop]))
        if left is not None:
            left -= stop - s.start
    return Dataset(data.inputs, data.outputs, data.sampling_time, exps, data.source)
