"""Full-field results of other DIC codes as jointwear field datasets (for ``compare``).

``read_field(files, *, format, length_unit=None, data_origin)`` reads one file per image (first =
reference), in the given order or a glob pattern's frame-number order:

``"vic3d-csv"``
    VIC-3D's CSV export: a header row of quoted column names, one row per point. Used columns:
    ``x``, ``y`` [pixel] (subset centre, reference image); ``X``, ``Y``, ``Z`` (reference
    position) and ``U``, ``V``, ``W`` (displacement) in the calibration's length unit, or ``u``,
    ``v`` [pixel] in a 2D export; ``sigma`` (VIC-3D's matching confidence [pixel]; -1 or empty
    marks a point the tool did not solve); ``flag`` (jointwear's own CSV export: the flag's name).
``"dice"``
    DICe's solution text files (``DICe_solution_*.txt``): ``***`` comment lines, then a
    comma-separated header row. Used columns: ``COORDINATE_X``, ``COORDINATE_Y`` [pixel];
    ``MODEL_COORDINATES_X/Y/Z`` and ``MODEL_DISPLACEMENT_X/Y/Z`` (stereo, length unit of the
    calibration) or ``DISPLACEMENT_X/Y`` [pixel] (2D); DICe's failure markers ``MATCH``,
    ``SIGMA`` and ``GAMMA`` (-1 on a subset DICe did not solve, whose displacement columns then
    hold 0); ``STATUS_FLAG`` is kept as ``foreign_status`` (its codes also mark how a solved
    subset was initialised, so it does not decide failure).

Nothing is guessed: a stereo file's length unit must be stated (``length_unit``: ``"mm"``,
``"m"``, ``"um"``, ``"in"`` or metres per unit); the points must be the same in every file (same
``x``, ``y``); the foreign tools' ``sigma`` is a matching confidence in pixels, not a
displacement uncertainty, so ``displacement_u`` is NaN ("not assessed") and the foreign value
is kept as ``foreign_sigma``.

Failure stays failure: a row the source marks failed (DICe ``MATCH``, ``SIGMA`` or ``GAMMA``
negative; VIC-3D ``sigma`` negative; a jointwear CSV's ``flag`` other than ``ok``) is flagged
``failed_in_source`` (or, from a jointwear CSV, with its own flag) and NaN in every component,
whatever numbers the row holds (DICe writes zeros); a row with an empty or non-finite
component is flagged ``not_reached``. The columns that decided are named in the
``flag`` variable's ``comment``.
"""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np
import xarray as xr

from jointwear.dic.field._measure import FIELD_FLAG_MEANINGS
from jointwear.dic.icgn import FLAG_NOT_REACHED
from jointwear.dic.subset import check_image_origin
from jointwear.errors import BadInputError, ParameterError

__all__ = ["read_field", "FIELD_FORMATS", "import_summary"]

FIELD_FORMATS = ("vic3d-csv", "dice")
_UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "cm": 1e-2, "in": 0.0254}

#: flags of an imported field: the field's own (a jointwear CSV's names map back to them),
#: among them ``failed_in_source`` (the source's own failure marker, value 12)
IMPORT_FLAG_MEANINGS = tuple(FIELD_FLAG_MEANINGS.split())
FLAG_FAILED_IN_SOURCE = IMPORT_FLAG_MEANINGS.index("failed_in_source")
#: format -> columns whose negative value marks a row the source did not solve
_FAILURE_COLUMNS = {"vic3d-csv": ("sigma",), "dice": ("MATCH", "SIGMA", "GAMMA")}
#: format -> the source's status column kept as ``foreign_status`` (not a failure test)
_STATUS_COLUMN = {"vic3d-csv": None, "dice": "STATUS_FLAG"}
#: text columns: jointwear's own CSV names its flag
_TEXT_COLUMNS = ("flag",)

