"""The result of an identification: the model and what it took to get it."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

__all__ = ["FitResult", "simulation_result"]


@dataclass(frozen=True)
class FitResult:
    """A fitted model with what it took to get it (immutable: derive a changed result
    with :func:`dataclasses.replace`).

    Attributes
    ----------
    model : Model
    method : str
    settings : dict
        Estimator settings, as stored in the model file's ``"estimation"`` entry.
    estimation_metrics : dict
        Metrics on the estimation data, keyed by metric then output.
    metrics_mode : {"one-step", "simulation"}
        Whether ``estimation_metrics`` are of one-step prediction or free-run simulation.
    history : dict
        Optional per-output arrays (e.g. parameter trajectories of recursive methods).
    """

    model: Any
    method: str
    settings: dict[str, Any]
    estimation_metrics: dict[str, dict[str, float]]
    n_samples: int
    history: dict[str, Any] = field(default_factory=dict)
    metrics_mode: str = "one-step"

    def _repr_html_(self) -> str:
        """The notebook display: :func:`blockid.plotting.notebook.fit_html`."""
        from blockid.plotting.notebook import fit_html

        return fit_html(self)

    def plot(self, data: Any = None, *, which: str | None = None) -> Any:
        """The report's figures of the fit (with bands from its standard errors, and a
        recursive estimator's parameter trajectories): a dict of matplotlib figures, or
        the one ``which`` names; see :func:`blockid.plotting.notebook.model_figures`."""
        from blockid.plotting.notebook import model_figures

        return model_figures(self.model, data, fit=self, which=which)

    def estimation_record(self) -> dict[str, Any]:
        """The ``"estimation"`` entry of the model file."""
        return {
            "method": self.method,
            "settings": self.settings,
            "n_samples": self.n_samples,
            f"{self.metrics_mode.replace('-', '_')}_on_estimation_data": self.estimation_metrics,
        }


def simulation_result(
    model: Any,
    data: Any,
    method: str,
    settings: dict[str, Any],
    metrics: dict[str, dict[str, float]],
    history: dict[str, Any] | None = None,
) -> FitResult:
    """The result of a fit on ``data`` whose ``metrics`` are of the model's free run
    (``metrics_mode="simulation"``): the simulation-error, state-space, block-ARX and
    network fits."""
    return FitResult(
        model=model,
        method=method,
        settings=settings,
        estimation_metrics=metrics,
        n_samples=data.n_samples,
        history={} if history is None else history,
        metrics_mode="simulation",
    )
