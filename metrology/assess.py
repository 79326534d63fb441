"""Full form assessment of a scan: per-layer roundness, whole-bore cylindricity, spectrum.

:func:`assess` runs, for a (z, theta) scan: optional outlier removal (reports the count),
optional filtering (Gaussian or 2RC, cut-off in UPR), centring by the limaçon (eccentricity and
its direction per layer, with a warning when the limaçon's neglected term e^2/(4R) exceeds a
tolerance), the four reference circles per layer (RONt/p/v/q), the four reference cylinders
(CYLt/p/v/q), the exact geometric least-squares cylinder, and the harmonic spectrum per layer.
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import xarray as xr

from jointwear.conventions import z_coord
from jointwear.errors import BadInputError
from jointwear.metrology.filters import (
    filter_profile,
    harmonic_spectrum,
    is_uniform,
    remove_outliers,
)
from jointwear.metrology.fit import fit_circle, fit_circle_polar, fit_cylinder_polar
from jointwear.metrology.form import (
    REFERENCES,
    circle_zone,
    circle_zones,
    cylinder_zone,
    limacon_error,
    normalise_reference,
    scan_variable,
)

__all__ = ["CentringWarning", "assess", "assess_points", "assess_point_file", "form_table"]

_PARAMS = {"t": "peak-to-valley", "p": "peak", "v": "valley", "q": "RMS"}


class CentringWarning(UserWarning):
    """The eccentricity is so large that the limaçon approximation is off by more than the
    stated tolerance (re-centre the part, or use the exact fits)."""


def _scan_var(scan: xr.Dataset | xr.DataArray) -> tuple[xr.DataArray, str]:
    if isinstance(scan, xr.DataArray):
        return scan, str(scan.name or "radius")
    return scan_variable(scan, "assess")


def assess(
    scan: xr.Dataset | xr.DataArray,
    *,
    references: tuple[str, ...] = tuple(REFERENCES),
    filter_upr: float | None = None,
    filter_kind: str = "gaussian",
    outliers: float | None = None,
    max_harmonic: int = 150,
    limacon_tolerance: float = 10e-9,
    radius: float | None = None,
    exact: bool = False,
) -> xr.Dataset:
    """Roundness per layer and cylindricity of a scan, for each reference.

    Parameters
    ----------
    scan : Dataset or DataArray
        ``radius`` or ``radial_deviation`` [m] over (``z`` [m], ``theta`` [degree]).
    references : tuple of str
        Any of "LS", "MZ", "MI", "MC".
    filter_upr : float, optional
        Filter cut-off [UPR] (e.g. 15, 50, 150, 500); None = unfiltered.
    filter_kind : {"gaussian", "2rc"}
        Filter type.
    outliers : float, optional
        Remove spikes beyond this many robust standard deviations (e.g. 4); None = keep all.
    max_harmonic : int
        Highest harmonic order in the spectrum.
    limacon_tolerance : float
        Warn (:class:`CentringWarning`) when e^2/(4R) exceeds this [m].
    radius : float, optional
        Bore radius for the centring check [m] (default: the mean radius, or the
        ``nominal_radius`` attribute of deviation data).
    exact : bool
        Also compute the exact geometric least-squares circle of each layer and, for several
        layers, the exact cylinder. Deviation data need the bore radius (``radius`` or the
        ``nominal_radius`` attribute); without it the request is refused, never ignored.

    Returns
    -------
    Dataset
        Per layer (``z``): ``RON{t,p,v,q}_{ref}`` [m], ``eccentricity`` [m],
        ``eccentricity_angle`` [degree, the scan's theta convention], ``outliers_removed``;
        scalars ``CYL{t,p,v,q}_{ref}`` [m], ``axis_tilt_x``/``_y`` [1]; ``harmonic_amplitude``
        (z, harmonic) [m]; settings and warnings in attrs.
    """
    da, name = _scan_var(scan)
    if set(da.dims) != {"z", "theta"}:
        raise BadInputError(f"assess: '{name}' must have dims (z, theta), found {da.dims}")
    da = da.transpose("z", "theta").sortby("theta")
    refs = tuple(normalise_reference(r) for r in references)
    z = np.asarray(da["z"].values, dtype=float)
    th = np.asarray(da["theta"].values, dtype=float)
    attrs: dict = {
        "title": "form assessment",
        "references": ",".join(refs),
        "model": "limaçon (linearised about the spindle axis) for LS/MZ/MI/MC; the exact "
        "geometric LS cylinder is given separately",
        "angle_convention_of_eccentricity_angle": f"theta of the scan (zero {da['theta'].attrs.get('angle_zero', '?')}, "
        f"{da['theta'].attrs.get('angle_direction', '?')})",
    }
    uniform = is_uniform(th)
    v, removed = _prepare(
        np.asarray(da.values, dtype=float), uniform, outliers, filter_upr, filter_kind, attrs
    )
    out, ecc = _roundness(th, v, refs)
    out["outliers_removed"] = (
        ("z",),
        removed,
        {"units": "1", "long_name": "points replaced as outliers"},
    )
    if radius is None:
        radius = _bore_radius(scan, da, name, v)
    _check_centring(ecc, radius, limacon_tolerance, attrs)
    if z.size > 1:
        out.update(_cylinders(z, th, v, refs))
    if exact:
        out.update(_exact_fits(z, th, v, name, radius))
    coords = {"z": da["z"]}
    if uniform and np.all(np.isfinite(v)):
        spec = harmonic_spectrum(v, max_order=max_harmonic)
        out["harmonic_amplitude"] = (
            ("z", "harmonic"),
            spec,
            {"units": "m", "long_name": "harmonic amplitude of each layer"},
        )
        coords["harmonic"] = (
            "harmonic",
            np.arange(spec.shape[1]),
            {"units": "1", "long_name": "harmonic order (undulations per revolution)"},
        )
    return xr.Dataset(out, coords=coords, attrs=attrs)


def _prepare(
    v: np.ndarray,
    uniform: bool,
    outliers: float | None,
    filter_upr: float | None,
    filter_kind: str,
    attrs: dict,
) -> tuple[np.ndarray, np.ndarray]:
    """Outlier removal and filtering of the (z, theta) values; returns (values, points removed
    per layer) and records both in ``attrs``."""
    removed = np.zeros(v.shape[0], dtype=np.int64)
    if outliers is not None:
        if not uniform:
            raise BadInputError(
                "assess: outlier removal needs a uniform angle grid (import with resample=True)"
            )
        v, mask = remove_outliers(v, threshold=float(outliers))
        removed = mask.sum(axis=1)
        attrs["outliers"] = (
            f"spikes farther than {outliers:g} robust standard deviations from the running median replaced by interpolation"
        )
    elif np.any(~np.isfinite(v)) and filter_upr is not None:
        raise BadInputError(
            "assess: the scan has missing points; pass outliers=<k> to fill them before filtering"
        )
    if filter_upr is not None:
        if not uniform:
            raise BadInputError(
                "assess: filtering needs a uniform angle grid (import with resample=True)"
            )
        v = filter_profile(v, float(filter_upr), kind=filter_kind)
        attrs["filter"] = f"{filter_kind} {float(filter_upr):g} UPR"
    else:
        attrs["filter"] = "none"
    return v, removed


def _zone_params(res, what: str, desc_of: str, dims: tuple, iso: str, ref: str) -> dict:
    """``{what}{t,p,v,q}_{ref}`` entries of one reference's zone results (``res``: one result,
    or a list of per-layer results)."""
    many = isinstance(res, list)
    out = {}
    for k, desc in _PARAMS.items():
        attr = {"t": "total", "p": "peak", "v": "valley", "q": "rms"}[k]
        val = np.array([getattr(r, attr) for r in res]) if many else getattr(res, attr)
        out[f"{what}{k}_{ref}"] = (
            dims,
            val,
            {"units": "m", "long_name": f"{desc_of} {what}{k} ({desc}) from the {iso} reference"},
        )
    return out


def _roundness(th: np.ndarray, v: np.ndarray, refs: tuple[str, ...]) -> tuple[dict, np.ndarray]:
    """RON{t,p,v,q} per layer for each reference, and the LS eccentricity (and its angle)."""
    out: dict[str, tuple] = {}
    ls_layers = []
    for ref in refs:
        results = circle_zones(th, v, reference=ref, what="scan")
        if ref == "LS":
            ls_layers = results
        out.update(_zone_params(results, "RON", "roundness", ("z",), REFERENCES[ref][0], ref))
    if not ls_layers:
        ls_layers = [circle_zone(th, v[i], reference="LS") for i in range(v.shape[0])]
    ecc = np.array([r.eccentricity for r in ls_layers])
    out["eccentricity"] = (
        ("z",),
        ecc,
        {"units": "m", "long_name": "distance of the LS centre from the spindle axis"},
    )
    out["eccentricity_angle"] = (
        ("z",),
        np.array([r.eccentricity_angle_deg for r in ls_layers]),
        {
            "units": "degree",
            "long_name": "direction of the LS centre offset (scan's theta convention)",
        },
    )
    return out, ecc


def _bore_radius(scan, da: xr.DataArray, name: str, v: np.ndarray) -> float | None:
    """The bore radius for the centring check: the mean radius, or the ``nominal_radius``
    attribute of deviation data (None if unknown)."""
    if name == "radius":
        return float(np.nanmean(v))
    src = scan.attrs if isinstance(scan, xr.Dataset) else da.attrs
    radius = src.get("nominal_radius")
    return float(radius) if radius is not None else None


def _check_centring(ecc: np.ndarray, radius: float | None, tolerance: float, attrs: dict) -> None:
    """Warn (:class:`CentringWarning`) when the limaçon's neglected term exceeds ``tolerance``."""
    if radius is None or not radius > 0:
        attrs["limacon_error_max"] = "not checked: bore radius unknown (pass radius=)"
        return
    err = limacon_error(float(np.max(ecc)), radius)
    attrs["limacon_error_max"] = err
    if err > tolerance:
        msg = (
            f"eccentricity up to {np.max(ecc) * 1e6:.3g} µm on radius {radius * 1e3:.4g} mm: the "
            f"limaçon approximation is off by up to e²/(4R) = {err * 1e9:.3g} nm (tolerance "
            f"{tolerance * 1e9:.3g} nm); re-centre the part or rely on the exact fit"
        )
        warnings.warn(msg, CentringWarning, stacklevel=3)
        attrs["centring_warning"] = msg


