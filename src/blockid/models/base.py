"""Common interface of blockid's models and the registry used to load model files."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, ClassVar

import numpy as np

from blockid.errors import DataError, ModelFileError

__all__ = ["Model", "MODEL_TYPES", "OneChannel", "excursion", "model_from_dict"]

#: ``structure -> class``, filled by :meth:`Model.__init_subclass__`.
MODEL_TYPES: dict[str, type[Model]] = {}


class Model(ABC):
    """A dynamic input/output model with named signals.

    Subclasses set ``structure`` (the name used in files and on the command line) and
    implement :meth:`simulate` (free run), :meth:`predict` (one step ahead),
    :attr:`max_lag`, :meth:`to_dict` and :meth:`from_dict`.

    Both :meth:`simulate` and :meth:`predict` return arrays of the full record length
    whose first :attr:`max_lag` samples are the initial conditions (copied from the
    measured outputs when given); metrics skip those samples.
    """

    structure: ClassVar[str] = ""
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    sampling_time: float | None

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if cls.structure:
            MODEL_TYPES[cls.structure] = cls

    @property
    @abstractmethod
    def max_lag(self) -> int:
        """Number of initial samples the model needs before it can produce outputs."""

    @abstractmethod
    def simulate(self, u: Any, y_initial: Any = None) -> np.ndarray:
        """Free-run simulation from the inputs alone (own past outputs fed back)."""

    @abstractmethod
    def predict(self, u: Any, y: Any) -> np.ndarray:
        """One-step-ahead prediction from inputs and measured past outputs."""

    @abstractmethod
    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable description (structure, signals, orders, parameters)."""

    @classmethod
    @abstractmethod
    def from_dict(cls, data: dict[str, Any]) -> Model:
        """Inverse of :meth:`to_dict`."""

    def _file_header(self) -> dict[str, Any]:
        """The first fields of every model's :meth:`to_dict`: its structure, signals and
        sampling time."""
        return {
            "structure": self.structure,
            "inputs": list(self.inputs),
            "outputs": list(self.outputs),
            "sampling_time": self.sampling_time,
        }

    def _repr_html_(self) -> str:
        """The notebook display: :func:`blockid.plotting.notebook.model_html`."""
        from blockid.plotting.notebook import model_html

        return model_html(self)

    def plot(self, data: Any = None, *, which: str | None = None) -> Any:
        """The report's figures of the model (free run on ``data``, blocks, linear
        dynamics): a dict of matplotlib figures, or the one ``which`` names; see
        :func:`blockid.plotting.notebook.model_figures`."""
        from blockid.plotting.notebook import model_figures

        return model_figures(self, data, which=which)

    def parameter_table(self) -> list[tuple[str, str]]:
        """``(name, values)`` rows for a printed table of the model's parameters: its
        named ``parameters``, each list of values on one row."""
        rows = []
        for name, value in self.parameters.items():  # type: ignore[attr-defined]
            values = value if isinstance(value, list) else [value]
            rows.append((str(name), ", ".join(f"{v:.6g}" for v in values)))
        return rows

    @property
    def n_free_parameters(self) -> int:
        """How many parameters a fit of this model estimates (``free_parameters()``'s
        size; models without that vector say it themselves)."""
        return int(np.asarray(self.free_parameters()).size)  # type: ignore[attr-defined]

    @property
    def linear_blocks(self) -> tuple[Any, ...]:
        """The model's :class:`~blockid.blocks.linear.LinearBlock` s, input side first
        (none for a model not built of blocks, such as ARX)."""
        return ()

    def linear_signals(self, u: Any) -> list[tuple[Any, np.ndarray, np.ndarray]]:
        """``(block, w, x)`` for every linear block: its input ``w`` and output ``x`` in a
        free run from rest on input ``u`` (empty for a model not built of blocks)."""
        return []

    def range_excursion(self, u: Any) -> dict[str, float]:
        """How far input ``u`` drives the signals whose ranges were recorded in
        estimation beyond them (free run from rest): per signal, the largest distance
        outside its range as a fraction of the range's width (0 inside). Empty when no
        ranges are recorded (linear models)."""
        return {}

    def fitted_poles(self) -> np.ndarray:
        """The poles the model's parameters put where they are: its ``poles()`` (of the
        model linearised at its operating point) without those a block holds by
        construction (an integrator's at 1, which a chain leaves out); empty for a model
        without poles (a network: its subsystems have them)."""
        poles = getattr(self, "poles", None)
        return np.zeros(0, dtype=complex) if poles is None else np.asarray(poles(), dtype=complex)

    def block_ranges(self) -> list[tuple[str, Any, tuple[float, float]]]:
        """``(name, block, (low, high))`` for every nonlinear block whose argument's range
        in estimation is recorded ("input block", "loop block p1", ...): what the blocks'
        :meth:`~blockid.blocks.base.Block.degeneracy` is judged on. Empty for a model
        without such blocks."""
        return []

    def _check_signals(self, u: Any, y: Any = None) -> tuple[np.ndarray, np.ndarray | None]:
        """Coerce ``u`` (N, nu) and ``y`` (N, ny) and check their shapes."""
        u = _columns(u, self.inputs, "input")
        bad = ~np.isfinite(u)
        if bad.any():
            row, col = np.argwhere(bad)[0]
            raise DataError(
                f"input '{self.inputs[col]}' is {u[row, col]} at sample {row} (0-based): a "
                "model runs on finite inputs only; remove or fill the gap"
            )
        if y is not None:
            y = _columns(y, self.outputs, "output")
        return u, y


