"""X3P (ISO 25178-72) files via ``x3pio``: point clouds of a bore as x, y, z points.

An X3P point cloud holds Cartesian points in metres; it becomes a table ``X [m]``, ``Y [m]``,
``Z [m]`` that goes through the same reader as a text export (layers = points of equal z; the
origin must be the spindle axis for ``import``, any origin for ``assess``). X3P profiles and
surfaces store heights along lengths, not over angle: they are refused with what to do.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from jointwear.errors import BadInputError

__all__ = ["x3p_text"]


def x3p_text(path: Path) -> str:
    """Tab-separated text (header, column names, points) of an X3P point cloud [m]."""
    import x3pio

    try:
        doc = x3pio.read(path)
    except x3pio.X3pChecksumError as exc:
        raise BadInputError(
            f"'{path}': X3P checksum mismatch ({exc}); the file was changed or damaged after it "
            "was written - re-export it"
        ) from None
    except (x3pio.X3pError, OSError, ValueError) as exc:
        raise BadInputError(f"'{path}': not a readable X3P file ({exc}); re-export it") from None
    if not isinstance(doc, x3pio.PointCloud):
        kind = type(doc).__name__.lower()
        raise BadInputError(
            f"'{path}': an X3P {kind} stores heights along lengths in metres, not a trace over "
            "angle, so it cannot be read as a roundness scan without guessing; export the bore "
            "as an X3P point cloud (x, y, z) or the trace as text"
        )
    pts = np.concatenate([layer.points() for layer in doc.layers], axis=0)
    ok = np.all(np.isfinite(pts), axis=1)
    lines = [
        "Instrument: X3P point cloud",
        "Units: m",
        "Z unit: m",
        f"Points not measured (dropped): {int((~ok).sum())}",
        "X [m]\tY [m]\tZ [m]",
    ]
    lines += [f"{x!r}\t{y!r}\t{z!r}" for x, y, z in pts[ok].tolist()]
    if ok.sum() == 0:
        raise BadInputError(f"'{path}': the X3P point cloud holds no measured points")
    return "\n".join(lines) + "\n"
