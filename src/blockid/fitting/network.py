"""Identify a network of subsystems, each from its own measured signals (paper A).

Each subsystem is fitted on its own input and output columns with its own structure
and method (paper A: S1 by RLS, S2 by AW-RLS, S3 by H-RLS); the result is a
:class:`~blockid.models.Network` that simulates the outputs from the external inputs
alone.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from blockid.data.dataset import Dataset, Experiment
from blockid.errors import BlockidError, DataError, EstimationError, ParameterError
from blockid.evaluation.metrics import metrics_by_output
from blockid.fitting.dispatch import fit_model
from blockid.fitting.result import FitResult, simulation_result
from blockid.models.network import Network

__all__ = ["SubsystemSpec", "parse_subsystem", "network_signals", "subset", "fit_network"]


@dataclass
class SubsystemSpec:
    """What to fit for one subsystem: signals, structure, method and options."""

    name: str
    inputs: list[str]
    outputs: list[str]
    structure: str
    method: str | None = None
    options: dict[str, Any] = field(default_factory=dict)


_SPEC = re.compile(r"^\s*([\w.-]+)\s*:\s*([^>|]+?)\s*->\s*([^|]+?)\s*\|\s*(\S+)\s*(.*)$")


def parse_subsystem(text: str) -> SubsystemSpec:
    """Read ``"S1: u1 -> v1 | arx na=1 nb=1 nk=1 method=rls"``.

    Option values stay text: :func:`~blockid.fitting.fit_model` converts and checks
    them through the registry (:mod:`blockid.fitting.registry`), as it does the
    command line's. Keys may be spelt with ``-`` or ``_`` (``input-block=dead-zone``).

    >>> s = parse_subsystem("S3: v1,v2 -> y1,y2 | arx na=2 nb=2 nk=1 method=hierarchical-rls")
    >>> s.inputs, s.outputs, s.method, s.options
    (['v1', 'v2'], ['y1', 'y2'], 'hierarchical-rls', {'na': '2', 'nb': '2', 'nk': '1'})
    """
    m = _SPEC.match(text)
    if not m:
        raise ParameterError(
            f"cannot read subsystem {text!r}; expected 'NAME: IN[,IN] -> OUT[,OUT] | "
            "STRUCTURE key=value ...', e.g. 'S1: u1 -> v1 | arx na=1 nb=1 nk=1 method=rls'"
        )
    name, ins, outs, structure, rest = m.groups()
    options: dict[str, Any] = {}
    for item in rest.split():
        if "=" not in item:
            raise ParameterError(f"subsystem {name}: option {item!r} must be key=value")
        key, val = item.split("=", 1)
        options[key.replace("-", "_")] = val
    method = options.pop("method", None)
    split = lambda s: [p.strip() for p in s.split(",") if p.strip()]  # noqa: E731
    return SubsystemSpec(name, split(ins), split(outs), structure, method, options)


def network_signals(specs: list[SubsystemSpec]) -> tuple[list[str], list[str]]:
    """The network's external inputs and the outputs its subsystems produce.

    External inputs are the subsystem inputs no subsystem produces, in order of first
    use; outputs are in the order the subsystems name them.

    >>> specs = [parse_subsystem("S1: u1 -> v1 | arx"), parse_subsystem("S2: v1,u2 -> y | arx")]
    >>> network_signals(specs)
    (['u1', 'u2'], ['v1', 'y'])
    """
    from blockid.models.network import check_wiring

    check_wiring([(spec.name, spec.inputs, spec.outputs) for spec in specs])
    outputs: list[str] = []
    for spec in specs:
        outputs += [o for o in spec.outputs if o not in outputs]
    inputs: list[str] = []
    for spec in specs:
        inputs += [i for i in spec.inputs if i not in outputs and i not in inputs]
    return inputs, outputs


def subset(data: Dataset, inputs: list[str], outputs: list[str]) -> Dataset:
    """The same experiments with the named columns (from inputs or outputs) only."""
    table = {n: ("u", j) for j, n in enumerate(data.inputs)}
    table.update({n: ("y", j) for j, n in enumerate(data.outputs)})
    missing = [n for n in [*inputs, *outputs] if n not in table]
    if missing:
        raise DataError(f"signal(s) {missing} are not in the data; available: {sorted(table)}")

    def cols(e: Experiment, names: list[str]) -> np.ndarray:
        return np.column_stack([getattr(e, table[n][0])[:, table[n][1]] for n in names])

    exps = [Experiment(e.name, cols(e, inputs), cols(e, outputs)) for e in data.experiments]
    return Dataset(tuple(inputs), tuple(outputs), data.sampling_time, exps, data.source)


def fit_network(data: Dataset, specs: list[SubsystemSpec]) -> FitResult:
    """Fit every subsystem on its own measured signals and assemble the network.

    ``data`` must contain every signal the specs name (internal signals such as v1, v2
    measured, as in paper A).
    """
    subsystems, settings, metrics = [], {}, {}
    for spec in specs:
        sub = subset(data, spec.inputs, spec.outputs)
        try:
            res = fit_model(sub, spec.structure, method=spec.method, **spec.options)
        except BlockidError as exc:
            raise type(exc)(f"subsystem {spec.name}: {exc}") from None
        except (TypeError, ValueError) as exc:
            shown = " ".join(f"{k}={v}" for k, v in spec.options.items())
            raise ParameterError(
                f"subsystem {spec.name}: an option value does not fit ({shown}): {exc}"
            ) from None
        subsystems.append((spec.name, res.model))
        settings[spec.name] = {"structure": spec.structure, "method": res.method, **res.settings}
        metrics[spec.name] = res.estimation_metrics
    network = Network(subsystems, sampling_time=data.sampling_time)
    net_data = subset(data, list(network.inputs), list(network.outputs))
    skip = network.max_lag
    y = np.vstack([e.y[skip:] for e in net_data.experiments])
    y_sim = np.vstack([network.simulate(e.u, e.y[:skip])[skip:] for e in net_data.experiments])
    if not np.all(np.isfinite(y_sim)):
        raise EstimationError("the assembled network's free-run simulation is not finite")
    return simulation_result(
        network,
        data,
        "network",
        {"subsystems": settings},
        metrics_by_output(y, y_sim, network.outputs),
    )
