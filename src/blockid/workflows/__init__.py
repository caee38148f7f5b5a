"""End-to-end workflows built on the library: comparison of structures, the papers'
reproductions and the demo. They return data; the CLI prints it."""

from blockid.workflows.compare import CompareResult, ModelScore, compare_structures

__all__ = ["CompareResult", "ModelScore", "compare_structures"]