#: format -> (x, y, position XYZ, displacement XYZ, 2D displacement, sigma, quality)
_COLUMNS = {
    "vic3d-csv": (
        "x",
        "y",
        ("X", "Y", "Z"),
        ("U", "V", "W"),
        ("u", "v"),
        "sigma",
        None,
    ),
    "dice": (
        "COORDINATE_X",
        "COORDINATE_Y",
        ("MODEL_COORDINATES_X", "MODEL_COORDINATES_Y", "MODEL_COORDINATES_Z"),
        ("MODEL_DISPLACEMENT_X", "MODEL_DISPLACEMENT_Y", "MODEL_DISPLACEMENT_Z"),
        ("DISPLACEMENT_X", "DISPLACEMENT_Y"),
        "SIGMA",
        "GAMMA",
    ),
}


def _scale(length_unit) -> float:
    from jointwear.dic.calibration import metres_per_unit

    s = metres_per_unit(length_unit, _UNITS)
    if s is None:
        raise ParameterError(
            f"length_unit={length_unit!r}: say what unit the file's lengths are in, one of "
            f"{', '.join(_UNITS)} or the number of metres per unit (--length-unit)"
        )
    return s


def _table(path: Path, fmt: str) -> dict[str, np.ndarray]:
    try:
        text = path.read_text(errors="replace")
    except OSError as exc:
        raise BadInputError(f"{fmt} file '{path}': {exc}") from None
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("***")]
    if fmt == "dice":
        lines = [ln for ln in lines if not ln.lstrip().startswith("#")]
    if len(lines) < 2:
        raise BadInputError(f"{fmt} file '{path}': no header and data rows found")
    dialect = csv.excel if "," in lines[0] else csv.excel_tab
    rows = list(csv.reader(lines, dialect))
    head = [re.sub(r"\s*\[.*\]$", "", h.strip().strip('"')) for h in rows[0]]
    cols: dict[str, np.ndarray] = {}
    body = rows[1:]
    for j, name in enumerate(head):
        if name in _TEXT_COLUMNS:
            cols[name] = np.array([r[j].strip() if j < len(r) else "" for r in body])
            continue
        vals = []
        for k, r in enumerate(body):
            v = r[j].strip() if j < len(r) else ""
            try:
                vals.append(float(v) if v else np.nan)
            except ValueError:
                raise BadInputError(
                    f"{fmt} file '{path}' row {k + 2}, column '{name}': {v!r} is not a number"
                ) from None
        cols[name] = np.array(vals)
    return cols


def _files(files) -> list[Path]:
    if isinstance(files, (str, Path)):
        from jointwear.filenames import GLOB_CHARS as _GLOB_CHARS
        from jointwear.filenames import natural_key as _natural_key

        p = Path(files)
        if p.is_file():
            return [p]
        if _GLOB_CHARS.search(p.name) and p.parent.is_dir():
            found = sorted((q for q in p.parent.glob(p.name) if q.is_file()), key=_natural_key)
            if not found:
                raise BadInputError(f"pattern '{files}' matches no file")
            return found
        raise BadInputError(f"'{files}' does not exist")
    out = [Path(f) for f in files]
    if not out:
        raise BadInputError("read_field: no files given")
    for f in out:
        if not f.is_file():
            raise BadInputError(f"'{f}' does not exist")
    return out


def _source_flags(tables: list[dict], fmt: str, shape: tuple[int, int]) -> tuple[np.ndarray, str]:
    """The source's own verdict on every row and the columns that gave it.

    Returns the flag (0 where the source did not mark the row failed; ``failed_in_source``
    where a failure column is negative; a jointwear CSV's own flag by its name, an unknown name
    ``failed_in_source``) and a sentence naming the tests applied.
    """
    flag = np.zeros(shape, np.int8)
    used = []
    for c in _FAILURE_COLUMNS[fmt]:
        if any(c in t for t in tables):
            for k, t in enumerate(tables):
                if c in t:
                    flag[k][t[c] < 0] = FLAG_FAILED_IN_SOURCE  # NaN < 0 is False
            used.append(f"{c} < 0")
    if any("flag" in t for t in tables):
        value = {name: v for v, name in enumerate(IMPORT_FLAG_MEANINGS)}
        for k, t in enumerate(tables):
            if "flag" in t:
                own = np.array([value.get(f, FLAG_FAILED_IN_SOURCE) if f else 0 for f in t["flag"]])
                flag[k] = np.where(own != 0, own, flag[k])
        used.append("the flag column's name other than ok")
    tests = ", ".join(used) if used else "none (the files have no failure column)"
    return flag, f"failed in the source by: {tests}; an empty or non-finite component: not_reached"


