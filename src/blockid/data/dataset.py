"""Input/output records: :class:`Experiment` and :class:`Dataset`.

A :class:`Dataset` holds one or more experiments recorded on the same plant, with the same
named input signals ``u`` and output signals ``y`` and, when known, one sampling time.
Each experiment is a contiguous record; models and estimators never join two experiments
into one regression (the first ``max_lag`` samples of every experiment only serve as
initial conditions).

Every check that can fail on user data raises :class:`~blockid.errors.DataError` whose
message names the source (file), column, data row and value, and says how to fix it.
On the happy path all checks are vectorised; the offending row is located only once an
error has been found.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from blockid.errors import DataError, OrderError, ParameterError

__all__ = ["Experiment", "Dataset"]

#: Relative tolerance on sampling-time agreement and on time-step jitter (1 %).
_TIME_TOLERANCE = 0.01

#: Function that maps 0-based data row positions to ``(file line, raw fields by column)``.
Locator = Callable[[Sequence[int]], Mapping[int, tuple[int, Mapping[str, str]]]]


def _frozen_2d(values: Any, what: str) -> np.ndarray:
    """Return ``values`` as a read-only C-contiguous float64 array of shape (N, k).

    A caller's writable array is copied, so that the record cannot change behind the
    dataset's back; an array that is already read-only float64 is used as it is.
    """
    try:
        arr = np.asarray(values)
    except ValueError as exc:  # a ragged list: rows of unequal length
        raise DataError(
            f"{what} is not a rectangular array ({exc}); give one array of samples x "
            "signals (several records: one Experiment each)"
        ) from None
    if arr.dtype.kind == "c":
        raise DataError(f"{what} is complex; blockid needs real-valued signals")
    try:
        arr = np.asarray(arr, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise DataError(f"{what} is not numeric ({exc})") from None
    if arr.ndim == 1:
        arr = arr.reshape(-1, 1)
    if arr.ndim != 2:
        raise DataError(
            f"{what} must be 1-D (one signal) or 2-D (samples x signals), got {arr.ndim}-D"
        )
    if arr.flags.writeable or not arr.flags.c_contiguous:
        arr = np.array(arr, dtype=np.float64, order="C", copy=True)
        arr.flags.writeable = False
    return arr


@dataclass(frozen=True, eq=False, repr=False)
class Experiment:
    """One contiguous input/output record.

    Parameters
    ----------
    name : str
        Name used in messages, plots and tables (file stem, experiment-column value...).
    u : ndarray of shape (N, nu)
        Input samples, float64. A 1-D array is taken as one input.
    y : ndarray of shape (N, ny)
        Output samples, float64. A 1-D array is taken as one output.

    Notes
    -----
    The arrays are stored read-only (a writable array passed in is copied first): an
    experiment is an immutable record. Copy an array before changing it.
    """

    name: str
    u: np.ndarray
    y: np.ndarray

    def __post_init__(self) -> None:
        u = _frozen_2d(self.u, f"experiment '{self.name}': u")
        y = _frozen_2d(self.y, f"experiment '{self.name}': y")
        if u.shape[0] != y.shape[0]:
            raise DataError(
                f"experiment '{self.name}': u has {u.shape[0]} samples but y has "
                f"{y.shape[0]}; every input and output needs one value per sample"
            )
        object.__setattr__(self, "u", u)
        object.__setattr__(self, "y", y)

    @property
    def n_samples(self) -> int:
        """Number of samples N."""
        return int(self.u.shape[0])

    def __repr__(self) -> str:
        return (
            f"Experiment(name={self.name!r}, n_samples={self.n_samples}, "
            f"nu={self.u.shape[1]}, ny={self.y.shape[1]})"
        )


def _check_signal_names(inputs: Iterable[str], outputs: Iterable[str]) -> tuple[tuple, tuple]:
    """Validate signal names: strings, non-empty, unique, not both input and output."""
    if isinstance(inputs, str) or isinstance(outputs, str):
        # A bare string is a sequence of characters: take it as one name.
        inputs = (inputs,) if isinstance(inputs, str) else inputs
        outputs = (outputs,) if isinstance(outputs, str) else outputs
    ins, outs = tuple(inputs), tuple(outputs)
    for kind, names in (("input", ins), ("output", outs)):
        if not names:
            raise DataError(f"no {kind} signal given; name at least one {kind} column")
        for name in names:
            if not isinstance(name, str) or not name:
                raise DataError(f"{kind} signal names must be non-empty strings, got {name!r}")
        seen: set[str] = set()
        for name in names:
            if name in seen:
                raise DataError(f"{kind} signal '{name}' is listed twice")
            seen.add(name)
    both = [name for name in ins if name in outs]
    if both:
        raise DataError(
            f"signal '{both[0]}' is listed both as an input and as an output; "
            "a signal is either one or the other"
        )
    return ins, outs


def _check_sampling_time(sampling_time: float | None) -> float | None:
    if sampling_time is None:
        return None
    try:
        value = float(sampling_time)
    except (TypeError, ValueError):
        raise ParameterError(
            f"sampling_time must be a positive number of seconds, got {sampling_time!r}",
            parameter="sampling_time",
        ) from None
    if not np.isfinite(value) or value <= 0.0:
        raise ParameterError(
            f"sampling_time must be a positive number of seconds, got {value!r}",
            parameter="sampling_time",
        )
    return value


def _close_matches(name: str, available: Sequence[str]) -> list[str]:
    """Names in ``available`` that look like ``name`` (same letters ignoring case first)."""
    same_case = [a for a in available if a.lower() == name.lower() or a.strip() == name.strip()]
    close = difflib.get_close_matches(name, list(available), n=3, cutoff=0.6)
    return list(dict.fromkeys(same_case + close))


def _name_list(names: Sequence[str], limit: int = 30) -> str:
    shown = ", ".join(f"'{n}'" for n in names[:limit])
    if len(names) > limit:
        shown += f" ... ({len(names) - limit} more)"
    return shown


def _unknown_name_message(prefix: str, kind: str, name: str, available: Sequence[str]) -> str:
    """``<source>: no column 'x' (did you mean 'y'?); available columns: ...``."""
    message = f"{prefix}no {kind} '{name}'"
    matches = _close_matches(name, available)
    if matches:
        message += f" (did you mean {' or '.join(repr(m) for m in matches)}?)"
    if available:
        message += f"; available {kind}s: {_name_list(list(available))}"
    else:
        message += f"; there are no {kind}s"
    return message


@dataclass(frozen=True, eq=False, repr=False)
class Dataset:
    """Input/output data of one plant: named signals, a sampling time, experiments.

    Parameters
    ----------
    inputs : tuple of str
        Names of the input signals, in the column order of every ``Experiment.u``.
    outputs : tuple of str
        Names of the output signals, in the column order of every ``Experiment.y``.
    sampling_time : float or None
        Sampling period in seconds (or the unit of the time column), ``None`` if unknown.
    experiments : list of Experiment
        One or more records with unique names.
    source : str or None
        Where the data came from (file names); used in error messages.

    Notes
    -----
    ``len(dataset)`` and :attr:`n_samples` give the total number of samples over all
    experiments; :attr:`n_experiments` the number of experiments.

    Examples
    --------
    >>> import numpy as np
    >>> data = Dataset.from_arrays(np.arange(5.0), 2 * np.arange(5.0), sampling_time=0.1)
    >>> data.inputs, data.outputs, len(data)
    (('u1',), ('y1',), 5)
    >>> data.select(1, 4).signal("y1")[0]
    array([2., 4., 6.])
    """

    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    sampling_time: float | None
    experiments: list[Experiment] = field(default_factory=list)
    source: str | None = None

    def __post_init__(self) -> None:
        inputs, outputs = _check_signal_names(self.inputs, self.outputs)
        object.__setattr__(self, "inputs", inputs)
        object.__setattr__(self, "outputs", outputs)
        object.__setattr__(self, "sampling_time", _check_sampling_time(self.sampling_time))
        experiments = list(self.experiments)
        object.__setattr__(self, "experiments", experiments)
        prefix = f"{self.source}: " if self.source else ""
        if not experiments:
            raise DataError(f"{prefix}the data set has no experiments")
        names: set[str] = set()
        for exp in experiments:
            if not isinstance(exp, Experiment):
                raise DataError(f"experiments must be Experiment objects, got {type(exp).__name__}")
            if exp.name in names:
                raise DataError(
                    f"{prefix}experiment name '{exp.name}' appears twice; "
                    "experiment names must be unique"
                )
            names.add(exp.name)
            if exp.u.shape[1] != len(inputs) or exp.y.shape[1] != len(outputs):
                raise DataError(
                    f"{prefix}experiment '{exp.name}' has {exp.u.shape[1]} input and "
                    f"{exp.y.shape[1]} output columns, but {len(inputs)} inputs "
                    f"({_name_list(inputs)}) and {len(outputs)} outputs "
                    f"({_name_list(outputs)}) are named"
                )
            if exp.n_samples == 0:
                raise DataError(f"{prefix}experiment '{exp.name}' has no samples")

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_arrays(
        cls,
        u: Any,
        y: Any,
        inputs: Sequence[str] | None = None,
        outputs: Sequence[str] | None = None,
        sampling_time: float | None = None,
        name: str = "experiment 1",
    ) -> Dataset:
        """Build a one-experiment data set from arrays.

        Parameters
        ----------
        u : array_like of shape (N,) or (N, nu)
            Input samples.
        y : array_like of shape (N,) or (N, ny)
            Output samples.
        inputs, outputs : sequence of str, optional
            Signal names; default ``u1, u2, ...`` and ``y1, y2, ...``.
        sampling_time : float, optional
            Sampling period.
        name : str
            Experiment name.

        Returns
        -------
        Dataset

        Raises
        ------
        DataError
            If ``u`` and ``y`` differ in length, the names do not match the number of
            columns, or a value is NaN or infinite.
        """
        u2 = _frozen_2d(u, "u")
        y2 = _frozen_2d(y, "y")
        if u2.shape[0] != y2.shape[0]:
            raise DataError(
                f"u has {u2.shape[0]} samples but y has {y2.shape[0]}; "
                "inputs and outputs need one value per sample"
            )
        ins = tuple(f"u{i + 1}" for i in range(u2.shape[1])) if inputs is None else inputs
        outs = tuple(f"y{i + 1}" for i in range(y2.shape[1])) if outputs is None else outputs
        ins, outs = _check_signal_names(ins, outs)
        for arr, names, label in ((u2, ins, "u"), (y2, outs, "y")):
            if arr.shape[1] != len(names):
                raise DataError(
                    f"{label} has {arr.shape[1]} columns but {len(names)} names were given "
                    f"({_name_list(names)})"
                )
            bad = ~np.isfinite(arr)
            if bad.any():
                row, col = np.argwhere(bad)[0]
                raise DataError(
                    f"signal '{names[col]}' is {arr[row, col]} at sample {row} (0-based); "
                    "remove or fill the gap before identification"
                )
            huge = np.abs(arr) > LARGEST_VALUE
            if huge.any():
                row, col = np.argwhere(huge)[0]
                raise DataError(
                    f"signal '{names[col]}' is {arr[row, col]:.6g} at sample {row} (0-based): "
                    f"{_TOO_LARGE}"
                )
        return cls(ins, outs, sampling_time, [Experiment(name, u2, y2)])

    @classmethod
    def from_frame(
        cls,
        df: pd.DataFrame,
        inputs: Sequence[str],
        outputs: Sequence[str],
        sampling_time: float | None = None,
        time_column: str | None = None,
        experiment_column: str | None = None,
        source: str | None = None,
    ) -> Dataset:
        """Build a data set from the columns of a DataFrame.

        Parameters
        ----------
        df : DataFrame
            One row per sample.
        inputs, outputs : sequence of str
            Column names of the input and output signals.
        sampling_time : float, optional
            Sampling period. If ``time_column`` is also given, the two must agree to 1 %.
        time_column : str, optional
            Column with the sample times (numbers, or ISO 8601 date-times converted to
            seconds). The sampling time is the median step; the times must increase with
            steps that stay within 1 % of it (within each experiment).
        experiment_column : str, optional
            Column whose value labels the experiment of each row. Rows of one experiment
            must be contiguous; experiments keep the order of first appearance and are
            named ``str(value)``. Without it the frame is one experiment "experiment 1".
        source : str, optional
            Name of the origin (file), used in error messages.

        Returns
        -------
        Dataset

        Raises
        ------
        DataError
            For a missing column, a non-numeric, empty, NaN or infinite cell, an empty
            frame, or a time column that is not increasing or not uniform. Data rows are
            numbered from 1 in the messages.
        """
        return _frame_to_dataset(
            df,
            inputs,
            outputs,
            sampling_time=sampling_time,
            time_column=time_column,
            experiment_column=experiment_column,
            source=source,
        )

    # ------------------------------------------------------------------ properties
    @property
    def n_samples(self) -> int:
        """Total number of samples over all experiments."""
        return sum(exp.n_samples for exp in self.experiments)

    @property
    def n_experiments(self) -> int:
        """Number of experiments."""
        return len(self.experiments)

    @property
    def n_inputs(self) -> int:
        """Number of input signals nu."""
        return len(self.inputs)

    @property
    def n_outputs(self) -> int:
        """Number of output signals ny."""
        return len(self.outputs)

    def __len__(self) -> int:
        return self.n_samples

    def __repr__(self) -> str:
        return (
            f"Dataset(inputs={self.inputs!r}, outputs={self.outputs!r}, "
            f"sampling_time={self.sampling_time!r}, experiments={self.n_experiments}, "
            f"n_samples={self.n_samples}, source={self.source!r})"
        )

    # ------------------------------------------------------------------ access
    def signal(self, name: str) -> list[np.ndarray]:
        """Samples of one signal: a list of 1-D arrays, one per experiment.

        Raises
        ------
        DataError
            If no input or output has that name (close names are suggested).
        """
        if name in self.inputs:
            j = self.inputs.index(name)
            return [np.ascontiguousarray(exp.u[:, j]) for exp in self.experiments]
        if name in self.outputs:
            j = self.outputs.index(name)
            return [np.ascontiguousarray(exp.y[:, j]) for exp in self.experiments]
        prefix = f"{self.source}: " if self.source else ""
        raise DataError(_unknown_name_message(prefix, "signal", name, self.inputs + self.outputs))

    def select(
        self, start: int | None = None, stop: int | None = None, what: str = "range"
    ) -> Dataset:
        """Keep samples ``start <= k < stop`` of every experiment (Python slice rules).

        Parameters
        ----------
        start, stop : int or None
            0-based sample indices, ``stop`` excluded; ``None`` is an open end. Negative
            indices are not allowed.
        what : str
            Name of the option the range came from, used in error messages.

        Returns
        -------
        Dataset
            A new data set sharing (read-only) memory with this one.

        Raises
        ------
        DataError
            If an index is negative, the range is empty, or it does not fit inside an
            experiment.
        """
        text = f"{'' if start is None else start}:{'' if stop is None else stop}"
        prefix = f"{self.source}: " if self.source else ""
        for value in (start, stop):
            if value is not None and (
                isinstance(value, bool) or not isinstance(value, int | np.integer)
            ):
                raise DataError(f"{what} {text}: sample indices must be integers")
            if value is not None and value < 0:
                raise DataError(
                    f"{what} {text}: negative sample indices are not allowed; "
                    "give 0-based indices from the start of each experiment"
                )
        lo = 0 if start is None else int(start)
        if stop is not None and int(stop) <= lo:
            raise DataError(f"{what} {text} is empty: the stop index must be larger than the start")
        selected = []
        for exp in self.experiments:
            n = exp.n_samples
            hi = n if stop is None else int(stop)
            if lo >= n or hi > n:
                raise DataError(
                    f"{prefix}{what} {text} does not fit experiment '{exp.name}', which has "
                    f"{n} samples (indices 0 to {n - 1}; a valid range is within 0:{n})"
                )
            selected.append(Experiment(exp.name, exp.u[lo:hi], exp.y[lo:hi]))
        return Dataset(self.inputs, self.outputs, self.sampling_time, selected, self.source)

    def shifted(self, u_offset: Any, y_offset: Any) -> Dataset:
        """The same record less the offsets (a number, or one per input / output), as
        the centred fits use it; names, sampling time and source kept."""
        return Dataset(
            self.inputs, self.outputs, self.sampling_time,
            [Experiment(e.name, e.u - u_offset, e.y - y_offset) for e in self.experiments],
            self.source,
        )  # fmt: skip

    def check_orders(self, max_lag: int, n_parameters: int, what: str) -> None:
        """Check that every experiment is long enough for a model.

        A regression on lags up to ``max_lag`` uses samples ``max_lag .. N-1`` of each
        experiment, so each needs more than ``max_lag`` samples, and all together must
        give at least one regression row per parameter:

        .. math:: \\sum_e (N_e - \\text{max\\_lag}) \\ge n_\\theta

        Parameters
        ----------
        max_lag : int
            Largest lag the model uses (e.g. ``max(na, nk + nb - 1)``).
        n_parameters : int
            Number of parameters to estimate.
        what : str
            What asks for it, e.g. ``"ARX model na=2, nb=2, nk=1"``; starts the message.

        Raises
        ------
        OrderError
            If the data are too short.
        """
        if max_lag < 0 or n_parameters < 1:
            raise ParameterError(
                f"check_orders needs max_lag >= 0 and n_parameters >= 1, got {max_lag}, "
                f"{n_parameters}"
            )
        for exp in self.experiments:
            if exp.n_samples <= max_lag:
                raise OrderError(
                    f"{what} looks back {max_lag} samples, so it needs more than {max_lag} "
                    f"samples in every experiment, but experiment '{exp.name}' has only "
                    f"{exp.n_samples}; lower the orders or delay, or use a longer range"
                )
        available = sum(exp.n_samples - max_lag for exp in self.experiments)
        if available < n_parameters:
            raise OrderError(
                f"{what} has {n_parameters} parameters and needs at least {n_parameters} "
                f"regression rows, but the data give only {available} ({self.n_samples} "
                f"samples minus {max_lag} initial samples per experiment); lower the "
                "orders or use a longer range"
            )

    def to_frame(self) -> pd.DataFrame:
        """All samples as one DataFrame.

        Columns: ``experiment`` (only with more than one experiment), ``time`` (only with
        a sampling time; starts at 0 in each experiment), then inputs, then outputs.
        """
        extra = (["experiment"] if self.n_experiments > 1 else []) + (
            ["time"] if self.sampling_time is not None else []
        )
        clash = [name for name in extra if name in self.inputs + self.outputs]
        if clash:
            raise DataError(
                f"cannot build a table: signal '{clash[0]}' has the name of the "
                f"'{clash[0]}' column; rename the signal"
            )
        columns: dict[str, Any] = {}
        if self.n_experiments > 1:
            columns["experiment"] = np.repeat(
                np.array([exp.name for exp in self.experiments], dtype=object),
                [exp.n_samples for exp in self.experiments],
            )
        if self.sampling_time is not None:
            columns["time"] = np.concatenate(
                [np.arange(exp.n_samples) * self.sampling_time for exp in self.experiments]
            )
        u = np.concatenate([exp.u for exp in self.experiments])
        y = np.concatenate([exp.y for exp in self.experiments])
        for j, name in enumerate(self.inputs):
            columns[name] = u[:, j]
        for j, name in enumerate(self.outputs):
            columns[name] = y[:, j]
        return pd.DataFrame(columns)


# ---------------------------------------------------------------------- frame parsing
class _Where:
    """Describes positions in one table for error messages.

    ``label`` names a column ("column" for tables, "variable" for .mat files);
    ``row_label`` a row ("data row" or "sample"). ``locate`` optionally maps data rows to
    file lines and the raw text of the cells, and is called only on the error path.
    """

    def __init__(
        self,
        source: str | None,
        label: str = "column",
        row_label: str = "data row",
        locate: Locator | None = None,
    ) -> None:
        self.source = source
        self.label = label
        self.row_label = row_label
        self.locate = locate
        self._found: dict[int, tuple[int, Mapping[str, str]]] = {}  # rows located so far

    @property
    def prefix(self) -> str:
        return f"{self.source}: " if self.source else ""

    def _located(self, rows: Sequence[int]) -> Mapping[int, tuple[int, Mapping[str, str]]]:
        missing = [r for r in rows if r not in self._found]
        if self.locate is not None and missing:
            try:
                self._found.update(self.locate(missing))
            except (OSError, ValueError):  # the message is still right without the line
                pass
        return self._found

    def rows(self, *rows: int) -> str:
        """``data row 5 (line 6)`` or ``data rows 5 and 6 (lines 6 and 7)``."""
        found = self._located(rows)
        numbers = " and ".join(str(r + 1) for r in rows)
        text = f"{self.row_label}{'s' if len(rows) > 1 else ''} {numbers}"
        if all(r in found for r in rows):
            lines = " and ".join(str(found[r][0]) for r in rows)
            text += f" (line{'s' if len(rows) > 1 else ''} {lines})"
        return text

    def raw(self, row: int, column: str) -> str | None:
        """The cell's text in the file, if known."""
        found = self._located([row])
        if row in found:
            return found[row][1].get(column, "")
        return None


