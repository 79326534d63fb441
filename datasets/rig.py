"""Virtual stereo rig: what the test rig's two cameras would record, with ground truth.

The mechanism is the reference study's four-bar (crank 0.10 m, coupler 0.40 m, follower 0.30 m,
ground 0.30 m, crank at 120 rev/min counter-clockwise). Motion is analytic planar four-bar
kinematics plus a prescribed out-of-plane motion: joint C (the journal) moves along z by
``z_c(t) = z_amplitude * sin(omega t + z_phase)``; the follower, which hangs on a spherical joint at
D, tilts so that its end follows C (``sin(psi) = z_c / L3``). Three speckled planar patches are
attached to the bodies:

* ``follower``: a plate on the follower between 20 % and 80 % of its length;
* ``journal``: a square cap centred on joint C, turning with the coupler, in front of the
  follower (it translates with C, including z_c);
* ``crank``: a plate on the crank (rendered only if in view).

Rendering is by exact ray casting: for every camera pixel the undistorted viewing ray (the
inverse of the lens model, solved to 1e-12) is intersected with each patch plane, and the
speckle texture - a band-limited field sampled at 1/4 of the pixel footprint - is sampled there
with a cubic B-spline in double precision; nearer patches hide farther ones. Optical blur is a
Gaussian point-spread function in the image, sensor noise is additive Gaussian, exposure scales
the brightness (and, with ``motion_blur_samples`` > 1, averages sub-frames over the exposure time),
and images are quantised to 8 bits. Calibration boards are rendered analytically with
pixel-footprint anti-aliasing.

World frame of the ground truth: the mechanism frame, x from joint A to joint D along the ground
link, y up (gravity along -y), z out of the mechanism plane towards the cameras.
"""

from __future__ import annotations

import functools
import json
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from jointwear._version import source_attribute
from jointwear.datasets._rig_config import DEFAULT_CODEC
from jointwear.datasets._rig_motion import (  # noqa: F401 (L1, L2, L4 re-exported)
    CODECS,
    L1,
    L2,
    L3,
    L4,
    PrescribedMotion,
    RigConfig,
    _rz,
    _truth_derivative,
    _truth_state,
    fourbar_pose,
)
from jointwear.dic import Camera, StereoCalibration
from jointwear.errors import BadInputError
from jointwear.outputs import write_image

__all__ = [
    "RigConfig",
    "PrescribedMotion",
    "VirtualRig",
    "fourbar_pose",
    "speckle_texture",
    "generate_rig",
    "CODECS",
]


# ---------------------------------------------------------------------------------------------
# textures and patches
def speckle_texture(
    shape: tuple[int, int], texel: float, speckle_size: float, *, seed: int = 0
) -> np.ndarray:
    """A band-limited speckle pattern in [0.1, 0.9] (float32) of ``shape`` texels.

    Speckles are Gaussian-smoothed random dots of about ``speckle_size`` [m] diameter at a fill
    factor near 50 %; ``texel`` is the texel size [m].
    """
    import cv2

    rng = np.random.default_rng(seed)
    sigma = 0.25 * speckle_size / texel
    field_ = rng.standard_normal(shape).astype(np.float32)
    field_ = cv2.GaussianBlur(field_, (0, 0), sigma)
    field_ /= field_.std() + 1e-12
    img = 0.5 + 0.4 * np.tanh(1.5 * field_)
    img = cv2.GaussianBlur(img.astype(np.float32), (0, 0), 0.35 * sigma)
    return img.astype(np.float32)


