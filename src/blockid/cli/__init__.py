"""The blockid command line (typer)."""

__all__: list[str] = []
