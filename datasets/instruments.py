"""Realistic roundness-instrument files with known truth (``jointwear.datasets.instruments``).

:func:`generate` builds a virtual measurement of a bore on a roundness instrument: any number of
layers and points, the part's set-up on the turntable (eccentricity and tilt of its axis relative
to the spindle, applied *exactly*, not through the limaçon), form harmonics, a known wear map,
Gaussian probe noise, quantisation of the readings, and the instrument's own angle convention.
:func:`write` writes it in every text layout the readers support (a folder of per-layer files with
a manifest / z in the file names / z in the headers, a long file, a wide file), with the chosen
delimiter, decimal separator, units, header and angle column (degrees, radians, sample index,
none, or Cartesian x/y).

The truth comes back as a contract Dataset in the canonical angle convention: ``radius`` (what
an ideal importer returns: the radius about the spindle axis, including set-up, form, wear,
noise and quantisation), ``radius_true`` without noise/quantisation, ``wear_depth`` (the
imposed wear) and ``form`` (the unworn bore's form deviation), plus the set-up in attributes.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr

from jointwear.conventions import CANONICAL, AngleConvention, theta_coord, z_coord
from jointwear.datasets import _instrument_defaults as D
from jointwear.datasets._instrument_defaults import ANGLE_COLUMNS, LAYOUTS
from jointwear.errors import BadInputError
from jointwear.io import atomic_path

__all__ = [
    "InstrumentScan",
    "default_wear",
    "generate",
    "write",
    "LAYOUTS",
    "ANGLE_COLUMNS",
]


def default_wear(
    theta_deg: np.ndarray, z: np.ndarray, *, depth: float = D.WEAR_DEPTH, width_mm: float = 15.0
) -> np.ndarray:
    """A two-lobe wear pattern like the reference study's (canonical theta, z from mid-width).

    Main lobe near theta = 90 degree, deepest at the first layer (most negative z) and fading
    along the bore; a smaller lobe near 280 degree. Depth [m] at the first layer.

    Parameters
    ----------
    theta_deg : ndarray
        Canonical angle [degree].
    z : ndarray
        Axial position [m] (broadcast against theta).
    depth : float
        Peak depth of the main lobe [m].
    width_mm : float
        Axial width of the bore over which the wear fades [mm].
    """
    th = np.asarray(theta_deg, dtype=float)
    zz = np.asarray(z, dtype=float)
    zrel = np.clip((zz + width_mm * 0.5e-3) / (width_mm * 1e-3), 0.0, 1.0)

    def lobe(centre, sigma):
        d = (th - centre + 180.0) % 360.0 - 180.0
        return np.exp(-0.5 * (d / sigma) ** 2)

    return depth * (
        lobe(90.0, 18.0) * (1.0 - 0.7 * zrel) + 0.35 * lobe(280.0, 14.0) * (0.4 + 0.6 * zrel)
    )


@dataclass(frozen=True)
class InstrumentScan:
    """A virtual measurement in instrument terms plus its truth.

    Attributes
    ----------
    theta_deg : ndarray (n_points,)
        Instrument angles of the samples, in the instrument's convention [degree].
    heights : ndarray (n_layers,)
        Instrument heights of the layers [m] (first layer at 0).
    radius : ndarray (n_layers, n_points)
        Measured radius about the spindle axis [m] (noise and quantisation included).
    nominal_radius : float
        Nominal bore radius [m]; deviation files hold ``radius - nominal_radius``.
    convention : AngleConvention
        The instrument's angle convention in the bearing frame.
    truth : Dataset
        Canonical-convention truth (see module docstring).
    """

    theta_deg: np.ndarray
    heights: np.ndarray
    radius: np.ndarray
    nominal_radius: float
    convention: AngleConvention
    truth: xr.Dataset = field(repr=False)
    metadata: dict = field(default_factory=dict)


def _imposed_wear(wear, theta_can: np.ndarray, zz: np.ndarray, shape, *, depth: float, z):
    """The imposed wear depth [m] at each instrument sample (``wear`` as in :func:`generate`)."""
    if wear is None:
        w = np.zeros(shape)
    elif isinstance(wear, str):
        if wear != "default":
            raise BadInputError(f"wear {wear!r}: use 'default', an array, a callable or None")
        w = default_wear(
            np.broadcast_to(theta_can, shape),
            np.broadcast_to(zz, shape),
            depth=depth,
            width_mm=max(np.ptp(z) * 1e3, 1.0),
        )
    elif callable(wear):
        w = np.asarray(
            wear(np.broadcast_to(theta_can, shape), np.broadcast_to(zz, shape)),
            dtype=float,
        )
    else:
        arr = np.asarray(wear, dtype=float)
        if arr.shape != shape:
            raise BadInputError(f"wear array has shape {arr.shape}, expected {shape}")
        # given on the canonical sorted grid -> reorder to instrument samples
        order = np.argsort(theta_can)
        w = np.empty_like(arr)
        w[:, order] = arr
    return w


def generate(
    *,
    n_layers: int = D.N_LAYERS,
    n_points: int = D.N_POINTS,
    radius: float = D.RADIUS,
    layer_spacing: float = D.LAYER_SPACING,
    eccentricity: tuple[float, float] = D.ECCENTRICITY,
    tilt: tuple[float, float] = D.TILT,
    harmonics: Mapping[int, float] | None = None,
    wear: str | np.ndarray | Callable[[np.ndarray, np.ndarray], np.ndarray] | None = "default",
    wear_depth: float = D.WEAR_DEPTH,
    noise: float = D.NOISE,
    quantisation: float = D.QUANTISATION,
    convention: AngleConvention | tuple[str, str] = D.CONVENTION,
    start_angle_deg: float = 0.0,
    seed: int = D.SEED,
    noise_seed: int | None = None,
) -> InstrumentScan:
    """Simulate a roundness-instrument scan of a (worn) bore with known truth.

    Parameters
    ----------
    n_layers, n_points : int
        Layers and points per layer (the reference study: 13 x 18000).
    radius : float
        Nominal bore radius [m].
    layer_spacing : float
        Distance between layers [m]; layers are centred on the bore's mid-width.
    eccentricity : (float, float)
        Part axis offset from the spindle at the mid-width, instrument x (0 degree) and y
        (90 degree in the instrument's direction) [m].
    tilt : (float, float)
        Part axis tilt dx/dz, dy/dz in the instrument frame [1].
    harmonics : mapping int -> float
        Form harmonics of the unworn bore: order (UPR) -> amplitude [m]; phases are random
        (seeded) and drift slowly along z. Default {2: 1.2 µm, 3: 0.8 µm, 4: 0.3 µm, 5: 0.25 µm,
        12: 0.05 µm}.
    wear : "default", array (n_layers, n_points), callable (theta_deg, z) -> m, or None
        Imposed wear depth, in the canonical convention (an array is on the canonical grid
        returned in ``truth``).
    wear_depth : float
        Peak depth of the default wear [m].
    noise : float
        Standard deviation of the probe noise [m].
    quantisation : float
        Resolution of the readings [m] (0 = none).
    convention : AngleConvention or (zero, direction)
        The instrument's angle convention in the bearing frame.
    start_angle_deg : float
        Instrument angle of the first sample [degree].
    seed : int
        Random seed of the bore's form (harmonic phases) and, unless ``noise_seed`` is given,
        of the noise.
    noise_seed : int, optional
        Separate seed for the probe noise: two scans of the same bore (before / after wear)
        share ``seed`` and differ in ``noise_seed``.
    """
    if n_layers < D.MIN_LAYERS or n_points < D.MIN_POINTS:
        raise BadInputError(
            f"need n_layers >= {D.MIN_LAYERS} and n_points >= {D.MIN_POINTS}, got {n_layers}, "
            f"{n_points}"
        )
    conv = convention if isinstance(convention, AngleConvention) else AngleConvention(*convention)
    rng = np.random.default_rng(seed)
    if harmonics is None:
        harmonics = {2: 1.2e-6, 3: 0.8e-6, 4: 0.3e-6, 5: 0.25e-6, 12: 0.05e-6}
    theta_inst = (start_angle_deg + np.arange(n_points) * 360.0 / n_points) % 360.0
    heights = np.arange(n_layers) * layer_spacing
    z = heights - 0.5 * (heights[0] + heights[-1])
    # canonical angle of each instrument sample
    theta_can = CANONICAL.from_physical(conv.to_physical(theta_inst))
    # form of the bore (defined on the part: canonical angle)
    tc = np.radians(theta_can)[None, :]
    zz = z[:, None]
    form = np.zeros((n_layers, n_points))
    for k, amp in harmonics.items():
        phase = rng.uniform(0, 2 * np.pi)
        drift = rng.uniform(-1, 1) * 50.0  # rad/m
        form += amp * np.cos(k * tc + phase + drift * zz)
    w = _imposed_wear(wear, theta_can, zz, form.shape, depth=wear_depth, z=z)
    rho = radius + form + w  # part radius profile at each sample's direction
    # exact set-up: part axis at (ex + tx z, ey + ty z) in the instrument frame
    phi = np.radians(theta_inst)[None, :]
    ex = eccentricity[0] + tilt[0] * zz
    ey = eccentricity[1] + tilt[1] * zz
    e = np.hypot(ex, ey)
    alpha = np.arctan2(ey, ex)
    r_true = e * np.cos(phi - alpha) + np.sqrt(rho**2 - (e * np.sin(phi - alpha)) ** 2)
    nrng = rng if noise_seed is None else np.random.default_rng(noise_seed)
    r = r_true + noise * nrng.standard_normal(r_true.shape)
    if quantisation > 0:
        r = radius + np.round((r - radius) / quantisation) * quantisation
    order = np.argsort(theta_can)
    tcoord = theta_coord(theta_can[order], CANONICAL)
    zc = z_coord(z, note="layers centred on the bore mid-width")

    def var(a, long_name):
        return (("z", "theta"), a[:, order], {"units": "m", "long_name": long_name})

    truth = xr.Dataset(
        {
            "radius": var(r, "radius about the spindle axis as the instrument reads it"),
            "radius_true": var(r_true, "radius about the spindle axis without noise"),
            "wear_depth": var(w, "imposed wear depth (positive = material removed)"),
            "form": var(form, "form deviation of the unworn bore"),
        },
        coords={"z": zc, "theta": tcoord},
        attrs={
            "title": "synthetic roundness scan (truth)",
            "source": "jointwear datasets instruments",
            "nominal_radius": radius,
            "eccentricity_x": eccentricity[0],
            "eccentricity_y": eccentricity[1],
            "tilt_x": tilt[0],
            "tilt_y": tilt[1],
            "setup_frame": "instrument x = instrument 0 degree, y = instrument 90 degree",
            "noise": noise,
            "quantisation": quantisation,
            "instrument_angle_zero": conv.zero,
            "instrument_angle_direction": conv.direction,
            "harmonics": json.dumps({str(k): v for k, v in harmonics.items()}),
            "seed": seed,
        },
    )
    return InstrumentScan(
        theta_deg=theta_inst,
        heights=heights,
        radius=r,
        nominal_radius=radius,
        convention=conv,
        truth=truth,
        metadata={"instrument": "Talyrond 565H (simulated)", "operator": "jointwear"},
    )


def _fmt(values: np.ndarray, decimals: int, decimal: str) -> list[str]:
    out = [f"{v:.{decimals}f}" for v in values]
    if decimal == ",":
        out = [s.replace(".", ",") for s in out]
    return out


def _table(cols: list[list[str]], delim: str) -> str:
    return "\n".join(delim.join(row) for row in zip(*cols, strict=True)) + "\n"


@dataclass(frozen=True)
class _TextFormat:
    """How :func:`write` spells a scan: value, units, angle column, separators, header."""

    scan: InstrumentScan
    layout: str
    value: str
    units: str
    angle: str
    sep: str
    decimal: str
    header: bool
    column_names: bool
    decimals: int

    def header_lines(self, extra: dict[str, str] | None = None) -> str:
        """Keyword/value metadata lines (none without ``header``)."""
        if not self.header:
            return ""
        scan, angle = self.scan, self.angle
        meta = {
            "Instrument": scan.metadata.get("instrument", "Talyrond"),
            "Operator": scan.metadata.get("operator", ""),
            "Units": self.units,
            # the angle unit and the span are stated, never left to the reader's judgement
            "Angle unit": {"deg": "deg", "rad": "rad", "index": "index"}.get(angle, ""),
            "Arc": "full" if angle != "xy" else "",
            "Z unit": "mm" if self.layout in ("long", "folder-header") else "",
            "Points": str(scan.radius.shape[1]),
            "Nominal radius": f"{scan.nominal_radius * 1e3:.6f} mm",
            # generated with a known truth: the importer keeps this (data contract: data_origin)
            "Data origin": "synthetic",
            **(extra or {}),
        }
        return "".join(f"{k}: {v}\n" for k, v in meta.items() if v != "")

    def layer_columns(self, i: int) -> tuple[list[str], list[list[str]]]:
        """Column names and formatted columns of layer ``i``."""
        scan, units, f = self.scan, self.units, D.LENGTH_UNITS[self.units]
        th, n = scan.theta_deg, scan.radius.shape[1]
        fmt = self.numbers
        if self.angle == "xy":
            t = np.radians(th)
            x = scan.radius[i] * np.cos(t) / f
            y = scan.radius[i] * np.sin(t) / f
            return [f"X [{units}]", f"Y [{units}]"], [fmt(x), fmt(y)]
        deviation = self.value == "deviation"
        vname = ("Deviation" if deviation else "Radius") + f" [{units}]"
        v = fmt((scan.radius[i] - (scan.nominal_radius if deviation else 0.0)) / f)
        if self.angle == "deg":
            return ["Angle (deg)", vname], [_fmt(th, 6, self.decimal), v]
        if self.angle == "rad":
            return ["Angle (rad)", vname], [_fmt(np.radians(th), 9, self.decimal), v]
        if self.angle == "index":
            return ["Index", vname], [[str(j) for j in range(n)], v]
        return [vname], [v]

    def numbers(self, values: np.ndarray) -> list[str]:
        """Values in the file's length unit, with its decimals and decimal separator."""
        return _fmt(values, self.decimals, self.decimal)

    def text(self, names: list[str], cols: list[list[str]], extra: dict | None = None) -> str:
        """A whole file: header, column names, table."""
        line = self.sep.join(names) + "\n" if self.column_names else ""
        return self.header_lines(extra) + line + _table(cols, self.sep)


def _folder_files(fmt: _TextFormat, path: Path) -> list[tuple[Path, str]]:
    """Per-layer files (and the manifest of the ``folder`` layout)."""
    scan, layout = fmt.scan, fmt.layout
    files, names = [], []
    for i in range(scan.radius.shape[0]):
        hz = scan.heights[i] * 1e3
        name = f"trace_z{hz:+.3f}mm.txt" if layout == "folder-names" else f"layer{i + 1:02d}.txt"
        extra = {"Height": f"{hz:.4f} mm"} if layout == "folder-header" else {}
        files.append((path / name, fmt.text(*fmt.layer_columns(i), extra)))
        names.append(name)
    if layout == "folder":
        man = "file,z_mm\n" + "".join(
            f"{nm},{scan.heights[i] * 1e3:.4f}\n" for i, nm in enumerate(names)
        )
        files.append((path / "manifest.csv", man))
    return files


def _long_text(fmt: _TextFormat) -> str:
    """All layers one below the other, with a height column first."""
    scan = fmt.scan
    nz, n = scan.radius.shape
    zcol: list[str] = []
    rest: list[list[str]] | None = None
    cn: list[str] = []
    for i in range(nz):
        cn, cols = fmt.layer_columns(i)
        zcol += _fmt(np.full(n, scan.heights[i] * 1e3), 4, fmt.decimal)
        rest = cols if rest is None else [a + b for a, b in zip(rest, cols, strict=True)]
    assert rest is not None
    return fmt.text(["Height [mm]"] + cn, [zcol] + rest)


def _wide_text(fmt: _TextFormat) -> str:
    """One angle column, then one value column per layer."""
    if fmt.angle == "xy":
        raise BadInputError("the wide layout holds one value column per layer; use angle='deg'")
    scan = fmt.scan
    nz = scan.radius.shape[0]
    cn0, cols0 = fmt.layer_columns(0)
    vcols = [fmt.layer_columns(i)[1][-1] for i in range(nz)]
    names = cn0[:-1] + [f"z={scan.heights[i] * 1e3:.3f}mm" for i in range(nz)]
    return fmt.text(names, cols0[:-1] + vcols)


def write(
    scan: InstrumentScan,
    path: str | Path,
    *,
    layout: str = D.LAYOUT,
    value: str = D.VALUE,
    units: str = D.UNITS,
    angle: str = D.ANGLE,
    delimiter: str = D.DELIMITER,
    decimal: str = D.DECIMAL,
    header: bool = True,
    column_names: bool = True,
    decimals: int | None = None,
) -> list[Path]:
    """Write ``scan`` as instrument text files.

    Parameters
    ----------
    scan : InstrumentScan
        From :func:`generate`.
    path : path
        Output folder (folder layouts) or file (long, wide, single; ``single`` writes the first
        layer only).
    layout : {"folder", "folder-names", "folder-header", "long", "wide", "single"}
        ``folder``: per-layer files ``layer01.txt`` ... plus ``manifest.csv`` (file, z in mm);
        ``folder-names``: z in the file names (``trace_z+2.000mm.txt``), no manifest;
        ``folder-header``: z as a ``Height`` keyword in each header.
    value : {"deviation", "radius"}
        Radial deviation from the nominal radius, or the radius.
    units : {"um", "mm", "m", "inch"}
        Length unit of the values (stated in the header when ``header``).
    angle : {"deg", "rad", "index", "none", "xy"}
        Angle column: degrees, radians, sample index, none (equal spacing implied), or Cartesian
        x / y columns instead of angle and value.
    delimiter : {"\\t", ";", ",", " "}
        Field separator.
    decimal : {".", ","}
        Decimal separator.
    header : bool
        Write keyword/value metadata lines.
    column_names : bool
        Write a line of column names.
    decimals : int, optional
        Digits after the decimal point (default: enough for 0.1 nm).

    Returns
    -------
    list of Path
        The files written (the manifest included).
    """
    if layout not in LAYOUTS:
        raise BadInputError(f"layout {layout!r} not supported; use one of {', '.join(LAYOUTS)}")
    if angle not in ANGLE_COLUMNS:
        raise BadInputError(f"angle {angle!r} not supported; use one of {', '.join(ANGLE_COLUMNS)}")
    if value not in D.VALUES:
        raise BadInputError(f"value must be 'deviation' or 'radius', got {value!r}")
    if units not in D.LENGTH_UNITS:
        raise BadInputError(f"units {units!r}: use one of {', '.join(D.LENGTH_UNITS)}")
    if decimal == delimiter:
        raise BadInputError("decimal separator and delimiter must differ")
    if angle == "xy" and value == "deviation":
        value = "radius"  # Cartesian points are absolute positions
    if decimals is None:
        decimals = max(0, int(np.ceil(-np.log10(1e-10 / D.LENGTH_UNITS[units]))))
    sep = "  " if delimiter == " " else delimiter
    fmt = _TextFormat(
        scan, layout, value, units, angle, sep, decimal, header, column_names, decimals
    )
    path = Path(path)
    if layout.startswith("folder"):
        path.mkdir(parents=True, exist_ok=True)
        files = _folder_files(fmt, path)
    elif layout == "single":
        files = [(path, fmt.text(*fmt.layer_columns(0)))]
    elif layout == "long":
        files = [(path, _long_text(fmt))]
    else:
        files = [(path, _wide_text(fmt))]
    for p, text in files:
        with atomic_path(p) as tmp:
            Path(tmp).write_text(text, encoding="utf-8")
    return [p for p, _ in files]
