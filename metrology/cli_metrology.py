"""``jointwear metrology import | assess | wearmap | plot``: a thin layer over the library."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import Overwrite
from jointwear._version import source_attribute


class AngleUnit(StrEnum):
    """Unit of the angle column."""

    deg = "deg"
    rad = "rad"
    index = "index"
    grad = "grad"


class Arc(StrEnum):
    """Angular span of each layer."""

    full = "full"
    partial = "partial"


class Preset(StrEnum):
    """Reader preset."""

    generic = "generic"
    talyrond = "talyrond"


class Layout(StrEnum):
    """Multi-layer layout."""

    auto = "auto"
    single = "single"
    folder = "folder"
    long = "long"
    wide = "wide"
    blocks = "blocks"


class Decimal(StrEnum):
    """Decimal separator."""

    point = "."
    comma = ","


class FilterKind(StrEnum):
    """Profile filter."""

    gaussian = "gaussian"
    rc2 = "2rc"


class Shape(StrEnum):
    """Unworn reference shape."""

    auto = "auto"
    cylinder = "cylinder"
    circle = "circle"
    form = "form"


class Reference(StrEnum):
    """ISO reference."""

    LS = "LS"
    MZ = "MZ"
    MI = "MI"
    MC = "MC"


class ValueKind(StrEnum):
    """Meaning of the value column(s)."""

    auto = "auto"
    radius = "radius"
    deviation = "deviation"


_SOURCE = source_attribute("metrology")


def _length_unit(value: str | None) -> str | None:
    """Validate a length-unit option at parse time (a bad value is a usage error, exit 2)."""
    if value is None:
        return None
    from jointwear.errors import BadInputError
    from jointwear.metrology.readers.table import unit_factor

    try:
        unit_factor(value)
    except BadInputError:
        raise typer.BadParameter(f"unit {value!r} is not known; use um, mm, m or inch") from None
    return value


def _outputs(inputs: list[Path], out: Path, suffix: str) -> list[Path]:
    """One output per input: ``out`` itself for one input, ``out/<name><suffix>`` for several."""
    if len(inputs) == 1 and out.suffix:
        return [out]
    out.mkdir(parents=True, exist_ok=True)
    names = [p.stem if p.is_file() else p.name for p in inputs]
    return [out / f"{n}{suffix}" for n in names]


def _expand_batch(paths: list[Path], batch: bool) -> list[Path]:
    if not batch:
        return paths
    from jointwear.errors import BadInputError

    items: list[Path] = []
    for p in paths:
        if not p.is_dir():
            raise BadInputError(f"--batch: '{p}' is not a folder of scans")
        children = sorted(c for c in p.iterdir() if not c.name.startswith("."))
        if not children:
            raise BadInputError(f"--batch: folder '{p}' is empty")
        items.extend(children)
    return items


def _assess_point_file(path: Path, target: Path | None, units: str | None) -> None:
    """``assess`` of a file of Cartesian points: exact LS circle per layer, printed in mm/µm."""
    from jointwear import io
    from jointwear.errors import BadInputError
    from jointwear.metrology.assess import assess_points
    from jointwear.metrology.readers.table import TextFormat, parse_file, unit_factor

    pf = parse_file(path, TextFormat(units=units))
    cols = list(pf.columns)
    if "x" not in cols or "y" not in cols:
        raise BadInputError(
            f"'{path}': not a netCDF scan, and its columns ({', '.join(cols)}) are not x, y "
            "points; import instrument traces with 'jointwear metrology import' first, or name "
            "the columns X, Y (and Z)"
        )
    if pf.units is None:
        raise BadInputError(
            f"'{path}': the length unit of the points is not stated; pass --units (um, mm, m)"
        )
    f = unit_factor(pf.units)
    x, y = pf.data[:, cols.index("x")] * f, pf.data[:, cols.index("y")] * f
    z = None
    if "z" in cols:
        zu = pf.column_units.get(str(cols.index("z"))) or pf.z_units or pf.units
        z = pf.data[:, cols.index("z")] * unit_factor(zu)
    ds = assess_points(x, y, z, source=str(path))
    typer.echo(f"{path}  (exact least-squares circle per layer; lengths in mm, form in µm)")
    for i in range(ds.sizes["z"]):
        typer.echo(
            f"  z {float(ds['z'][i]) * 1e3:9.4f}  n {int(ds['n_points'][i]):6d}  arc "
            f"{float(ds['arc'][i]):6.1f} deg  centre ({float(ds['x0'][i]) * 1e3:.9g}, "
            f"{float(ds['y0'][i]) * 1e3:.9g})  radius {float(ds['radius'][i]) * 1e3:.12g}  "
            f"RONt {float(ds['RONt_LS'][i]) * 1e6:.4f}  RONq {float(ds['RONq_LS'][i]) * 1e6:.4f}"
        )
    if target is not None:
        io.save(ds, target, inputs=[path], source=_SOURCE, parameters={"units": pf.units})
        typer.echo(f"wrote {target}")


def import_cmd(
    paths: Annotated[
        list[Path],
        typer.Argument(
            help="Scan(s): a text export, a folder of per-layer files, or (with --batch) "
            "folders holding many scans."
        ),
    ],
    out: Annotated[
        Path,
        typer.Option("--out", "-o", help="Output .nc (one scan) or folder (several scans)."),
    ] = Path("scan.nc"),
    overwrite: Overwrite = False,
    angle_zero: Annotated[
        str | None,
        typer.Option(
            "--angle-zero",
            help="Where the instrument's 0 degree points in the bearing frame: +x, +y, -x, "
            "-y or degrees CCW from +x. Required (never guessed).",
        ),
    ] = None,
    angle_direction: Annotated[
        str | None,
        typer.Option(
            "--angle-direction", help="clockwise or counterclockwise, seen from +z. Required."
        ),
    ] = None,
    preset: Annotated[
        Preset,
        typer.Option("--preset", help="generic or talyrond (values in µm, whole revolutions)."),
    ] = Preset.generic,
    layout: Annotated[
        Layout, typer.Option("--layout", help="auto, single, folder, long or wide.")
    ] = Layout.auto,
    units: Annotated[
        str | None,
        typer.Option(
            "--units",
            help="Length unit of files that do not state it: um, mm, m or inch (a unit the "
            "file contradicts is an error).",
            callback=_length_unit,
        ),
    ] = None,
    delimiter: Annotated[
        str | None, typer.Option("--delimiter", help="tab, semicolon, comma or whitespace.")
    ] = None,
    decimal: Annotated[
        Decimal | None, typer.Option("--decimal", help="Decimal separator: '.' or ','.")
    ] = None,
    header_lines: Annotated[
        int | None, typer.Option("--header-lines", help="Lines before the numeric table.")
    ] = None,
    columns: Annotated[
        str | None,
        typer.Option(
            "--columns",
            help="Comma-separated column meanings: angle_deg, angle_rad, index, x, y, z, "
            "radius, deviation, ignore.",
        ),
    ] = None,
    value: Annotated[
        ValueKind,
        typer.Option(
            "--value-kind",
            "--value",
            help="Values are radius or deviation (auto: from the column name, else from "
            "unambiguous numbers, else refused).",
        ),
    ] = ValueKind.auto,
    angle_unit: Annotated[
        AngleUnit | None,
        typer.Option(
            "--angle-unit",
            help="Unit of the angle column when the file does not state it: deg, rad or "
            "index (point number over one turn).",
        ),
    ] = None,
    arc: Annotated[
        Arc | None,
        typer.Option(
            "--arc",
            help="Each layer is one full turn or a partial arc (settles an ambiguous angle "
            "unit; 'full' is needed for files without an angle column).",
        ),
    ] = None,
    z_units: Annotated[
        str | None,
        typer.Option(
            "--z-units",
            help="Unit of z (column, header, file names) when not stated: mm, um, m.",
        ),
    ] = None,
    sheet: Annotated[
        str | None,
        typer.Option("--sheet", help="Worksheet of an Excel workbook with several sheets."),
    ] = None,
    layer_spacing_mm: Annotated[
        float | None, typer.Option("--layer-spacing-mm", help="Layer spacing [mm].")
    ] = None,
    z_mid_mm: Annotated[
        float | None,
        typer.Option(
            "--z-mid-mm",
            help="Instrument height of the bearing mid-width [mm] (default: middle of the layers).",
        ),
    ] = None,
    expected_points: Annotated[
        int | None, typer.Option("--expected-points", help="Points every layer must have.")
    ] = None,
    allow_partial: Annotated[
        bool, typer.Option("--allow-partial", help="Accept incomplete layers (NaN).")
    ] = False,
    resample: Annotated[
        bool, typer.Option("--resample", help="Interpolate layers onto one uniform grid.")
    ] = False,
    batch: Annotated[
        bool,
        typer.Option("--batch", help="Each entry of each PATH folder is a separate scan."),
    ] = False,
    pattern: Annotated[
        str,
        typer.Option("--pattern", help="Glob of the per-layer files in a folder, e.g. '*.txt'."),
    ] = "*",
    instrument: Annotated[
        str | None, typer.Option("--instrument", help="Instrument name for 'source'.")
    ] = None,
    ignore_header: Annotated[
        list[str] | None,
        typer.Option(
            "--ignore-header",
            help="A header claim known to be wrong (repeat): units, nominal_radius, points, "
            "filter, layers, z_extent, layer_spacing, z.",
        ),
    ] = None,
    z_source: Annotated[
        str,
        typer.Option(
            "--z-source",
            help="Where z comes from: auto, option, column, numbers, manifest, header, names, "
            "spacing (auto refuses when two sources disagree).",
        ),
    ] = "auto",
    thousands: Annotated[
        str | None,
        typer.Option("--thousands", help="Thousands separator of the numbers: , . ' or space."),
    ] = None,
    radius_range_mm: Annotated[
        tuple[float, float] | None,
        typer.Option(
            "--radius-range-mm", help="Plausible bore radius MIN MAX [mm] (default 0.5 2000)."
        ),
    ] = None,
    max_deviation_mm: Annotated[
        float | None,
        typer.Option("--max-deviation-mm", help="Largest plausible |deviation| [mm] (default 1)."),
    ] = None,
    nominal_tolerance: Annotated[
        float | None,
        typer.Option(
            "--nominal-tolerance",
            help="Relative tolerance of the radius against the header's nominal (default 0.05).",
        ),
    ] = None,
    min_form_nm: Annotated[
        float | None,
        typer.Option(
            "--min-form-nm", help="Smallest plausible peak-to-valley of deviations [nm] (10)."
        ),
    ] = None,
) -> None:
    """Import roundness/cylindricity text exports into contract netCDF files."""
    from jointwear import io
    from jointwear.metrology.readers import read_scan, read_talyrond

    _require_convention(angle_zero, angle_direction)
    reader = read_talyrond if preset == "talyrond" else read_scan
    items, targets = _import_items(paths, batch, out)
    opts = dict(
        layout=str(layout),
        delimiter=delimiter,
        decimal=str(decimal) if decimal is not None else None,
        header_lines=header_lines,
        columns=tuple(c.strip() for c in columns.split(",")) if columns else None,
        value=str(value),
        angle_unit=str(angle_unit) if angle_unit is not None else None,
        arc=str(arc) if arc is not None else None,
        z_units=z_units,
        sheet=sheet,
        layer_spacing=layer_spacing_mm * 1e-3 if layer_spacing_mm is not None else None,
        z_mid=z_mid_mm * 1e-3 if z_mid_mm is not None else "centre",
        expected_points=expected_points,
        allow_partial=allow_partial,
        resample=resample,
        pattern=pattern,
        ignore_header=tuple(ignore_header or ()),
        z_source=z_source,
        thousands=thousands,
        radius_range=tuple(v * 1e-3 for v in radius_range_mm) if radius_range_mm else None,
        max_deviation=max_deviation_mm * 1e-3 if max_deviation_mm is not None else None,
        nominal_tolerance=nominal_tolerance,
        min_form=min_form_nm * 1e-9 if min_form_nm is not None else None,
    )
    if instrument is not None:
        opts["instrument"] = instrument
    if units is not None:
        opts["units"] = units
    for item, target in zip(items, targets, strict=True):
        io.check_writable(target)
        ds = reader(item, convention=(angle_zero, angle_direction), **opts)
        files = ds.attrs.get("files", [])
        io.save(
            ds,
            target,
            inputs=[Path(f) for f in files],
            parameters={"angle_zero": angle_zero, "angle_direction": angle_direction, **opts},
            source=ds.attrs.get("source", _SOURCE),
        )
        var = "radius" if "radius" in ds else "radial_deviation"
        typer.echo(
            f"{target}: {var} {ds.sizes['z']} layers x {ds.sizes['theta']} points "
            f"(instrument 0 deg along {angle_zero}, {ds.attrs['instrument_angle_direction']})"
        )
        if ds.attrs.get("z_unconfirmed"):
            typer.echo(f"  note: {ds.attrs['z_unconfirmed']}")


def _require_convention(angle_zero: str | None, angle_direction: str | None) -> None:
    if angle_zero is None or angle_direction is None:
        from jointwear.errors import ConventionError

        raise ConventionError(
            "give the instrument's angle convention: --angle-zero (where its 0 degree points "
            "in the bearing frame: +x, +y, -x, -y or degrees) and --angle-direction "
            "(clockwise or counterclockwise seen from +z); text exports rarely state it and "
            "jointwear never guesses it"
        )


def _import_items(paths: list[Path], batch: bool, out: Path) -> tuple[list, list[Path]]:
    """(what to import: a path or a list of layer files per scan, the output of each)."""
    from jointwear.errors import BadInputError

    if batch:
        items: list = _expand_batch(paths, batch)
    elif len(paths) > 1 and all(p.is_file() for p in paths):
        items = [list(paths)]  # several files: the layers of one scan
    else:
        items = list(paths)
    names = [i if isinstance(i, Path) else i[0].parent for i in items]
    if len(items) > 1 and out.suffix:
        raise BadInputError(f"{len(items)} scans to import: --out must be a folder, not '{out}'")
    return items, _outputs(names, out, ".nc")


def assess_cmd(
    scans: Annotated[
        list[Path],
        typer.Argument(
            help="Imported scan(s) (.nc), or text/Excel files of x, y (and z) points, which "
            "get an exact least-squares circle per layer (need not surround the origin)."
        ),
    ],
    filter_upr: Annotated[
        float | None,
        typer.Option(
            "--filter",
            help="Filter cut-off in UPR (undulations per revolution), e.g. 15, 50, 150, 500.",
        ),
    ] = None,
    filter_kind: Annotated[
        FilterKind, typer.Option("--filter-kind", help="gaussian or 2rc.")
    ] = FilterKind.gaussian,
    reference: Annotated[
        list[Reference] | None,
        typer.Option("--reference", "-r", help="LS, MZ, MI, MC (repeat; default: all four)."),
    ] = None,
    outliers: Annotated[
        float | None,
        typer.Option("--outliers", help="Remove spikes beyond this many robust std devs."),
    ] = None,
    exact: Annotated[
        bool,
        typer.Option(
            "--exact",
            help="Also the exact geometric LS circle per layer (and cylinder for several layers).",
        ),
    ] = False,
    nominal_radius_mm: Annotated[
        float | None,
        typer.Option(
            "--nominal-radius-mm",
            help="Bore radius in mm for the centring check and --exact on deviation data "
            "(default: the mean radius, or the file's nominal radius).",
        ),
    ] = None,
    units: Annotated[
        str | None,
        typer.Option(
            "--units",
            help="Length unit of a point file that does not state it: um, mm, m or inch.",
            callback=_length_unit,
        ),
    ] = None,
    csv: Annotated[Path | None, typer.Option("--csv", help="Write the table as CSV.")] = None,
    out: Annotated[
        Path | None,
        typer.Option("--out", "-o", help="Write the full result as netCDF (file or folder)."),
    ] = None,
    overwrite: Overwrite = False,
) -> None:
    """Roundness per layer and cylindricity (LS/MZ/MI/MC), printed as a table."""
    import warnings

    import pandas as pd

    from jointwear import io
    from jointwear.metrology.assess import CentringWarning, assess, form_table

    refs = tuple(str(r) for r in reference) if reference else ("LS", "MZ", "MI", "MC")
    filter_kind = str(filter_kind)
    if csv is not None:
        io.check_writable(csv)
    targets = _outputs(scans, out, "_form.nc") if out is not None else [None] * len(scans)
    tables = []
    if nominal_radius_mm is not None and not nominal_radius_mm > 0:
        raise typer.BadParameter(
            f"must be a positive radius in mm, got {nominal_radius_mm:g}",
            param_hint="--nominal-radius-mm",
        )
    for scan_path, target in zip(scans, targets, strict=True):
        if scan_path.suffix.lower() not in (".nc", ".nc4", ".netcdf"):
            _assess_point_file(scan_path, target, units)
            continue
        scan = io.load(scan_path)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", CentringWarning)
            result = assess(
                scan,
                references=refs,
                filter_upr=filter_upr,
                filter_kind=filter_kind,
                outliers=outliers,
                exact=exact,
                radius=nominal_radius_mm * 1e-3 if nominal_radius_mm is not None else None,
            )
        for w in caught:
            typer.echo(f"warning: {scan_path}: {w.message}", err=True)
        table = form_table(result)
        typer.echo(f"{scan_path}  (filter: {result.attrs['filter']}; values in µm)")
        typer.echo(table.to_string(index=False, float_format=lambda v: f"{v:.3f}"))
        if target is not None:
            params = {
                "filter_upr": filter_upr,
                "filter_kind": filter_kind,
                "references": list(refs),
                "outliers": outliers,
            }
            _save_form(result, target, scan_path, scan, params)
        table.insert(0, "scan", str(scan_path))
        tables.append(table)
    if csv is not None and tables:
        with io.atomic_path(csv) as tmp:
            pd.concat(tables, ignore_index=True).to_csv(tmp, index=False)
        typer.echo(f"wrote {csv}")


def wearmap_cmd(
    worn: Annotated[list[Path], typer.Argument(help="Worn scan(s) (.nc).")],
    before: Annotated[
        Path | None, typer.Option("--before", help="Scan of the same bearing before wear.")
    ] = None,
    out: Annotated[
        Path, typer.Option("--out", "-o", help="Output .nc (or folder for several).")
    ] = Path("wear.nc"),
    overwrite: Overwrite = False,
    angle_offset_deg: Annotated[
        float,
        typer.Option("--angle-offset-deg", help="Set-up rotation of the before scan [degree]."),
    ] = 0.0,
    register: Annotated[
        bool, typer.Option("--register", help="Estimate the rotation from the unworn regions.")
    ] = False,
    shape: Annotated[
        Shape,
        typer.Option(
            "--shape",
            help="Unworn reference: auto (cylinder with --before, else form), cylinder, circle "
            "(per layer) or form (centre per layer, taper and lobing smooth in z).",
        ),
    ] = Shape.auto,
    threshold: Annotated[
        float, typer.Option("--threshold", help="Unworn = within this many robust std devs.")
    ] = 3.0,
    radius_mm: Annotated[
        float | None, typer.Option("--radius-mm", help="Bore radius for the volume [mm].")
    ] = None,
    plot: Annotated[
        Path | None, typer.Option("--plot", help="Also save a wear-map figure (PNG).")
    ] = None,
) -> None:
    """Wear depth over (z, theta) from a worn scan and a before-scan or fitted reference."""
    from jointwear import io
    from jointwear.metrology.wearmap import wear_map

    targets = _outputs(worn, out, "_wear.nc")
    ref = io.load(before) if before is not None else None
    for path, target in zip(worn, targets, strict=True):
        io.check_writable(target)
        w = io.load(path)
        ds = wear_map(
            w,
            ref,
            angle_offset_deg=angle_offset_deg,
            register=register,
            shape=str(shape),
            threshold=threshold,
            radius=radius_mm * 1e-3 if radius_mm else None,
        )
        inputs = [path] + ([before] if before is not None else [])
        io.save(
            ds,
            target,
            inputs=inputs,
            source=_SOURCE,
            parents=[w],
            parameters={
                "angle_offset_deg": angle_offset_deg,
                "register": register,
                "shape": str(shape),
                "threshold": threshold,
            },
        )
        typer.echo(f"{target}: {_wear_summary(ds)}")
        if plot is not None:
            from jointwear.metrology.plot import plot_wear_map

            fig_path = (
                plot if len(worn) == 1 else plot.with_name(f"{target.stem}{plot.suffix or '.png'}")
            )
            import matplotlib.pyplot as plt

            plt.close(plot_wear_map(ds, path=fig_path))
            typer.echo(f"wrote {fig_path}")


def plot_cmd(
    wear: Annotated[Path, typer.Argument(help="Wear map (.nc) with wear_depth(z, theta).")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Figure file (PNG, PDF, SVG).")] = Path(
        "wear_map.png"
    ),
    overwrite: Overwrite = False,
    layers: Annotated[
        str | None,
        typer.Option("--layers", help="Comma-separated layer indices for the polar plot."),
    ] = None,
    title: Annotated[str | None, typer.Option("--title", help="Figure title.")] = None,
) -> None:
    """Plot a wear map: unrolled angle x z map and per-layer polar plot."""
    import matplotlib.pyplot as plt

    from jointwear import io
    from jointwear.errors import BadInputError
    from jointwear.metrology.plot import plot_wear_map

    ds = io.load(wear)
    try:
        idx = [int(v) for v in layers.split(",")] if layers else None
    except ValueError:
        raise BadInputError(f"--layers {layers!r}: expected integers like 0,6,12") from None
    plt.close(plot_wear_map(ds, layers=idx, path=out, title=title))
    typer.echo(f"wrote {out}")


def _save_form(result, target: Path, scan_path: Path, scan, params: dict) -> None:
    """Write one scan's form assessment (netCDF, provenance of the scan)."""
    from jointwear import io

    result.attrs["source"] = _SOURCE
    io.save(result, target, inputs=[scan_path], parameters=params, source=_SOURCE, parents=[scan])
    typer.echo(f"wrote {target}")


def _wear_summary(ds) -> str:
    """One line: every wear-map quantity with its standard uncertainty."""
    from jointwear.metrology.wear_quantities import format_pm

    def pm(name: str, scale: float, unit: str) -> str:
        return format_pm(float(ds[name]), float(ds[f"{name}_u"]), scale, unit)

    return (
        f"max wear {pm('max_wear_depth', 1e-6, 'µm')}, worn volume "
        f"{pm('worn_volume', 1e-9, 'mm³')}, wear cylindricity {pm('wear_cylindricity', 1e-6, 'µm')}, "
        f"cylindricity {pm('cylindricity_before', 1e-6, 'µm')} -> "
        f"{pm('cylindricity_after', 1e-6, 'µm')} (MZ; standard uncertainties, k = 1)"
    )


def register(app: typer.Typer) -> None:
    """Add the metrology commands."""
    app.command("import")(import_cmd)
    app.command("assess")(assess_cmd)
    app.command("wearmap")(wearmap_cmd)
    app.command("plot")(plot_cmd)