def _num(value: float) -> str:
    """A number for a message: ``0.05``, not ``np.float64(0.05)`` or 0.05000000000000071."""
    return f"{float(value):.10g}"


def _decimal_comma_hint(text: str) -> str:
    stripped = text.strip().lstrip("+-")
    if stripped.count(",") == 1 and stripped.replace(",", "").isdigit():
        return " (a decimal comma? blockid expects a decimal point, as in 1.5)"
    return ""


def _numeric_column(df: pd.DataFrame, column: Any, name: str, where: _Where) -> np.ndarray:
    """One column as float64; errors name the first non-numeric, empty or non-finite cell."""
    series = df[column]
    if isinstance(series, pd.DataFrame):
        raise DataError(
            f"{where.prefix}{where.label} '{name}' appears more than once; "
            f"give every {where.label} a unique name"
        )
    dtype = series.dtype
    if pd.api.types.is_bool_dtype(dtype) or (
        pd.api.types.is_numeric_dtype(dtype) and not pd.api.types.is_complex_dtype(dtype)
    ):
        values = series.to_numpy(dtype=np.float64, na_value=np.nan)
    else:
        converted = pd.to_numeric(series, errors="coerce")
        not_numbers = (converted.isna() & series.notna()).to_numpy()
        if not_numbers.any():
            row = int(np.argmax(not_numbers))
            raw = where.raw(row, name)
            value = raw if raw is not None else str(series.iloc[row])
            raise DataError(
                f"{where.prefix}{where.label} '{name}', {where.rows(row)}: {value!r} is not "
                f"a number{_decimal_comma_hint(value)}; fix or remove that row"
            )
        values = converted.to_numpy(dtype=np.float64, na_value=np.nan)
    finite = np.isfinite(values)
    if not finite.all():
        row = int(np.argmin(finite))
        _raise_missing(where, name, row, infinite=float(values[row]))
    huge = np.abs(values) > LARGEST_VALUE
    if huge.any():
        row = int(np.argmax(huge))
        raise DataError(
            f"{where.prefix}{where.label} '{name}', {where.rows(row)}: {values[row]:.6g} is "
            f"too large: {_TOO_LARGE}"
        )
    return values