class OneChannel:
    """What a model of one input and one output with offsets (a chain of blocks, a
    feedback loop) keeps beside its blocks: its sampling time, the offsets of its two
    signals, the ranges seen in estimation, and how its file holds them."""

    inputs: tuple[str]
    outputs: tuple[str]
    sampling_time: float | None
    input_offset: float
    output_offset: float
    ranges: dict[str, list[float]]

    def output_sensitivities(self, u: Any, y_initial: Any = None) -> tuple[Any, Any]:
        """Free-run output (N, 1) and its derivative (N, 1, p) to the free parameters,
        as every model that provides its sensitivities gives them (the model's own
        ``simulate_with_sensitivities``, shaped like a model of several outputs)."""
        y, dy = self.simulate_with_sensitivities(u, y_initial)  # type: ignore[attr-defined]
        return np.asarray(y, float)[:, None], np.asarray(dy, float)[:, None, :]

    def _set_channel(
        self, sampling_time: float | None, input_offset: float, output_offset: float, ranges: Any
    ) -> None:
        self.sampling_time = sampling_time
        self.input_offset = float(input_offset)
        self.output_offset = float(output_offset)
        self.ranges = {k: [float(v[0]), float(v[1])] for k, v in (ranges or {}).items()}

    def _channel_settings(self, changes: dict[str, Any]) -> dict[str, Any]:
        """The keyword arguments that rebuild the model's sampling time, offsets and ranges
        (the ranges dropped when ``changes`` move an offset)."""
        kwargs: dict[str, Any] = dict(
            sampling_time=self.sampling_time,
            input_offset=self.input_offset,
            output_offset=self.output_offset,
            ranges=self.ranges,
        )
        if "input_offset" in changes or "output_offset" in changes:
            kwargs["ranges"] = None
        return kwargs

    def _channel_file(self) -> dict[str, Any]:
        """The last fields of the model's :meth:`~Model.to_dict`."""
        return {
            "parameters": self.parameters,  # type: ignore[attr-defined]
            "offsets": {
                "inputs": {self.inputs[0]: self.input_offset},
                "outputs": {self.outputs[0]: self.output_offset},
            },
            "estimation_ranges": self.ranges,
        }

    @staticmethod
    def _channel_from_file(data: dict[str, Any], name: str, holder: str) -> dict[str, Any]:
        """The keyword arguments :meth:`_channel_file` wrote (after checking that the file
        names one input and one output: ``name`` the model in the message, ``holder`` what
        has one of each)."""
        for key in ("inputs", "outputs"):
            if len(data[key]) != 1:
                raise ModelFileError(
                    f"the {name} model file names {len(data[key])} {key} ({data[key]}); "
                    f"{holder} has one input and one output: the file was edited or damaged"
                )
        offsets = file_offsets(data, name)
        given = {"input_offset": offsets["inputs"][0], "output_offset": offsets["outputs"][0]}
        ranges = data.get("estimation_ranges") or {}
        if not isinstance(ranges, dict) or not all(
            isinstance(v, list | tuple) and len(v) == 2 for v in ranges.values()
        ):
            raise ModelFileError(
                f"the {name} model file's estimation_ranges ({str(ranges)[:80]}) are not "
                "pairs [low, high] by signal: the file was edited or damaged, refit or restore it"
            )
        return dict(sampling_time=data.get("sampling_time"), ranges=ranges, **given)


