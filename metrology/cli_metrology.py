"""``jointwear metrology import | assess | wearmap | plot``: a thin layer over the library."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import AngleDirection, AngleZero, FigureOut, Overwrite
from jointwear._cli_dataclass import options_from
from jointwear._version import source_attribute
from jointwear.metrology import _cli_options as opt
from jointwear.metrology._cli_options import FilterKind, Shape
from jointwear.metrology.choices import REFERENCES, UNWORN_THRESHOLD, WEAR_SHAPE

_SOURCE = source_attribute("metrology")


def _assess_point_file(path: Path, target: Path | None, units: str | None) -> None:
    """``assess`` of a file of Cartesian points: exact LS circle per layer, printed in mm/µm."""
    from jointwear import io
    from jointwear.metrology.assess import assess_point_file

    ds, units = assess_point_file(path, units)
    typer.echo(f"{path}  (exact least-squares circle per layer; lengths in mm, form in µm)")
    for i in range(ds.sizes["z"]):
        typer.echo(
            f"  z {float(ds['z'][i]) * 1e3:9.4f}  n {int(ds['n_points'][i]):6d}  arc "
            f"{float(ds['arc'][i]):6.1f} deg  centre ({float(ds['x0'][i]) * 1e3:.9g}, "
            f"{float(ds['y0'][i]) * 1e3:.9g})  radius {float(ds['radius'][i]) * 1e3:.12g}  "
            f"RONt {float(ds['RONt_LS'][i]) * 1e6:.4f}  RONq {float(ds['RONq_LS'][i]) * 1e6:.4f}"
        )
    if target is not None:
        io.save(ds, target, inputs=[path], source=_SOURCE, parameters={"units": units})
        typer.echo(f"wrote {target}")


@options_from("reading", opt.ScanFlags)
def import_cmd(
    paths: opt.ScanPaths,
    out: opt.ImportOut = Path("scan.nc"),
    overwrite: Overwrite = False,
    angle_zero: AngleZero = None,
    angle_direction: AngleDirection = None,
    preset: opt.PresetOpt = opt.Preset.generic,
    batch: opt.Batch = False,
    *,
    reading: opt.ScanFlags,
) -> None:
    """Import roundness/cylindricity text exports into contract netCDF files."""
    from jointwear.metrology.readers.importing import import_scans

    def summary(target: Path, ds) -> None:
        var = "radius" if "radius" in ds else "radial_deviation"
        typer.echo(
            f"{target}: {var} {ds.sizes['z']} layers x {ds.sizes['theta']} points "
            f"(instrument 0 deg along {angle_zero}, {ds.attrs['instrument_angle_direction']})"
        )
        if ds.attrs.get("missing_points"):
            typer.echo(
                f"  note: {ds.attrs['missing_points']} point(s) missing in the file (read as "
                "NaN; fits skip them)"
            )
        if ds.attrs.get("z_unconfirmed"):
            typer.echo(f"  note: {ds.attrs['z_unconfirmed']}")

    import_scans(
        paths,
        out,
        angle_zero=angle_zero,
        angle_direction=angle_direction,
        preset=str(preset),
        batch=batch,
        on_saved=summary,
        **reading.keywords(),
    )


def assess_cmd(
    scans: opt.AssessScans,
    filter_upr: opt.FilterUpr = None,
    filter_kind: opt.FilterKindOpt = FilterKind.gaussian,
    reference: opt.ReferenceOpt = None,
    outliers: opt.Outliers = None,
    exact: opt.Exact = False,
    nominal_radius_mm: opt.NominalRadiusMm = None,
    units: opt.Units = None,
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
    from jointwear.metrology.readers.importing import output_paths

    refs = tuple(str(r) for r in reference) if reference else tuple(REFERENCES)
    filter_kind = str(filter_kind)
    if csv is not None:
        io.check_writable(csv)
    targets = output_paths(scans, out, "_form.nc") if out is not None else [None] * len(scans)
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
    ] = Shape(WEAR_SHAPE),
    threshold: Annotated[
        float, typer.Option("--threshold", help="Unworn = within this many robust std devs.")
    ] = UNWORN_THRESHOLD,
    radius_mm: Annotated[
        float | None, typer.Option("--radius-mm", help="Bore radius for the volume [mm].")
    ] = None,
    plot: Annotated[
        Path | None, typer.Option("--plot", help="Also save a wear-map figure (PNG).")
    ] = None,
    unworn: Annotated[
        str | None,
        typer.Option(
            "--unworn",
            help="Theta arcs known to be unworn, START:END[,START:END...] [degree, canonical "
            "convention; START > END wraps through 0]: skips the search for unworn points.",
        ),
    ] = None,
    unworn_z_mm: Annotated[
        str | None,
        typer.Option(
            "--unworn-z-mm",
            help="z ranges known to be unworn, START:END[,...] [mm]; with --unworn both hold.",
        ),
    ] = None,
) -> None:
    """Wear depth over (z, theta) from a worn scan and a before-scan or fitted reference."""
    from jointwear import io
    from jointwear.metrology.readers.importing import output_paths
    from jointwear.metrology.wearmap import wear_map

    arcs = _ranges(unworn, "--unworn", 1.0)
    z_ranges = _ranges(unworn_z_mm, "--unworn-z-mm", 1e-3)
    targets = output_paths(worn, out, "_wear.nc")
    ref = io.load(before) if before is not None else None
    for path, target in zip(worn, targets, strict=True):
        io.check_writable(target)
        w = io.load(path)
        try:
            ds = wear_map(
                w,
                ref,
                angle_offset_deg=angle_offset_deg,
                register=register,
                shape=str(shape),
                threshold=threshold,
                radius=radius_mm * 1e-3 if radius_mm else None,
                unworn=arcs,
                unworn_z=z_ranges,
            )
        except Exception as exc:
            given = {
                "--before": before,
                "--out": target,
                "--angle-offset-deg": angle_offset_deg or None,
                "--register": register or None,
                "--shape": shape if str(shape) != WEAR_SHAPE else None,
                "--threshold": threshold if threshold != UNWORN_THRESHOLD else None,
                "--radius-mm": radius_mm,
                "--unworn-z-mm": unworn_z_mm,
            }
            _rethrow_with_command(exc, path, given)
            raise
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
                "unworn": unworn,
                "unworn_z_mm": unworn_z_mm,
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
    out: FigureOut = Path("wear_map.png"),
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


def _ranges(text: str | None, flag: str, scale: float) -> list[tuple[float, float]] | None:
    """``START:END[,START:END...]`` as (start, end) pairs times ``scale`` (None stays None)."""
    if text is None:
        return None
    try:
        pairs = [tuple(float(v) * scale for v in part.split(":")) for part in text.split(",")]
    except ValueError:
        pairs = [()]
    if not pairs or any(len(p) != 2 for p in pairs):
        raise typer.BadParameter(
            f"{text!r}: expected START:END pairs joined by commas, e.g. 200:330 or 330:30,150:200",
            param_hint=flag,
        )
    return pairs


def _rethrow_with_command(exc, path: Path, given: dict) -> None:
    """A wear map refused with unworn arcs: the message ends with the command to run (the
    options ``given`` that are not None, flags as True)."""
    import shlex

    from jointwear.errors import BadInputError
    from jointwear.metrology._wear_unseen import WearMapRefusal, format_arcs

    if not isinstance(exc, WearMapRefusal):
        return
    cmd = ["jointwear", "metrology", "wearmap", str(path)]
    for flag, value in given.items():
        if value is True:
            cmd.append(flag)
        elif value is not None:
            cmd += [flag, f"{value:g}" if isinstance(value, float) else str(value)]
    if exc.unworn_arcs:
        fix = (
            "if the bore is known to be unworn at theta "
            f"{format_arcs(exc.unworn_arcs)} degree (canonical convention; the arcs the data "
            "find least worn), run: " + shlex.join([*cmd, "--unworn", format_arcs(exc.unworn_arcs)])
        )
    else:  # no arcs to offer (or the arcs given cannot rule the wear out): the library's fix
        fix = exc.fix
    raise BadInputError(f"{exc.reason}; {fix}") from None


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
