"""Filters for closed (roundness) profiles, harmonic spectrum and outlier removal.

Profiles are sampled uniformly over one revolution; filtering is done exactly in the Fourier
domain of the closed profile (circular convolution, no end effects). Cut-offs are given in
undulations per revolution (UPR).

Gaussian filter (ISO 16610-21, closed profile)
    Mean line transmission of harmonic k: ``H(k) = exp(-pi * (alpha * k / k_c)**2)`` with
    ``alpha = sqrt(ln 2 / pi)``, so ``H(k_c) = 0.5`` (50 % at the cut-off), phase-correct.
2RC filter (ISO 4291 / the analogue filter of ISO 3274:1975)
    Two cascaded RC stages. The high-pass (residual) transmission is
    ``H_hp(k) = (i k/k0)^2 / (1 + i k/k0)^2`` with ``k0 = k_c / sqrt(3)``, i.e.
    ``|H_hp(k)| = (k/k0)^2 / (1 + (k/k0)^2)``, 75 % at the cut-off; the mean line is the input
    minus the high-passed profile. Not phase-correct (as the analogue filter is not).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError

__all__ = [
    "STANDARD_CUTOFFS",
    "transmission",
    "filter_profile",
    "harmonic_spectrum",
    "remove_outliers",
    "is_uniform",
]

#: Standard cut-offs [UPR].
STANDARD_CUTOFFS = (15, 50, 150, 500, 1500)

_ALPHA = np.sqrt(np.log(2.0) / np.pi)


def transmission(k: np.ndarray, cutoff_upr: float, kind: str = "gaussian") -> np.ndarray:
    """Complex mean-line transmission of harmonic order(s) ``k`` for a cut-off [UPR].

    Parameters
    ----------
    k : array_like
        Harmonic orders [UPR] (>= 0).
    cutoff_upr : float
        Cut-off [UPR] (> 0).
    kind : {"gaussian", "2rc"}
        Filter type.

    Returns
    -------
    ndarray of complex
        Transmission of the long-wave (mean line) component; the residual (short-wave)
        transmission is ``1 - H``.
    """
    if not cutoff_upr > 0:
        raise BadInputError(f"filter cut-off must be > 0 UPR, got {cutoff_upr!r}")
    k = np.asarray(k, dtype=float)
    if kind == "gaussian":
        return np.exp(-np.pi * (_ALPHA * k / cutoff_upr) ** 2).astype(complex)
    if kind in ("2rc", "2cr", "rc"):
        q = 1j * k * np.sqrt(3.0) / cutoff_upr
        return 1.0 - q**2 / (1.0 + q) ** 2
    raise BadInputError(f"filter {kind!r} is not known; use 'gaussian' or '2rc'")


def is_uniform(theta_deg: np.ndarray, *, rtol: float = 1e-6) -> bool:
    """True if ``theta_deg`` (sorted) is a uniform grid over one revolution."""
    th = np.asarray(theta_deg, dtype=float)
    n = th.size
    if n < 4:
        return False
    step = 360.0 / n
    return bool(np.allclose(np.diff(th), step, rtol=0, atol=rtol * step * 1e3))


def _values(profile, what: str) -> tuple[np.ndarray, xr.DataArray | None]:
    if isinstance(profile, xr.DataArray):
        if "theta" not in profile.dims:
            raise BadInputError(f"{what}: expected a 'theta' dimension, found {profile.dims}")
        da = profile.transpose(..., "theta")
        if not is_uniform(da["theta"].values):
            raise BadInputError(
                f"{what}: the angles are not a uniform grid over one revolution; import with "
                "resample=True to interpolate onto one"
            )
        return np.asarray(da.values, dtype=float), da
    return np.asarray(profile, dtype=float), None


def filter_profile(
    profile: np.ndarray | xr.DataArray, cutoff_upr: float, *, kind: str = "gaussian"
) -> np.ndarray | xr.DataArray:
    """Mean line (long-wave component) of closed profile(s) sampled uniformly in angle.

    Parameters
    ----------
    profile : ndarray (..., n) or DataArray with a ``theta`` dimension
        Radius or radial deviation [m]; the last axis (or ``theta``) is one revolution.
        NaN points are not allowed (remove or fill them first).
    cutoff_upr : float
        Cut-off [UPR], e.g. 15, 50, 150, 500 or any value.
    kind : {"gaussian", "2rc"}
        Filter (see module docstring).

    Returns
    -------
    ndarray or DataArray
        Filtered profile, same shape and units.
    """
    v, da = _values(profile, "filter")
    if not np.all(np.isfinite(v)):
        raise BadInputError(
            "filter: the profile contains NaN points; remove outliers with fill=True or import "
            "complete layers before filtering"
        )
    n = v.shape[-1]
    k = np.arange(n // 2 + 1)
    h = transmission(k, cutoff_upr, kind)
    out = np.fft.irfft(np.fft.rfft(v, axis=-1) * h, n, axis=-1)
    if da is not None:
        res = da.copy(data=out)
        res.attrs = dict(da.attrs)
        res.attrs["filter"] = f"{kind} {cutoff_upr:g} UPR (mean line)"
        return res.transpose(*profile.dims)
    return out


def harmonic_spectrum(
    profile: np.ndarray | xr.DataArray, *, max_order: int | None = None
) -> np.ndarray | xr.DataArray:
    """Amplitude of each harmonic of closed profile(s) sampled uniformly in angle.

    A profile ``sum_k A_k cos(k theta + phi_k)`` gives ``A_k`` [same units as the profile]
    for k >= 1 (k = 0: the mean).

    Parameters
    ----------
    profile : ndarray (..., n) or DataArray with a ``theta`` dimension
        Radius or deviation [m].
    max_order : int, optional
        Highest order returned (default n // 2).

    Returns
    -------
    ndarray (..., max_order + 1) or DataArray with a ``harmonic`` dimension [UPR]
    """
    v, da = _values(profile, "harmonic spectrum")
    if not np.all(np.isfinite(v)):
        raise BadInputError("harmonic spectrum: the profile contains NaN points")
    n = v.shape[-1]
    spec = np.abs(np.fft.rfft(v, axis=-1)) / n
    spec[..., 1:] *= 2.0
    if n % 2 == 0:
        spec[..., -1] /= 2.0
    kmax = n // 2 if max_order is None else min(int(max_order), n // 2)
    spec = spec[..., : kmax + 1]
    if da is None:
        return spec
    dims = [d for d in da.dims if d != "theta"] + ["harmonic"]
    coords = {d: da[d] for d in dims if d in da.coords and d != "harmonic"}
    coords["harmonic"] = np.arange(kmax + 1)
    return xr.DataArray(
        spec,
        dims=dims,
        coords=coords,
        attrs={"units": da.attrs.get("units", "m"), "long_name": "harmonic amplitude"},
    )


def remove_outliers(
    profile: np.ndarray, *, threshold: float = 4.0, window: int | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Robust removal of spikes (dust, scratches) from closed profile(s).

    Each profile is compared with its running median over ``window`` neighbouring points
    (periodic; default n/1000 rounded up to an odd number >= 5), which follows form and waviness
    but not isolated spikes; points farther than ``threshold`` robust standard deviations
    (RMS of the difference without its largest 1 %) are replaced by linear interpolation
    between their valid neighbours (periodic). NaN points are filled the same way.

    Parameters
    ----------
    profile : ndarray (..., n)
        Uniformly sampled closed profile(s) [m].
    threshold : float
        Robust standard deviations beyond which a point is an outlier.
    window : int, optional
        Running-median window [points].

    Returns
    -------
    cleaned : ndarray
        Profile with outliers replaced.
    removed : ndarray of bool
        Which points were replaced (NaN points included).
    """
    from scipy.ndimage import median_filter

    v = np.asarray(profile, dtype=float)
    flat = v.reshape(-1, v.shape[-1])
    n = flat.shape[-1]
    w = window or max(5, int(np.ceil(n / 1000)))
    w += 1 - w % 2
    out = flat.copy()
    removed = np.zeros_like(flat, dtype=bool)
    for i, row in enumerate(flat):
        ok = np.isfinite(row)
        filled = row if ok.all() else _fill(row, ok)
        med = median_filter(filled, size=w, mode="wrap")
        d = filled - med
        c = np.median(d[ok])
        a = np.abs(d[ok] - c)
        # trimmed RMS (largest 1 % dropped): the difference to a running median is too peaked
        # for the MAD to estimate its spread
        scale = float(np.sqrt(np.mean(a[a <= np.quantile(a, 0.99)] ** 2)))
        bad = ~ok
        if scale > 0:
            bad |= np.abs(d - c) > threshold * scale
        removed[i] = bad
        out[i] = _fill(row, ~bad) if bad.any() else row
    return out.reshape(v.shape), removed.reshape(v.shape)


def _fill(row: np.ndarray, ok: np.ndarray) -> np.ndarray:
    n = row.size
    idx = np.arange(n)
    good = idx[ok]
    if good.size == 0:
        raise BadInputError("outlier removal: no valid point left in a profile")
    xp = np.concatenate([good - n, good, good + n])
    fp = np.concatenate([row[good]] * 3)
    return np.interp(idx, xp, fp)
