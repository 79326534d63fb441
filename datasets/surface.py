"""A speckled surface of known shape and displacement seen by the virtual rig's stereo cameras.

Ground truth for full-field stereo DIC (``jointwear dic field``): the surface is the graph
``z = shape(x, y)`` [m] in the rig's world (mechanism) frame; a material point ``(X, Y,
shape(X, Y))`` moves by ``(u0, v0, w(X, Y))`` (in-plane rigid translation, any out-of-plane
field) or, with ``stretch``, by ``(stretch (X - xc), 0, w)`` (a uniform in-plane strain along
x about ``xc``). Rendering is exact ray casting as in :mod:`jointwear.datasets.rig`: every pixel's
viewing ray (lens distortion inverted) is intersected with the deformed surface by fixed-point
iteration, and the speckle texture (:func:`~jointwear.datasets.rig.speckle_texture`, a quarter
pixel per texel) is sampled at the material coordinates found there (cubic spline in double
precision: OpenCV's ``remap`` quantises positions to 1/32 texel, a bias of up to 0.004 pixel
that does not average out over a subset); then optical blur, noise
and 8-bit quantisation.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from jointwear.datasets.rig import RigConfig, VirtualRig, speckle_texture

__all__ = ["SurfaceMotion", "SurfaceScene"]

Shape = Callable[[np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class SurfaceMotion:
    """Motion of the surface's material points (see module docstring); lengths in m."""

    u0: float = 0.0
    v0: float = 0.0
    w: Shape | None = None
    stretch: float = 0.0

    def material(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Reference (material) coordinates of the current in-plane position (x, y)."""
        if self.stretch:
            xc = SurfaceScene.centre_x
            return xc + (x - xc) / (1.0 + self.stretch), y - self.v0
        return x - self.u0, y - self.v0

    def displacement(self, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
        """Displacement (..., 3) [m] of the material points (X, Y)."""
        wz = self.w(X, Y) if self.w is not None else np.zeros_like(X)
        ux = self.stretch * (X - SurfaceScene.centre_x) if self.stretch else X * 0 + self.u0
        return np.stack([ux, Y * 0 + self.v0, wz], axis=-1)


class SurfaceScene:
    """Renders a speckled surface patch for the virtual rig's two cameras.

    Parameters
    ----------
    shape : callable (x, y) -> z [m]
        Reference surface in the world frame.
    size : (float, float)
        Patch extent along x and y [m], centred on the rig's ``look_at`` point.
    config : RigConfig, optional
        The rig (image size, field of view, noise, blur); default a 640 x 480 rig with a
        0.2 m field of view (0.31 mm per pixel).
    seed : int
        Texture seed.
    """

    centre_x = 0.29  # RigConfig().look_at[0]

    def __init__(
        self,
        shape: Shape | None = None,
        *,
        size: tuple[float, float] = (0.12, 0.09),
        config: RigConfig | None = None,
        seed: int = 0,
    ) -> None:
        self.config = config or RigConfig(width=640, height=480, fov_width=0.2)
        self.rig = VirtualRig(self.config)
        self.calibration = self.rig.calibration
        self.shape = shape or (lambda x, y: 0.0 * x)
        cx, cy, _ = self.config.look_at
        self.centre_x = cx
        self.origin = np.array([cx - size[0] / 2, cy - size[1] / 2])
        self.size = size
        self.texel = self.rig.pixel_footprint / 4
        n = (int(np.ceil(size[1] / self.texel)) + 8, int(np.ceil(size[0] / self.texel)) + 8)
        self.texture = speckle_texture(n, self.texel, 4.0 * self.rig.pixel_footprint, seed=seed)
        from scipy import ndimage

        self._coef = ndimage.spline_filter(self.texture.astype(np.float64), order=3, mode="mirror")

    def render(self, camera: str, motion: SurfaceMotion | None = None, *, noise_seed: int = 0):
        """The 8-bit image of ``camera`` with the surface moved by ``motion``."""
        import cv2

        motion = motion or SurfaceMotion()
        c = self.config
        cam = self.calibration.cameras[camera]
        d = self.rig.rays(camera)
        C = cam.centre
        lam = (0.0 - C[2]) / d[..., 2]
        for _ in range(30):
            p = C + lam[..., None] * d
            X, Y = motion.material(p[..., 0], p[..., 1])
            z = self.shape(X, Y)
            if motion.w is not None:
                z = z + motion.w(X, Y)
            lam = (z - C[2]) / d[..., 2]
        p = C + lam[..., None] * d
        X, Y = motion.material(p[..., 0], p[..., 1])
        from scipy import ndimage

        mx = (X - self.origin[0]) / self.texel + 4
        my = (Y - self.origin[1]) / self.texel + 4
        inside = (X >= self.origin[0]) & (X <= self.origin[0] + self.size[0])
        inside &= (Y >= self.origin[1]) & (Y <= self.origin[1] + self.size[1])
        # exact cubic spline sampling in float64 (cv2.remap quantises the sample position to
        # 1/32 texel; at 4 texels per pixel that error is nearly constant over a subset and
        # moved an image's matches by up to 0.004 pixel against the truth)
        tex = ndimage.map_coordinates(self._coef, [my, mx], order=3, mode="mirror", prefilter=False)
        img = np.where(inside, tex, c.background / 255.0) * 255.0 * c.exposure
        if c.blur_sigma_px > 0:
            img = cv2.GaussianBlur(img.astype(np.float32), (0, 0), c.blur_sigma_px)
        rng = np.random.default_rng([c.seed, noise_seed, 0 if camera == "left" else 1])
        if c.noise_sigma > 0:
            img = img + rng.normal(0.0, c.noise_sigma, img.shape)
        return np.clip(np.rint(img), 0, 255).astype(np.uint8)

    def pair(self, motion: SurfaceMotion | None = None, *, noise_seed: int = 0):
        """(left, right) images."""
        return (
            self.render("left", motion, noise_seed=noise_seed),
            self.render("right", motion, noise_seed=noise_seed),
        )

    def measure(self, pairs, **options):
        """:func:`~jointwear.dic.measure_field` of this scene's (left, right) image ``pairs``
        (from :meth:`pair`) with the rig's calibration and the patch's left ROI
        (:meth:`roi_left`); ``options`` (``subset_size``, ``step``, ...) are passed on."""
        from jointwear.dic import measure_field

        return measure_field(
            [p[0] for p in pairs],
            [p[1] for p in pairs],
            calibration=self.calibration,
            roi=self.roi_left(),
            **options,
        )

    def roi_left(self, shrink_px: float = 10.0) -> tuple[float, float, float, float]:
        """Rectangle (x0, y0, x1, y1) [pixel] of the left image inside the patch's image."""
        ox, oy = self.origin
        sx, sy = self.size
        corners = np.array([[ox, oy], [ox + sx, oy], [ox + sx, oy + sy], [ox, oy + sy]])
        P = np.column_stack([corners, self.shape(corners[:, 0], corners[:, 1])])
        uv = self.calibration.left.project(P)
        lo = np.sort(uv, axis=0)
        return (
            float(lo[1, 0] + shrink_px),
            float(lo[1, 1] + shrink_px),
            float(lo[2, 0] - shrink_px),
            float(lo[2, 1] - shrink_px),
        )
