"""Validation reports (``jointwear.reports``): self-contained HTML with figures, and the demo."""

__all__: list[str] = []
