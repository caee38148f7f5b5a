"""Paper B end to end: simulate the electrohydraulic excavator arm, identify
Hammerstein–Wiener, Hammerstein, Wiener and ARX models with the paper's orders, and
compare their free-run simulation error on a different, general trajectory (Table 2).

* Estimation data: the paper's multisine (0.05, 0.1, 0.2, 0.4, 0.5 Hz; 20 Hz sampling;
  55 s), ten runs averaged. Validation data: one run of a general trajectory (an
  operator's point-to-point moves, low-passed at the multisine's top frequency 0.5 Hz
  and kept within the estimation record's current range: see
  :func:`blockid.plants.electrohydraulic.electrohydraulic_experiment`).
* Orders (SPEC conventions): na = 3, nb = 3 (b_0 = 1 fixed), nk = 8, two-segment cubic
  input block (r1 = 3), cubic output block without constant (r2 = 3).
* Two estimators per structure: the **paper's** key-term RLS with internal-variable
  estimation and forgetting 0.98 for the first 200 samples of a pass, then 1 (B5); and
  blockid's **default** (refinement on free-run simulation error; least squares for
  ARX). A structure's "best" row is the estimator with the lower validation MSE; a
  failed estimator is shown with its reason.
* Every MSE is of free-run simulation on the validation record (the model's own past
  outputs fed back), in (rad/s)^2.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from blockid.data.dataset import Dataset
from blockid.errors import EstimationError
from blockid.evaluation.validate import evaluate
from blockid.fitting.dispatch import fit_model
from blockid.fitting.key_term import fit_key_term_rls

__all__ = ["PAPER_MSE", "ORDERS", "ElectrohydraulicReproduction", "reproduce_electrohydraulic"]

#: Paper B, Table 2: prediction MSE of each identified model.
PAPER_MSE = {"hammerstein-wiener": 0.0321, "hammerstein": 0.0417, "wiener": 0.1081, "arx": 0.1218}

#: Paper B's orders in blockid's conventions, per structure.
ORDERS = {
    "hammerstein-wiener": {"na": 3, "nb": 3, "nk": 8, "r1": 3, "r2": 3},
    "hammerstein": {"na": 3, "nb": 3, "nk": 8, "r1": 3},
    "wiener": {"na": 3, "nb": 3, "nk": 8, "r2": 3},
    "arx": {"na": 3, "nb": 3, "nk": 8},
}
STRUCTURES = tuple(ORDERS)
PAPER, DEFAULT = "paper (key-term RLS)", "default (simulation error)"


@dataclass
class ElectrohydraulicReproduction:
    """Results of :func:`reproduce_electrohydraulic`."""

    table: list[dict[str, Any]] = field(default_factory=list)
    best: dict[str, dict[str, Any]] = field(default_factory=dict)
    parameters: dict[str, Any] = field(default_factory=dict)
    outputs: dict[str, Any] = field(default_factory=dict)
    models: dict[str, Any] = field(default_factory=dict)
    figures: list[str] = field(default_factory=list)
    validation_bandwidth: float | None = 0.5

    def reductions(self) -> dict[str, float]:
        """How much lower the best H-W MSE is than each other structure's (fraction)."""
        hw = self.best["hammerstein-wiener"]["mse"]["velocity"]
        return {
            s: 1.0 - hw / self.best[s]["mse"]["velocity"]
            for s in STRUCTURES
            if s != "hammerstein-wiener" and s in self.best
        }

    def to_dict(self) -> dict[str, Any]:
        return {
            "table": self.table,
            "best": self.best,
            "hw_reduction": self.reductions() if "hammerstein-wiener" in self.best else None,
            "parameters": self.parameters,
            "paper": {
                "mse": PAPER_MSE,
                "hw_reduction": {"hammerstein": 0.13, "wiener": 0.54, "arx": 0.58},
            },
            "figures": self.figures,
            "validation_bandwidth": self.validation_bandwidth,
            "note": "mse: free-run simulation on the validation (general trajectory) record",
        }


def _datasets(seed: int, validation_bandwidth: float | None) -> dict[str, Dataset]:
    from blockid.plants.electrohydraulic import electrohydraulic_experiment

    exp = electrohydraulic_experiment(seed=seed, validation_bandwidth=validation_bandwidth)
    return {
        kind: Dataset.from_frame(
            exp[kind], ["current"], ["velocity"], time_column="t", source=f"electrohydraulic {kind}"
        )
        for kind in ("estimation", "validation")
    }


