"""Reported values (``jointwear import reported``) as calibration data.

A reported-measurement file (the netCDF ``jointwear import reported`` writes, or its TOML) gives
scalar quantities, each with its cycles, standard uncertainty and place (:mod:`jointwear.reported`).
Those of kind ``max_wear_depth`` and ``cylindricity`` at cycles > 0 become calibration data: the
simulated map is reduced on the measured layers over the whole circle (every degree), by the
same functions as a measured map's band (:func:`jointwear.sim.calibrate._data.band_quantities`),
as compare does for the same file:

* a cylindricity is the reported *growth* ``C(N) - C(0)`` against the cylindricity of the
  simulated wear (the simulation starts from a perfect bore), with the new bore's form as a
  rectangular term of u_D (:func:`jointwear.reported.cylindricity_growth`); of the reference the
  file states (``LS`` or ``MZ``);
* a maximum wear depth as reported, at a layer or over the measured layers.

What the calibration cannot settle is refused (exit 3), naming the field that settles it: an
uncertainty not stated, a missing new-bore cylindricity, a reference ``unstated``, a layer
whose position depends on an unstated ``layers.first`` or ``layers.z_centre``. Angles and
``other`` quantities are not calibration data (said in the posterior's notes); the new bore
(cycles = 0) is the baseline of the growth, not a datum.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError
from jointwear.sim.calibrate._data import Band, Datum

__all__ = ["reported_data"]

#: reported kinds that are calibration data, with their calibration quantity
_KINDS = {"max_wear_depth": "max_wear_depth", "cylindricity": "cylindricity"}


def _layer_z(attrs: dict, layer: int, path: Path, name: str) -> np.ndarray:
    """z [m] of layer ``layer`` (0: every layer) of the file's [layers] table."""
    n, step = int(attrs["layers_count"]), float(attrs["layers_spacing_m"])
    centre = float(attrs.get("layers_z_centre_m", math.nan))
    offsets = (np.arange(n) - (n - 1) / 2.0) * step
    if layer:
        offsets = offsets[layer - 1 : layer]
    if not np.isfinite(centre):
        raise BadInputError(
            f"{path}: quantity.{name} is measured on layers whose position along the bore is "
            "unstated (layers.z_centre = 'unstated'); a calibration needs it: state "
            "layers.z_centre (z from the bearing mid-width), or give the value inline in "
            "[[calibrate.values]] with z = [...]"
        )
    first = str(attrs.get("layers_first", ""))
    if first == "unstated" and np.any(offsets != 0) and layer:
        raise BadInputError(
            f"{path}: quantity.{name} is at layer {layer}, whose end of the bore is unstated "
            "(layers.first = 'unstated'); state layers.first = '+z' or '-z'"
        )
    sign = -1.0 if first == "+z" else 1.0  # layer 1 at the +z end: z falls with the number
    return np.sort(centre + sign * offsets)


def _place(attrs: dict, q: dict, path: Path, name: str) -> np.ndarray:
    if "z_m" in q:
        return np.array([float(q["z_m"])])
    return _layer_z(attrs, int(q.get("layer", 0)), path, name)


def reported_data(
    ds: xr.Dataset, path: Path, first_band: int
) -> tuple[list[Band], list[Datum], list[str]]:
    """The bands (measured layers), data and notes of a reported dataset ``ds`` from ``path``.

    ``first_band`` is the index the first band gets in the calibration's list of bands.
    """
    bands: list[Band] = []
    data: list[Datum] = []
    notes: list[str] = []
    where: dict[tuple, int] = {}
    from jointwear.reported import cylindricity_growth

    for name, var in ds.data_vars.items():
        q = dict(var.attrs)
        kind = q.get("kind")
        if kind is None or str(name).endswith("_u"):
            continue
        cycles = float(q.get("cycles", math.nan))
        if kind not in _KINDS:
            notes.append(f"{path.name}: quantity.{name} ({kind}) is not calibration data")
            continue
        if cycles == 0.0:
            continue  # the new bore: a growth's baseline
        u = float(ds[f"{name}_u"].values)
        value, basis = float(var.values), f"reported: {ds[f'{name}_u'].attrs.get('comment', '')}"
        reference = "MZ"
        if kind == "cylindricity":
            reference = str(q.get("reference", "unstated"))
            if reference not in ("LS", "MZ"):
                raise BadInputError(
                    f"{path}: quantity.{name}.reference = {reference!r}: the least-squares and "
                    "the minimum-zone cylindricity differ, and a calibration cannot take both; "
                    "state reference = 'LS' or 'MZ'"
                )
            value, u, why = cylindricity_growth(ds, str(name))
            basis = f"{why}; {basis}"
        if not (np.isfinite(u) and u > 0):
            raise BadInputError(
                f"{path}: quantity.{name}: the uncertainty is not known ({basis}); the "
                "likelihood needs it: state its uncertainty (standard, expanded, accuracy, ...) "
                "and, for a cylindricity, the new bore's value at cycles = 0"
            )
        z = _place(dict(ds.attrs), q, path, str(name))
        key = (tuple(z), reference, cycles)  # one band per place: its quantities share a run
        if key not in where:
            nan = np.full((len(z), 360), np.nan)
            bands.append(
                Band(z, np.arange(360.0), nan, nan, None, cylindricity_reference=reference)
            )
            where[key] = first_band + len(bands) - 1
        data.append(Datum(_KINDS[kind], cycles, value, u, f"{path}#{name}", where[key], basis))
    if not data:
        raise BadInputError(
            f"{path}: no maximum wear depth or cylindricity after cycles > 0 with its "
            "uncertainty: nothing to calibrate on"
        )
    return bands, data, notes
