"""Paper A end to end: simulate the wind tunnel, identify the block-oriented network and
the conventional linear model, and compare them on validation data (paper A, Table 2).

For each operating condition (110 kPa / Ma 0.578 and 130 kPa / Ma 0.822):

* **block-oriented**: S1 exhaust valve ARX (na = nb = nk = 1), S2 choke finger backlash
  followed by a linear block (na = 2, nb = 1, nk = 1, b_0 = 1), S3 flow field
  two-input two-output ARX (na = 2 own and cross lags, nb = 2, nk = 1) around the
  operating point — each identified from its own measured signals, then simulated
  *from u1, u2 alone* (S3 fed with the simulated v1, v2);
* **conventional**: a two-input two-output ARX of the same orders straight from u1, u2 to
  y1, y2, fitted by least squares.

Three estimator sets identify the network: the **paper's** (S1 by RLS, S2 by AW-RLS, S3
by H-RLS with forgetting), blockid's **default** (S1 by least squares, S2 by refinement
on free-run simulation error, S3 by least squares) and the default with **S3 as a block
model** of two inputs and two outputs (a cubic per input around a linear state space
whose order the data choose, :mod:`blockid.fitting.block_state_space`, fitted on its
free-run error). Every number is a free-run simulation
on the validation record: RMSE and maximum absolute error (paper A's "MAE") of the
stagnation pressure P0 (y1, kPa) and the Mach number (y2).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from blockid.data.dataset import Dataset
from blockid.errors import EstimationError
from blockid.evaluation.validate import evaluate
from blockid.fitting.arx import fit_arx
from blockid.fitting.network import SubsystemSpec, fit_network, subset

__all__ = ["ESTIMATORS", "PAPER_TABLE", "WindTunnelReproduction", "reproduce_windtunnel"]

#: S1 and S2 by blockid's default estimators (least squares; simulation error).
_DEFAULT_ACTUATORS = (
    SubsystemSpec("S1", ["u1"], ["v1"], "arx", "batch", {"na": 1, "nb": 1, "nk": 1}),
    SubsystemSpec(
        "S2", ["u2"], ["v2"], "backlash", "simulation-error", {"na": 2, "nb": 1, "nk": 1}
    ),
)

#: Subsystem specifications of the three estimator sets.

ESTIMATORS: dict[str, list[SubsystemSpec]] = {
    "paper (RLS, AW-RLS, H-RLS)": [
        SubsystemSpec("S1", ["u1"], ["v1"], "arx", "rls", {"na": 1, "nb": 1, "nk": 1}),
        SubsystemSpec("S2", ["u2"], ["v2"], "backlash", "aw-rls", {"na": 2, "nb": 1, "nk": 1}),
        SubsystemSpec(
            "S3",
            ["v1", "v2"],
            ["y1", "y2"],
            "arx",
            "hierarchical-rls",
            {
                "na": 2,
                "nb": 2,
                "nk": 1,
                "center": True,
                "forgetting": 0.98,
                "passes": 3,
            },
        ),
    ],
    "default (LS, simulation error, LS)": [
        *_DEFAULT_ACTUATORS,
        SubsystemSpec(
            "S3",
            ["v1", "v2"],
            ["y1", "y2"],
            "arx",
            "batch",
            {"na": 2, "nb": 2, "nk": 1, "center": True},
        ),
    ],
    # S3 as a block model of two inputs and two outputs: a cubic per input around a
    # linear state space whose order the data choose (issue 18)
    "S3 block model (LS, simulation error, block state space)": [
        *_DEFAULT_ACTUATORS,
        SubsystemSpec(
            "S3",
            ["v1", "v2"],
            ["y1", "y2"],
            "block-state-space",
            None,
            {"input_block": "polynomial:degree=3"},
        ),
    ],
}

#: Paper A, Table 2 (validation): RMSE and maximum absolute error of P0 and Ma.
PAPER_TABLE = [
    {
        "condition": condition,
        "model": model,
        "rmse": {"y1": rmse_p0, "y2": rmse_mach},
        "max_abs_error": {"y1": max_p0, "y2": max_mach},
    }
    for condition, model, rmse_p0, rmse_mach, max_p0, max_mach in (
        # condition, model: RMSE of P0 and Ma, maximum absolute error of P0 and Ma
        ("110kPa", "block-oriented", 0.0256, 0.00033, 0.0937, 0.0012),
        ("110kPa", "conventional", 0.0287, 0.0004, 0.1252, 0.0026),
        ("130kPa", "block-oriented", 0.0367, 0.0005, 0.1105, 0.0041),
        ("130kPa", "conventional", 0.0391, 0.0009, 0.1843, 0.0059),
    )
]


@dataclass
class WindTunnelReproduction:
    """Results of :func:`reproduce_windtunnel`."""

    table: list[dict[str, Any]] = field(default_factory=list)
    parameters: dict[str, Any] = field(default_factory=dict)
    truth: dict[str, Any] = field(default_factory=dict)
    outputs: dict[str, Any] = field(default_factory=dict)  # (condition, model) -> ModelOutput
    figures: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return {
            "table": self.table,
            "parameters": self.parameters,
            "truth": self.truth,
            "paper": PAPER_TABLE,
            "figures": self.figures,
            "note": "all metrics: free-run simulation from u1, u2 on the validation record",
        }


def _datasets(condition: str, seed: int, n_samples: int) -> dict[str, Dataset]:
    from blockid.plants.windtunnel import windtunnel_experiment

    out = {}
    for kind in ("estimation", "validation"):
        df = windtunnel_experiment(condition, n_samples=n_samples, seed=seed, kind=kind)
        out[kind] = Dataset.from_frame(
            df,
            ["u1", "u2"],
            ["v1", "v2", "y1", "y2"],
            time_column="t",
            source=f"wind tunnel {condition} {kind}",
        )
    return out


def _row(condition: str, model: str, estimator: str, metrics: dict | None, error: str | None):
    row: dict[str, Any] = {"condition": condition, "model": model, "estimator": estimator}
    if metrics is None:
        row["error"] = error
        return row
    for key in ("rmse", "max_abs_error", "mse", "fit_percent"):
        row[key] = {y: metrics[key][y] for y in ("y1", "y2")}
    return row


def reproduce_windtunnel(
    seed: int = 0, n_samples: int = 1200, figures_dir: str | Path | None = None
) -> WindTunnelReproduction:
    """Run paper A's experiment on the simulated tunnel (see the module docstring)."""
    from blockid.plants.windtunnel import CONDITIONS, WindTunnelParameters

    result = WindTunnelReproduction()
    for condition in CONDITIONS:
        p = WindTunnelParameters.for_condition(condition)
        result.truth[condition] = {
            "S1": {"a": [p.valve_a], "b": [p.valve_b]},
            "S2": {
                "m_left": p.finger_backlash[0],
                "c_left": p.finger_backlash[1],
                "m_right": p.finger_backlash[2],
                "c_right": p.finger_backlash[3],
                "a": list(p.finger_a),
                "b": [p.finger_b],
            },
        }
        data = _datasets(condition, seed, n_samples)
        result.parameters[condition] = {}
        for estimator, specs in ESTIMATORS.items():
            try:
                fit = fit_network(data["estimation"], specs)
            except EstimationError as exc:
                result.table.append(_row(condition, "block-oriented", estimator, None, str(exc)))
                continue
            val = evaluate(fit.model, data["validation"], "simulation")
            result.outputs[(condition, estimator)] = val
            result.table.append(_row(condition, "block-oriented", estimator, val.metrics, None))
            net = fit.model
            s1 = net["S1"]
            result.parameters[condition][estimator] = {
                "S1": {"a": s1.a["v1"]["v1"].tolist(), "b": s1.b["v1"]["u1"].tolist()},
                "S2": net["S2"].parameters,
            }
        conv_est = subset(data["estimation"], ["u1", "u2"], ["y1", "y2"])
        conv_val = subset(data["validation"], ["u1", "u2"], ["y1", "y2"])
        conv = fit_arx(conv_est, 2, 2, 1, method="batch", center=True)
        val = evaluate(conv.model, conv_val, "simulation")
        result.outputs[(condition, "conventional")] = val
        result.table.append(_row(condition, "conventional", "least squares", val.metrics, None))
    if figures_dir is not None:
        result.figures = [str(p) for p in _figures(result, Path(figures_dir))]
    return result