def _field_variables(disp, sig, flag, unit: str, format: str, sig_c: str) -> dict:
    """Displacement (uncertainty not assessed), the foreign sigma and the flag of an import."""
    data = {
        "displacement": xr.DataArray(
            disp,
            dims=("time", "point", "axis"),
            attrs={
                "units": unit,
                "long_name": f"displacement from the reference image ({format})",
                "ancillary_variables": "displacement_u flag",
            },
        ),
        "displacement_u": xr.DataArray(
            np.full_like(disp, np.nan),
            dims=("time", "point", "axis"),
            attrs={
                "units": unit,
                "long_name": "standard uncertainty of displacement: not assessed (the foreign "
                "sigma is a matching confidence in pixels, see foreign_sigma)",
            },
        ),
        "foreign_sigma": xr.DataArray(
            np.where((sig >= 0) & (flag == 0), sig, np.nan),
            dims=("time", "point"),
            attrs={"units": "pixel", "long_name": f"{sig_c} column of the {format} files"},
        ),
        "flag": xr.DataArray(
            flag,
            dims=("time", "point"),
            attrs={
                "units": "1",
                "long_name": "field quality flag (imported: the source's failures kept)",
                "flag_values": np.arange(len(IMPORT_FLAG_MEANINGS), dtype=np.int8),
                "flag_meanings": " ".join(IMPORT_FLAG_MEANINGS),
            },
        ),
    }
    return data