@dataclass(frozen=True, eq=False)
class Patch:
    """A speckled rectangle in a body frame: corner ``origin`` + [0, size_a] e_a + [0, size_b] e_b."""

    body: str
    origin: np.ndarray  # body frame [m]
    e_a: np.ndarray
    e_b: np.ndarray
    size: tuple[float, float]
    texel: float
    texture: np.ndarray = field(repr=False)

    @functools.cached_property
    def spline(self) -> np.ndarray:
        """Cubic B-spline coefficients of the texture (mirror boundary), for exact sampling."""
        from scipy import ndimage

        return ndimage.spline_filter(np.asarray(self.texture, np.float64), order=3, mode="mirror")

    def sample(self, mx: np.ndarray, my: np.ndarray) -> np.ndarray:
        """The texture at texel positions (mx, my), cubic B-spline in float64.

        (OpenCV's ``remap`` quantises positions to 1/32 texel: at 4 texels per pixel an error
        nearly constant over a subset, which biased the ground truth of the tracked motion by up
        to 0.004 pixel - about 0.4 µm of out-of-plane displacement on the default rig.)
        """
        from scipy import ndimage

        return ndimage.map_coordinates(
            self.spline, [my, mx], order=3, mode="mirror", prefilter=False
        )

    def corners_body(self) -> np.ndarray:
        a, b = self.size
        return np.array(
            [
                self.origin,
                self.origin + a * self.e_a,
                self.origin + a * self.e_a + b * self.e_b,
                self.origin + b * self.e_b,
            ]
        )


# ---------------------------------------------------------------------------------------------
def _look_at_camera(
    centre: np.ndarray, target: np.ndarray, K: np.ndarray, dist: np.ndarray, size: tuple[int, int]
) -> Camera:
    z = target - centre
    z /= np.linalg.norm(z)
    x = np.array([1.0, 0.0, 0.0]) - z * z[0]
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    R = np.stack([x, y, z])
    return Camera(K, dist, R, -R @ centre, size)


