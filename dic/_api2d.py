"""Public names of the 2D subset-DIC engine."""

__all__: list[str] = []
