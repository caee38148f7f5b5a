"""Run a model on a data set, free-run or one step ahead, and score it."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from blockid.data.dataset import Dataset
from blockid.errors import DataError, ParameterError
from blockid.evaluation.metrics import json_safe, metrics_by_output, undefined_notes
from blockid.evaluation.plausibility import divergence, output_range_notes, pole_notes

__all__ = ["MODES", "ModelOutput", "evaluate", "score_model"]

#: ``mode -> column suffix``: free-run simulation and one-step-ahead prediction.
MODES = {"simulation": "sim", "one-step": "pred"}


@dataclass
class ModelOutput:
    """Model output on every experiment of a data set, with its metrics.

    Attributes
    ----------
    mode : {"simulation", "one-step", "k-step"}
        ``"k-step"``: the prediction ``horizon`` samples ahead
        (:func:`~blockid.evaluation.horizon.predict`).
    data : Dataset
        The measured data the model ran on.
    outputs : list of ndarray
        Model output per experiment, (N_e, ny). The first ``skip`` samples of each are
        initial conditions copied from the measurement.
    skip : int
        Initial samples left out of the metrics in every experiment.
    initial_samples : int, optional
        The measured outputs each free run started from when given to
        :func:`evaluate` (``initial_samples``); None: the first ``max_lag``.
    metrics : dict
        ``{"mse": {"y1": ...}, "rmse": ..., "mae": ..., "max_abs_error": ...,
        "fit_percent": ...}`` over all experiments, initial samples excluded.
    warnings : list of str
        E.g. that the data drive a block-oriented model outside the ranges it was
        estimated on (its polynomial blocks extrapolate there), that its output leaves
        the measured output's range or its linear part has poles on, near or beyond the
        unit circle or at the Nyquist frequency
        (:mod:`blockid.evaluation.plausibility`), or that a metric is undefined (the
        fit percent of a constant output).
    diverged : str, optional
        Why the model output has diverged on these data (not finite, or astronomically
        beyond the measured range: :func:`~blockid.evaluation.plausibility.divergence`);
        None when it has not. Its metrics then mean nothing: ``simulate`` and
        ``predict`` stop with an error.
    horizon : int, optional
        ``"k-step"``: the samples ahead predicted.
    """

    mode: str
    data: Dataset
    outputs: list[np.ndarray]
    skip: int
    metrics: dict[str, dict[str, float]]
    warnings: list[str] = field(default_factory=list)
    initial_samples: int | None = None
    diverged: str | None = None
    horizon: int | None = None

    def to_frame(self) -> pd.DataFrame:
        """The data as a table, with a ``<output>_sim`` / ``<output>_pred`` column each."""
        frame = self.data.to_frame()
        y_hat = np.vstack(self.outputs)
        for j, name in enumerate(self.data.outputs):
            frame[f"{name}_{MODES.get(self.mode, 'pred')}"] = y_hat[:, j]  # k-step: pred
        return frame

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (no sample arrays); an undefined metric is ``null``.

        ``initial_samples`` (the measured outputs each simulation started from) follows
        ``initial_samples_per_experiment`` when they were given to :func:`evaluate`.
        """
        doc: dict[str, Any] = {
            "mode": self.mode,
            "n_samples": int(sum(len(y) for y in self.outputs)),
            "initial_samples_per_experiment": self.skip,
        }
        if self.initial_samples is not None:
            doc["initial_samples"] = self.initial_samples
        if self.horizon is not None:
            doc["horizon"] = self.horizon
        doc.update(metrics=self.metrics, warnings=self.warnings)
        if self.diverged is not None:
            doc["diverged"] = self.diverged
        return json_safe(doc)


