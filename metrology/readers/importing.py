"""Import instrument exports into contract netCDF files: what ``jointwear metrology import`` does.

:func:`import_scans` reads each scan (a file, a folder of layer files, several layer files, or
with ``batch`` every entry of folders of scans) with :func:`~.scan.read_scan` (or the Talyrond
preset) and writes one netCDF per scan with its provenance; the command line only parses its
options and prints what this returns.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import xarray as xr

from jointwear import io
from jointwear._version import source_attribute
from jointwear.errors import BadInputError, ConventionError

__all__ = ["import_scans", "output_paths"]


_SOURCE = source_attribute("metrology")


def output_paths(inputs: list[Path], out: Path, suffix: str) -> list[Path]:
    """One output per input: ``out`` itself for one input, ``out/<name><suffix>`` for several."""
    if len(inputs) == 1 and out.suffix:
        return [out]
    out.mkdir(parents=True, exist_ok=True)
    names = [p.stem if p.is_file() else p.name for p in inputs]
    return [out / f"{n}{suffix}" for n in names]


def _expand_batch(paths: list[Path]) -> list[Path]:
    """Every entry of every folder in ``paths`` (each one scan)."""
    items: list[Path] = []
    for p in paths:
        if not p.is_dir():
            raise BadInputError(f"--batch: '{p}' is not a folder of scans")
        children = sorted(c for c in p.iterdir() if not c.name.startswith("."))
        if not children:
            raise BadInputError(f"--batch: folder '{p}' is empty")
        items.extend(children)
    return items


def _scans(paths: list[Path], batch: bool, out: Path) -> tuple[list, list[Path]]:
    """(what to import: a path or a list of layer files per scan, the output of each)."""
    if batch:
        items: list = _expand_batch(paths)
    elif len(paths) > 1 and all(p.is_file() for p in paths):
        items = [list(paths)]  # several files: the layers of one scan
    else:
        items = list(paths)
    names = [i if isinstance(i, Path) else i[0].parent for i in items]
    if len(items) > 1 and out.suffix:
        raise BadInputError(f"{len(items)} scans to import: --out must be a folder, not '{out}'")
    return items, output_paths(names, out, ".nc")


def import_scans(
    paths: list[Path],
    out: Path,
    *,
    angle_zero: str | None,
    angle_direction: str | None,
    preset: str = "generic",
    batch: bool = False,
    on_saved: Callable[[Path, xr.Dataset], None] | None = None,
    **options,
) -> list[Path]:
    """Read scans and write each as a contract netCDF file.

    Parameters
    ----------
    paths : list of Path
        A text export, a folder of per-layer files, several per-layer files of one scan, or
        (``batch``) folders whose every entry is a scan.
    out : Path
        Output ``.nc`` for one scan, else a folder (``<name>.nc`` per scan).
    angle_zero, angle_direction : str
        The instrument's angle convention in the bearing frame (required: never guessed).
    preset : str
        Reader, by name (:data:`~jointwear.metrology.choices.READERS`: ``generic``
        :func:`~.scan.read_scan`, ``talyrond`` :func:`~.talyrond.read_talyrond`, or one added
        with :func:`~.registry.register`).
    batch : bool
        Each entry of each folder in ``paths`` is a separate scan.
    on_saved : callable, optional
        Called with (output path, dataset) after each scan is written.
    **options
        Keywords of :func:`~.scan.read_scan` (SI units); recorded as the parameters.

    Returns
    -------
    list of Path
        The files written.
    """
    from jointwear.metrology.readers.registry import reader_for

    if angle_zero is None or angle_direction is None:
        raise ConventionError(
            "give the instrument's angle convention: --angle-zero (where its 0 degree points "
            "in the bearing frame: +x, +y, -x, -y or degrees) and --angle-direction "
            "(clockwise or counterclockwise seen from +z); text exports rarely state it and "
            "jointwear never guesses it"
        )
    reader = reader_for(preset)
    items, targets = _scans(paths, batch, out)
    for item, target in zip(items, targets, strict=True):
        io.check_writable(target)
        ds = reader(item, convention=(angle_zero, angle_direction), **options)
        io.save(
            ds,
            target,
            inputs=[Path(f) for f in ds.attrs.get("files", [])],
            parameters={"angle_zero": angle_zero, "angle_direction": angle_direction, **options},
            source=ds.attrs.get("source", _SOURCE),
        )
        if on_saved is not None:
            on_saved(target, ds)
    return targets
