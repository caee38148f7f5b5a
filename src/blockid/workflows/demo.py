"""The built-in example run by ``blockid demo`` / ``make demo``: paper B's experiment."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

__all__ = ["run_demo"]


def run_demo(output_dir: str | Path, seed: int = 0) -> Any:
    """Reproduce paper B on the simulated electrohydraulic arm and keep everything.

    Writes to ``output_dir``: the estimation and validation records
    (``electrohydraulic_estimation.csv``, ``electrohydraulic_validation.csv``), the best
    model file of every structure (``model_<structure>.json``), the figures of the
    reproduction and ``results.json`` (what ``blockid reproduce electrohydraulic
    --json`` prints). Returns the :class:`ElectrohydraulicReproduction`.
    """
    from blockid.models import save_model
    from blockid.plants.electrohydraulic import electrohydraulic_experiment
    from blockid.workflows.reproduce_electrohydraulic import reproduce_electrohydraulic

    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    exp = electrohydraulic_experiment(seed=seed)
    for kind in ("estimation", "validation"):
        exp[kind][["t", "current", "velocity"]].to_csv(
            out / f"electrohydraulic_{kind}.csv", index=False
        )
    result = reproduce_electrohydraulic(seed=seed, figures_dir=out)
    for structure, best in result.best.items():
        model = result.models[(structure, best["estimator"])]
        save_model(
            model, out / f"model_{structure}.json", {"estimator": best["estimator"]}, overwrite=True
        )
    (out / "results.json").write_text(json.dumps(result.to_dict(), indent=2) + "\n")
    return result