#: Largest magnitude a sample may have: below it the powers of the polynomial blocks (up
#: to degree 9) and their squares in least squares stay finite in float64 (1e15^18 =
#: 1e270); physical signals in any sensible unit are far smaller.
LARGEST_VALUE = 1e15
_TOO_LARGE = (
    f"values beyond {LARGEST_VALUE:g} overflow the fits' squares and products; rescale the "
    "signal (e.g. to SI units or by its typical size) and fit again"
)


def _raise_missing(where: _Where, name: str, row: int, infinite: float = np.nan) -> None:
    """Raise for an empty, NaN (or, if ``infinite`` is +-inf, infinite) cell."""
    raw = where.raw(row, name)
    if np.isinf(infinite):
        problem = f"is infinite ({repr(raw) if raw is not None else _num(infinite)})"
    elif raw is not None and not raw.strip():
        problem = "is empty"
    else:
        problem = f"has a missing value ({raw if raw is not None else 'NaN'!r})"
    raise DataError(
        f"{where.prefix}{where.label} '{name}', {where.rows(row)} {problem}; every "
        "sample needs a value: remove that row or fill the gap (e.g. by interpolation), "
        "or split the record into experiments at the gap"
    )


def _time_values(df: pd.DataFrame, column: Any, name: str, where: _Where) -> np.ndarray:
    """Time column in its own unit; ISO 8601 date-times become seconds from the first."""
    series = df[column]
    stamps = None
    if isinstance(series, pd.Series):
        if pd.api.types.is_datetime64_any_dtype(series.dtype):
            stamps = series
        elif not pd.api.types.is_numeric_dtype(series.dtype):
            numbers = pd.to_numeric(series, errors="coerce")
            if (numbers.isna() & series.notna()).any():  # text, not numbers: date-times?
                try:
                    stamps = pd.to_datetime(series, format="ISO8601")
                except (ValueError, TypeError):
                    stamps = None  # _numeric_column reports the first bad cell
    if stamps is None:
        return _numeric_column(df, column, name, where)
    gaps = stamps.isna().to_numpy()
    if gaps.any():
        _raise_missing(where, name, int(np.argmax(gaps)))
    return (stamps - stamps.iloc[0]).dt.total_seconds().to_numpy(dtype=np.float64)


