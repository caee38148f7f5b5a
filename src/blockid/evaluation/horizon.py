"""Prediction ``k`` samples ahead: what a model predicts from the outputs measured until
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
its free run at every horizon. Dynamics before a chain's last linear block (the first
linear block of a Wiener-Hammerstein model, a backlash) are not set by measured outputs:
each window restarts them at rest, so such a model's prediction beyond one step forgets
them; a note says so.

A choice: every target sample is predicted by its own short run, so the cost is about
``N (k + L)`` model steps for the samples whose window starts inside the record (a
10 000-sample record at ``k = 20``: 10 000 short runs; the runs are independent, and a
model's ``simulate`` is its compiled kernel); the others share the one free run.
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
    if all(np.array_equal(a, b, equal_nan=True) for a, b in pairs):
        free.warnings.append(
            "the model's one-step prediction is its free run (no predictor but its free "
            "run), so it predicts by its free run at every horizon"
        )
        return free
    lag = int(model.max_lag)
    outputs = []
    for exp, run_free in zip(data.experiments, free.outputs, strict=True):
        out = np.array(run_free, dtype=float, copy=True)
        for t in range(lag + int(horizon), exp.n_samples):
            start = t - int(horizon) - lag + 1  # > 0: the window starts inside the record
            with np.errstate(all="ignore"):
                run = model.simulate(exp.u[start : t + 1], exp.y[start : start + lag])
            out[t] = run[-1]
        outputs.append(out)
    if len(getattr(model, "linear_blocks", ())) > 1 or _dynamic_input_block(model):
        free.warnings.append(
            "the model has dynamics before its last linear block, which measured outputs "
            "do not set: each prediction restarts them at rest, "
            f"{int(horizon) + lag} samples back"
        )
    return _rescored(free, outputs)


def _dynamic_input_block(model: Any) -> bool:
    """Whether a chain has a block with memory (a backlash) before its last linear one."""
    blocks = list(getattr(model, "blocks", ()))
    last = getattr(model, "last_linear_index", None)
    if last is None:
        return False
    return any(getattr(b, "role", "") == "dynamic" for b in blocks[:last])


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
