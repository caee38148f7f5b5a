"""Networks of models connected by named signals (paper A's block-oriented network).

Paper A models the wind tunnel as three subsystems::

    u1 -> S1 (ARX)                  -> v1 --+
    u2 -> S2 (backlash -> linear)   -> v2 --+--> S3 (two-input two-output ARX) -> y1, y2

A :class:`Network` holds subsystems (any blockid models) in an order in which every
subsystem's inputs are either external inputs of the network or outputs of earlier
subsystems. Its inputs are the external inputs; its outputs are the outputs of all
subsystems (internal signals such as v1, v2 included), so that measured internal
signals can provide initial conditions and be scored too.

Free-run simulation runs the subsystems in order, each fed with *simulated* upstream
signals: the network output is computed from the external inputs alone. One-step
prediction runs each subsystem on measured signals.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from blockid.errors import ModelFileError, OrderError
from blockid.models.base import Model, model_from_dict

__all__ = ["Network", "check_wiring"]


def check_wiring(connections: Sequence[tuple[str, Sequence[str], Sequence[str]]]) -> None:
    """Refuse wiring a network cannot simulate: a cycle, or a signal made twice.

    Parameters
    ----------
    connections : sequence of (name, inputs, outputs)
        Each subsystem's name and the signals it reads and makes.

    Raises
    ------
    OrderError
        Naming the cycle (``'S1' -> v1 -> 'S2' -> v2 -> 'S1'``): every signal in it is
        made inside the network, so none is an external input and the loop has no
        start; naming a signal two subsystems make, a name two subsystems share, or a
        subsystem that reads or makes no signal.

    Examples
    --------
    >>> check_wiring([("S1", ["u"], ["v"]), ("S2", ["v"], ["y"])])
    >>> try:
    ...     check_wiring([("S1", ["v2"], ["v1"]), ("S2", ["v1"], ["v2"])])
    ... except OrderError as exc:
    ...     print(str(exc).split(";")[0])
    the subsystems form a cycle: 'S1' -> v1 -> 'S2' -> v2 -> 'S1'
    """
    names = [name for name, _, _ in connections]
    for name, inputs, outputs in connections:
        if names.count(name) > 1:
            raise OrderError(
                f"{names.count(name)} subsystems are named {name!r}; give each its own name"
            )
        for what, signals in (("reads", inputs), ("makes", outputs)):
            if not signals:
                raise OrderError(f"subsystem {name!r} {what} no signal; name at least one")
    maker: dict[str, str] = {}
    for name, _, outputs in connections:
        for sig in outputs:
            if sig in maker:
                raise OrderError(
                    f"signal {sig!r} is made by subsystem {maker[sig]!r} and by {name!r}; "
                    "each signal must come from one subsystem"
                )
            maker[sig] = name
    reads = {name: list(inputs) for name, inputs, _ in connections}
    state: dict[str, int] = {}  # 1: on the current path, 2: done

    def visit(name: str, path: list[tuple[str, str]]) -> None:
        state[name] = 1
        for sig in reads[name]:
            up = maker.get(sig)
            if up is None or state.get(up) == 2:
                continue
            if state.get(up) == 1:  # back to a subsystem on the path: a cycle
                loop = path[[n for n, _ in path].index(up) :] if up != name else []
                steps = [*loop, (name, sig)] if up != name else [(name, sig)]
                text = " -> ".join(f"{n!r} -> {s}" for n, s in _downstream(steps))
                raise OrderError(
                    f"the subsystems form a cycle: {text} -> {up!r}; every signal in it is "
                    "made inside the network, so the loop has no external input to start "
                    "from. Feed one of them from outside (a measured input), or model the "
                    "loop inside one subsystem"
                )
            visit(up, [*path, (name, sig)])
        state[name] = 2

    for name, _, _ in connections:
        if name not in state:
            visit(name, [])


def _downstream(steps: list[tuple[str, str]]) -> list[tuple[str, str]]:
    """A cycle found walking upstream (``(reader, signal read)`` pairs), written in the
    direction the signals flow: ``(maker, signal made)`` pairs."""
    reversed_steps = steps[::-1]
    makers = [reversed_steps[-1][0], *[n for n, _ in reversed_steps[:-1]]]
    return [(m, sig) for m, (_, sig) in zip(makers, reversed_steps, strict=True)]


class Network(Model):
    """Subsystems connected by signal names.

    Parameters
    ----------
    subsystems : sequence of (name, Model)
        In an order where each subsystem's inputs are external or produced earlier.
    sampling_time : float, optional

    Examples
    --------
    >>> from blockid.models import ARX
    >>> s1 = ARX(["u1"], ["v1"], 1, 1, 1, a={"v1": {"v1": [-0.62]}}, b={"v1": {"u1": [0.39]}})
    >>> s3 = ARX(["v1"], ["y1"], 1, 1, 1, a={"y1": {"y1": [-0.5]}}, b={"y1": {"v1": [1.0]}})
    >>> net = Network([("S1", s1), ("S3", s3)])
    >>> net.inputs, net.outputs
    (('u1',), ('v1', 'y1'))
    """

    structure = "network"

    def __init__(
        self, subsystems: Sequence[tuple[str, Model]], sampling_time: float | None = None
    ) -> None:
        self.subsystems = [(str(name), model) for name, model in subsystems]
        if not self.subsystems:
            raise OrderError("a network needs at least one subsystem")
        names = [n for n, _ in self.subsystems]
        if len(set(names)) != len(names):
            raise OrderError(f"subsystem names must be unique; got {names}")
        check_wiring([(n, m.inputs, m.outputs) for n, m in self.subsystems])
        produced: list[str] = []
        external: list[str] = []
        for name, model in self.subsystems:
            for sig in model.inputs:
                if sig not in produced and sig not in external:
                    external.append(sig)
            for sig in model.outputs:
                if sig in produced or sig in external:
                    raise OrderError(
                        f"signal {sig!r} of subsystem {name!r} is produced twice or used before "
                        "it is produced; list subsystems upstream first, each signal made once"
                    )
                produced.append(sig)
        self.inputs = tuple(external)
        self.outputs = tuple(produced)
        self.sampling_time = sampling_time

    def __getitem__(self, name: str) -> Model:
        for n, model in self.subsystems:
            if n == name:
                return model
        raise KeyError(name)

    @property
    def max_lag(self) -> int:
        return max(model.max_lag for _, model in self.subsystems)

    def _columns(self, model: Model, table: dict[str, np.ndarray], which: str) -> np.ndarray:
        names = model.inputs if which == "inputs" else model.outputs
        return np.column_stack([table[n] for n in names])

    def simulate(self, u: Any, y_initial: Any = None) -> np.ndarray:
        """Free-run simulation of every subsystem from the external inputs alone.

        ``y_initial`` (rows: first samples; columns: :attr:`outputs`) gives each
        subsystem's initial outputs; without it every subsystem starts at rest. Up to
        :attr:`max_lag` rows, each subsystem gets its own ``max_lag`` first of them;
        more rows go to every subsystem whole (a chain then estimates its start:
        :meth:`ChainModel.simulate <blockid.models.ChainModel.simulate>`).
        """
        u, _ = self._check_signals(u)
        y0 = None
        if y_initial is not None:
            _, y0 = self._check_signals(u[: len(np.asarray(y_initial))], y_initial)
        table = {name: u[:, j] for j, name in enumerate(self.inputs)}
        for _, model in self.subsystems:
            init = None
            if y0 is not None:
                cols = [self.outputs.index(n) for n in model.outputs]
                rows = y0.shape[0] if y0.shape[0] > self.max_lag else model.max_lag
                init = y0[:rows, cols]
            out = model.simulate(self._columns(model, table, "inputs"), init)
            for j, name in enumerate(model.outputs):
                table[name] = out[:, j]
        return np.column_stack([table[n] for n in self.outputs])

    def predict(self, u: Any, y: Any) -> np.ndarray:
        """One-step-ahead prediction of each subsystem from measured signals."""
        u, y = self._check_signals(u, y)
        table = {name: u[:, j] for j, name in enumerate(self.inputs)}
        table.update({name: y[:, j] for j, name in enumerate(self.outputs)})
        out = []
        for _, model in self.subsystems:
            out.append(
                model.predict(
                    self._columns(model, table, "inputs"), self._columns(model, table, "outputs")
                )
            )
        pred = np.column_stack(out)
        order = [n for _, m in self.subsystems for n in m.outputs]
        return pred[:, [order.index(n) for n in self.outputs]]

    def parameter_table(self) -> list[tuple[str, str]]:
        """One row per subsystem: its name and structure (their own files hold more)."""
        return [(name, sub.structure) for name, sub in self.subsystems]

    def to_dict(self) -> dict[str, Any]:
        return {
            **self._file_header(),
            "subsystems": [{"name": n, "model": m.to_dict()} for n, m in self.subsystems],
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Network:
        subs = data["subsystems"]
        if not isinstance(subs, list):
            raise ModelFileError("a network's 'subsystems' must be a list")
        subsystems = []
        for s in subs:
            try:
                subsystems.append((s["name"], model_from_dict(s["model"])))
            except ModelFileError as exc:  # say which subsystem is damaged
                raise ModelFileError(f"subsystem {s['name']!r}: {exc}") from None
        return cls(subsystems, sampling_time=data.get("sampling_time"))