def _sampling_step(t: np.ndarray, rows: np.ndarray, name: str, where: _Where) -> float | None:
    """Median step of an increasing, uniform time vector; ``None`` for fewer than 2 samples."""
    if t.size < 2:
        return None
    steps = np.diff(t)
    backwards = np.flatnonzero(steps <= 0.0)
    if backwards.size:
        i = int(backwards[0])
        raise DataError(
            f"{where.prefix}time {where.label} '{name}' does not increase at "
            f"{where.rows(int(rows[i]), int(rows[i + 1]))}: {_num(t[i + 1])} follows {_num(t[i])}; "
            "sort the rows by time, or mark separate records with an experiment column"
        )
    step = float(np.median(steps))
    jitter = np.flatnonzero(np.abs(steps - step) > _TIME_TOLERANCE * step)
    if jitter.size:
        i = int(jitter[0])
        raise DataError(
            f"{where.prefix}time {where.label} '{name}' is not uniformly sampled: the step "
            f"between {where.rows(int(rows[i]), int(rows[i + 1]))} is {_num(steps[i])} but the "
            f"median step is {_num(step)} (more than 1 % apart); blockid needs a constant "
            "sampling time: resample the record, or split it into experiments at the gap"
        )
    # the mean step over the record is exact up to the rounding of the time stamps; 12
    # significant digits give 0.05 back for t = k * 0.05 written as text
    return float(f"{(t[-1] - t[0]) / (t.size - 1):.12g}")


