"""Compiled (numba) kernels: private, pure functions on arrays; NumPy is their only dependency."""

__all__: list[str] = []
