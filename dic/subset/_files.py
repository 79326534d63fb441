"""Correlate image files: a pair, or a sequence (folder, pattern, video), read, correlated and
saved to netCDF in one call (what ``jointwear dic correlate`` runs).

A pair is written from the correlator's :class:`~jointwear._netcdf.Record` without importing
xarray (a third of the command's start-up; the file is the one :func:`jointwear.io.save` writes
of the library's Dataset); a sequence goes through xarray.
"""

from __future__ import annotations

import contextlib
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from jointwear.dic.subset._params import UPDATE_ZNCC, CorrelationParams, check_image_origin
from jointwear.errors import BadInputError, ParameterError

if TYPE_CHECKING:
    import xarray as xr

    from jointwear._netcdf import Record

__all__ = ["correlate_files", "is_sequence_input", "read_points_file"]


def read_points_file(path: Path):
    """Points of interest from a text file: one ``x, y`` [pixel] per line (comma or blank
    separated; ``#`` comments and a non-numeric header line are skipped)."""
    if not path.is_file():
        raise BadInputError(f"--points '{path}' does not exist")
    rows = []
    for k, line in enumerate(path.read_text(errors="replace").splitlines(), start=1):
        text = line.split("#", 1)[0].replace(",", " ").replace(";", " ").split()
        if not text:
            continue
        try:
            vals = [float(v) for v in text]
        except ValueError:
            if not rows and k == 1:
                continue  # a header line
            raise BadInputError(
                f"--points '{path}' line {k}: {line.strip()!r} is not two numbers x, y (pixels)"
            ) from None
        if len(vals) != 2:
            raise BadInputError(
                f"--points '{path}' line {k}: expected two numbers x, y (pixels), got {len(vals)}"
            )
        rows.append(vals)
    if not rows:
        raise BadInputError(f"--points '{path}' holds no points (expected lines 'x, y' in pixels)")
    return np.array(rows)


def is_sequence_input(deformed: str | Path | None) -> bool:
    """True when ``deformed`` (None, a folder, pattern or video) makes the input a sequence."""
    from jointwear.dic.footage import is_image_sequence

    return deformed is None or (not Path(deformed).is_file() and is_image_sequence(str(deformed)))


def _read_sequence(reference: Path, deformed: Path | None):
    """(frames, fps) and the input files of a sequence."""
    from jointwear.dic.footage import is_image_sequence, list_image_sequence
    from jointwear.dic.subset._sequence import read_frames, read_image

    if deformed is not None:  # a reference named unlike the frames, then the frames
        if not reference.is_file():
            raise BadInputError(f"reference image '{reference}' does not exist")
        files = list_image_sequence(str(deformed), what="frames")[0]
        frames = [read_image(reference)] + [read_image(f) for f in files]
        return (frames, None), [reference, *files]
    if not reference.exists() and not is_image_sequence(reference):
        raise BadInputError(f"'{reference}' does not exist")
    inputs = [reference] if reference.is_file() else []
    return read_frames(reference), inputs


def _correlate_pair(reference, deformed, *, roi, points, seed_points, params) -> Record:
    from jointwear.dic.subset._correlator import SubsetCorrelator
    from jointwear.dic.subset._sequence import read_image

    ref_img = read_image(reference)
    def_img = read_image(deformed)
    if sys.stderr.isatty():  # the bar shows only on a terminal: rich is imported only then
        from jointwear.progress import progress_bar

        bar = progress_bar("correlating", total=2)
    else:
        bar = contextlib.nullcontext()
    with bar as progress:
        corr = SubsetCorrelator(ref_img, roi=roi, points=points, params=params)
        if progress is not None:
            task = progress.tasks[0].id
            progress.update(task, advance=1, description=f"correlating {corr.n_points} points")
        res = corr.match(def_img, seed_points=seed_points)
        if progress is not None:
            progress.update(task, advance=1)
    return corr.to_record(res)


def correlate_files(
    reference: str | Path,
    deformed: str | Path | None,
    out: str | Path,
    *,
    params: CorrelationParams | None = None,
    roi: Sequence[float] | None = None,
    points: np.ndarray | str | Path | None = None,
    seed_points: np.ndarray | None = None,
    reference_mode: str | None = None,
    frame_rate: float | None = None,
    update_zncc: float = UPDATE_ZNCC,
    update_every: int | None = None,
    plot: str | Path | None = None,
    data_origin: str = "measured",
) -> tuple[xr.Dataset | Record, float]:
    """Correlate an image pair or a sequence and save the field to ``out`` (netCDF).

    Parameters
    ----------
    reference : path
        Reference image, or a folder of frames, a pattern or a video (a sequence).
    deformed : path or None
        Deformed image; a folder / pattern of the later frames of a sequence whose reference is
        ``reference``; None for a sequence in ``reference``.
    out : path
        netCDF file to write.
    params : CorrelationParams, optional
        Correlation options (defaults: :class:`CorrelationParams`).
    roi, points, seed_points
        As in :func:`jointwear.dic.correlate` (``roi`` and ``points`` exclude each other);
        ``points`` may be a text file (:func:`read_points_file`).
    reference_mode, frame_rate, update_zncc, update_every
        Sequences only: as in :func:`correlate_sequence` (``reference_mode`` None: absolute).
    plot : path, optional
        Also write a quick-look figure (png).
    data_origin : {"measured", "synthetic"}
        What the images are (camera images or generated ones): the file's ``data_origin``.

    Returns
    -------
    (Dataset or Record, float)
        The saved field (a pair's as a :class:`~jointwear._netcdf.Record`: ``field["u"].values``
        etc.; ``.to_dataset()`` for the Dataset) and the correlation time [s].
    """
    from jointwear._version import source_attribute
    from jointwear.io import check_writable

    reference = Path(reference)
    deformed = None if deformed is None else Path(deformed)
    params = params or CorrelationParams()
    check_writable(out)
    if plot is not None:
        check_writable(plot, what="figure")
    if points is not None and roi is not None:
        raise ParameterError("give either points= or roi=, not both")
    check_image_origin(data_origin)
    if isinstance(points, (str, Path)):
        points = read_points_file(Path(points))
    t0 = time.perf_counter()
    sequence = is_sequence_input(deformed)
    if sequence:
        from jointwear.dic.subset._sequence import correlate_sequence
        from jointwear.io import save as write

        frames, inputs = _read_sequence(reference, deformed)
        field = correlate_sequence(
            frames,
            reference=reference_mode or "absolute",
            roi=roi,
            points=points,
            frame_rate=frame_rate,
            update_zncc=update_zncc,
            update_every=update_every,
            seed_points=seed_points,
            progress=None,
            params=params,
        )
    else:
        from jointwear._netcdf import write_record as write

        field = _correlate_pair(
            reference, deformed, roi=roi, points=points, seed_points=seed_points, params=params
        )
        inputs = [reference, deformed]
    elapsed = time.perf_counter() - t0
    field.attrs["data_origin"] = data_origin
    write(field, out, inputs=inputs, parameters=params, source=source_attribute("dic.correlate"))
    if plot is not None:
        from jointwear.dic.subset._quicklook import save_quicklook

        save_quicklook(field if sequence else field.to_dataset(), plot, title=reference.name)
    return field, elapsed