def _figures(result: WindTunnelReproduction, folder: Path) -> list[Path]:
    import matplotlib.pyplot as plt

    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for condition in ("110kPa", "130kPa"):
        conv = result.outputs.get((condition, "conventional"))
        block = next(
            (
                v
                for (c, k), v in result.outputs.items()
                if c == condition and k != "conventional" and k.startswith("default")
            ),
            None,
        )
        if conv is None or block is None:
            continue
        fig, axes = plt.subplots(2, 1, figsize=(9, 5.5), sharex=True)
        exp_b = block.data.experiments[0]
        t = np.arange(exp_b.n_samples) * (block.data.sampling_time or 1.0)
        for ax, name in zip(axes, ("y1", "y2"), strict=True):
            jb = block.data.outputs.index(name)
            jc = conv.data.outputs.index(name)
            ax.plot(t, exp_b.y[:, jb], color="0.2", lw=0.9, label="measured")
            ax.plot(
                t,
                block.outputs[0][:, jb],
                color="C1",
                lw=1.0,
                label=f"block-oriented (RMSE {block.metrics['rmse'][name]:.3g})",
            )
            ax.plot(
                t,
                conv.outputs[0][:, jc],
                color="C0",
                lw=1.0,
                ls="--",
                label=f"conventional (RMSE {conv.metrics['rmse'][name]:.3g})",
            )
            ax.set_ylabel({"y1": "P0 [kPa]", "y2": "Ma"}[name])
            ax.legend(fontsize=8, loc="upper right")
        axes[0].set_title(
            f"Wind tunnel {condition}: free-run simulation from u1, u2 on the validation record",
            fontsize=10,
        )
        axes[-1].set_xlabel("time [s]")
        fig.tight_layout()
        path = folder / f"windtunnel_{condition}_validation.png"
        fig.savefig(path, dpi=110)
        paths.append(path)
    plt.close("all")
    return paths
