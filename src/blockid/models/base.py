"""Common interface of blockid's models and the registry used to load model files."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, ClassVar

import numpy as np

from blockid.errors import DataError, ModelFileError

__all__ = ["Model", "MODEL_TYPES", "model_from_dict"]

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

    def _check_signals(self, u: Any, y: Any = None) -> tuple[np.ndarray, np.ndarray | None]:
        """Coerce ``u`` (N, nu) and ``y`` (N, ny) and check their shapes."""
        u = np.asarray(u, dtype=float)
        if u.ndim == 1:
            u = u[:, None]
        if u.ndim != 2 or u.shape[1] != len(self.inputs):
            raise DataError(
                f"the model has {len(self.inputs)} input(s) {list(self.inputs)} but got an "
                f"input array of shape {u.shape}"
            )
        if y is not None:
            y = np.asarray(y, dtype=float)
            if y.ndim == 1:
                y = y[:, None]
            if y.ndim != 2 or y.shape[1] != len(self.outputs):
                raise DataError(
                    f"the model has {len(self.outputs)} output(s) {list(self.outputs)} but got "
                    f"an output array of shape {y.shape}"
                )
        return u, y


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
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        raise ModelFileError(
            f"the {structure} model description is damaged or incomplete ({type(exc).__name__}: "
            f"{exc})"
        ) from None