def read_field(
    files,
    *,
    format: str,
    length_unit=None,
    data_origin: str,
    times=None,
) -> xr.Dataset:
    """Another DIC code's field results as a field dataset (see module docstring).

    Parameters
    ----------
    files : path, pattern or list of paths
        One file per image, the reference first.
    format : {"vic3d-csv", "dice"}
        The tool that wrote them.
    length_unit : str or float
        Unit of the stereo lengths (``"mm"``...; or metres per unit). Not needed for 2D files.
    data_origin : {"measured", "synthetic"}
        What the images were.
    times : sequence of float, optional
        Time of every image [s] (default: no time base, the image index).
    """
    if format not in FIELD_FORMATS:
        raise ParameterError(f"format={format!r}: expected one of {', '.join(FIELD_FORMATS)}")
    check_image_origin(data_origin)
    paths = _files(files)
    cx, cy, pos_c, disp_c, disp2_c, sig_c, q_c = _COLUMNS[format]
    tables = [_table(p, format) for p in paths]
    first = tables[0]
    for c in (cx, cy):
        if c not in first:
            raise BadInputError(
                f"{format} file '{paths[0]}' has no column '{c}' (columns: {', '.join(first)}); "
                "is it the right --format?"
            )
    stereo = all(c in first for c in pos_c + disp_c)
    if not stereo and not all(c in first for c in disp2_c):
        want = ", ".join(disp_c + disp2_c)
        raise BadInputError(f"{format} file '{paths[0]}' has neither of the columns {want}")
    if not stereo and length_unit is not None:
        raise BadInputError(
            f"{format} file '{paths[0]}' is a 2D solution ({', '.join(disp2_c)}, no "
            f"{', '.join(pos_c)}): its coordinates and displacements are in pixels, which "
            f"length_unit={length_unit!r} cannot convert (no pixel size is known); drop the "
            "length unit (the field is kept in pixel)"
        )
    scale = _scale(length_unit) if stereo else 1.0
    x, y = first[cx], first[cy]
    n = len(x)
    n_t = len(paths)
    names = disp_c if stereo else disp2_c
    disp = np.full((n_t, n, len(names)), np.nan)
    sig = np.full((n_t, n), np.nan)
    qual = np.full((n_t, n), np.nan)
    for k, (p, tab) in enumerate(zip(paths, tables, strict=True)):
        if len(tab.get(cx, [])) != n or not (
            np.allclose(tab[cx], x, equal_nan=True) and np.allclose(tab[cy], y, equal_nan=True)
        ):
            raise BadInputError(
                f"{format} file '{p}': its points (x, y) differ from those of '{paths[0]}'; "
                "export every image with the same points (same AOI and step)"
            )
        for i, c in enumerate(names):
            if c not in tab:
                raise BadInputError(f"{format} file '{p}' has no column '{c}'")
            disp[k, :, i] = tab[c] * scale
        if sig_c in tab:
            sig[k] = tab[sig_c]
        if q_c and q_c in tab:
            qual[k] = tab[q_c]
    flag, decided = _source_flags(tables, format, (n_t, n))
    no_data = ~np.isfinite(disp).all(axis=-1) & (flag == 0)
    flag[no_data] = FLAG_NOT_REACHED
    missing = flag != 0
    disp[missing] = np.nan
    qual[missing] = np.nan
    axes = ["x", "y", "z"] if stereo else ["x", "y"]
    unit = "m" if stereo else "pixel"
    data = _field_variables(disp, sig, flag, unit, format, sig_c)
    data["flag"].attrs["comment"] = decided
    status_c = _STATUS_COLUMN[format]
    if status_c and status_c in first:
        status = np.array([t.get(status_c, np.full(n, np.nan)) for t in tables])
        data["foreign_status"] = xr.DataArray(
            status, dims=("time", "point"), attrs={"units": "1", "long_name": f"{status_c} column"}
        )
    if q_c and np.isfinite(qual).any():
        data["foreign_quality"] = xr.DataArray(
            qual, dims=("time", "point"), attrs={"units": "1", "long_name": f"{q_c} column"}
        )
    if stereo:
        P = np.column_stack([first[c] for c in pos_c]) * scale
        data["position"] = xr.DataArray(
            np.where(missing[0][:, None], np.nan, P),
            dims=("point", "axis"),
            attrs={"units": "m", "long_name": f"reference position of the point ({format})"},
        )
    coords = {
        "point": ("point", np.arange(n), {"long_name": "measurement point"}),
        "x": ("point", x, {"units": "pixel", "long_name": "subset centre column, reference"}),
        "y": ("point", y, {"units": "pixel", "long_name": "subset centre row, reference"}),
        "axis": ("axis", axes, {"long_name": "vector component"}),
        "image": ("time", np.arange(n_t), {"long_name": "image index (0 = reference)"}),
        "source_file": ("time", [p.name for p in paths], {"long_name": "imported file"}),
    }
    if times is not None:
        t = np.asarray(times, float)
        if t.shape != (n_t,) or np.any(np.diff(t) <= 0):
            raise BadInputError(f"times: expected {n_t} increasing values [s]")
        coords["time"] = ("time", t, {"units": "s", "long_name": "time of the image"})
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update(
        {
            "title": f"{'stereo' if stereo else '2D'} DIC field imported from {format}",
            "data_origin": data_origin,
            "external_tool": format,
            "field_frame": "the foreign tool's frame (as exported)",
        }
    )
    if stereo:
        ds.attrs["length_unit_of_the_files_m"] = scale
    return ds


def import_summary(ds: xr.Dataset) -> str:
    """'119/123 points with data in the last image (4 failed in the source)': the count of
    points with data and of each failure in the last image."""
    flag = ds.flag.values[-1]
    names = str(ds.flag.attrs["flag_meanings"]).split()
    text = f"{int((flag == 0).sum())}/{flag.size} points with data in the last image"
    counts = [f"{int((flag == v).sum())} {names[v]}" for v in np.unique(flag[flag != 0])]
    return text + (f" ({', '.join(counts)})" if counts else "")
