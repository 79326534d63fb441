"""What the compared numbers are: ``data_origin`` of each side (measured, synthetic, simulated).

Every jointwear file states its origin in the global attribute ``data_origin``
(``"measured"``, ``"synthetic"`` or ``"simulated"``, the data contract). A side made of several
files takes the weakest claim: one synthetic input makes the measured side synthetic. A file
that does not state its origin is shown as *not stated* - never assumed measured - unless its
own ``source`` attribute says which jointwear generator or simulator wrote it.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

import xarray as xr

__all__ = ["ORIGINS", "NOT_STATED", "origin_of", "side_origin"]

ORIGINS = ("measured", "synthetic", "simulated")
NOT_STATED = "not stated"

#: ``source`` patterns of jointwear's own writers (provenance, not a guess from the numbers)
_SOURCE_PATTERNS = (
    (re.compile(r"jointwear\.datasets|\(virtual|virtual rig|synthetic", re.I), "synthetic"),
    (re.compile(r"\(sim\.|jointwear\.sim|simulat", re.I), "simulated"),
)


def origin_of(ds: xr.Dataset) -> str:
    """``data_origin`` of one dataset (from its attribute, else its jointwear ``source``)."""
    value = str(ds.attrs.get("data_origin", "")).strip().lower()
    if str(ds.attrs.get("data_origin_stated", "yes")).lower() == "no":
        return NOT_STATED  # a foreign file taken for its role in the comparison, not by its word
    if value in ORIGINS:
        return value
    source = str(ds.attrs.get("source", ""))
    for pattern, origin in _SOURCE_PATTERNS:
        if pattern.search(source):
            return origin
    return NOT_STATED


def side_origin(datasets: Sequence[xr.Dataset]) -> str:
    """Origin of one side: any synthetic input makes it synthetic; any unstated one, not stated."""
    found = {origin_of(ds) for ds in datasets}
    if not found:
        return NOT_STATED
    if "synthetic" in found:
        return "synthetic"
    if NOT_STATED in found:
        return NOT_STATED
    if len(found) > 1:
        return "mixed (" + " and ".join(sorted(found)) + ")"
    return found.pop()