class VirtualRig:
    """Renders the virtual rig's images.

    Parameters
    ----------
    config : RigConfig
        Rig parameters (see :class:`RigConfig`).
    """

    def __init__(
        self,
        config: RigConfig | None = None,
        *,
        motion: PrescribedMotion | xr.Dataset | None = None,
    ) -> None:
        self.config = cfg = config or RigConfig()
        if isinstance(motion, xr.Dataset):
            motion = PrescribedMotion.from_dataset(motion)
        self.motion = motion
        f = cfg.focal_px
        target = np.asarray(cfg.look_at, dtype=float)
        cams = {}
        for name, sign, df in (("left", -1.0, 1.0), ("right", 1.0, 1.003)):
            K = np.array(
                [
                    [f * df, 0.0, (cfg.width - 1) / 2 + sign * cfg.principal_offset_px[0]],
                    [0.0, f * df * 1.0005, (cfg.height - 1) / 2 + cfg.principal_offset_px[1]],
                    [0.0, 0.0, 1.0],
                ]
            )
            centre = target + np.array([sign * cfg.baseline / 2, 0.0, cfg.distance])
            dist = np.asarray(cfg.distortion, dtype=float) * (1.0 if name == "left" else 0.9)
            cams[name] = _look_at_camera(centre, target, K, dist, (cfg.width, cfg.height))
        self.calibration = StereoCalibration(
            cams["left"],
            cams["right"],
            source="virtual rig (exact)",
            world_frame="mechanism frame (x A->D, y up, z out of plane towards the cameras)",
        )
        self._rays: dict[str, np.ndarray] = {}
        self._tiles: dict[str, np.ndarray] = {}
        self.patches = self._make_patches()

    # ---- geometry --------------------------------------------------------------------------
    @property
    def pixel_footprint(self) -> float:
        """Object-space size of one pixel at the mechanism plane [m]."""
        return self.config.distance / self.config.focal_px

    def noise_floor_z(self, sigma_u: float) -> float:
        """Stereo out-of-plane noise floor per point ``Z^2/(f B) sqrt(2) sigma_u`` [m]."""
        c = self.config
        return c.distance**2 / (c.focal_px * c.baseline) * np.sqrt(2) * sigma_u

    def _make_patches(self) -> list[Patch]:
        c = self.config
        texel = self.pixel_footprint / 4
        ex, ey = np.array([1.0, 0, 0]), np.array([0, 1.0, 0])
        specs = [
            (
                "follower",
                np.array([0.2 * L3, -c.follower_width / 2, 0.0]),
                (0.6 * L3, c.follower_width),
            ),
            (
                "journal",
                np.array([-c.journal_size / 2, -c.journal_size / 2, 0.0]),
                (c.journal_size,) * 2,
            ),
            ("crank", np.array([0.015, -0.015, 0.0]), (0.075, 0.03)),
        ]
        out = []
        for i, (body, origin, size) in enumerate(specs):
            shape = (int(np.ceil(size[1] / texel)) + 4, int(np.ceil(size[0] / texel)) + 4)
            size_m = c.speckle_size or 4.0 * self.pixel_footprint
            tex = speckle_texture(shape, texel, size_m, seed=c.seed * 100 + i + 1)
            out.append(Patch(body, origin, ex, ey, size, texel, tex))
        return out

    def rays(
        self, camera: str, region: tuple[int, int, int, int] | None = None, *, tile: int = 64
    ) -> np.ndarray:
        """Unit world ray directions of the pixel centres (H, W, 3), or of ``region``
        ``(y0, y1, x0, x1)``; computed lazily in tiles and cached."""
        cam = self.calibration.cameras[camera]
        w, h = cam.image_size
        if camera not in self._rays:
            self._rays[camera] = np.zeros((h, w, 3))
            self._tiles[camera] = np.zeros(((h + tile - 1) // tile, (w + tile - 1) // tile), bool)
        y0, y1, x0, x1 = region or (0, h, 0, w)
        done = self._tiles[camera]
        ty0, ty1, tx0, tx1 = y0 // tile, (y1 - 1) // tile + 1, x0 // tile, (x1 - 1) // tile + 1
        todo = np.argwhere(~done[ty0:ty1, tx0:tx1]) + [ty0, tx0]
        if len(todo):
            blocks = []
            for ty, tx in todo:
                ys, xs = (
                    slice(ty * tile, min((ty + 1) * tile, h)),
                    slice(tx * tile, min((tx + 1) * tile, w)),
                )
                u, v = np.meshgrid(
                    np.arange(xs.start, xs.stop, dtype=float),
                    np.arange(ys.start, ys.stop, dtype=float),
                )
                blocks.append((ys, xs, u.shape, np.stack([u.ravel(), v.ravel()], axis=1)))
            d = cam.rays(np.concatenate([b[3] for b in blocks]))
            k = 0
            for ys, xs, shape, uv in blocks:
                n = len(uv)
                self._rays[camera][ys, xs] = d[k : k + n].reshape(*shape, 3)
                k += n
            done[todo[:, 0], todo[:, 1]] = True
        return self._rays[camera][y0:y1, x0:x1]

    # ---- rendering -------------------------------------------------------------------------
    def _render_radiance(self, camera: str, t: float) -> np.ndarray:
        c = self.config
        cam = self.calibration.cameras[camera]
        w, h = cam.image_size
        img = np.full((h, w), c.background / 255.0, dtype=np.float32)
        depth = np.full((h, w), np.inf)
        pose = fourbar_pose(t, c, self.motion)
        C = cam.centre
        for patch in self.patches:
            R, p = pose[patch.body]
            corners = patch.corners_body() @ R.T + p
            Xc = cam.world_to_camera(corners)
            if np.any(Xc[:, 2] <= 0):
                continue
            uv = cam.project(corners)
            x0, y0 = np.floor(uv.min(0)).astype(int) - 3
            x1, y1 = np.ceil(uv.max(0)).astype(int) + 4
            x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, w), min(y1, h)
            if x1 <= x0 or y1 <= y0:
                continue
            d = self.rays(camera, (y0, y1, x0, x1))
            n = R[:, 2]
            p0 = R @ patch.origin + p
            denom = d @ n
            with np.errstate(divide="ignore", invalid="ignore"):
                tt = ((p0 - C) @ n) / denom
            X = C + tt[..., None] * d
            rel = X - p0
            a = rel @ (R @ patch.e_a)
            b = rel @ (R @ patch.e_b)
            inside = (tt > 0) & (a >= 0) & (a <= patch.size[0]) & (b >= 0) & (b <= patch.size[1])
            sub_depth = depth[y0:y1, x0:x1]
            inside &= tt < sub_depth
            if not np.any(inside):
                continue
            sub = img[y0:y1, x0:x1]
            sub[inside] = patch.sample(a[inside] / patch.texel + 2, b[inside] / patch.texel + 2)
            sub_depth[inside] = tt[inside]
        return img

    def render(self, camera: str, t: float, *, frame_index: int = 0) -> np.ndarray:
        """The 8-bit grey image camera ``camera`` records at time ``t`` [s]."""
        import cv2

        c = self.config
        n = c.motion_blur_samples
        if n == 1:
            rad = self._render_radiance(camera, t)
        else:
            ts = t + (np.arange(n) / (n - 1) - 0.5) * c.exposure_time
            rad = np.mean([self._render_radiance(camera, ti) for ti in ts], axis=0)
        img = rad * 255.0 * c.exposure
        if c.blur_sigma_px > 0:
            img = cv2.GaussianBlur(img, (0, 0), c.blur_sigma_px)
        rng = np.random.default_rng([c.seed, frame_index, 0 if camera == "left" else 1])
        if c.noise_sigma > 0:
            img = img + rng.normal(0.0, c.noise_sigma, img.shape)
        return np.clip(np.rint(img), 0, 255).astype(np.uint8)

    def frame_times(self) -> np.ndarray:
        """Times of the frames the cameras record [s] (before dropping/duplicating)."""
        return np.arange(self.config.n_frames) / self.config.fps

    # ---- calibration boards -----------------------------------------------------------------
    def board_poses(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Board poses (R, origin) in the mechanism frame; the last one lies on the mechanism
        plane with columns along +x and rows along -y (the world-frame view)."""
        c = self.config
        rng = np.random.default_rng(c.seed + 7)
        sx, sy = c.board_squares
        s = c.board_square_size
        target = np.asarray(c.look_at, dtype=float)
        base = np.diag([1.0, -1.0, -1.0])  # board x = +x, y = -y, z = -z (faces the cameras)
        poses = []
        for k in range(c.board_views):
            ang = 2 * np.pi * k / max(c.board_views, 1)
            tilt = np.deg2rad(rng.uniform(20, 35))
            axis = np.array([np.cos(ang), np.sin(ang), 0.0])
            Kx = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
            Rt = np.eye(3) + np.sin(tilt) * Kx + (1 - np.cos(tilt)) * Kx @ Kx
            R = Rt @ _rz(np.deg2rad(rng.uniform(-10, 10))) @ base
            centre = target + np.array(
                [rng.uniform(-0.03, 0.03), rng.uniform(-0.03, 0.03), rng.uniform(-0.08, 0.12)]
            )
            origin = centre - R @ np.array([sx * s / 2, sy * s / 2, 0.0])
            poses.append((R, origin))
        R = base
        origin = target - R @ np.array([sx * s / 2, sy * s / 2, 0.0])
        poses.append((R, origin))
        return poses

    def world_board_origin(self) -> np.ndarray:
        """Mechanism-frame position of the first inner corner of the world-frame board [m]."""
        R, origin = self.board_poses()[-1]
        s = self.config.board_square_size
        return origin + R @ np.array([s, s, 0.0])

    def _charuco_texture(self) -> tuple[np.ndarray, float]:
        """The ChArUco board as OpenCV draws it (1-square white margin), box-filtered down to
        about the camera's pixel footprint; and its texel size [m]."""
        import cv2

        if getattr(self, "_charuco_tex", None) is None:
            c = self.config
            sx, sy = c.board_squares
            d = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, c.board_dictionary.upper()))
            board = cv2.aruco.CharucoBoard((sx, sy), c.board_square_size, c.board_marker_size, d)
            board.setLegacyPattern(bool(c.board_legacy))
            fine = 240  # texels per square, drawn
            img = board.generateImage(((sx + 2) * fine, (sy + 2) * fine), marginSize=fine)
            per_square = max(int(round(c.board_square_size / self.pixel_footprint)), 8)
            per_square = min(per_square, fine)
            img = cv2.resize(
                img, ((sx + 2) * per_square, (sy + 2) * per_square), interpolation=cv2.INTER_AREA
            )
            self._charuco_tex = (img.astype(np.float32) / 255.0, c.board_square_size / per_square)
        return self._charuco_tex

    def render_board(
        self, camera: str, R: np.ndarray, origin: np.ndarray, *, index: int = 0
    ) -> np.ndarray:
        """Image of the calibration board (squares ``board_squares``, 1-square white margin):
        a chessboard rendered analytically (pixel-footprint anti-aliasing) or a ChArUco board
        (``board_kind="charuco"``) drawn by OpenCV and mapped onto the board plane."""
        import cv2

        c = self.config
        cam = self.calibration.cameras[camera]
        rays = self.rays(camera)
        C = cam.centre
        n = R[:, 2]
        denom = rays @ n
        with np.errstate(divide="ignore", invalid="ignore"):
            tt = ((origin - C) @ n) / denom
        X = C + tt[..., None] * rays
        rel = X - origin
        bx = rel @ R[:, 0]
        by = rel @ R[:, 1]
        s = c.board_square_size
        sx, sy = c.board_squares

        def tri(x, wpx):
            f = x / s
            k = np.floor(f)
            frac = f - k
            sign = np.where(k % 2 == 0, 1.0, -1.0)
            return np.clip(sign * np.minimum(frac, 1 - frac) * s / np.maximum(wpx, 1e-12), -1, 1)

        white, black = 0.9, 0.08
        inside = (bx >= 0) & (bx <= sx * s) & (by >= 0) & (by <= sy * s)
        margin = (bx >= -s) & (bx <= (sx + 1) * s) & (by >= -s) & (by <= (sy + 1) * s) & ~inside
        if c.board_kind == "charuco":
            tex, texel = self._charuco_texture()
            # texel centres: board coordinate (k + 0.5) * texel - s for texel k
            mx = ((bx + s) / texel - 0.5).astype(np.float32)
            my = ((by + s) / texel - 0.5).astype(np.float32)
            val = cv2.remap(
                tex, np.nan_to_num(mx, nan=-10.0), np.nan_to_num(my, nan=-10.0),
                cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=1.0,
            )  # fmt: skip
            img = black + (white - black) * val
            out = np.where(inside | margin, img, c.background / 255.0)
        else:
            gx_u = np.abs(np.gradient(bx, axis=1)) + np.abs(np.gradient(bx, axis=0))
            gy_u = np.abs(np.gradient(by, axis=1)) + np.abs(np.gradient(by, axis=0))
            val = 0.5 + 0.5 * tri(bx, 0.5 * gx_u) * tri(by, 0.5 * gy_u)
            img = black + (white - black) * val
            out = np.where(inside, img, np.where(margin, white, c.background / 255.0))
        out = np.where(tt > 0, out, c.background / 255.0)
        out = (out * 255.0 * c.exposure).astype(np.float32)
        if c.blur_sigma_px > 0:
            out = cv2.GaussianBlur(out, (0, 0), c.blur_sigma_px)
        rng = np.random.default_rng([c.seed, 10_000 + index, 0 if camera == "left" else 1])
        out = out + rng.normal(0.0, c.noise_sigma, out.shape)
        return np.clip(np.rint(out), 0, 255).astype(np.uint8)

    def board_images(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """(left, right) board images, the world-frame view last."""
        return list(self.iter_board_images())

    def iter_board_images(self) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """The board images of :meth:`board_images`, rendered one pair at a time."""
        for i, (R, o) in enumerate(self.board_poses()):
            yield (
                self.render_board("left", R, o, index=i),
                self.render_board("right", R, o, index=i),
            )

    # ---- regions of interest ----------------------------------------------------------------
    def body_rois(self, *, shrink_px: float = 6.0) -> dict[str, list[list[float]]]:
        """Polygons [pixel] of each patch in the left reference image (frame 0), shrunk inwards."""
        cam = self.calibration.left
        pose = fourbar_pose(0.0, self.config, self.motion)
        out = {}
        w, h = cam.image_size
        for patch in self.patches:
            R, p = pose[patch.body]
            uv = cam.project(patch.corners_body() @ R.T + p)
            ctr = uv.mean(0)
            vec = uv - ctr
            uv = ctr + vec * (1 - shrink_px / np.linalg.norm(vec, axis=1, keepdims=True))
            if np.all((uv >= 0) & (uv < [w, h])):
                out[patch.body] = uv.round(2).tolist()
        return out

    # ---- ground truth -----------------------------------------------------------------------
    def ground_truth(self, times: np.ndarray | None = None) -> xr.Dataset:
        """Ground truth over ``times`` [s] (default: every frame), mechanism frame."""
        from jointwear import conventions as C

        c = self.config
        t = self.frame_times() if times is None else np.asarray(times, dtype=float)
        m = self.motion
        fp = np.array([_truth_state(ti, c, m)["follower_position"] for ti in t])
        fv = np.array([_truth_derivative(ti, c, "follower_position", m) for ti in t])
        jp = np.array([_truth_state(ti, c, m)["journal_position"] for ti in t])
        jv = np.array([_truth_derivative(ti, c, "journal_position", m) for ti in t])
        ca = np.array([_truth_state(ti, c, m)["crank_angle"][0] for ti in t])
        poses = [fourbar_pose(ti, c, m) for ti in t]
        bodies = [p.body for p in self.patches]
        rot = np.array([[pp[b][0] for b in bodies] for pp in poses])
        org = np.array([[pp[b][1] for b in bodies] for pp in poses])
        ds = xr.Dataset(
            {
                "follower_position": (("time", "axis"), fp, C.variable_attrs("follower_position")),
                "follower_velocity": (("time", "axis"), fv, C.variable_attrs("follower_velocity")),
                "journal_position": (
                    ("time", "axis"),
                    jp,
                    {"units": "m", "long_name": "position of the journal cap centre"},
                ),
                "journal_displacement": (
                    ("time", "axis"),
                    jp - jp[:1],
                    {
                        "units": "m",
                        "long_name": "displacement of the journal cap centre since the first frame (z = out of plane)",
                    },
                ),
                "journal_velocity": (
                    ("time", "axis"),
                    jv,
                    {"units": "m s-1", "long_name": "velocity of the journal cap centre"},
                ),
                "crank_angle": ("time", ca, C.variable_attrs("crank_angle")),
                "body_rotation": (
                    ("time", "body", "row", "col"),
                    rot,
                    {"units": "1", "long_name": "body-to-mechanism rotation of each patch's body"},
                ),
                "body_origin": (
                    ("time", "body", "axis"),
                    org,
                    {"units": "m", "long_name": "origin of each patch's body frame"},
                ),
            },
            coords={
                "time": ("time", t, {"units": "s", "long_name": C.COORDINATES["time"][1]}),
                "axis": ("axis", ["x", "y", "z"], {"long_name": "vector component"}),
                "body": ("body", bodies, {"long_name": "rigid body carrying a speckle patch"}),
                "row": ("row", [0, 1, 2], {"long_name": "matrix row"}),
                "col": ("col", [0, 1, 2], {"long_name": "matrix column"}),
            },
        )
        cal = self.calibration.to_dataset()
        for name in ("camera_matrix", "distortion", "rotation", "translation", "image_size"):
            ds[f"true_{name}"] = (
                cal[name].rename({"axis": "axis"}) if name == "translation" else cal[name]
            )
            ds[f"true_{name}"].attrs["long_name"] = "true " + cal[name].attrs["long_name"]
        ds.attrs.update(
            {
                "title": "jointwear virtual rig ground truth",
                "frame": "mechanism frame: x from A to D, y up, z out of plane towards the cameras",
                "rig_config": json.dumps(_jsonable(asdict(c))),
                "baseline_m": self.calibration.baseline,
                "focal_px": c.focal_px,
                "pixel_footprint_m": self.pixel_footprint,
                "noise_floor_z_per_point_m_at_0p01px": self.noise_floor_z(0.01),
                "world_board_origin_m": self.world_board_origin().tolist(),
                "rendering": "exact ray casting + cubic B-spline sampling (float64) of a band-limited speckle texture",
                "motion": "analytic four-bar kinematics, z_c = z_amplitude sin(omega t + z_phase)"
                if self.motion is None
                else "prescribed from data (cubic splines of crank_angle and/or z of joint C)",
            }
        )
        return ds


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def _write_video(path: Path, frames, fps: float, codec: str, size: tuple[int, int]) -> None:
    import cv2

    fourcc, _, _ = CODECS[codec]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), fps, size, False)
    if not writer.isOpened():
        raise BadInputError(
            f"OpenCV could not open a '{codec}' ({fourcc}) video writer for '{path}'; choose "
            f"another codec ({', '.join(CODECS)})"
        )
    if codec == "mjpg":
        writer.set(cv2.VIDEOWRITER_PROP_QUALITY, 100)
    try:
        for frame in frames:
            writer.write(frame)
    finally:
        writer.release()