def _fit(structure: str, estimator: str, data: Dataset) -> Any:
    orders = ORDERS[structure]
    if estimator == PAPER:
        return fit_key_term_rls(data, structure, forgetting="0.98:200,1", **orders)
    return fit_model(data, structure, **orders)


def reproduce_electrohydraulic(
    seed: int = 0,
    figures_dir: str | Path | None = None,
    validation_bandwidth: float | None = 0.5,
) -> ElectrohydraulicReproduction:
    """Run paper B's experiment on the simulated plant (see the module docstring).

    ``validation_bandwidth`` [Hz] is passed to
    :func:`~blockid.plants.electrohydraulic.electrohydraulic_experiment`: the validation
    command is low-passed there (default 0.5 Hz, the multisine's top component); None
    keeps the step-like moves, which ask the models to extrapolate in frequency
    (``docs/reproduction.md``).
    """
    data = _datasets(seed, validation_bandwidth)
    result = ElectrohydraulicReproduction(validation_bandwidth=validation_bandwidth)
    for structure in STRUCTURES:
        for estimator in (PAPER, DEFAULT):
            label = (
                "default (least squares)"
                if (structure, estimator) == ("arx", DEFAULT)
                else (estimator)
            )
            row: dict[str, Any] = {"model": structure, "estimator": label}
            try:
                fit = _fit(structure, estimator, data["estimation"])
            except EstimationError as exc:
                row["error"] = str(exc)
                result.table.append(row)
                continue
            sim = evaluate(fit.model, data["validation"], "simulation")
            row["mse"] = sim.metrics["mse"]
            row["rmse"] = sim.metrics["rmse"]
            row["fit_percent"] = sim.metrics["fit_percent"]
            row["method"] = fit.method
            result.table.append(row)
            key = (structure, label)
            result.outputs[key] = sim
            result.models[key] = fit.model
            best = result.best.get(structure)
            if best is None or row["mse"]["velocity"] < best["mse"]["velocity"]:
                result.best[structure] = {
                    "estimator": label,
                    "mse": row["mse"],
                    "fit_percent": row["fit_percent"],
                }
            params = getattr(fit.model, "parameters", None)
            if params is None:  # ARX
                params = {
                    "a": fit.model.a["velocity"]["velocity"].tolist(),
                    "b": fit.model.b["velocity"]["current"].tolist(),
                }
            result.parameters.setdefault(structure, {})[label] = params
    if figures_dir is not None:
        result.figures = [str(p) for p in _figures(result, Path(figures_dir), data)]
    return result


def _figures(result: ElectrohydraulicReproduction, folder: Path, data: dict) -> list[Path]:
    import matplotlib.pyplot as plt

    from blockid.plotting.figures import plot_blocks

    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    val = data["validation"]
    exp = val.experiments[0]
    t = np.arange(exp.n_samples) * (val.sampling_time or 1.0)
    fig, axes = plt.subplots(
        len(result.best), 1, figsize=(9, 2.3 * len(result.best)), sharex=True, squeeze=False
    )
    for ax, (structure, best) in zip(axes[:, 0], result.best.items(), strict=True):
        sim = result.outputs[(structure, best["estimator"])]
        ax.plot(t, exp.y[:, 0], color="0.2", lw=0.9, label="measured")
        ax.plot(
            t, sim.outputs[0][:, 0], color="C1", lw=1.0, label=f"{structure} ({best['estimator']})"
        )
        ax.set_ylabel("rad/s")
        ax.set_title(
            f"{structure}: free-run simulation on the validation trajectory, "
            f"MSE {best['mse']['velocity']:.3g}",
            fontsize=9,
        )
        ax.legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("time [s]")
    fig.tight_layout()
    path = folder / "electrohydraulic_validation.png"
    fig.savefig(path, dpi=110)
    paths.append(path)
    hw = result.best.get("hammerstein-wiener")
    if hw is not None:
        model = result.models[("hammerstein-wiener", hw["estimator"])]
        u = data["estimation"].experiments[0].u[:, 0]
        fig = plot_blocks(model, u=u)
        fig.suptitle("identified Hammerstein-Wiener blocks (input: current [A])", fontsize=9)
        fig.tight_layout()
        path = folder / "electrohydraulic_hw_blocks.png"
        fig.savefig(path, dpi=110)
        paths.append(path)
    plt.close("all")
    return paths
