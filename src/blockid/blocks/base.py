"""Common interface of the nonlinear blocks.

A *static* block maps each input sample to an output sample, ``w = N(u)``. A
*dynamic* (hysteretic) block such as backlash has memory: its output depends on its
own previous output as well. Blocks evaluate on NumPy arrays, expose their parameters
by name (as the model files and JSON output name them, see SPEC.md "Conventions"),
serialise to plain dictionaries, and can plot their input-output curve.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, ClassVar

import numpy as np

__all__ = ["Block", "StaticBlock", "DynamicBlock", "BLOCK_TYPES", "block_from_dict"]

#: Registry ``kind -> class`` filled by :meth:`Block.__init_subclass__`; used to load
#: blocks back from model files.
BLOCK_TYPES: dict[str, type[Block]] = {}


class Block(ABC):
    """Base class of all nonlinear blocks.

    Subclasses set the class attribute ``kind`` (the name used in model files, e.g.
    ``"polynomial"``) and implement :attr:`parameters`, :meth:`to_dict` and
    :meth:`from_dict`.
    """

    kind: ClassVar[str] = ""
    #: True when the block output is ``regressors(u) @ to_vector()``.
    linear_in_parameters: ClassVar[bool] = False

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if cls.kind:
            BLOCK_TYPES[cls.kind] = cls

    @property
    @abstractmethod
    def parameters(self) -> dict[str, Any]:
        """Named parameters, JSON-serialisable (floats or lists of floats)."""

    def to_dict(self) -> dict[str, Any]:
        """Plain-dict form ``{"kind": ..., **parameters}`` for model files."""
        return {"kind": self.kind, **self.parameters}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Block:
        """Inverse of :meth:`to_dict`."""
        params = {k: v for k, v in data.items() if k != "kind"}
        return cls(**params)

    def __repr__(self) -> str:
        inner = ", ".join(f"{k}={v!r}" for k, v in self.parameters.items())
        return f"{type(self).__name__}({inner})"


class StaticBlock(Block):
    """A memoryless nonlinearity ``w(k) = N(u(k))``."""

    @abstractmethod
    def __call__(self, u: np.ndarray) -> np.ndarray:
        """Evaluate the block on an array of inputs (any shape)."""


class DynamicBlock(Block):
    """A nonlinearity with memory (e.g. backlash): ``x(k) = N(u(k), x(k-1))``."""

    @abstractmethod
    def simulate(self, u: np.ndarray, x0: float = 0.0) -> np.ndarray:
        """Run the block over the input sequence ``u`` from the initial output ``x0``."""


def block_from_dict(data: dict[str, Any]) -> Block:
    """Rebuild a block from :meth:`Block.to_dict` output."""
    from blockid.errors import ModelFileError

    kind = data.get("kind") if isinstance(data, dict) else None
    if kind not in BLOCK_TYPES:
        known = ", ".join(sorted(BLOCK_TYPES)) or "none loaded"
        raise ModelFileError(f"unknown block kind {kind!r}; known kinds: {known}")
    return BLOCK_TYPES[kind].from_dict(data)