def generate_rig(
    out: str | Path,
    config: RigConfig | None = None,
    *,
    video: bool = True,
    images: bool = True,
    codec: str = DEFAULT_CODEC,
    calibration_images: bool = True,
    motion: PrescribedMotion | xr.Dataset | None = None,
    progress: Callable[[str, int, int], None] | None = None,
) -> dict[str, Path]:
    """Render the virtual rig to ``out``: footage, board images, ground truth and ROI file.

    Writes ``left/`` and ``right/`` (PNG frames named ``frame_<index>.png``; a dropped frame's
    number is missing), ``left<ext>``/``right<ext>`` videos, ``calibration/left|right/board_XX.png``
    (the last view is the world-frame board lying on the mechanism plane), ``truth.nc`` (ground
    truth with provenance) and ``bodies.toml`` (regions of interest for ``jointwear dic track``).

    ``motion`` (a :class:`PrescribedMotion` or a Dataset such as a simulator output with
    ``crank_angle`` and ``follower_position``/``journal_position``) replaces the analytic motion.
    ``progress(stage, done, total)`` is called after each rendered frame (stage ``"left"`` or
    ``"right"``) and each calibration view (``"calibration"``), for a progress display.

    Returns
    -------
    dict
        Paths of what was written.
    """

    from jointwear import io

    if codec not in CODECS:
        raise BadInputError(f"codec {codec!r} is not available; choose one of {', '.join(CODECS)}")
    rig = VirtualRig(config, motion=motion)
    c = rig.config
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written: dict[str, Path] = {}
    n = c.n_frames
    dropped = set(c.drop_frames)
    duplicated = set(c.duplicate_frames)
    # a duplicated frame k re-sends frame k's image in frame k+1's slot; a dropped frame is absent
    content = {k: (k - 1 if (k - 1) in duplicated else k) for k in range(n) if k not in dropped}
    times = rig.frame_times()
    for cam in ("left", "right"):
        folder = out / cam

        def frames(cam=cam, folder=folder):
            last: tuple[int, np.ndarray] | None = None
            for k, src in content.items():
                if last is None or last[0] != src:
                    last = (src, rig.render(cam, times[src], frame_index=src))
                img = last[1]
                if images:
                    folder.mkdir(exist_ok=True)
                    write_image(folder / f"frame_{k:06d}.png", img)
                if progress is not None:
                    progress(cam, k + 1, n)
                yield img

        if video:
            path = out / f"{cam}{CODECS[codec][1]}"
            _write_video(path, frames(), c.fps, codec, (c.width, c.height))
            written[f"{cam}_video"] = path
        else:
            for _ in frames():
                pass
        if images:
            written[f"{cam}_images"] = folder
    if calibration_images:
        n_views = len(rig.board_poses())
        for i, (L, R) in enumerate(rig.iter_board_images()):
            if progress is not None:
                progress("calibration", i + 1, n_views)
            for cam, img in (("left", L), ("right", R)):
                folder = out / "calibration" / cam
                folder.mkdir(parents=True, exist_ok=True)
                write_image(folder / f"board_{i:02d}.png", img)
        written["calibration"] = out / "calibration"
    truth = rig.ground_truth()
    truth["frame_recorded"] = (
        "time",
        np.array([0 if k in dropped else 1 for k in range(n)], dtype=np.int8),
        {
            "units": "1",
            "long_name": "frame present in the footage (0 = dropped)",
            "flag_values": np.array([0, 1], dtype=np.int8),
            "flag_meanings": "dropped recorded",
        },
    )
    truth.attrs["duplicated_frames"] = json.dumps(list(c.duplicate_frames))
    truth.attrs["dropped_frames"] = json.dumps(list(c.drop_frames))
    written["truth"] = io.save(
        truth, out / "truth.nc", parameters=asdict(c), source=source_attribute("datasets.rig")
    )
    written["bodies"] = _write_bodies_toml(rig, out / "bodies.toml")
    return written


