"""Say why the points of a DIC result were flagged, when most of an image's were.

A result whose points are mostly (or all) flagged is not silent: :func:`flag_report` names,
for each such image, the flag that dominates and what would change it, with the figure that
decides it (the median epipolar error against the gate, the median ZNCC against
``zncc_min``, ...), in the command line's terms. The commands print these lines on stderr and
exit 1 when an image has no valid point at all, unless ``--allow-empty``.

The result is read through ``result[name].values / .dims / .attrs`` and ``result.attrs`` only,
so it may be a Dataset or the xarray-free :class:`~jointwear._netcdf.Record` that ``dic
correlate`` writes for an image pair (which then starts without importing xarray).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import xarray as xr

    from jointwear._netcdf import Record

__all__ = ["FlagReport", "flag_report"]

#: an image is reported when more than this share of its points is flagged
MOSTLY = 0.5


@dataclass(frozen=True)
class FlagReport:
    """What :func:`flag_report` found.

    Attributes
    ----------
    lines : tuple of str
        One line per image with mostly flagged points (or one for all of them when they
        agree).
    empty : tuple of str
        The images with no valid point (their names, or indices along ``time``).
    """

    lines: tuple[str, ...]
    empty: tuple[str, ...]

    def empty_message(self) -> str | None:
        """The error line for images without a valid point (None when there are none)."""
        if not self.empty:
            return None
        which = ", ".join(self.empty[:8]) + (" ..." if len(self.empty) > 8 else "")
        return (
            f"no valid point in image(s) {which}: the result holds only flagged points "
            "(the reasons above); --allow-empty writes it with exit code 0"
        )


def _values(ds: xr.Dataset | Record, name: str, k: int | None, where: np.ndarray) -> np.ndarray:
    """The ``where`` points' values of variable ``name`` in image ``k``."""
    values = ds[name].values if k is None or "time" not in ds[name].dims else ds[name].values[k]
    return np.asarray(values, float).reshape(where.shape)[where]


def _median(ds: xr.Dataset | Record, name: str, k: int | None, where: np.ndarray) -> float | None:
    if name not in ds:
        return None
    values = _values(ds, name, k, where)
    values = values[np.isfinite(values)]
    return float(np.median(values)) if values.size else None


def _ran_out(ds: xr.Dataset | Record, k: int | None, where: np.ndarray) -> str | None:
    """'the iterations ran out ...' when most of the ``where`` points stopped at the limit."""
    limit = ds.attrs.get("dic_max_iterations")
    if limit is None or "iterations" not in ds:
        return None
    it = _values(ds, "iterations", k, where)
    stopped = int((it >= int(limit)).sum())
    if stopped <= it.size / 2:
        return None
    return (
        f"the iterations ran out: {stopped} of these {it.size} points stopped at "
        f"--max-iterations {int(limit)} before the update fell below --tolerance; raise "
        "--max-iterations (or give better guesses: --seed, a smaller motion between images)"
    )


