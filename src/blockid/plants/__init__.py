"""Simulated seed plants (paper A wind tunnel, paper B electrohydraulic servo)."""

__all__: list[str] = []