def _columns(x: Any, names: Any, what: str) -> np.ndarray:
    """``x`` as a float array of one column per name in ``names`` (a 1-D ``x`` is one
    column); a DataError names the ``what`` ("input", "output") whose shape is wrong."""
    x = np.asarray(x, dtype=float)
    if x.ndim == 1:
        x = x[:, None]
    if x.ndim != 2 or x.shape[1] != len(names):
        raise DataError(
            f"the model has {len(names)} {what}(s) {list(names)} but got an "
            f"{what} array of shape {x.shape}"
        )
    return x


def file_offsets(data: dict[str, Any], name: str) -> dict[str, list[Any]]:
    """The offsets a model file's ``offsets`` table gives its inputs and outputs, in the
    order of its signals (``{"inputs": {name: value}, "outputs": {...}}``; a missing or
    empty table: 0); a table that does not name exactly the model's signals is refused
    (``name``: the model, for the message)."""
    offsets = data.get("offsets") or {}
    if not isinstance(offsets, dict) or (offsets and set(offsets) != {"inputs", "outputs"}):
        offsets = {"inputs": offsets, "outputs": offsets}  # what the message shows
    out: dict[str, list[Any]] = {}
    for key in ("inputs", "outputs"):
        table, names = offsets.get(key, {}), list(data[key])
        if not isinstance(table, dict) or (table and set(table) != set(names)):
            raise ModelFileError(
                f"the {name} model file's offsets of its {key} ({table!r}) must give each of "
                f"{names} a number: the file was edited or damaged, refit or restore it"
            )
        out[key] = [table.get(n, 0.0) for n in names]
    return out


def excursion(seen: Any, values: np.ndarray) -> float:
    """The largest distance of ``values`` outside ``[lo, hi]`` over ``hi - lo`` (0 inside;
    infinite for non-finite values)."""
    if values.size == 0:
        return 0.0
    if not np.all(np.isfinite(values)):
        return float("inf")
    lo, hi = seen
    span = max(hi - lo, 1e-300)
    return max(float(lo - values.min()), float(values.max() - hi), 0.0) / span


def model_from_dict(data: dict[str, Any]) -> Model:
    """Rebuild any model from its :meth:`Model.to_dict` form."""
    structure = data.get("structure") if isinstance(data, dict) else None
    if structure not in MODEL_TYPES:
        known = ", ".join(sorted(MODEL_TYPES))
        raise ModelFileError(f"unknown model structure {structure!r}; known: {known}")
    try:
        return MODEL_TYPES[structure].from_dict(data)
    except ModelFileError:
        raise
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as exc:
        raise ModelFileError(
            f"the {structure} model description is damaged or incomplete ({type(exc).__name__}: "
            f"{exc})"
        ) from None
