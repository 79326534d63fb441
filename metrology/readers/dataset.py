"""Layers to a contract Dataset: common angle grid, z from the mid-width, provenance."""

from __future__ import annotations

import re

import numpy as np
import xarray as xr

from jointwear.conventions import CANONICAL, AngleConvention, convert_theta, theta_coord, z_coord
from jointwear.errors import BadInputError, ConventionError
from jointwear.metrology.readers.layers import _Layer
from jointwear.metrology.readers.table import _NUM
from jointwear.metrology.readers.units import unit_factor

__all__ = []


def _as_convention(convention) -> AngleConvention:
    if convention is None:
        raise ConventionError(
            "the instrument's angle convention is not given: say where the instrument's 0 degree "
            "points in the bearing frame and which way its angle turns, e.g. "
            "convention=('-x', 'clockwise') (CLI: --angle-zero -x --angle-direction clockwise); "
            "text exports rarely state it and jointwear never guesses it"
        )
    if isinstance(convention, AngleConvention):
        return convention
    try:
        zero, direction = convention
    except (TypeError, ValueError):
        raise ConventionError(
            f"convention {convention!r}: expected an AngleConvention or (zero, direction)"
        ) from None
    return AngleConvention(zero, direction)


def _assemble(
    layers: list[_Layer],
    *,
    convention: AngleConvention,
    z_mid: float | str,
    instrument: str,
    fmt_notes: dict,
    metadata: dict,
    files: list[str],
    layout: str,
    allow_partial: bool,
    resample: bool,
) -> xr.Dataset:
    kinds = {lay.kind for lay in layers}
    if len(kinds) > 1:
        raise BadInputError(
            f"layers mix radius and deviation values ({', '.join(sorted(kinds))}); pass "
            "columns=... so every layer has the same meaning"
        )
    kind = kinds.pop()
    counts = [lay.value.size for lay in layers]
    n = max(counts)
    if len(set(counts)) > 1 and not (allow_partial or resample):
        k = int(np.argmin(counts))
        raise BadInputError(
            f"'{layers[k].source}': layer {k + 1} has {counts[k]} points but the other layers "
            f"have {n}; the layer looks truncated - re-export it, or pass allow_partial=True "
            "(missing points become NaN) or resample=True"
        )
    # common angle grid: the first complete layer's, unless layers differ -> uniform grid
    ref = next(lay for lay in layers if lay.value.size == n)
    step = 360.0 / n
    notes = {}
    for lay in layers:  # angles written with a few decimals: snap to the exact uniform grid
        j = np.arange(lay.value.size)
        th0 = float(np.mean(lay.theta_deg - j * step))
        if lay.value.size == n and np.max(np.abs(lay.theta_deg - th0 - j * step)) < 1e-3 * step:
            k0 = round(th0 / step)
            if abs(th0 - k0 * step) < 1e-6 * step:  # on the grid: no 359.9999999 for 0
                th0 = k0 * step
            lay.theta_deg = round(th0, 9) + j * step
            notes["angles_snapped"] = (
                "angles within 0.1 % of a sample step of a uniform grid were set to that grid"
            )
    grid = np.mod(ref.theta_deg, 360.0)
    same = all(
        lay.value.size == n and np.allclose(np.mod(lay.theta_deg, 360.0), grid, atol=1e-6)
        for lay in layers
    )
    if not same:
        grid = np.arange(n) * 360.0 / n
        notes["resampled"] = (
            "layers had different angle samples; every layer was interpolated (periodic, "
            f"linear) onto a uniform grid of {n} points"
        )
    values = np.full((len(layers), n), np.nan)
    for i, lay in enumerate(layers):
        th = np.mod(lay.theta_deg, 360.0)
        if same:
            values[i] = lay.value
        elif allow_partial and not resample:
            # keep the points that fall on the grid, NaN elsewhere
            idx = np.rint(th / (360.0 / n)).astype(int) % n
            values[i, idx] = lay.value
        else:
            o = np.argsort(th)
            tt, vv = th[o], lay.value[o]
            values[i] = np.interp(
                grid,
                np.concatenate([tt[-1:] - 360, tt, tt[:1] + 360]),
                np.concatenate([vv[-1:], vv, vv[:1]]),
            )
    order = np.argsort(grid)
    grid, values = grid[order], values[:, order]
    zs = np.array([lay.z if lay.z is not None else np.nan for lay in layers], dtype=float)
    if np.unique(zs).size != zs.size:
        raise BadInputError(
            f"two layers have the same z ({', '.join(f'{v:g}' for v in zs)} m); check the "
            "manifest / file names / layer_spacing"
        )
    zo = np.argsort(zs)
    zs, values = zs[zo], values[zo]
    if z_mid == "centre":
        mid = 0.5 * (zs.min() + zs.max())
        znote = (
            "z = instrument height minus the middle of the measured layers (assumed to be the "
            "bearing mid-width; pass z_mid to set it)"
        )
    else:
        mid = float(z_mid)
        znote = f"z = instrument height minus {mid:g} m (the bearing mid-width, given)"
    name = "radius" if kind == "radius" else "radial_deviation"
    da = xr.DataArray(
        values,
        dims=("z", "theta"),
        coords={"z": z_coord(zs - mid, note=znote), "theta": theta_coord(grid, convention)},
        attrs={
            "units": "m",
            "long_name": "measured bore radius"
            if kind == "radius"
            else "measured radial deviation (about the instrument's spindle axis)",
        },
    )
    ds = xr.Dataset({name: da})
    ds = convert_theta(ds, CANONICAL)
    ds["z"].attrs["instrument_height_of_z0"] = float(mid)
    origin = _data_origin(metadata)
    attrs = {
        "title": "roundness/cylindricity scan",
        "source": f"{'measurement' if origin == 'measured' else origin}: {instrument}",
        "data_origin": origin,
        "instrument": instrument,
        "instrument_angle_zero": convention.zero,
        "instrument_angle_direction": convention.direction,
        "instrument_angle_note": (
            f"the instrument's 0 degree points along {convention.zero} of the bearing frame and its "
            f"angle increases {convention.direction} seen from +z (stated by the user); theta "
            "has been converted to the canonical convention"
        ),
        "layout": layout,
        "files": files,
        "n_layers": len(layers),
        "n_points_per_layer": int(n),
        "reader_guesses": fmt_notes,
        "instrument_metadata": metadata,
        **notes,
    }
    nominal = _nominal_radius(metadata)
    if nominal is not None:
        attrs["nominal_radius"] = nominal
    ds.attrs.update(attrs)
    return ds


def _data_origin(meta: dict) -> str:
    """``data_origin`` from a ``Data origin:`` header line (generated files say "synthetic").

    An instrument export without that line is taken as measured (it came from the instrument);
    a stated origin is kept whatever it is, so an imported generated scan stays synthetic.
    """
    for k, v in meta.items():
        if str(k).strip().lower().replace("_", " ") == "data origin":
            value = str(v).strip().lower()
            if value in ("measured", "synthetic", "simulated"):
                return value
            raise BadInputError(
                f"header 'Data origin: {v}' is not one of measured, synthetic, simulated; "
                "correct the header line"
            )
    return "measured"


def _nominal_radius(meta: dict) -> float | None:
    for k, v in meta.items():
        kl = k.lower().strip()
        if kl in ("nominal radius", "radius", "nominal_radius", "diameter", "nominal diameter"):
            m = re.match(rf"^\s*({_NUM})\s*([A-Za-zµμ\"]+)?", str(v))
            if m and m.group(2):
                try:
                    val = float(m.group(1).replace(",", ".")) * unit_factor(m.group(2))
                except BadInputError:
                    return None
                return val / 2 if "diameter" in kl else val
    return None
