"""Region of interest of a full-field measurement: rectangle, polygon or mask image.

``read_roi(spec, shape)`` turns a user's ROI into a boolean mask of the reference image
(H, W): a rectangle ``(x0, y0, x1, y1)`` [pixel, inclusive] or its text ``"x0,y0,x1,y1"``, a
polygon TOML file (``[roi] polygon = [[x, y], ...]`` [pixel]; several ``[[roi.polygon]]`` are not
supported), a mask image (non-zero = inside, same size as the reference), or ``None`` (the whole
image).

``grid_points(mask, subset_size, step, border)`` lays out subset centres on a regular grid over
the mask: a centre is kept when it lies inside, and ``complete`` says whether the whole subset
square lies inside too. Subsets that cross the ROI edge mix the specimen with whatever lies
beyond it (background, another part): their matches can have a ZNCC of 0.99 and still be off
by a large fraction of a pixel, so the field flags them (``subset_crosses_roi_edge``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from jointwear.errors import BadInputError, ParameterError

__all__ = ["RoiGrid", "read_roi", "grid_points"]


@dataclass(frozen=True)
class RoiGrid:
    """Subset centres over a ROI.

    Attributes
    ----------
    centres : ndarray (N, 2)
        ``(x, y)`` [pixel] of the subset centres in the reference image.
    index : ndarray (N, 2) int
        ``(row, column)`` of each centre in the regular grid (for strain windows).
    complete : ndarray (N,) bool
        The whole subset lies inside the ROI.
    description : str
        What the ROI was (for the output's attributes).
    """

    centres: np.ndarray
    index: np.ndarray
    complete: np.ndarray
    description: str


def _polygon_mask(poly: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    import cv2

    mask = np.zeros(shape, np.uint8)
    cv2.fillPoly(mask, [np.round(poly * 16).astype(np.int32)], 1, shift=4)
    return mask.astype(bool)


def _read_polygon(path: Path) -> np.ndarray:
    import tomllib

    try:
        doc = tomllib.loads(path.read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise BadInputError(f"ROI polygon '{path}': not readable TOML ({exc})") from None
    poly = doc.get("roi", {}).get("polygon") if isinstance(doc.get("roi"), dict) else None
    if poly is None:
        poly = doc.get("polygon")
    try:
        arr = np.asarray(poly, dtype=float)
    except (TypeError, ValueError):
        arr = np.zeros((0,))
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] < 3 or not np.isfinite(arr).all():
        raise BadInputError(
            f"ROI polygon '{path}': expected '[roi] polygon = [[x, y], [x, y], [x, y], ...]' "
            "with at least 3 vertices in pixels"
        )
    return arr


def read_roi(spec, shape: tuple[int, int]) -> tuple[np.ndarray, str]:
    """A boolean ROI mask (H, W) of the reference image and a description of it.

    Parameters
    ----------
    spec : None, sequence of 4 numbers, str, Path or ndarray
        ``None`` (whole image), a rectangle ``(x0, y0, x1, y1)`` [pixel, inclusive] or its text
        ``"x0,y0,x1,y1"``, a polygon TOML file, a mask image file, or a boolean/0-1 array.
    shape : (H, W)
        Reference image size [pixel].
    """
    h, w = shape
    if spec is None:
        return np.ones(shape, bool), "whole image"
    if isinstance(spec, np.ndarray) and spec.ndim == 2:
        if spec.shape != (h, w):
            raise BadInputError(
                f"ROI mask of {spec.shape[1]}x{spec.shape[0]} pixels does not match the "
                f"reference image of {w}x{h}"
            )
        return spec.astype(bool), "mask array"
    if isinstance(spec, str) and "," in spec and not Path(spec).exists():
        try:
            spec = [float(v) for v in spec.split(",")]
        except ValueError:
            raise BadInputError(
                f"--roi {spec!r}: expected x0,y0,x1,y1 (pixels), a polygon .toml or a mask image"
            ) from None
    if isinstance(spec, (str, Path)):
        path = Path(spec)
        if not path.is_file():
            raise BadInputError(
                f"ROI '{path}' does not exist (expected x0,y0,x1,y1, a polygon .toml or a mask "
                "image)"
            )
        if path.suffix.lower() == ".toml":
            poly = _read_polygon(path)
            return _polygon_mask(poly, shape), f"polygon from '{path.name}' ({len(poly)} vertices)"
        from jointwear.dic.subset import read_image

        img = read_image(path)
        if img.shape != (h, w):
            raise BadInputError(
                f"ROI mask '{path}' is {img.shape[1]}x{img.shape[0]} pixels, the reference image "
                f"{w}x{h}; the mask must have the reference's size"
            )
        return np.asarray(img) != 0, f"mask image '{path.name}' (non-zero = inside)"
    if isinstance(spec, Sequence) or isinstance(spec, np.ndarray):
        vals = np.asarray(spec, dtype=float).ravel()
        if vals.size != 4 or not np.isfinite(vals).all():
            raise BadInputError(f"ROI {spec!r}: expected (x0, y0, x1, y1) [pixel]")
        x0, y0, x1, y1 = vals
        if not (0 <= x0 < x1 <= w - 1 and 0 <= y0 < y1 <= h - 1):
            raise ParameterError(
                f"ROI {tuple(float(v) for v in vals)} must satisfy 0 <= x0 < x1 <= {w - 1} and "
                f"0 <= y0 < y1 <= {h - 1} (image of {w}x{h} pixels)"
            )
        mask = np.zeros(shape, bool)
        mask[int(np.ceil(y0)) : int(np.floor(y1)) + 1, int(np.ceil(x0)) : int(np.floor(x1)) + 1] = 1
        return mask, f"rectangle x {x0:g}..{x1:g}, y {y0:g}..{y1:g} pixel"
    raise BadInputError(f"ROI {spec!r}: expected x0,y0,x1,y1, a polygon .toml or a mask image")


def grid_points(mask: np.ndarray, subset_size: int, step: int, border: int = 4) -> RoiGrid:
    """Subset centres every ``step`` pixels over the ROI ``mask`` (see module docstring).

    The grid is anchored so that the first centre sits half a subset (plus the border margin
    and 2 pixels of slack near the image edges) inside the ROI's bounding box; centres whose
    subset would leave the image (border margin included) are not laid out.
    """
    h, w = mask.shape
    half = subset_size // 2
    ys, xs = np.nonzero(mask)
    if xs.size == 0:
        raise BadInputError("ROI: no pixel of the reference image lies inside it")
    lo = border + 2 + half
    x_min, x_max = max(xs.min() + half, lo), min(xs.max() - half, w - 1 - lo)
    y_min, y_max = max(ys.min() + half, lo), min(ys.max() - half, h - 1 - lo)
    if x_min > x_max or y_min > y_max:
        # the ROI is narrower than a subset: centres on the ROI itself, subsets incomplete
        x_min, x_max = max(xs.min(), lo), min(xs.max(), w - 1 - lo)
        y_min, y_max = max(ys.min(), lo), min(ys.max(), h - 1 - lo)
    gx = np.arange(x_min, x_max + 1, step, dtype=float)
    gy = np.arange(y_min, y_max + 1, step, dtype=float)
    gx += (x_max - gx[-1]) // 2 if gx.size else 0
    gy += (y_max - gy[-1]) // 2 if gy.size else 0
    X, Y = np.meshgrid(gx, gy)
    R, C = np.meshgrid(np.arange(gy.size), np.arange(gx.size), indexing="ij")
    inside = mask[Y.astype(int), X.astype(int)]
    if not inside.any():
        raise BadInputError(
            f"ROI: no subset centre of a {step}-pixel grid lies inside it (subset {subset_size} "
            "pixels); enlarge the ROI or reduce --step/--subset"
        )
    # completeness: every pixel of the subset square inside (summed-area table)
    sat = np.zeros((h + 1, w + 1), np.int64)
    sat[1:, 1:] = mask.astype(np.int64).cumsum(0).cumsum(1)
    xi, yi = X[inside].astype(int), Y[inside].astype(int)
    x0, x1 = np.clip(xi - half, 0, w - 1), np.clip(xi + half, 0, w - 1)
    y0, y1 = np.clip(yi - half, 0, h - 1), np.clip(yi + half, 0, h - 1)
    count = sat[y1 + 1, x1 + 1] - sat[y0, x1 + 1] - sat[y1 + 1, x0] + sat[y0, x0]
    complete = count == subset_size * subset_size
    centres = np.column_stack([X[inside], Y[inside]])
    index = np.column_stack([R[inside], C[inside]])
    return RoiGrid(centres, index, complete, "")
