__version__ = "0.1.0"


def source_attribute(part: str | None = None) -> str:
    """The CF ``source`` attribute: jointwear's version and the part that made the data.

    ``source_attribute("sim.wear")`` -> ``"jointwear 0.1.0 (sim.wear)"``; the version comes
    from ``jointwear.__version__`` (never written out by hand).
    """
    return f"jointwear {__version__}" + (f" ({part})" if part else "")
