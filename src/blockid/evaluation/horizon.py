"""k-step-ahead prediction: what a model predicts ``k`` samples ahead from the outputs
measured until then, the horizon a model-predictive controller looks over.

``ŷ(t | t - k)`` runs the model over the inputs up to ``t`` from the measured outputs up
to ``t - k`` only: its free run (:meth:`simulate`) over the window ``t - k - L + 1 ..
t``, started from the ``L = max_lag`` measured outputs that open the window, and the
last sample taken. One step ahead it is the model's one-step prediction (measured past
outputs fed in: for an ARX model the least-squares predictor; a model fitted by
simulation error has no noise model and predicts with its own difference equation);
``k`` at least the record's length, it is the free run. Between the two it shows how
fast a model's prediction degrades with the horizon, which neither the one-step figure
(optimistic for control) nor the free run (pessimistic) says.

A choice: every target sample is predicted by its own short run, so the cost is about
``N (k + L)`` model steps (a 10 000-sample record at ``k = 20``: 10 000 short runs; the
runs are independent, and a model's ``simulate`` is its compiled kernel).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from blockid.data.dataset import Dataset
from blockid.errors import DataError, ParameterError

__all__ = ["k_step_prediction"]


def k_step_prediction(model: Any, data: Dataset, steps: int) -> Any:
    """``model``'s ``steps``-step-ahead prediction on ``data`` with its metrics, as a
    :class:`~blockid.evaluation.validate.ModelOutput` (``mode`` ``"k-step"``; the first
    ``max_lag + steps - 1`` samples of each experiment, which no prediction of that
    horizon reaches, are copied from the measurement and not scored).

    Raises
    ------
    ParameterError
        For ``steps`` (the horizon) not a whole number >= 1.
    DataError
        When an experiment is too short for one prediction of that horizon.
    """
    from blockid.evaluation.metrics import metrics_by_output, undefined_notes
    from blockid.evaluation.validate import ModelOutput

    if isinstance(steps, bool) or not isinstance(steps, int | np.integer) or steps < 1:
        raise ParameterError(
            f"the prediction's steps ahead must be a whole number >= 1, got {steps!r}",
            parameter="steps",
        )
    if tuple(data.inputs) != tuple(model.inputs) or tuple(data.outputs) != tuple(model.outputs):
        raise DataError(
            f"the model expects inputs {list(model.inputs)} and outputs {list(model.outputs)}, "
            f"but the data have inputs {list(data.inputs)} and outputs {list(data.outputs)}"
        )
    lag = int(model.max_lag)
    skip = lag + int(steps) - 1
    outputs = []
    for exp in data.experiments:
        if exp.n_samples <= skip:
            raise DataError(
                f"experiment {exp.name!r} has {exp.n_samples} samples: a {steps}-step "
                f"prediction needs more than max_lag + steps - 1 = {skip}; give fewer "
                "steps ahead or a longer record"
            )
        out = np.array(exp.y, dtype=float, copy=True)
        for t in range(skip, exp.n_samples):
            start = t - skip
            with np.errstate(all="ignore"):
                run = model.simulate(exp.u[start : t + 1], exp.y[start : start + lag])
            out[t] = run[-1]
        outputs.append(out)
    y = np.vstack([e.y[skip:] for e in data.experiments])
    y_hat = np.vstack([o[skip:] for o in outputs])
    metrics = metrics_by_output(y, y_hat, data.outputs)
    return ModelOutput("k-step", data, outputs, skip, metrics, undefined_notes(metrics))
