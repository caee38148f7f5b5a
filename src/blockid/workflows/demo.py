"""The built-in example run by ``blockid demo`` / ``make demo``."""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["run_demo"]


def run_demo(output_dir: str | Path, seed: int = 0) -> dict[str, Any]:
    """Identify paper A's wind-tunnel actuator loop and flow field from simulated data.

    Writes the data (``windtunnel_estimation.csv``, ``windtunnel_validation.csv``), the
    model files and a figure to ``output_dir`` and returns the numbers: the exhaust
    valve loop S1 identified by RLS against the simulator's truth, and the flow field S3
    (two-input two-output ARX, na = nb = 2, nk = 1) by batch least squares and by
    hierarchical RLS, scored by free-run simulation on the validation record.
    """
    from blockid.data import Dataset
    from blockid.evaluation import evaluate
    from blockid.fitting import fit_arx, subset
    from blockid.models import save_model
    from blockid.plants.windtunnel import windtunnel_experiment
    from blockid.plotting import plot_model_output

    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    frames = {
        kind: windtunnel_experiment("110kPa", seed=seed, kind=kind)
        for kind in ("estimation", "validation")
    }
    data = {}
    for kind, df in frames.items():
        df.drop(columns=["x_true"]).to_csv(out / f"windtunnel_{kind}.csv", index=False)
        data[kind] = Dataset.from_frame(
            df, ["u1", "u2"], ["v1", "v2", "y1", "y2"], time_column="t", source=kind
        )
    s1 = fit_arx(subset(data["estimation"], ["u1"], ["v1"]), 1, 1, 1, method="rls")
    save_model(s1.model, out / "s1_exhaust_valve.json", s1.estimation_record(), overwrite=True)
    flow = {}
    for method, kw in (("batch", {}), ("hierarchical-rls", {"forgetting": 0.98, "passes": 5})):
        res = fit_arx(
            subset(data["estimation"], ["v1", "v2"], ["y1", "y2"]),
            2,
            2,
            1,
            method=method,
            center=True,
            max_mse_ratio=None,
            **kw,
        )
        val = evaluate(res.model, subset(data["validation"], ["v1", "v2"], ["y1", "y2"]))
        flow[method] = val
        save_model(
            res.model, out / f"s3_flow_field_{method}.json", res.estimation_record(), overwrite=True
        )
    fig = plot_model_output(flow["batch"], data_label="validation record (110 kPa)")
    fig.savefig(out / "flow_field_simulation.png", dpi=110)
    return {
        "s1": {
            "a": s1.model.a["v1"]["v1"].tolist(),
            "b": s1.model.b["v1"]["u1"].tolist(),
            "true": {"a": [-0.62], "b": [0.39]},
        },
        "flow_field": {m: v.metrics for m, v in flow.items()},
        "output_dir": str(out),
    }
