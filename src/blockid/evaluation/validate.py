"""Run a model on a data set, free-run or one step ahead, and score it."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from blockid.data.dataset import Dataset
from blockid.errors import DataError, ParameterError
from blockid.evaluation.metrics import json_safe, metrics_by_output, undefined_notes

__all__ = ["MODES", "ModelOutput", "evaluate"]

#: ``mode -> column suffix``: free-run simulation and one-step-ahead prediction.
MODES = {"simulation": "sim", "one-step": "pred"}


@dataclass
class ModelOutput:
    """Model output on every experiment of a data set, with its metrics.

    Attributes
    ----------
    mode : {"simulation", "one-step"}
    data : Dataset
        The measured data the model ran on.
    outputs : list of ndarray
        Model output per experiment, (N_e, ny). The first ``skip`` samples of each are
        initial conditions copied from the measurement.
    skip : int
        Initial samples left out of the metrics in every experiment.
    metrics : dict
        ``{"mse": {"y1": ...}, "rmse": ..., "mae": ..., "max_abs_error": ...,
        "fit_percent": ...}`` over all experiments, initial samples excluded.
    warnings : list of str
        E.g. that the data drive a block-oriented model outside the ranges it was
        estimated on (its polynomial blocks extrapolate there), or that a metric is
        undefined (the fit percent of a constant output).
    """

    mode: str
    data: Dataset
    outputs: list[np.ndarray]
    skip: int
    metrics: dict[str, dict[str, float]]
    warnings: list[str] = field(default_factory=list)

    def to_frame(self) -> pd.DataFrame:
        """The data as a table, with a ``<output>_sim`` / ``<output>_pred`` column each."""
        frame = self.data.to_frame()
        y_hat = np.vstack(self.outputs)
        for j, name in enumerate(self.data.outputs):
            frame[f"{name}_{MODES[self.mode]}"] = y_hat[:, j]
        return frame

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (no sample arrays); an undefined metric is ``null``."""
        return json_safe(
            {
                "mode": self.mode,
                "n_samples": int(sum(len(y) for y in self.outputs)),
                "initial_samples_per_experiment": self.skip,
                "metrics": self.metrics,
                "warnings": self.warnings,
            }
        )


def evaluate(model: Any, data: Dataset, mode: str = "simulation") -> ModelOutput:
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
    """
    if mode not in MODES:
        raise ParameterError(f"mode must be one of {', '.join(MODES)}; got {mode!r}")
    if tuple(data.inputs) != tuple(model.inputs) or tuple(data.outputs) != tuple(model.outputs):
        raise DataError(
            f"the model expects inputs {list(model.inputs)} and outputs {list(model.outputs)}, "
            f"but the data have inputs {list(data.inputs)} and outputs {list(data.outputs)}"
        )
    skip = model.max_lag
    data.check_orders(skip, 1, what=f"the {model.structure} model")
    outputs = []
    for exp in data.experiments:
        if mode == "simulation":
            outputs.append(model.simulate(exp.u, exp.y[:skip]))
        else:
            outputs.append(model.predict(exp.u, exp.y))
    y = np.vstack([exp.y[skip:] for exp in data.experiments])
    y_hat = np.vstack([out[skip:] for out in outputs])
    metrics = metrics_by_output(y, y_hat, data.outputs)
    warnings: list[str] = undefined_notes(metrics)
    for model_part in getattr(model, "subsystems", [(None, model)]):
        sub = model_part[1]
        if hasattr(sub, "extrapolation"):
            for exp in data.experiments:
                cols = [
                    list(data.inputs).index(n) if n in data.inputs else None for n in sub.inputs
                ]
                if None in cols:
                    continue  # fed by another subsystem: checked through its own input
                for note in sub.extrapolation(exp.u[:, cols]):
                    prefix = f"{model_part[0]}: " if model_part[0] else ""
                    warnings.append(f"{prefix}{note} (experiment {exp.name!r})")
    return ModelOutput(mode, data, outputs, skip, metrics, warnings)
