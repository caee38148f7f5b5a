"""End-to-end workflows built on the library: comparison of structures, the papers'
reproductions and the demo. They return data; the CLI prints it.

Names are imported on first use (PEP 562), so that the command line starts fast.
"""

from __future__ import annotations

from blockid._lazy import lazy_names

_WHERE = {
    "CompareResult": "compare",
    "ModelScore": "compare",
    "compare_structures": "compare",
}

__all__, __getattr__, __dir__ = lazy_names(__name__, _WHERE)