def _cylinders(z: np.ndarray, th: np.ndarray, v: np.ndarray, refs: tuple[str, ...]) -> dict:
    """CYL{t,p,v,q} for each reference and the LS axis tilt."""
    zz = np.broadcast_to(z[:, None], v.shape)
    tt = np.broadcast_to(th[None, :], v.shape)
    out: dict[str, tuple] = {}
    for ref in refs:
        res = cylinder_zone(zz, tt, v, reference=ref)
        out.update(_zone_params(res, "CYL", "cylindricity", (), REFERENCES[ref][1], ref))
        if ref == "LS":
            for i, ax in enumerate("xy"):
                out[f"axis_tilt_{ax}"] = (
                    (),
                    res.tilt[i],
                    {"units": "1", "long_name": f"LS axis slope d{ax}/dz (scan frame)"},
                )
    return out


def _exact_fits(
    z: np.ndarray, th: np.ndarray, v: np.ndarray, name: str, radius: float | None
) -> dict[str, tuple]:
    """Exact geometric LS circle per layer (and cylinder for several layers) of r(z, theta)."""
    if name != "radius":
        if radius is None or not radius > 0:
            raise BadInputError(
                "assess: exact=True (--exact) on radial deviations needs the bore radius to "
                "rebuild the radii: pass radius= (--nominal-radius-mm), or import radii"
            )
        v = v + radius
    out: dict[str, tuple] = {}
    fits = [fit_circle_polar(th, v[i]) for i in range(z.size)]
    out["RONt_LS_exact"] = (
        ("z",),
        np.array([np.nanmax(f.residual) - np.nanmin(f.residual) for f in fits]),
        {"units": "m", "long_name": "RONt from the exact geometric least-squares circle"},
    )
    out["radius_LS_exact_layer"] = (
        ("z",),
        np.array([f.radius for f in fits]),
        {"units": "m", "long_name": "radius of the exact geometric least-squares circle"},
    )
    if z.size > 1:
        zz = np.broadcast_to(z[:, None], v.shape)
        tt = np.broadcast_to(th[None, :], v.shape)
        fit = fit_cylinder_polar(zz, tt, v)
        out["CYLt_LS_exact"] = (
            (),
            float(np.nanmax(fit.residual) - np.nanmin(fit.residual)),
            {"units": "m", "long_name": "CYLt from the exact geometric least-squares cylinder"},
        )
        out["radius_LS_exact"] = (
            (),
            fit.radius,
            {"units": "m", "long_name": "radius of the exact geometric least-squares cylinder"},
        )
    return out