def _agreeing_sampling_time(steps: Sequence[tuple[str, float]], what: str) -> float | None:
    """One sampling time from several ``(label, step)`` pairs that agree within 1 %."""
    if not steps:
        return None
    values = np.array([s for _, s in steps])
    lo, hi = int(np.argmin(values)), int(np.argmax(values))
    if values[hi] > values[lo] * (1.0 + _TIME_TOLERANCE):
        raise DataError(
            f"{what}: {steps[lo][0]} has sampling time {_num(values[lo])} but {steps[hi][0]} has "
            f"{_num(values[hi])}; all experiments must share one sampling time"
        )
    return float(np.median(values))


def _split_rows(
    df: pd.DataFrame, column: Any, name: str, where: _Where
) -> list[tuple[Any, np.ndarray]]:
    """Row positions of each experiment, in order of first appearance."""
    series = df[column]
    if isinstance(series, pd.DataFrame):
        raise DataError(f"{where.prefix}{where.label} '{name}' appears more than once")
    codes, labels = pd.factorize(series, sort=False)
    missing = np.flatnonzero(codes < 0)
    if missing.size:
        raise DataError(
            f"{where.prefix}experiment {where.label} '{name}', {where.rows(int(missing[0]))} "
            "is empty; every row needs an experiment label"
        )
    # Rows of one experiment must form one block: labels change exactly n-1 times.
    changes = np.flatnonzero(codes[1:] != codes[:-1]) + 1
    if changes.size != len(labels) - 1:
        starts = np.concatenate(([0], changes))
        seen: set[int] = set()
        for s in starts:
            code = int(codes[s])
            if code in seen:
                first = int(np.argmax(codes == code))
                raise DataError(
                    f"{where.prefix}experiment '{labels[code]}' in {where.label} '{name}' "
                    f"starts again at {where.rows(int(s))} after other experiments (it "
                    f"first appears at {where.rows(first)}); the rows of one experiment "
                    "must be contiguous"
                )
            seen.add(code)
    bounds = np.concatenate(([0], changes, [len(codes)]))
    return [
        (labels[int(codes[bounds[k]])], np.arange(bounds[k], bounds[k + 1]))
        for k in range(len(bounds) - 1)
    ]


