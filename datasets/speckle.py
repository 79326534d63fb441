"""Speckle images with exact ground truth, rendered analytically (``jointwear.datasets.speckle``).

The pattern is a sum of Gaussian blobs scattered at random in the *reference* plane. A deformed
image is not produced by interpolating a raster: every pixel ``x`` of the deformed image is mapped
back to the reference plane, ``X = x - u(X)`` (closed form for rigid/affine fields, Newton
iterations otherwise), and the blobs are evaluated there, so the displacement truth ``u(X)``
carries no interpolation bias. Optical blur (a Gaussian point-spread function in the image
plane) is applied analytically to every blob through the local Jacobian of the field, which is
exact for rigid and affine fields and first-order accurate for curved ones.

Intensity: ``I = lo + (hi - lo) * (1 - exp(-S))`` with ``S`` the blob sum, ``lo, hi = 0.5 -/+
contrast / 2`` of the full scale; then gain/offset, Gaussian noise, rounding and clipping to the
bit depth.

Displacements are Lagrangian: a material point at reference position ``X`` (pixel coordinates,
x to the right, y down, pixel centres at integers) moves to ``x = X + u(X)``. That is what a
subset-DIC engine measures at its reference subset centres.

Public API
----------
``SpeckleParams``           frozen dataclass of the pattern and camera parameters
``RigidField``, ``AffineField``, ``SinusoidalField``, ``rotation``   displacement fields
``speckle_image(shape, field=None, *, params, seed)``      one image (2D array)
``speckle_pair(shape, field, *, params, seed, gain, offset)`` -> ``SpecklePair``
``speckle_sequence(shape, fields, *, params, seed)``        frames over a list of fields
``truth_dataset(field, shape, step)``                      ground-truth u, v grid (xarray)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from dataclasses import field as dc_field

import numpy as np
import xarray as xr
from numba import njit

from jointwear.datasets._speckle_params import SpeckleParams
from jointwear.errors import ParameterError

__all__ = [
    "SpeckleParams",
    "Field",
    "RigidField",
    "AffineField",
    "SinusoidalField",
    "rotation",
    "SpecklePair",
    "speckle_image",
    "speckle_pair",
    "speckle_sequence",
    "truth_dataset",
]


# --------------------------------------------------------------------------------------------
# displacement fields
# --------------------------------------------------------------------------------------------


class Field:
    """A displacement field ``u(X)``: material point ``X`` moves to ``x = X + u(X)`` [pixel].

    Subclasses implement :meth:`displacement` and :meth:`gradient`; :meth:`inverse` solves
    ``X + u(X) = x`` by Newton iterations unless overridden by a closed form.
    """

    def displacement(self, X: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Displacement ``(u, v)`` [pixel] of the material points at ``(X, Y)`` [pixel]."""
        raise NotImplementedError

    def gradient(self, X: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, ...]:
        """Displacement gradient ``(du/dX, du/dY, dv/dX, dv/dY)`` [1] at ``(X, Y)``."""
        raise NotImplementedError

    def forward(self, X: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Deformed position ``x = X + u(X)`` [pixel]."""
        u, v = self.displacement(X, Y)
        return np.asarray(X, float) + u, np.asarray(Y, float) + v

    def inverse(
        self, x: np.ndarray, y: np.ndarray, *, tol: float = 1e-11, max_iter: int = 50
    ) -> tuple[np.ndarray, np.ndarray]:
        """Reference position ``X`` of the material point now at ``x`` (Newton iterations)."""
        x = np.asarray(x, float)
        y = np.asarray(y, float)
        X, Y = x.copy(), y.copy()
        for _ in range(max_iter):
            fx, fy = self.forward(X, Y)
            rx, ry = fx - x, fy - y
            ux, uy, vx, vy = self.gradient(X, Y)
            a, b, c, d = 1.0 + ux, uy, vx, 1.0 + vy
            det = a * d - b * c
            dX = (d * rx - b * ry) / det
            dY = (-c * rx + a * ry) / det
            X -= dX
            Y -= dY
            if np.max(np.abs(dX), initial=0.0) < tol and np.max(np.abs(dY), initial=0.0) < tol:
                break
        else:
            raise ParameterError(
                f"{type(self).__name__}: the field cannot be inverted (Newton iterations did not "
                "converge); the mapping X -> X + u(X) must be one-to-one - reduce the amplitude"
            )
        return X, Y


@dataclass(frozen=True)
class AffineField(Field):
    """Homogeneous deformation ``u(X) = t + G (X - c)``.

    Parameters
    ----------
    gradient_matrix : 2x2 tuple
        Displacement gradient ``((du/dX, du/dY), (dv/dX, dv/dY))`` [1].
    translation : (float, float)
        Displacement ``t`` of the centre [pixel].
    center : (float, float)
        Centre ``c`` [pixel]; ``None`` means the image centre is not known, so (0, 0).
    """

    gradient_matrix: tuple[tuple[float, float], tuple[float, float]] = ((0.0, 0.0), (0.0, 0.0))
    translation: tuple[float, float] = (0.0, 0.0)
    center: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        G = np.asarray(self.gradient_matrix, float)
        if G.shape != (2, 2) or not np.all(np.isfinite(G)):
            raise ParameterError("AffineField.gradient_matrix must be a finite 2x2 matrix")
        if abs(np.linalg.det(np.eye(2) + G)) < 1e-6:
            raise ParameterError(
                "AffineField: I + gradient_matrix is singular; the mapping is not invertible"
            )

    @classmethod
    def from_strain(
        cls,
        *,
        exx: float = 0.0,
        eyy: float = 0.0,
        exy: float = 0.0,
        rotation_deg: float = 0.0,
        translation: tuple[float, float] = (0.0, 0.0),
        center: tuple[float, float] = (0.0, 0.0),
    ) -> AffineField:
        """Stretch ``U = I + [[exx, exy], [exy, eyy]]`` followed by a rotation [degree].

        The deformation gradient is ``F = R U``; ``rotation_deg`` is positive from +x towards +y
        of the image (clockwise on screen, because y points down).
        """
        th = math.radians(rotation_deg)
        R = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
        U = np.array([[1.0 + exx, exy], [exy, 1.0 + eyy]])
        G = R @ U - np.eye(2)
        return cls(
            gradient_matrix=((G[0, 0], G[0, 1]), (G[1, 0], G[1, 1])),
            translation=(float(translation[0]), float(translation[1])),
            center=(float(center[0]), float(center[1])),
        )

    def displacement(self, X, Y):
        G = self.gradient_matrix
        dx = np.asarray(X, float) - self.center[0]
        dy = np.asarray(Y, float) - self.center[1]
        u = self.translation[0] + G[0][0] * dx + G[0][1] * dy
        v = self.translation[1] + G[1][0] * dx + G[1][1] * dy
        return u, v

    def gradient(self, X, Y):
        G = self.gradient_matrix
        one = np.ones(np.shape(X))
        return G[0][0] * one, G[0][1] * one, G[1][0] * one, G[1][1] * one

    def inverse(self, x, y, **_):
        F = np.eye(2) + np.asarray(self.gradient_matrix, float)
        Fi = np.linalg.inv(F)
        rx = np.asarray(x, float) - self.center[0] - self.translation[0]
        ry = np.asarray(y, float) - self.center[1] - self.translation[1]
        return (
            self.center[0] + Fi[0, 0] * rx + Fi[0, 1] * ry,
            self.center[1] + Fi[1, 0] * rx + Fi[1, 1] * ry,
        )


def RigidField(
    translation: tuple[float, float] = (0.0, 0.0),
    theta_deg: float = 0.0,
    center: tuple[float, float] = (0.0, 0.0),
) -> AffineField:
    """Rigid motion: rotation by ``theta_deg`` [degree] about ``center`` [pixel], then translation.

    ``theta_deg`` is positive from +x towards +y of the image (clockwise on screen).
    """
    return AffineField.from_strain(rotation_deg=theta_deg, translation=translation, center=center)


def rotation(theta_deg: float, center: tuple[float, float]) -> AffineField:
    """Pure rotation by ``theta_deg`` [degree] about ``center`` [pixel]."""
    return RigidField((0.0, 0.0), theta_deg, center)


@dataclass(frozen=True)
class SinusoidalField(Field):
    """``u = A_x sin(2 pi s / wavelength + phase)``, ``v = A_y sin(...)`` with ``s = X cos a + Y sin a``.

    Parameters
    ----------
    amplitude : (float, float)
        Amplitudes ``(A_x, A_y)`` [pixel].
    wavelength : float
        Wavelength along the direction ``a`` [pixel].
    direction_deg : float
        Direction ``a`` of the wave vector [degree from +x towards +y].
    phase : float
        Phase [rad].
    """

    amplitude: tuple[float, float] = (1.0, 0.0)
    wavelength: float = 100.0
    direction_deg: float = 0.0
    phase: float = 0.0

    def __post_init__(self) -> None:
        k = 2 * math.pi / self.wavelength if self.wavelength > 0 else math.inf
        if not (self.wavelength > 0) or k * math.hypot(*self.amplitude) >= 0.9:
            raise ParameterError(
                f"SinusoidalField: 2*pi*amplitude/wavelength = {k * math.hypot(*self.amplitude):.3g} "
                "must stay below 0.9 so that the mapping is one-to-one; lower the amplitude or "
                "lengthen the wavelength"
            )

    def _arg(self, X, Y):
        a = math.radians(self.direction_deg)
        s = np.asarray(X, float) * math.cos(a) + np.asarray(Y, float) * math.sin(a)
        return 2 * math.pi * s / self.wavelength + self.phase

    def displacement(self, X, Y):
        sn = np.sin(self._arg(X, Y))
        return self.amplitude[0] * sn, self.amplitude[1] * sn

    def gradient(self, X, Y):
        a = math.radians(self.direction_deg)
        k = 2 * math.pi / self.wavelength
        cs = np.cos(self._arg(X, Y)) * k
        ax, ay = self.amplitude
        return (
            ax * cs * math.cos(a),
            ax * cs * math.sin(a),
            ay * cs * math.cos(a),
            ay * cs * math.sin(a),
        )


# --------------------------------------------------------------------------------------------
# rendering
# --------------------------------------------------------------------------------------------


@njit(cache=True)
def _render_kernel(X, Y, F, bx, by, ba, cell_start, cell_count, x0, y0, cell, ncx, ncy, s2, b2):
    """Blob sum at reference positions (X, Y) with local forward Jacobians F (H, W, 4)."""
    H, W = X.shape
    out = np.zeros((H, W))
    for i in range(H):
        for j in range(W):
            xr = X[i, j]
            yr = Y[i, j]
            f00 = F[i, j, 0]
            f01 = F[i, j, 1]
            f10 = F[i, j, 2]
            f11 = F[i, j, 3]
            det_f = abs(f00 * f11 - f01 * f10)
            c00 = s2 * (f00 * f00 + f01 * f01) + b2
            c01 = s2 * (f00 * f10 + f01 * f11)
            c11 = s2 * (f10 * f10 + f11 * f11) + b2
            det_c = c00 * c11 - c01 * c01
            i00 = c11 / det_c
            i01 = -c01 / det_c
            i11 = c00 / det_c
            scale = s2 * det_f / math.sqrt(det_c)
            cx = int(math.floor((xr - x0) / cell))
            cy = int(math.floor((yr - y0) / cell))
            acc = 0.0
            for gy in range(cy - 1, cy + 2):
                if gy < 0 or gy >= ncy:
                    continue
                for gx in range(cx - 1, cx + 2):
                    if gx < 0 or gx >= ncx:
                        continue
                    c = gy * ncx + gx
                    for k in range(cell_start[c], cell_start[c] + cell_count[c]):
                        dxr = xr - bx[k]
                        dyr = yr - by[k]
                        dx = f00 * dxr + f01 * dyr
                        dy = f10 * dxr + f11 * dyr
                        q = i00 * dx * dx + 2.0 * i01 * dx * dy + i11 * dy * dy
                        if q < 50.0:
                            acc += ba[k] * math.exp(-0.5 * q)
            out[i, j] = acc * scale
    return out


@dataclass(frozen=True)
class _Blobs:
    x: np.ndarray
    y: np.ndarray
    amp: np.ndarray
    bounds: tuple[float, float, float, float]


def _scatter_blobs(bounds, params: SpeckleParams, rng: np.random.Generator) -> _Blobs:
    xmin, xmax, ymin, ymax = bounds
    area = (xmax - xmin) * (ymax - ymin)
    n = rng.poisson(params.density * area / (math.pi * (params.speckle_size / 2) ** 2))
    return _Blobs(
        x=rng.uniform(xmin, xmax, n),
        y=rng.uniform(ymin, ymax, n),
        amp=rng.uniform(0.8, 1.6, n),
        bounds=bounds,
    )


def _render(blobs: _Blobs, X, Y, F, params: SpeckleParams) -> np.ndarray:
    sigma = params.speckle_size / 4.0
    b = params.blur_std
    # cell size: blobs further than ~sqrt(50) effective sigmas contribute nothing (q < 50 cut)
    cell = max(1.0, 7.5 * math.sqrt(sigma**2 + b**2))
    xmin, xmax, ymin, ymax = blobs.bounds
    ncx = max(1, int(math.ceil((xmax - xmin) / cell)))
    ncy = max(1, int(math.ceil((ymax - ymin) / cell)))
    gx = np.clip(((blobs.x - xmin) / cell).astype(np.int64), 0, ncx - 1)
    gy = np.clip(((blobs.y - ymin) / cell).astype(np.int64), 0, ncy - 1)
    cid = gy * ncx + gx
    order = np.argsort(cid, kind="stable")
    counts = np.bincount(cid, minlength=ncx * ncy).astype(np.int64)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    return _render_kernel(
        np.ascontiguousarray(X, dtype=np.float64),
        np.ascontiguousarray(Y, dtype=np.float64),
        np.ascontiguousarray(F, dtype=np.float64),
        blobs.x[order],
        blobs.y[order],
        blobs.amp[order],
        starts,
        counts,
        xmin,
        ymin,
        cell,
        ncx,
        ncy,
        sigma**2,
        b**2,
    )


def _check_shape(shape) -> tuple[int, int]:
    try:
        h, w = (int(s) for s in shape)
    except (TypeError, ValueError):
        raise ParameterError(f"image shape must be (height, width), got {shape!r}") from None
    if h < 8 or w < 8 or h > 20000 or w > 20000:
        raise ParameterError(f"image shape {shape!r} must be between 8 and 20000 pixels per side")
    return h, w


def _preimage_bounds(fields, shape, margin) -> tuple[float, float, float, float]:
    h, w = shape
    xs = [np.array([-margin, w - 1 + margin])]
    ys = [np.array([-margin, h - 1 + margin])]
    border_x = np.concatenate(
        [np.linspace(0, w - 1, 64), np.full(64, w - 1.0), np.linspace(0, w - 1, 64), np.zeros(64)]
    )
    border_y = np.concatenate(
        [np.zeros(64), np.linspace(0, h - 1, 64), np.full(64, h - 1.0), np.linspace(0, h - 1, 64)]
    )
    for f in fields:
        if f is None:
            continue
        X, Y = f.inverse(border_x, border_y)
        xs.append(X)
        ys.append(Y)
        # curved fields: also sample the interior
        gx, gy = np.meshgrid(np.linspace(0, w - 1, 16), np.linspace(0, h - 1, 16))
        X, Y = f.inverse(gx.ravel(), gy.ravel())
        xs.append(X)
        ys.append(Y)
    allx = np.concatenate(xs)
    ally = np.concatenate(ys)
    return (
        float(allx.min() - margin),
        float(allx.max() + margin),
        float(ally.min() - margin),
        float(ally.max() + margin),
    )


def _to_image(
    S: np.ndarray,
    params: SpeckleParams,
    rng: np.random.Generator,
    gain: float = 1.0,
    offset: float = 0.0,
) -> np.ndarray:
    lo = 0.5 - params.contrast / 2
    hi = 0.5 + params.contrast / 2
    pattern = 1.0 - np.exp(-S)
    if params.dark_speckles:
        pattern = 1.0 - pattern
    full = params.full_scale
    img = (lo + (hi - lo) * pattern) * full * gain + offset
    if params.noise_std > 0:
        img = img + rng.normal(0.0, params.noise_std, img.shape)
    if params.bit_depth:
        img = np.clip(np.rint(img), 0, full)
        dtype = np.uint8 if params.bit_depth <= 8 else np.uint16
        return img.astype(dtype)
    return img


def _render_frame(blobs, field: Field | None, shape, params, rng, gain=1.0, offset=0.0):
    h, w = shape
    x, y = np.meshgrid(np.arange(w, dtype=float), np.arange(h, dtype=float))
    if field is None:
        X, Y = x, y
        F = np.zeros((h, w, 4))
        F[..., 0] = 1.0
        F[..., 3] = 1.0
    else:
        X, Y = field.inverse(x, y)
        ux, uy, vx, vy = field.gradient(X, Y)
        F = np.stack([1.0 + ux, uy, vx, 1.0 + vy], axis=-1)
    S = _render(blobs, X, Y, F, params)
    return _to_image(S, params, rng, gain, offset)


def _rngs(seed: int | None, n: int) -> tuple[np.random.Generator, list[np.random.Generator]]:
    ss = np.random.SeedSequence(seed)
    children = ss.spawn(n + 1)
    return np.random.default_rng(children[0]), [np.random.default_rng(c) for c in children[1:]]


def speckle_image(
    shape: tuple[int, int],
    field: Field | None = None,
    *,
    params: SpeckleParams | None = None,
    seed: int | None = 0,
) -> np.ndarray:
    """Render one speckle image, optionally deformed by ``field``.

    Parameters
    ----------
    shape : (int, int)
        Image size (height, width) [pixel].
    field : Field, optional
        Displacement field applied to the pattern (None: the reference pattern).
    params : SpeckleParams, optional
        Pattern and camera parameters.
    seed : int
        Seed of the pattern and the noise (the same seed gives the same pattern).

    Returns
    -------
    ndarray
        ``uint8``/``uint16`` image (or float grey levels with ``bit_depth=0``).
    """
    return speckle_sequence(shape, [field], params=params, seed=seed)[0]


def speckle_sequence(
    shape: tuple[int, int],
    fields: Sequence[Field | None],
    *,
    params: SpeckleParams | None = None,
    seed: int | None = 0,
    gains: Sequence[float] | None = None,
    offsets: Sequence[float] | None = None,
) -> list[np.ndarray]:
    """Render the same pattern under each field of ``fields`` (``None`` = undeformed).

    Each frame gets its own independent noise; ``gains``/``offsets`` change brightness and
    contrast per frame (grey levels: ``I' = gain * I + offset`` before noise and rounding).
    """
    params = params or SpeckleParams()
    shape = _check_shape(shape)
    fields = list(fields)
    sigma_eff = math.sqrt((params.speckle_size / 4) ** 2 + params.blur_std**2)
    bounds = _preimage_bounds(fields, shape, 8 * sigma_eff + 2)
    pattern_rng, noise_rngs = _rngs(seed, len(fields))
    blobs = _scatter_blobs(bounds, params, pattern_rng)
    gains = list(gains) if gains is not None else [1.0] * len(fields)
    offsets = list(offsets) if offsets is not None else [0.0] * len(fields)
    if len(gains) != len(fields) or len(offsets) != len(fields):
        raise ParameterError(
            f"speckle_sequence: {len(fields)} fields but {len(gains)} gains and "
            f"{len(offsets)} offsets; give one per field"
        )
    return [
        _render_frame(blobs, f, shape, params, rng, g, o)
        for f, rng, g, o in zip(fields, noise_rngs, gains, offsets, strict=True)
    ]


@dataclass(frozen=True)
class SpecklePair:
    """A reference image, a deformed image and the exact displacement field between them."""

    reference: np.ndarray
    deformed: np.ndarray
    field: Field
    params: SpeckleParams = dc_field(default_factory=SpeckleParams)

    def truth(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Exact displacement ``(u, v)`` [pixel] of reference points ``(x, y)`` [pixel]."""
        return self.field.displacement(np.asarray(x, float), np.asarray(y, float))


def speckle_pair(
    shape: tuple[int, int],
    field: Field,
    *,
    params: SpeckleParams | None = None,
    seed: int | None = 0,
    gain: float = 1.0,
    offset: float = 0.0,
) -> SpecklePair:
    """A reference/deformed speckle pair with exact truth.

    Parameters
    ----------
    shape : (int, int)
        Image size (height, width) [pixel].
    field : Field
        Displacement field of the deformed image relative to the reference.
    params : SpeckleParams, optional
        Pattern and camera parameters.
    seed : int
        Seed of pattern and noise.
    gain, offset : float
        Brightness change of the deformed image: ``I' = gain * I + offset`` [grey levels].
    """
    params = params or SpeckleParams()
    ref, dfm = speckle_sequence(
        shape, [None, field], params=params, seed=seed, gains=[1.0, gain], offsets=[0.0, offset]
    )
    return SpecklePair(reference=ref, deformed=dfm, field=field, params=params)


def truth_dataset(field: Field, shape: tuple[int, int], step: int = 1) -> xr.Dataset:
    """Ground-truth displacement on a pixel grid of the reference image, as an xarray Dataset.

    Variables ``u``, ``v`` [pixel] and the gradients ``du_dx`` ... [1] over ``(y, x)``.
    """
    h, w = _check_shape(shape)
    xs = np.arange(0, w, step, dtype=float)
    ys = np.arange(0, h, step, dtype=float)
    X, Y = np.meshgrid(xs, ys)
    u, v = field.displacement(X, Y)
    ux, uy, vx, vy = field.gradient(X, Y)
    dims = ("y", "x")

    def var(a, units, name):
        return xr.DataArray(
            np.asarray(a, float), dims=dims, attrs={"units": units, "long_name": name}
        )

    ds = xr.Dataset(
        {
            "u": var(u, "pixel", "true displacement along x (image columns)"),
            "v": var(v, "pixel", "true displacement along y (image rows, down)"),
            "du_dx": var(ux, "1", "true du/dx"),
            "du_dy": var(uy, "1", "true du/dy"),
            "dv_dx": var(vx, "1", "true dv/dx"),
            "dv_dy": var(vy, "1", "true dv/dy"),
        },
        coords={
            "x": ("x", xs, {"units": "pixel", "long_name": "reference image column"}),
            "y": ("y", ys, {"units": "pixel", "long_name": "reference image row"}),
        },
        attrs={"title": "synthetic speckle ground truth", "field": repr(field)},
    )
    return ds
