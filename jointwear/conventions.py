"""The data contract: coordinate and variable names, units, and the angle/axial conventions.

Every jointwear module reads and writes :class:`xarray.Dataset` objects that follow this
contract (documented in ``docs/conventions.md``). This module holds the names and units, builds
correctly-annotated coordinates, converts angle coordinates between conventions and validates
datasets.

Angle conventions
-----------------
An angle convention says where ``theta = 0`` points in the bearing frame and which way theta
increases, seen from +z. ``angle_zero`` is one of ``"+x"``, ``"+y"``, ``"-x"``, ``"-y"`` or a number
of degrees measured counter-clockwise from +x (e.g. ``"37.5"``); ``angle_direction`` is
``"clockwise"`` or ``"counterclockwise"``. The canonical convention is the reference study's:
zero along -x, increasing clockwise (:data:`CANONICAL`).
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from jointwear.errors import ConventionError

if TYPE_CHECKING:  # xarray is imported where a DataArray is made (jointwear info reads headers)
    import xarray as xr

__all__ = [
    "AngleConvention",
    "CANONICAL",
    "COORDINATES",
    "VARIABLES",
    "REQUIRED_GLOBAL_ATTRS",
    "angle_convention_of",
    "convert_theta",
    "to_canonical",
    "theta_coord",
    "z_coord",
    "variable_attrs",
    "annotate",
    "validate",
    "check_convention",
    "is_partial",
    "describe_status",
]

#: Coordinates of the contract: name -> (units, long_name).
COORDINATES: dict[str, tuple[str, str]] = {
    "time": ("s", "elapsed time since the start of the record"),
    "theta": ("degree", "angle around the bearing axis"),
    "z": ("m", "axial position along the bearing, 0 at mid-width"),
    "axis": ("1", "vector component"),
    "cycles": ("1", "crank revolutions completed"),
    "point": ("1", "index of a tracked point or subset"),
    "camera": ("1", "stereo camera"),
}

#: Variables of the contract: name -> (units, long_name). Units are UDUNITS strings.
VARIABLES: dict[str, tuple[str, str]] = {
    "wear_depth": ("m", "wear depth of the bearing surface (positive = material removed)"),
    "radius": ("m", "measured or simulated bore radius"),
    "radial_deviation": ("m", "radial deviation from the reference radius"),
    "follower_velocity": ("m s-1", "velocity of the follower centre of mass"),
    "follower_position": ("m", "position of the follower centre of mass"),
    "journal_offset": ("m", "journal centre relative to the bearing centre, bearing frame"),
    "journal_displacement": (
        "m",
        "displacement of the journal (or its cap) from its first position",
    ),
    "contact_force": ("N", "magnitude of the resultant contact force in joint C"),
    "crank_angle": ("rad", "crank angle from +x, counter-clockwise"),
    "displacement": ("m", "displacement of a tracked point"),
    "zncc": ("1", "zero-normalised cross-correlation coefficient"),
}

#: Global attributes every file written by jointwear carries.
REQUIRED_GLOBAL_ATTRS = ("Conventions", "title", "source", "history", "provenance")

_AXIS_ANGLES = {"+x": 0.0, "x": 0.0, "+y": 90.0, "y": 90.0, "-x": 180.0, "-y": 270.0}
_DIRECTIONS = {
    "clockwise": -1.0,
    "cw": -1.0,
    "counterclockwise": 1.0,
    "ccw": 1.0,
    "anticlockwise": 1.0,
    "counter-clockwise": 1.0,
}
_DIRECTION_NAMES = {-1.0: "clockwise", 1.0: "counterclockwise"}


@dataclass(frozen=True)
class AngleConvention:
    """Where theta = 0 points in the bearing frame and which way theta grows (seen from +z).

    Parameters
    ----------
    zero : str
        ``"+x"``, ``"+y"``, ``"-x"``, ``"-y"``, or degrees counter-clockwise from +x as a string or
        number (e.g. ``"37.5"``).
    direction : str
        ``"clockwise"`` or ``"counterclockwise"``.
    """

    zero: str = "-x"
    direction: str = "clockwise"

    def __post_init__(self) -> None:
        object.__setattr__(self, "zero", str(self.zero).strip())
        object.__setattr__(self, "direction", str(self.direction).strip().lower())
        self.zero_angle_deg  # noqa: B018 - validates
        if self.direction not in _DIRECTIONS:
            raise ConventionError(
                f"angle_direction {self.direction!r} is not understood; use 'clockwise' or "
                "'counterclockwise' (seen from +z of the bearing frame)"
            )
        object.__setattr__(self, "direction", _DIRECTION_NAMES[_DIRECTIONS[self.direction]])

    @property
    def zero_angle_deg(self) -> float:
        """Direction of theta = 0, in degrees counter-clockwise from +x of the bearing frame."""
        key = self.zero.lower()
        if key in _AXIS_ANGLES:
            return _AXIS_ANGLES[key]
        try:
            value = float(key)
        except ValueError:
            raise ConventionError(
                f"angle_zero {self.zero!r} is not understood; use '+x', '+y', '-x', '-y' or a "
                "number of degrees counter-clockwise from +x of the bearing frame"
            ) from None
        if not np.isfinite(value):
            raise ConventionError(f"angle_zero {self.zero!r} must be finite")
        return value % 360.0

    @property
    def sign(self) -> float:
        """+1 for counter-clockwise, -1 for clockwise."""
        return _DIRECTIONS[self.direction]

    def to_physical(self, theta_deg: np.ndarray) -> np.ndarray:
        """Angle in this convention -> degrees counter-clockwise from +x."""
        return self.zero_angle_deg + self.sign * np.asarray(theta_deg, dtype=float)

    def from_physical(self, psi_deg: np.ndarray) -> np.ndarray:
        """Degrees counter-clockwise from +x -> angle in this convention, in [0, 360)."""
        return _wrap(self.sign * (np.asarray(psi_deg, dtype=float) - self.zero_angle_deg))

    def attrs(self, note: str | None = None) -> dict[str, str]:
        """The theta attributes that state this convention."""
        return {
            "angle_zero": self.zero,
            "angle_direction": self.direction,
            "angle_note": note
            or (
                f"theta = 0 along {self.zero} of the bearing frame, increasing {self.direction} "
                "seen from +z"
            ),
        }


#: The reference study's convention: zero along -x, increasing clockwise seen from +z.
CANONICAL = AngleConvention("-x", "clockwise")


def _wrap(theta_deg: np.ndarray) -> np.ndarray:
    """Wrap to [0, 360), snapping values within 1e-9 degree of 360 to 0."""
    out = np.mod(theta_deg, 360.0)
    out = np.where(np.abs(out - 360.0) < 1e-9, 0.0, out)
    return out


def angle_convention_of(obj: xr.DataArray | xr.Dataset, *, what: str = "data") -> AngleConvention:
    """Read the angle convention stated on the ``theta`` coordinate; refuse if missing."""
    if "theta" not in obj.coords:
        raise ConventionError(f"{what} has no 'theta' coordinate")
    attrs = obj.coords["theta"].attrs
    missing = [k for k in ("angle_zero", "angle_direction") if k not in attrs]
    if missing:
        raise ConventionError(
            f"{what}: the theta coordinate does not state its angle convention (missing "
            f"attribute(s) {', '.join(missing)}); set them, e.g. with "
            "jointwear.conventions.theta_coord(..., convention=AngleConvention(zero, direction)), "
            "or pass the convention explicitly - jointwear never guesses it"
        )
    return AngleConvention(attrs["angle_zero"], attrs["angle_direction"])


def convert_theta(
    obj: xr.DataArray | xr.Dataset,
    to: AngleConvention = CANONICAL,
    *,
    source: AngleConvention | None = None,
    note: str | None = None,
) -> xr.DataArray | xr.Dataset:
    """Re-express the ``theta`` coordinate of ``obj`` in another angle convention.

    The values move with their angles (a feature at physical direction psi stays at psi); the
    coordinate is wrapped to [0, 360) and re-sorted ascending.

    Parameters
    ----------
    obj : DataArray or Dataset
        Data with a ``theta`` coordinate [degree].
    to : AngleConvention
        Target convention (default: canonical).
    source : AngleConvention, optional
        Convention of ``obj``; by default read from the theta attributes (error if absent).
    note : str, optional
        Free-text ``angle_note`` for the result.
    """
    src = source or angle_convention_of(obj)
    theta = np.asarray(obj["theta"].values, dtype=float)
    if theta.size and not np.all(np.isfinite(theta)):
        raise ConventionError("theta coordinate contains NaN or infinite values")
    new = to.from_physical(src.to_physical(theta))
    old_attrs = dict(obj["theta"].attrs)
    out = obj.assign_coords(theta=("theta", new))
    out = out.sortby("theta")
    attrs = {
        k: v
        for k, v in old_attrs.items()
        if k not in ("angle_zero", "angle_direction", "angle_note")
    }
    attrs.update(to.attrs(note))
    attrs.setdefault("units", "degree")
    attrs.setdefault("long_name", COORDINATES["theta"][1])
    out["theta"].attrs = attrs
    return out


def to_canonical(obj: xr.DataArray | xr.Dataset, *, source: AngleConvention | None = None):
    """Shorthand for :func:`convert_theta` to :data:`CANONICAL`."""
    return convert_theta(obj, CANONICAL, source=source)


def theta_coord(
    theta_deg: Iterable[float],
    convention: AngleConvention = CANONICAL,
    *,
    note: str | None = None,
) -> xr.DataArray:
    """A ``theta`` coordinate [degree] with units and the convention attributes."""
    values = np.asarray(theta_deg, dtype=float)
    attrs = {"units": "degree", "long_name": COORDINATES["theta"][1]}
    attrs.update(convention.attrs(note))
    import xarray as xr

    return xr.DataArray(values, dims="theta", attrs=attrs, name="theta")


def z_coord(z_m: Iterable[float], *, note: str | None = None) -> xr.DataArray:
    """A ``z`` coordinate [m], 0 at the bearing mid-width, increasing towards +z."""
    attrs = {
        "units": "m",
        "long_name": COORDINATES["z"][1],
        "z_zero": "bearing mid-width",
        "z_direction": "+z",
    }
    if note:
        attrs["z_note"] = note
    import xarray as xr

    return xr.DataArray(np.asarray(z_m, dtype=float), dims="z", attrs=attrs, name="z")


def variable_attrs(name: str, **extra: str) -> dict[str, str]:
    """``units`` and ``long_name`` of a contract variable, plus any extra attributes."""
    if name not in VARIABLES:
        raise KeyError(f"{name!r} is not a contract variable; known: {', '.join(VARIABLES)}")
    units, long_name = VARIABLES[name]
    return {"units": units, "long_name": long_name, **extra}


def annotate(ds: xr.Dataset) -> xr.Dataset:
    """Fill in ``units``/``long_name`` of contract variables and coordinates that lack them."""
    ds = ds.copy()
    for name in list(ds.data_vars) + list(ds.coords):
        table = VARIABLES if name in VARIABLES else COORDINATES if name in COORDINATES else None
        if table is None:
            continue
        units, long_name = table[name]
        ds[name].attrs.setdefault("units", units)
        ds[name].attrs.setdefault("long_name", long_name)
    return ds


def _check_monotonic(values: np.ndarray) -> bool:
    if values.size < 2:
        return True
    d = np.diff(values)
    return bool(np.all(d > 0) or np.all(d < 0))


def validate(
    ds: xr.Dataset, *, require_provenance: bool = False, what: str = "dataset"
) -> xr.Dataset:
    """Check a dataset against the data contract; raise one error listing every problem.

    Checks: every data variable has ``units`` and ``long_name``; contract variables and
    coordinates use the contract units; ``theta`` states its convention and lies in [0, 360);
    ``z`` states its origin; numeric dimension coordinates are strictly monotonic; with
    ``require_provenance`` the global attributes of :data:`REQUIRED_GLOBAL_ATTRS` are present
    and ``provenance`` is valid JSON.

    Returns
    -------
    Dataset
        ``ds`` itself, so the call can be chained.
    """
    problems: list[str] = []
    for name, var in ds.data_vars.items():
        for key in ("units", "long_name"):
            if key not in var.attrs:
                problems.append(f"variable '{name}' has no '{key}' attribute")
        if name in VARIABLES and "units" in var.attrs:
            expected = VARIABLES[name][0]
            ok = var.attrs["units"] == expected or (
                name == "displacement" and var.attrs["units"] == "pixel"
            )
            if not ok:
                problems.append(
                    f"variable '{name}' has units {var.attrs['units']!r}, the contract says {expected!r}"
                )
    for name in ds.coords:
        coord = ds.coords[name]
        if name in COORDINATES:
            units = COORDINATES[name][0]
            if units != "1" and coord.attrs.get("units") != units:
                problems.append(
                    f"coordinate '{name}' has units {coord.attrs.get('units')!r}, the contract says {units!r}"
                )
        if name in ds.dims and coord.dtype.kind in "fiu" and coord.ndim == 1:
            vals = coord.values
            if not np.all(np.isfinite(vals)):
                problems.append(f"coordinate '{name}' contains NaN or infinite values")
            elif not _check_monotonic(vals):
                problems.append(f"coordinate '{name}' is not strictly monotonic")
    if "theta" in ds.coords:
        attrs = ds.coords["theta"].attrs
        for key in ("angle_zero", "angle_direction"):
            if key not in attrs:
                problems.append(f"coordinate 'theta' does not state '{key}'")
        if "angle_zero" in attrs and "angle_direction" in attrs:
            try:
                AngleConvention(attrs["angle_zero"], attrs["angle_direction"])
            except ConventionError as exc:
                problems.append(f"coordinate 'theta': {exc}")
        th = np.asarray(ds.coords["theta"].values, dtype=float)
        if th.size and (np.nanmin(th) < 0 or np.nanmax(th) >= 360):
            problems.append("coordinate 'theta' must lie in [0, 360) degree")
    if "z" in ds.coords:
        for key in ("z_zero", "z_direction"):
            if key not in ds.coords["z"].attrs:
                problems.append(f"coordinate 'z' does not state '{key}'")
    if require_provenance:
        for key in REQUIRED_GLOBAL_ATTRS:
            if key not in ds.attrs:
                problems.append(f"global attribute '{key}' is missing")
        if "provenance" in ds.attrs:
            try:
                json.loads(ds.attrs["provenance"])
            except (TypeError, ValueError):
                problems.append("global attribute 'provenance' is not valid JSON")
    if problems:
        raise ConventionError(
            f"{what} does not follow the jointwear data contract (docs/conventions.md):\n  - "
            + "\n  - ".join(problems)
        )
    return ds


def check_convention(obj: xr.DataArray | xr.Dataset, what: str) -> AngleConvention:
    """Alias of :func:`angle_convention_of` for use at module boundaries."""
    return angle_convention_of(obj, what=what)


def _attrs(obj: xr.Dataset | Mapping[str, object]) -> Mapping[str, object]:
    return obj.attrs if hasattr(obj, "attrs") else obj  # a Dataset, DataArray or Header


def is_partial(obj: xr.Dataset | Mapping[str, object]) -> bool:
    """True if a dataset (or its global attributes) is the partial result of a run that stopped.

    Long runs write what they computed when interrupted (Ctrl-C, SIGTERM, a failure) with the
    global attribute ``status``: ``"complete"``, ``"partial"`` (``jointwear sim wear``) or
    ``"stopped after N frames: ..."`` (``jointwear dic track``). A dataset without ``status``
    is complete.
    """
    status = str(_attrs(obj).get("status", "complete")).strip().lower()
    return status != "complete"


def describe_status(obj: xr.Dataset | Mapping[str, object]) -> str | None:
    """One line saying that, and how far, a partial result got (None if complete).

    For example ``"PARTIAL result: the run stopped after 30000 of 1e+06 cycles (status
    'partial'); continue it with --resume"``.
    """
    attrs = _attrs(obj)
    if not is_partial(attrs):
        return None
    status = str(attrs.get("status"))
    done, target = attrs.get("cycles_done"), attrs.get("cycles_target")
    if done is not None and target is not None:
        progress = f"the run stopped after {float(done):g} of {float(target):g} cycles"
    elif attrs.get("frames_processed") is not None:
        progress = f"the run stopped after {int(attrs['frames_processed'])} frames"
    else:
        progress = "the run that wrote it did not finish"
    return f"PARTIAL result: {progress} (status {status!r}); continue it with --resume"
