"""Integer-pixel initial guesses: OpenCV template matching, rotation sweep, seed selection.

``integer_search`` finds, for one reference subset, the integer displacement maximising the
normalised cross-correlation (``cv2.matchTemplate`` with ``TM_CCOEFF_NORMED``, i.e. ZNCC) inside
a search window of the deformed image. With ``angles_deg`` the reference subset is first rotated
(sampled on its B-spline) so that seeds on strongly rotated parts are still found.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["integer_search", "rotated_template", "pick_seeds"]


def _as_f32(a: np.ndarray) -> np.ndarray:
    out = np.asarray(a, dtype=np.float32)
    if not np.all(np.isfinite(out)):
        out = np.where(
            np.isfinite(out), out, np.float32(np.nanmean(out) if np.isfinite(out).any() else 0)
        )
    return np.ascontiguousarray(out)


def rotated_template(ref_spline, xc: float, yc: float, half: int, theta_deg: float) -> np.ndarray:
    """The reference subset as it would look after a rotation by ``theta_deg`` [degree].

    Samples the reference interpolant at ``X = c + R(-theta) xi`` for the subset grid ``xi``.
    """
    from scipy import ndimage

    th = math.radians(theta_deg)
    r = np.arange(-half, half + 1, dtype=float)
    dx, dy = np.meshgrid(r, r)
    xs = xc + math.cos(th) * dx + math.sin(th) * dy
    ys = yc - math.sin(th) * dx + math.cos(th) * dy
    # interpolate on a local crop (the rotated subset fits in a disc of radius half * sqrt(2))
    h, w = ref_spline.shape
    m = int(math.ceil(half * math.sqrt(2.0))) + 4
    x0, x1 = max(int(xc) - m, 0), min(int(xc) + m + 1, w)
    y0, y1 = max(int(yc) - m, 0), min(int(yc) + m + 1, h)
    crop = ref_spline.image[y0:y1, x0:x1]
    ok = ref_spline.valid[y0:y1, x0:x1]
    if not ok.all():
        crop = np.where(ok, crop, crop[ok].mean() if ok.any() else 0.0)
    return ndimage.map_coordinates(crop, [ys - y0, xs - x0], order=3, mode="mirror")


def integer_search(
    ref_spline,
    deformed: np.ndarray,
    xc: float,
    yc: float,
    half: int,
    radius: int,
    guess: tuple[float, float] = (0.0, 0.0),
    angles_deg: tuple[float, ...] = (0.0,),
) -> tuple[float, float, float, float]:
    """Best integer displacement of the subset at (xc, yc) within ``radius`` [pixel] of ``guess``.

    Returns
    -------
    (u, v, zncc, theta_deg)
        Displacement [pixel], the peak ZNCC and the template rotation [degree] that won.
        ``zncc`` is NaN when the window does not fit in the image.
    """
    import cv2

    h, w = deformed.shape
    gx = xc + guess[0]
    gy = yc + guess[1]
    x0 = int(round(gx)) - half - radius
    y0 = int(round(gy)) - half - radius
    x1 = int(round(gx)) + half + radius
    y1 = int(round(gy)) + half + radius
    x0c, y0c = max(x0, 0), max(y0, 0)
    x1c, y1c = min(x1, w - 1), min(y1, h - 1)
    if x1c - x0c < 2 * half or y1c - y0c < 2 * half:
        return math.nan, math.nan, math.nan, 0.0
    window = _as_f32(deformed[y0c : y1c + 1, x0c : x1c + 1])
    best = (math.nan, math.nan, -np.inf, 0.0)
    for ang in angles_deg:
        if ang == 0.0 and xc == int(xc) and yc == int(yc):
            ixc, iyc = int(xc), int(yc)
            tpl = ref_spline.image[iyc - half : iyc + half + 1, ixc - half : ixc + half + 1]
        else:
            tpl = rotated_template(ref_spline, xc, yc, half, ang)
        tpl = _as_f32(tpl)
        if float(tpl.std()) == 0.0:
            continue
        res = cv2.matchTemplate(window, tpl, cv2.TM_CCOEFF_NORMED)
        res = np.nan_to_num(res, nan=-1.0)
        _, maxval, _, maxloc = cv2.minMaxLoc(res)
        if maxval > best[2]:
            # top-left corner of the best match -> centre position -> displacement
            cx = x0c + maxloc[0] + half
            cy = y0c + maxloc[1] + half
            best = (float(cx - xc), float(cy - yc), float(maxval), float(ang))
    if not np.isfinite(best[2]):
        return math.nan, math.nan, math.nan, 0.0
    return best


def pick_seeds(
    centres: np.ndarray, usable: np.ndarray, texture: np.ndarray, n_groups: int
) -> tuple[np.ndarray, list[list[int]]]:
    """Split points into ``n_groups`` bands of rows and list seed candidates for each.

    Returns the group index of every point and, per group, up to 5 candidate seed indices:
    well-textured usable points close to the centre of the band, best first.
    """
    n = centres.shape[0]
    order = np.lexsort((centres[:, 0], centres[:, 1]))
    group = np.empty(n, dtype=np.int64)
    bounds = np.linspace(0, n, n_groups + 1).astype(int)
    candidates: list[list[int]] = []
    for g in range(n_groups):
        idx = order[bounds[g] : bounds[g + 1]]
        group[idx] = g
        idx = idx[usable[idx]]
        if idx.size == 0:
            candidates.append([])
            continue
        centre = centres[idx].mean(axis=0)
        dist = np.hypot(*(centres[idx] - centre).T)
        near = idx[np.argsort(dist)[: max(10, idx.size // 10)]]
        ranked = near[np.argsort(-texture[near], kind="stable")]
        candidates.append([int(i) for i in ranked[:5]])
    return group, candidates
