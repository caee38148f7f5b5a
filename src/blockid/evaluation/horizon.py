r"""Prediction ``k`` samples ahead: what a model predicts from the outputs measured until
``k`` samples before, the horizon a model-predictive controller looks over; one step
ahead and the free run are its two ends.

``ŷ(t | t - k)`` runs the model over the inputs up to ``t`` from the measured outputs up
to ``t - k`` only: its free run (:meth:`simulate`) over the window ``t - k - L + 1 ..
t``, started from the ``L = max_lag`` measured outputs that open the window, and the
last sample taken. Where the window would start before the record (``t - k < L``) it
starts at the record's start, from the ``L`` measured outputs every free run starts
from (MATLAB's ``predict`` uses the initial conditions there too): that sample's
prediction is the free run's, since a model's run over the inputs up to ``t`` is the
first ``t + 1`` samples of its run over the whole record. Hence the two ends, exactly:

* ``horizon=1`` is the model's one-step prediction (:func:`evaluate` ``"one-step"``,
  the model's own predictor: for an ARX model the least-squares predictor, which the
  window reproduces; a state space with its predictor gain ``K`` corrects its state by
  every measured output, which a window of ``L`` outputs cannot);
* ``horizon`` at least the longest record less ``L`` is the free run (:func:`evaluate`
  ``"simulation"``), the very same arrays.

Between the two it shows how fast a model's prediction degrades with the horizon, which
neither the one-step figure (optimistic for control) nor the free run (pessimistic)
says. Every horizon is scored from sample ``L`` on, as the free run and the one-step
prediction are; the first ``k - 1`` samples scored are predicted from the initial
conditions, at a horizon shorter than ``k``.

A model whose one-step prediction is its free run, sample for sample (no predictor but
its free run: a state space fitted as output error, a block state space), predicts by
its free run at every horizon.

A chain of blocks (:class:`~blockid.models.ChainModel`: Hammerstein, Wiener,
Wiener-Hammerstein, backlash, output error) predicts as its one-step predictor does,
``k`` steps on: the blocks before its last linear block run over the whole record from
rest (measured outputs do not set them: a window restarting them would forget the
first linear block of a Wiener-Hammerstein model), the last linear block's past
outputs ``x`` are recovered from the measured outputs (the output blocks inverted), and
its prediction ``P_k`` is the usual recursion over the horizon,

.. math::

    P_j(t) = -\sum_i a_i P_{j-i}(t-i) + \sum_l b_l w(t - n_k - l), \qquad
    P_{j \le 0} = x,

one vectorised pass per step ahead; then the blocks after it. For a chain whose first
block is its linear one (output error, Wiener) this is the window's prediction, to
rounding.

A choice: every other model predicts every target sample by its own short run, so the
cost is about ``N (k + L)`` model steps for the samples whose window starts inside the
record (a 10 000-sample record at ``k = 20``: 10 000 short runs; the runs are
independent, and a model's ``simulate`` is its compiled kernel); the others share the
one free run. A chain costs ``k`` vectorised passes over the record.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from blockid.data.dataset import Dataset
from blockid.errors import ParameterError

__all__ = ["predict"]


def predict(model: Any, data: Dataset, horizon: int = 1) -> Any:
    """``model``'s prediction ``horizon`` samples ahead on ``data`` with its metrics
    (module docstring), as a :class:`~blockid.evaluation.validate.ModelOutput`.

    Parameters
    ----------
    model : Model
    data : Dataset
    horizon : int
        ``k`` >= 1: 1 is the one-step prediction (``mode`` ``"one-step"``); more is
        ``mode`` ``"k-step"``, with ``horizon`` recorded; at least the longest record
        less ``max_lag`` it is the free run.

    Raises
    ------
    ParameterError
        For a ``horizon`` that is not a whole number >= 1.
    BlockidError
        What :func:`~blockid.evaluation.evaluate` raises for the one-step prediction
        (a model that cannot predict, data that do not fit it).

    Examples
    --------
    >>> import numpy as np
    >>> from blockid.data import Dataset
    >>> from blockid.evaluation import evaluate, predict
    >>> from blockid.fitting import fit_arx
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(300)
    >>> y = np.convolve(u, [0.0, 1.0, 0.5])[:300] + 0.01 * rng.standard_normal(300)
    >>> data = Dataset.from_arrays(u, y, ["u"], ["y"])
    >>> model = fit_arx(data, na=1, nb=2, nk=1).model
    >>> far = predict(model, data, horizon=300)
    >>> bool(np.array_equal(far.outputs[0], evaluate(model, data).outputs[0]))
    True
    """
    from blockid.evaluation.validate import evaluate

    if isinstance(horizon, bool) or not isinstance(horizon, int | np.integer) or horizon < 1:
        raise ParameterError(
            f"the prediction horizon must be a whole number >= 1 (samples ahead; 1: one "
            f"step), got {horizon!r}",
            parameter="horizon",
        )
    one = evaluate(model, data, "one-step")
    if horizon == 1:
        return one
    free = evaluate(model, data, "simulation")
    free.mode, free.horizon = "k-step", int(horizon)
    pairs = zip(one.outputs, free.outputs, strict=True)
    # the two can differ only from the second sample predicted on: a record of max_lag + 1
    # samples or fewer tells nothing of the model's predictor
    longer = any(exp.n_samples > int(model.max_lag) + 1 for exp in data.experiments)
    if longer and all(np.array_equal(a, b, equal_nan=True) for a, b in pairs):
        free.warnings.append(
            "the model's one-step prediction is its free run (no predictor but its free "
            "run), so it predicts by its free run at every horizon"
        )
        return free
    lag, k = int(model.max_lag), int(horizon)
    outputs = []
    for exp, run_free in zip(data.experiments, free.outputs, strict=True):
        out = np.array(run_free, dtype=float, copy=True)
        if k + lag < exp.n_samples:  # some windows start inside the record
            if hasattr(model, "x_from_y"):  # a chain: its outputs invert to its last block's
                out[k + lag :] = _chain_ahead(model, exp, k)[k + lag :, None]
            else:
                for t in range(lag + k, exp.n_samples):
                    start = t - k - lag + 1  # > 0: the window starts inside the record
                    with np.errstate(all="ignore"):
                        run = model.simulate(exp.u[start : t + 1], exp.y[start : start + lag])
                    out[t] = run[-1]
        outputs.append(out)
    return _rescored(free, outputs)


def _chain_ahead(model: Any, exp: Any, k: int) -> np.ndarray:
    """A chain's ``k``-step prediction on one experiment (module docstring): the last
    linear block's ``P_k`` from the outputs recovered from the measured ones, then the
    blocks after it (as :meth:`~blockid.models.ChainModel.predict` applies them)."""
    block, last = model.linear, model.last_linear_index
    x = model.x_from_y(exp.y[:, 0] - model.output_offset)
    w = model.internal(exp.u)
    n0, n = block.max_lag, x.size
    forced = np.zeros(n - n0)  # Σ_l b_l w(t - nk - l), t >= n0
    for i, b in enumerate(block.b):
        forced += b * w[n0 - block.nk - i : n - block.nk - i]
    earlier = [x] * block.na  # earlier[-i] = P_{j-i}; P_{j<=0} = x
    p = x
    for _ in range(k):
        p = x.copy()  # the first n0 samples: measured, as the one-step predictor keeps them
        p[n0:] = forced
        for i, a in enumerate(block.a, start=1):
            p[n0:] -= a * earlier[-i][n0 - i : n - i]
        earlier = [*earlier[1:], p] if block.na else earlier
    return model._run_from(p, last + 1) + model.output_offset


def _rescored(base: Any, outputs: list[np.ndarray]) -> Any:
    """``base`` (the free run, mode and horizon set) with ``outputs``, their metrics and
    their notes (the free run's notes on its poles and on extrapolation kept)."""
    from blockid.evaluation.metrics import metrics_by_output, undefined_notes
    from blockid.evaluation.plausibility import divergence, output_range_notes

    skip, names = base.skip, base.data.outputs
    y = np.vstack([e.y[skip:] for e in base.data.experiments])
    free = np.vstack([o[skip:] for o in base.outputs])
    y_hat = np.vstack([o[skip:] for o in outputs])
    of_free = set(undefined_notes(base.metrics) + output_range_notes(y, free, names, "free run"))
    base.outputs = outputs
    base.metrics = metrics_by_output(y, y_hat, names)
    what = f"{base.horizon}-step prediction"
    kept = [w for w in base.warnings if w not in of_free]
    base.warnings = undefined_notes(base.metrics) + output_range_notes(y, y_hat, names, what)
    base.warnings += kept
    base.diverged = divergence(y, y_hat, names)
    return base
