"""Measure a field from image files (2D or stereo) and save it, in one call (what
``jointwear dic field`` runs)."""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path

import xarray as xr

from jointwear.dic.field._measure import FieldParams
from jointwear.errors import BadInputError

__all__ = ["image_list", "measure_field_files"]


def image_list(values: Sequence[str] | None, what: str):
    """One folder/pattern, several image files, or a reference file followed by a folder or
    pattern of the later images (the first image is the reference)."""
    if not values:
        return None
    from jointwear.dic.footage import is_image_sequence, list_image_sequence

    if len(values) == 1 and is_image_sequence(values[0]):
        return values[0]
    out: list[Path] = []
    for k, v in enumerate(values):
        if Path(v).is_file():
            out.append(Path(v))
        elif k > 0 and is_image_sequence(v):
            out += list_image_sequence(v, what=f"{what} images")[0]
        elif is_image_sequence(v):
            raise BadInputError(
                f"{what}: '{v}' is a folder or pattern of images, which can only follow the "
                "reference image (or stand alone)"
            )
        else:
            raise BadInputError(f"{what} image '{v}' does not exist")
    return out


def _input_files(values: Sequence[str] | None) -> list[Path]:
    from jointwear.dic.footage import is_image_sequence, list_image_sequence

    out: list[Path] = []
    for v in values or []:
        if is_image_sequence(v):
            out += list_image_sequence(v)[0]
        elif Path(v).is_file():
            out.append(Path(v))
    return out


def measure_field_files(
    images: Sequence[str] | None,
    out: str | Path,
    *,
    left: Sequence[str] | None = None,
    right: Sequence[str] | None = None,
    calibration: str | Path | None = None,
    params: FieldParams | None = None,
    roi: str | None = None,
    points: str | Path | None = None,
    frame_rate: float | None = None,
    data_origin: str = "measured",
    csv: str | Path | None = None,
    plot: str | Path | None = None,
) -> tuple[xr.Dataset, float, list[Path]]:
    """Measure a field from 2D ``images`` or stereo ``left``/``right`` + ``calibration`` files.

    Parameters
    ----------
    images : sequence of str, optional
        2D: image files, one folder / pattern, or a reference file then a folder / pattern.
    out : path
        netCDF file to write.
    left, right : sequence of str, optional
        Stereo: the cameras' images (as ``images``); ``calibration`` is the stereo calibration.
    params : FieldParams, optional
        Options (default :class:`FieldParams`).
    roi : str, optional
        ``x0,y0,x1,y1`` [pixel], a polygon TOML or a mask image (:func:`read_roi`).
    points : path, optional
        Text file of subset centres ``x, y`` [pixel] instead of a grid.
    frame_rate, data_origin
        As in :func:`measure_field`.
    csv, plot : path, optional
        Also write CSV files (one per image) / a contour figure of the last image.

    Returns
    -------
    (Dataset, float, list of Path)
        The saved field, the measuring time [s] and the CSV files written.
    """
    from jointwear._version import source_attribute
    from jointwear.dic.field._io import save_field_plot, write_field_csv
    from jointwear.dic.field._measure import measure_field
    from jointwear.dic.subset import read_points_file
    from jointwear.io import check_writable, save

    params = params or FieldParams()
    check_writable(out)
    for p, what in ((plot, "figure"), (csv, "CSV")):
        if p is not None:
            check_writable(p, what=what)
    pts = read_points_file(Path(points)) if points is not None else None
    t0 = time.perf_counter()
    common = dict(roi=roi, points=pts, frame_rate=frame_rate, data_origin=data_origin)
    if left or right:
        from jointwear.dic.calibration import read_calibration

        cal = read_calibration(calibration)
        left_images, right_images = image_list(left, "--left"), image_list(right, "--right")
        ds = measure_field(left_images, right_images, calibration=cal, params=params, **common)
        inputs = _input_files(left) + _input_files(right) + [Path(calibration)]
    else:
        ds = measure_field(image_list(images, "IMAGES"), params=params, **common)
        inputs = _input_files(images)
    inputs += [Path(e) for e in (roi, points) if e is not None and Path(e).is_file()]
    elapsed = time.perf_counter() - t0
    save(ds, out, inputs=inputs, parameters=params, source=source_attribute("dic.field"))
    files = write_field_csv(ds, csv) if csv is not None else []
    if plot is not None:
        save_field_plot(ds, plot)
    return ds, elapsed, files