def _label_text(value: Any) -> str:
    """``str(value)``, but 3 rather than 3.0 for whole floats read from a file."""
    if isinstance(value, float | np.floating) and float(value).is_integer():
        return str(int(value))
    return str(value)


def _frame_to_dataset(
    df: pd.DataFrame,
    inputs: Sequence[str],
    outputs: Sequence[str],
    sampling_time: float | None = None,
    time_column: str | None = None,
    experiment_column: str | None = None,
    source: str | None = None,
    *,
    name: str = "experiment 1",
    split_prefix: str | None = None,
    where: _Where | None = None,
    empty_message: str | None = None,
) -> Dataset:
    """Worker behind :meth:`Dataset.from_frame` and the file readers.

    ``name`` names the single experiment; with ``experiment_column`` experiments are
    named ``str(value)``, or ``f"{split_prefix}/{value}"`` when ``split_prefix`` is set.
    ``where`` (file lines, variable names) and ``empty_message`` tune the messages.
    """
    where = where if where is not None else _Where(source)
    ins, outs = _check_signal_names(inputs, outputs)
    dt = _check_sampling_time(sampling_time)
    for option, column in (("time_column", time_column), ("experiment_column", experiment_column)):
        if column is not None and column in ins + outs:
            kind = "an input" if column in ins else "an output"
            raise DataError(
                f"{where.prefix}{option} '{column}' is also listed as {kind}; a {where.label} "
                "is either a signal, the time or the experiment label"
            )
    if time_column is not None and time_column == experiment_column:
        raise DataError(f"{where.prefix}time_column and experiment_column are both '{time_column}'")

    by_name = {str(c): c for c in df.columns}
    available = [str(c) for c in df.columns]
    needed = list(ins + outs) + [c for c in (time_column, experiment_column) if c is not None]
    for wanted in needed:
        if wanted not in by_name:
            raise DataError(_unknown_name_message(where.prefix, where.label, wanted, available))
    if len(df) == 0:
        raise DataError(empty_message or f"{where.prefix}the table has no data rows")

    u = np.empty((len(df), len(ins)))
    y = np.empty((len(df), len(outs)))
    for j, signal in enumerate(ins):
        u[:, j] = _numeric_column(df, by_name[signal], signal, where)
    for j, signal in enumerate(outs):
        y[:, j] = _numeric_column(df, by_name[signal], signal, where)
    u.flags.writeable = False
    y.flags.writeable = False

    if experiment_column is None:
        groups: list[tuple[str, np.ndarray]] = [(name, np.arange(len(df)))]
    else:
        groups = [
            (_label_text(v) if split_prefix is None else f"{split_prefix}/{_label_text(v)}", rows)
            for v, rows in _split_rows(df, by_name[experiment_column], experiment_column, where)
        ]

    if time_column is not None:
        t = _time_values(df, by_name[time_column], time_column, where)
        steps = []
        for label, rows in groups:
            step = _sampling_step(t[rows], rows, time_column, where)
            if step is not None:
                steps.append((f"experiment '{label}'", step))
        if not steps:
            raise DataError(
                f"{where.prefix}cannot infer the sampling time from time {where.label} "
                f"'{time_column}': every experiment has a single sample; pass sampling_time",
                parameter="sampling_time",
            )
        inferred = _agreeing_sampling_time(
            steps, f"{where.prefix}time {where.label} '{time_column}'"
        )
        if dt is not None:
            worst = max(steps, key=lambda s: abs(s[1] - dt))
            if abs(worst[1] - dt) > _TIME_TOLERANCE * dt:
                raise DataError(
                    f"{where.prefix}sampling_time {_num(dt)} disagrees with time {where.label} "
                    f"'{time_column}', whose step is {_num(worst[1])} in {worst[0]}; give one "
                    "of the two, or correct the sampling time"
                )
        else:
            dt = inferred
    elif dt is not None:
        _check_unused_time_column(df, dt, groups, ins + outs, experiment_column, where)

    experiments = [
        Experiment(label, u[rows[0] : rows[-1] + 1], y[rows[0] : rows[-1] + 1])
        for label, rows in groups
    ]
    return Dataset(ins, outs, dt, experiments, source)