def assess_points(
    x: np.ndarray, y: np.ndarray, z: np.ndarray | None = None, *, source: str = "points"
) -> xr.Dataset:
    """Exact least-squares circle of each layer of a Cartesian point set (any arc, any centre).

    Parameters
    ----------
    x, y : ndarray
        Point coordinates [m]; the points need not surround the origin.
    z : ndarray, optional
        Layer height of each point [m]; points of equal z form a layer (default: one layer).
    source : str
        Name of the input for messages.

    Returns
    -------
    Dataset
        Per layer (``z``): ``x0``, ``y0``, ``radius`` [m] of the geometric LS circle (Gauss-Newton
        to machine precision), ``RON{t,p,v,q}_LS`` [m] from the orthogonal residuals,
        ``n_points``, ``arc`` [degree] covered about the fitted centre.
    """
    x = np.asarray(x, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    zz = np.zeros_like(x) if z is None else np.asarray(z, dtype=float).ravel()
    levels = np.unique(zz)
    cols: dict[str, list] = {k: [] for k in ("x0", "y0", "radius", "t", "p", "v", "q", "n", "arc")}
    for level in levels:
        sel = zz == level
        fit = fit_circle(x[sel], y[sel])
        res = fit.residual
        ang = np.sort(np.arctan2(y[sel] - fit.y0, x[sel] - fit.x0))
        gaps = np.diff(np.concatenate([ang, ang[:1] + 2 * np.pi]))
        for k, val in (
            ("x0", fit.x0),
            ("y0", fit.y0),
            ("radius", fit.radius),
            ("t", np.nanmax(res) - np.nanmin(res)),
            ("p", np.nanmax(res)),
            ("v", -np.nanmin(res)),
            ("q", fit.rms),
            ("n", int(sel.sum())),
            ("arc", float(np.degrees(2 * np.pi - np.max(gaps)))),
        ):
            cols[k].append(val)
    m = {"units": "m"}
    ds = xr.Dataset(
        {
            "x0": (("z",), cols["x0"], {**m, "long_name": "x of the LS circle centre"}),
            "y0": (("z",), cols["y0"], {**m, "long_name": "y of the LS circle centre"}),
            "radius": (("z",), cols["radius"], {**m, "long_name": "radius of the LS circle"}),
            **{
                f"RON{k}_LS": (
                    ("z",),
                    cols[k],
                    {**m, "long_name": f"roundness RON{k} ({_PARAMS[k]}) from the exact LS circle"},
                )
                for k in _PARAMS
            },
            "n_points": (("z",), cols["n"], {"units": "1", "long_name": "points in the layer"}),
            "arc": (
                ("z",),
                cols["arc"],
                {"units": "degree", "long_name": "angle covered about the fitted centre"},
            ),
        },
        coords={
            "z": z_coord(
                levels,
                note="layer height as given in the point file (not re-centred on the "
                "bearing mid-width)",
            )
        },
        attrs={
            "title": "form assessment of a point set",
            "model": "exact geometric least-squares circle per layer (orthogonal distances; "
            "Levenberg-Marquardt then Gauss-Newton with double-double residuals)",
            "input": source,
        },
    )
    return ds


def assess_point_file(path, units: str | None = None) -> tuple[xr.Dataset, str]:
    """:func:`assess_points` of a text/Excel file of x, y (and z) points.

    Parameters
    ----------
    path : path
        The file; its columns must be named X, Y (and Z).
    units : str, optional
        Length unit of the points when the file does not state it (um, mm, m, inch).

    Returns
    -------
    (Dataset, str)
        The exact least-squares circle per layer, and the unit the points were read in.
    """
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
    return assess_points(x, y, z, source=str(path)), pf.units


def form_table(result: xr.Dataset) -> pd.DataFrame:
    """Per-layer table of an :func:`assess` result in micrometres (one row per layer + bore).

    With exact fits, ``RONt_LS_exact_um`` and ``radius_LS_exact_mm`` per layer (the bore row:
    CYLt and radius of the exact cylinder).
    """

    rows = []
    refs = result.attrs.get("references", "LS,MZ,MI,MC").split(",")
    for i, zv in enumerate(result["z"].values):
        row = {"layer": i + 1, "z_mm": float(zv) * 1e3}
        for ref in refs:
            row[f"RONt_{ref}_um"] = float(result[f"RONt_{ref}"].values[i]) * 1e6
        if "RONt_LS_exact" in result:
            row["RONt_LS_exact_um"] = float(result["RONt_LS_exact"].values[i]) * 1e6
            row["radius_LS_exact_mm"] = float(result["radius_LS_exact_layer"].values[i]) * 1e3
        row["ecc_um"] = float(result["eccentricity"].values[i]) * 1e6
        row["outliers"] = int(result["outliers_removed"].values[i])
        rows.append(row)
    df = pd.DataFrame(rows)
    if f"CYLt_{refs[0]}" in result:
        cyl = {"layer": "bore", "z_mm": np.nan}
        for ref in refs:
            cyl[f"RONt_{ref}_um"] = float(result[f"CYLt_{ref}"]) * 1e6
        if "CYLt_LS_exact" in result:
            cyl["RONt_LS_exact_um"] = float(result["CYLt_LS_exact"]) * 1e6
            cyl["radius_LS_exact_mm"] = float(result["radius_LS_exact"]) * 1e3
        df = pd.concat([df, pd.DataFrame([cyl])], ignore_index=True)
    return df