def evaluate(
    model: Any, data: Dataset, mode: str = "simulation", initial_samples: int | None = None
) -> ModelOutput:
    """Run ``model`` on ``data`` and compute the metrics.

    Parameters
    ----------
    model : Model
        Any blockid model; its signal names must be present in ``data``.
    data : Dataset
    mode : {"simulation", "one-step"}
        Free-run simulation from the inputs (initial conditions: the first
        ``model.max_lag`` measured outputs of each experiment) or one-step-ahead
        prediction from measured past outputs.
    initial_samples : int, optional
        Free run only: start every experiment from its first ``initial_samples``
        measured outputs (``model.simulate(u, y[:n])``; more than ``max_lag`` of them
        make a block-oriented model estimate its initial state, see
        :meth:`~blockid.models.ChainModel.simulate`) and score it from sample
        ``max(initial_samples, max_lag)`` on (**choice**: samples the start used are not
        scored, nor the first ``max_lag`` ones, which a model given fewer outputs fills
        from rest). Must leave at least one sample of every experiment. None (default):
        the first ``max_lag``.

    Raises
    ------
    ParameterError
        For an unknown mode, or an ``initial_samples`` that is not a whole number >= 1,
        is given with one-step prediction, or leaves no sample of an experiment.
    """
    if mode not in MODES:
        raise ParameterError(f"mode must be one of {', '.join(MODES)}; got {mode!r}")
    if tuple(data.inputs) != tuple(model.inputs) or tuple(data.outputs) != tuple(model.outputs):
        raise DataError(
            f"the model expects inputs {list(model.inputs)} and outputs {list(model.outputs)}, "
            f"but the data have inputs {list(data.inputs)} and outputs {list(data.outputs)}"
        )
    data.check_orders(model.max_lag, 1, what=f"the {model.structure} model")
    n_init = _initial_samples(initial_samples, mode, data)
    skip = model.max_lag if n_init is None else max(n_init, model.max_lag)
    start = model.max_lag if n_init is None else n_init
    outputs = []
    for exp in data.experiments:
        if mode == "simulation":
            outputs.append(model.simulate(exp.u, exp.y[:start]))
        else:
            outputs.append(model.predict(exp.u, exp.y))
    y = np.vstack([exp.y[skip:] for exp in data.experiments])
    y_hat = np.vstack([out[skip:] for out in outputs])
    metrics = metrics_by_output(y, y_hat, data.outputs)
    warnings: list[str] = undefined_notes(metrics)
    what = "free run" if mode == "simulation" else "one-step prediction"
    warnings += output_range_notes(y, y_hat, data.outputs, what)
    for model_part in getattr(model, "subsystems", [(None, model)]):
        sub = model_part[1]
        prefix = f"{model_part[0]}: " if model_part[0] else ""
        warnings += [prefix + note for note in pole_notes(sub.fitted_poles())]
        if hasattr(sub, "extrapolation"):
            for exp in data.experiments:
                cols = [
                    list(data.inputs).index(n) if n in data.inputs else None for n in sub.inputs
                ]
                if None in cols:
                    continue  # fed by another subsystem: checked through its own input
                for note in sub.extrapolation(exp.u[:, cols]):
                    warnings.append(f"{prefix}{note} (experiment {exp.name!r})")
    diverged = divergence(y, y_hat, data.outputs, model.fitted_poles())
    return ModelOutput(mode, data, outputs, skip, metrics, warnings, n_init, diverged)


def score_model(model: Any, data: Dataset) -> tuple[ModelOutput, ModelOutput | None, str | None]:
    """The scores ``compare`` and ``identify`` report: free-run simulation and one-step
    prediction on ``data`` (a model that cannot predict one step ahead, such as a
    network fed by simulated signals, gives None and the reason)."""
    from blockid.errors import BlockidError

    simulation = evaluate(model, data, "simulation")
    try:
        return simulation, evaluate(model, data, "one-step"), None
    except BlockidError as exc:
        return simulation, None, str(exc)


def _initial_samples(value: Any, mode: str, data: Dataset) -> int | None:
    """``initial_samples`` checked against the mode and the data (see :func:`evaluate`)."""
    if value is None:
        return None
    if mode != "simulation":
        raise ParameterError(
            "initial_samples applies to free-run simulation only (one-step prediction "
            "reads every measured past output)",
            parameter="initial_samples",
        )
    whole = isinstance(value, int | np.integer) and not isinstance(value, bool)
    if not whole or value < 1:
        raise ParameterError(
            f"initial_samples must be a whole number >= 1 (measured outputs to start "
            f"from), got {value!r}",
            parameter="initial_samples",
        )
    shortest = min(data.experiments, key=lambda e: e.n_samples)
    if value >= shortest.n_samples:
        raise ParameterError(
            f"initial_samples={value} leaves no sample to score in experiment "
            f"{shortest.name!r}, which has {shortest.n_samples}; give fewer",
            parameter="initial_samples",
        )
    return int(value)