#: Column names that look like sample times: ``t``, ``time``, ``Time [s]``, ``t_s``...
_TIME_NAME = re.compile(r"^(t|time)([\s_\-\[(.].*)?$", re.IGNORECASE)


def _time_like(names: Iterable[str]) -> list[str]:
    """The names among ``names`` that look like a time column."""
    return [n for n in names if _TIME_NAME.match(str(n).strip())]


def _check_unused_time_column(
    df: pd.DataFrame,
    dt: float,
    groups: Sequence[tuple[str, np.ndarray]],
    signals: Sequence[str],
    experiment_column: str | None,
    where: _Where,
) -> None:
    """Refuse a given sampling time that a time-like column of the table contradicts.

    Without ``time_column`` the table's time column is not read, so a sampling time
    that disagrees with it would pass unnoticed. Only a clean column counts: numbers,
    increasing with a uniform step (1 %) in every experiment.
    """
    for name in _time_like(str(c) for c in df.columns):
        if name in signals or name == experiment_column:
            continue
        column = df[name] if name in df.columns else None
        if not isinstance(column, pd.Series):
            continue
        t = pd.to_numeric(column, errors="coerce").to_numpy(dtype=np.float64, na_value=np.nan)
        if not np.all(np.isfinite(t)):
            continue
        steps = [np.diff(t[rows]) for _, rows in groups if rows.size > 1]
        if not steps:
            continue
        all_steps = np.concatenate(steps)
        step = float(np.median(all_steps))
        if step <= 0 or np.any(np.abs(all_steps - step) > _TIME_TOLERANCE * step):
            continue
        if abs(step - dt) > _TIME_TOLERANCE * dt:
            raise DataError(
                f"{where.prefix}sampling_time {_num(dt)} disagrees with {where.label} "
                f"'{name}', which looks like the sample times and steps by {_num(step)}; "
                f"give one of the two: time_column='{name}' to take the sampling time from "
                "it, or the sampling time that matches it",
                parameter="sampling_time",
            )


def _concat(datasets: Sequence[Dataset], source: str | None = None) -> Dataset:
    """Join the experiments of data sets with the same signals and sampling time."""
    first = datasets[0]
    for other in datasets[1:]:
        if other.inputs != first.inputs or other.outputs != first.outputs:
            raise DataError(
                f"{other.source} has signals {other.inputs + other.outputs} but "
                f"{first.source} has {first.inputs + first.outputs}"
            )
    known = [(str(d.source), d.sampling_time) for d in datasets if d.sampling_time is not None]
    if known and len(known) != len(datasets):
        missing = next(d for d in datasets if d.sampling_time is None)
        raise DataError(f"{missing.source} has no sampling time but {known[0][0]} has one")
    dt = _agreeing_sampling_time(known, "sampling times differ")
    experiments = [exp for d in datasets for exp in d.experiments]
    return Dataset(first.inputs, first.outputs, dt, experiments, source)
