"""Compiled (numba) kernels: private, pure functions on arrays; NumPy is their only dependency.

numba compiles a kernel once per argument type, and a read-only or strided array is
another type than a writable contiguous one: a model's frozen parameter arrays and a
fit's fresh ones cost two compilations of the same kernel (the polynomial state
space's free run was compiled six times in one test run). :func:`writable` gives the
one type every caller passes.
"""

from typing import Any

import numpy as np

__all__ = ["writable"]


def writable(values: Any, dtype: Any = None) -> np.ndarray:
    """``values`` as the kernels are compiled for (as ``dtype`` when given): a
    C-contiguous writable array (a read-only or strided one is copied; the kernels never
    write to an input, so a copy changes nothing but the compiled version used)."""
    array = np.asarray(values, dtype=dtype)
    if array.flags.writeable and array.flags.c_contiguous:
        return array
    return np.array(array, order="C", copy=True)