def _write_bodies_toml(rig: VirtualRig, path: Path) -> Path:
    rois = rig.body_rois()
    c = rig.config
    pose0 = fourbar_pose(0.0, c, rig.motion)
    lines = [
        "# Regions of interest for `jointwear dic track`, written by `jointwear datasets rig`.",
        "# Polygons in pixels of the left camera's first frame.",
        "[track]",
        'data_origin = "synthetic"   # rendered footage, not filmed: the report says so',
        "subset_size = 21",
        "step = 10",
        "# mechanism-frame position of the world origin when the calibration's world frame is the",
        "# rig's board view (the last calibration image pair); use [0, 0, 0] with the exact cameras",
        "world_origin = [" + ", ".join(f"{v:.9f}" for v in rig.world_board_origin()) + "]",
        "",
    ]
    for body, poly in rois.items():
        role = {"follower": "follower", "journal": "journal", "crank": "crank"}[body]
        lines.append(f"[bodies.{body}]")
        lines.append(f'role = "{role}"')
        lines.append("polygon = [" + ", ".join(f"[{x:.2f}, {y:.2f}]" for x, y in poly) + "]")
        if body == "follower":
            lines.append(
                "# follower centre of mass at the first frame, mechanism frame [m] (the world frame "
                "of a calibration made with the rig's board view)"
            )
            lines.append(
                "centroid_mechanism = ["
                + ", ".join(f"{v:.9f}" for v in pose0["follower_centroid"])
                + "]"
            )
        if body == "journal":
            lines.append("# journal cap centre at the first frame, mechanism frame [m]")
            lines.append(
                "centroid_mechanism = [" + ", ".join(f"{v:.9f}" for v in pose0["journal"][1]) + "]"
            )
        if body == "crank":
            lines.append(f"reference_angle_deg = {np.rad2deg(pose0['crank_angle']):.6f}")
        lines.append("")
    with open(path, "w") as fh:
        fh.write("\n".join(lines))
    return path


def _replace(cfg: RigConfig, **kw: Any) -> RigConfig:
    return replace(cfg, **kw)
