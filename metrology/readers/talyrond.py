"""Taylor Hobson Talyrond preset.

What is publicly known about Talyrond text exports is little: Taylor Hobson's roundness software
(Talyrond / Ultra / Metrology 4.0) exports traces as plain text or CSV, one trace (layer) per file
or per block, and a published dataset of Talyrond TR31c traces (Zenodo record 7004548, Aalto
University) distributes them as CSV with 3600 points per revolution and the radial displacement in
micrometres. No published specification of the export layouts was found, so this preset *is* the
generic text reader (:func:`jointwear.metrology.readers.text.read_scan`) with the defaults such a
trace needs: values in micrometres unless the file states a unit, every trace one full
revolution (``arc="full"``: a file without an angle column holds equally spaced points over one
turn, and an angle column must span one turn), and the instrument name
goes into ``source``. Everything the generic reader sniffs is still sniffed and recorded, and
every default can be overridden.

The instrument's angle zero and direction in the bearing frame are not in the export: they must
be given (``convention``) and are recorded, never guessed.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import xarray as xr

from jointwear.conventions import AngleConvention
from jointwear.metrology.readers.scan import read_scan

__all__ = ["TALYROND_DEFAULTS", "read_talyrond"]

#: Defaults of the preset (any can be overridden by the same keyword).
TALYROND_DEFAULTS: dict[str, object] = {
    "units": "um",
    "value": "auto",
    "instrument": "Taylor Hobson Talyrond",
    "arc": "full",
}


def read_talyrond(
    paths: str | Path | Iterable[str | Path],
    *,
    convention: AngleConvention | tuple[str, str] | None = None,
    **options,
) -> xr.Dataset:
    """Read Talyrond text exports (one trace, a folder of traces, a long or a wide file).

    Parameters
    ----------
    paths : path, folder or list of paths
        The export(s).
    convention : AngleConvention or (zero, direction)
        Where the instrument's 0 degree points in the bearing frame and which way its angle
        turns (seen from +z). Required.
    **options
        Any option of :func:`~jointwear.metrology.readers.text.read_scan` (``reading=`` a
        :class:`~jointwear.metrology.readers.scan.ScanReading`, or its fields, which replace
        the reading's); defaults :data:`TALYROND_DEFAULTS` where neither sets the option (values
        in µm unless the header states a unit; the header's unit wins over this default but not
        over an explicit ``units=``).

    Returns
    -------
    Dataset
        ``radial_deviation`` (or ``radius``) [m] over (z, theta) in the canonical convention.
    """
    reading = options.pop("reading", None)
    given = reading.given() if reading is not None else {}
    options = given | {k: v for k, v in options.items() if v is not None}  # None = not given
    opts = dict(TALYROND_DEFAULTS)
    explicit_units = "units" in options
    opts.update(options)
    if not explicit_units:
        # the header's unit (if any) must win over the preset default: try without it first
        from jointwear.errors import BadInputError

        try:
            return read_scan(paths, convention=convention, **{**opts, "units": None})
        except BadInputError as exc:
            if "unit" not in str(exc) or "not stated" not in str(exc):
                raise
    return read_scan(paths, convention=convention, **opts)
