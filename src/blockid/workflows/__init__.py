"""End-to-end workflows built on the library: comparison of structures, the papers'
reproductions and the demo. They return data; the CLI prints it.

Names are imported on first use (PEP 562), so that the command line starts fast.
"""

from __future__ import annotations

import importlib
from typing import Any

_WHERE = {
    "CompareResult": "compare",
    "ModelScore": "compare",
    "compare_structures": "compare",
}

__all__ = sorted(_WHERE)


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        value = getattr(importlib.import_module(f"blockid.workflows.{_WHERE[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'blockid.workflows' has no attribute {name!r}")