def _hint(meaning: str, ds: xr.Dataset | Record, k: int | None, where: np.ndarray) -> str:
    """What would change the flag ``meaning``, with the figure that decides it."""
    if meaning == "epipolar_mismatch":
        rep = _median(ds, "reprojection", k, where)
        gate = ds.attrs.get("dic_epipolar_max_pixel")
        epi = ds.attrs.get("dic_median_epipolar_error_pixel")
        figure = f"median RMS reprojection residual {rep:.2f} pixel" if rep is not None else ""
        if epi is not None:
            figure += f" (reference pair: median epipolar error {float(epi):.2f} pixel)"
        return (
            f"{figure} against --epipolar-max {gate} pixel: the calibration does not fit the "
            "images (wrong cameras, left and right swapped, a bumped rig) or the right "
            "matches are on the wrong feature; raise --epipolar-max only for a calibration "
            "known to be that coarse"
        )
    if meaning == "low_correlation":
        z = _median(ds, "zncc", k, where)
        zmin = ds.attrs.get("dic_zncc_min")
        figure = f"median ZNCC {z:.3f}" if z is not None else "ZNCC"
        return (
            f"{figure} below --zncc-min{f' {zmin}' if zmin is not None else ''}: the pattern "
            "changed (decorrelation, glare, large strain within the subset); a larger --subset "
            "or, for a sequence, an incremental reference helps; lower --zncc-min only for a "
            "pattern known to be poor"
        )
    if meaning == "not_converged" and (ran_out := _ran_out(ds, k, where)):
        return ran_out
    if meaning in ("not_converged", "not_reached", "diverged"):
        return (
            "the motion was not found from the guesses: it may exceed --search-radius, or the "
            "images may not show the same pattern; give --seed x,y at a point that moved little, "
            "raise --search-radius, or check the image order"
        )
    if meaning == "subset_outside_image":
        return (
            "the subsets reach beyond the image (or its 4-pixel border): move the ROI inside "
            "the image or use a smaller --subset"
        )
    if meaning == "no_texture":
        return (
            "too little contrast under the subsets: the ROI covers background or an unspeckled "
            "area; restrict the ROI or use a larger --subset"
        )
    if meaning == "invalid_pixels":
        return "the subsets hold invalid (NaN) pixels: restrict the ROI to valid pixels"
    if meaning == "subset_crosses_roi_edge":
        return "the ROI's edge cuts the subsets: use a smaller --subset or a larger ROI"
    if meaning in ("neighbour_outlier", "uncertainty_outlier"):
        factors = (
            f"--neighbour-outlier-factor {ds.attrs.get('dic_neighbour_outlier_factor')}, "
            f"--u-outlier-factor {ds.attrs.get('dic_u_outlier_factor')}"
        )
        return (
            "the matches disagree with their neighbours (or, without neighbours, their own "
            "uncertainty is high) by more than the tests allow in units of the image's median "
            f"uncertainty ({factors}): on most of an image that is not a few outliers but "
            "a field the grid does not resolve (a discontinuity, a crack, a strain "
            "concentration finer than --step) or a texture too faint for the --subset; use "
            "a smaller --step or a larger --subset, or raise the factors (0 turns a test off)"
        )
    if meaning == "left_right_inconsistent":
        return (
            "the subsets straddle a depth step or a second surface (forward and backward "
            "stereo matches disagree): use a smaller --subset or restrict the ROI"
        )
    return "see the flag's meaning in the documentation"


def flag_report(ds: xr.Dataset | Record, *, name: str = "flag", names=None) -> FlagReport:
    """Report the images of ``ds`` whose points are mostly flagged (see module docstring).

    Parameters
    ----------
    ds : Dataset or Record
        A DIC result with a CF flag variable ``name`` (``flag_meanings``), over ``time`` (or
        a single image).
    names : sequence of str, optional
        Image names to quote (default: the index).
    """
    flag = ds[name]
    meanings = str(flag.attrs.get("flag_meanings", "")).split()
    values = np.asarray(flag.attrs.get("flag_values", np.arange(len(meanings))))
    has_time = "time" in flag.dims
    arr = flag.values if has_time else flag.values[None]
    groups: dict[str, list] = {}  # dominant flag -> [labels, worst line]
    empty: list[str] = []
    for k in range(arr.shape[0]):
        f = np.asarray(arr[k]).ravel()
        bad = f != 0
        if f.size == 0 or bad.mean() <= MOSTLY:
            continue
        label = repr(str(names[k])) if names is not None else str(k)
        if not (~bad).any():
            empty.append(label)
        codes, counts = np.unique(f[bad], return_counts=True)
        top = int(codes[np.argmax(counts)])
        idx = np.flatnonzero(values == top)
        meaning = meanings[int(idx[0])] if idx.size else f"flag {top}"
        if meaning in groups:
            groups[meaning][0].append(label)
            continue
        where = (np.asarray(arr[k]) == top).ravel()
        hint = _hint(meaning, ds, k if has_time else None, where)
        text = (
            f"{int(bad.sum())} of {f.size} points flagged, mostly {meaning} ({int(counts.max())})"
        )
        groups[meaning] = [[label], f"{text}: {hint}"]
    lines = []
    for labels, text in groups.values():
        which = ", ".join(labels[:6]) + (f" and {len(labels) - 6} more" if len(labels) > 6 else "")
        lines.append(f"image{'s' if len(labels) > 1 else ''} {which}: {text}")
    return FlagReport(tuple(lines), tuple(empty))


def check_flags(ds: xr.Dataset | Record, *, allow_empty: bool, names=None, echo=None) -> None:
    """Command line: print :func:`flag_report`'s lines as warnings on stderr; raise
    :class:`~jointwear.errors.ValidationFailed` (exit 1) when an image has no valid point,
    unless ``allow_empty`` (then it is a warning too). Call after the result was written."""
    from jointwear.errors import ValidationFailed

    if echo is None:
        import typer

        def echo(text: str) -> None:
            typer.echo(text, err=True)

    report = flag_report(ds, names=names)
    for line in report.lines:
        echo(f"warning: {line}")
    message = report.empty_message()
    if message is None:
        return
    if not allow_empty:
        raise ValidationFailed(message)
    echo(f"warning: {message}")
