"""Calibration files: jointwear's own (``.nc``) and the importers of OpenCV FileStorage and
VIC-3D calibrations, converted to :class:`~jointwear.dic.StereoCalibration` in metres."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np

from jointwear.dic.calibration._camera import (
    Camera,
    StereoCalibration,
    cardan_to_matrix,
)
from jointwear.errors import BadInputError

__all__ = ["read_opencv_calibration", "read_vic3d_calibration", "read_calibration"]

_LENGTH_UNITS = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "um": 1e-6, "in": 0.0254}


def metres_per_unit(length_unit: str | float, units: dict = _LENGTH_UNITS) -> float | None:
    """Metres per unit of ``length_unit``: a name in ``units``, or a positive number of
    metres per unit; None if it is neither."""
    if isinstance(length_unit, str) and length_unit.strip() in units:
        return units[length_unit.strip()]
    try:
        scale = float(length_unit)
    except (TypeError, ValueError):
        return None
    return scale if np.isfinite(scale) and scale > 0 else None


def _length_scale(length_unit: str | float) -> float:
    """Metres per unit of ``length_unit`` (a unit name, or a number of metres per unit)."""
    scale = metres_per_unit(length_unit)
    if scale is None:
        raise BadInputError(
            f"length_unit {length_unit!r} is not known; use one of {', '.join(_LENGTH_UNITS)} "
            "(the unit the calibration board's square size was given in), or the number of "
            "metres per unit of T (e.g. 0.025 when T is in squares of a 25 mm board)"
        )
    return scale


def _check_rotation(R: Any, where: str) -> np.ndarray:
    """A proper rotation matrix from a 3x3 matrix or a Rodrigues vector, or a clear error."""
    import cv2

    arr = np.asarray(R, dtype=float)
    if arr.size == 3:
        if not np.all(np.isfinite(arr)):
            raise BadInputError(
                f"{where}: the Rodrigues rotation vector {arr.ravel()} is not finite"
            )
        arr = cv2.Rodrigues(arr.reshape(3, 1))[0]
    if arr.shape != (3, 3) or not np.all(np.isfinite(arr)):
        raise BadInputError(
            f"{where}: expected a finite 3x3 rotation matrix or a 3-element Rodrigues vector, "
            f"got shape {arr.shape}"
        )
    err = float(np.max(np.abs(arr @ arr.T - np.eye(3))))
    det = float(np.linalg.det(arr))
    if err <= 1e-5 and det > 0:  # rounded when written: the nearest rotation
        U, _, Vt = np.linalg.svd(arr)
        return U @ Vt
    if err > 1e-6 or abs(det - 1) > 1e-6:
        kind = (
            "a reflection (det = -1)" if det < 0 else f"not orthonormal (|R R^T - I| = {err:.2g})"
        )
        raise BadInputError(
            f"{where} is not a rotation matrix: {kind}, det = {det:.6g}; check that the key holds "
            "stereoCalibrate's R (left-to-right rotation), not R1/R2/P1/P2 or a transposed copy"
        )
    return arr


#: Distortion vector lengths OpenCV writes (k1 k2 p1 p2 [k3 [k4 k5 k6 [s1..s4 [tauX tauY]]]]).
_OPENCV_DIST_SIZES = (4, 5, 8, 12, 14)


def _opencv_distortion(d: Any, where: str) -> np.ndarray:
    arr = np.asarray(d, dtype=float).ravel()
    if arr.size not in _OPENCV_DIST_SIZES:
        raise BadInputError(
            f"{where}: a distortion vector of {arr.size} coefficients; OpenCV writes 4, 5, 8, 12 "
            "or 14 (k1 k2 p1 p2 [k3 [k4 k5 k6 [s1 s2 s3 s4 [tauX tauY]]]])"
        )
    if not np.all(np.isfinite(arr)):
        raise BadInputError(f"{where}: the distortion coefficients {arr.tolist()} are not finite")
    if arr.size > 8 and np.any(arr[8:] != 0):
        raise BadInputError(
            f"{where}: non-zero thin-prism/tilt coefficients (s1..s4, tauX, tauY = "
            f"{arr[8:].tolist()}); jointwear's camera model has k1, k2, p1, p2, k3, k4, k5, k6 "
            "only - recalibrate without CALIB_THIN_PRISM_MODEL/CALIB_TILTED_MODEL"
        )
    return arr[:8]


def _check_lens(cam: Camera, where: str) -> None:
    """Refuse a lens model whose radial mapping folds back within the image (undistortion would
    be ambiguous there): r_d = r * radial(r) must increase up to the farthest image corner."""
    w, h = cam.image_size
    K = cam.matrix
    corners = np.array([[0, 0], [w, 0], [0, h], [w, h]], dtype=float) - K[:2, 2]
    r_max = float(np.max(np.hypot(corners[:, 0] / K[0, 0], corners[:, 1] / K[1, 1])))
    r = np.linspace(0.0, r_max, 2001)
    k1, k2, _, _, k3, k4, k5, k6 = cam.distortion
    r2 = r * r
    rd = r * (1 + r2 * (k1 + r2 * (k2 + r2 * k3))) / (1 + r2 * (k4 + r2 * (k5 + r2 * k6)))
    bad = np.flatnonzero(np.diff(rd) <= 0)
    if bad.size:
        r_fold = float(r[bad[0]])
        raise BadInputError(
            f"{where}: the lens distortion folds back at {r_fold:.3f} (normalised radius), inside "
            f"the {w}x{h} px image (corner at {r_max:.3f}); the coefficients "
            f"{cam.distortion.tolist()} cannot be those of this camera - check the file and the "
            "image size"
        )


_OPENCV_KEYS = {
    "K1": ("K1", "M1", "cameraMatrix1", "camera_matrix_left", "left_camera_matrix"),
    "D1": ("D1", "dist1", "distCoeffs1", "distortion_left", "left_distortion"),
    "K2": ("K2", "M2", "cameraMatrix2", "camera_matrix_right", "right_camera_matrix"),
    "D2": ("D2", "dist2", "distCoeffs2", "distortion_right", "right_distortion"),
    "R": ("R", "rotation", "R_lr"),
    "T": ("T", "translation", "T_lr"),
}


def _fs_array(node: Any) -> np.ndarray | None:
    """A cv::FileNode as an array: an ``opencv-matrix``, a sequence of numbers or a number."""
    if node.isSeq():
        items = [node.at(i) for i in range(node.size())]
        if items and all(item.isSeq() for item in items):  # nested lists: rows of a matrix
            rows = [_fs_array(item) for item in items]
            if any(r is None for r in rows) or len({r.size for r in rows}) != 1:
                return None
            return np.stack([r.ravel() for r in rows])
        if not all(item.isReal() or item.isInt() for item in items):
            return None
        return np.asarray([item.real() for item in items], dtype=float)
    if node.isReal() or node.isInt():
        return np.asarray([node.real()], dtype=float)
    mat = node.mat()
    return None if mat is None else np.asarray(mat, dtype=float)


def _read_opencv_file(path: Path) -> tuple[dict[str, tuple[np.ndarray, str]], Any]:
    """Keys of :data:`_OPENCV_KEYS` found in one FileStorage file, and its image size (or None)."""
    import cv2

    if not path.exists():
        raise BadInputError(f"OpenCV calibration file '{path}' does not exist")
    try:
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
        ok = fs.isOpened()
    except (cv2.error, SystemError):  # OpenCV 5 raises SystemError on truncated/empty files
        ok = False
    if not ok:
        raise BadInputError(
            f"'{path}' could not be read as an OpenCV FileStorage YAML/XML file; check that it "
            "starts with '%YAML:1.0' or '<?xml' and was written by cv::FileStorage"
        )
    found: dict[str, tuple[np.ndarray, str]] = {}
    size = None
    try:
        for key, names in _OPENCV_KEYS.items():
            for name in names:
                node = fs.getNode(name)
                if not node.empty():
                    arr = _fs_array(node)
                    if arr is not None:
                        found[key] = (arr, name)
                        break
        w, h = fs.getNode("image_width"), fs.getNode("image_height")
        if not w.empty() and not h.empty():
            size = (int(w.real()), int(h.real()))
        for name in ("image_size", "imageSize"):
            node = fs.getNode(name)
            if size is None and not node.empty():
                arr = _fs_array(node)
                if arr is not None and arr.size >= 2:
                    size = (int(arr.ravel()[0]), int(arr.ravel()[1]))
    except BadInputError:
        raise
    except (cv2.error, SystemError, ValueError, TypeError, OverflowError) as exc:
        raise BadInputError(
            f"'{path}': an entry of the OpenCV FileStorage file cannot be read ({exc}); the "
            "file is corrupt or truncated - write it again with cv::FileStorage"
        ) from None
    finally:
        fs.release()
    return found, size


def read_opencv_calibration(
    path: str | Path | list[str | Path] | tuple[str | Path, ...],
    *,
    length_unit: str | float,
    image_size: tuple[int, int] | None = None,
    extrinsics: str | Path | None = None,
) -> StereoCalibration:
    """Import a stereo calibration saved by OpenCV (``cv::FileStorage`` YAML or XML).

    The file(s) hold the two intrinsic matrices and distortion vectors and ``stereoCalibrate``'s
    ``R``, ``T`` (left-camera to right-camera: ``X_right = R X_left + T``). They may be split over
    two files as OpenCV's ``stereo_calib`` sample writes them: ``intrinsics.yml`` (``M1 D1 M2
    D2``) and ``extrinsics.yml`` (``R T R1 R2 P1 P2 Q``; the rectification entries are not used).
    Accepted names: ``K1/M1/cameraMatrix1``, ``D1/dist1/distCoeffs1``, ``K2/M2/cameraMatrix2``,
    ``D2/dist2/distCoeffs2``, ``R`` (3x3 matrix or Rodrigues vector), ``T``, and
    ``image_width``/``image_height`` or ``image_size``/``imageSize``. Distortion vectors of 4, 5,
    8, 12 or 14 coefficients are accepted; thin-prism and tilt terms must be zero.

    Parameters
    ----------
    path : path, or list/tuple of paths
        The ``.yml``/``.yaml``/``.xml``/``.json`` file, or several files whose keys are merged
        (a key found in two files must have the same value in both).
    length_unit : {"m", "mm", "cm", "um", "in"} or float
        Unit of ``T``: OpenCV uses whatever unit the board square size was given in; the file
        does not say, so it must be stated. A number is taken as metres per unit (e.g. ``0.025``
        when ``stereo_calib`` ran with its default square size 1 on a 25 mm board).
    image_size : (width, height), optional
        Image size [pixel] when the files do not hold it (``stereo_calib`` does not write it).
    extrinsics : path, optional
        A further file to merge (the ``extrinsics.yml`` of ``stereo_calib``).

    Returns
    -------
    StereoCalibration
        World frame = left camera frame; translations in metres.
    """
    paths = [Path(p) for p in (path if isinstance(path, (list, tuple)) else [path])]
    if extrinsics is not None:
        paths.append(Path(extrinsics))
    if not paths:
        raise BadInputError("read_opencv_calibration: no file given")
    scale = _length_scale(length_unit)
    found: dict[str, tuple[np.ndarray, str, Path]] = {}
    holds: dict[Path, list[str]] = {}
    size = image_size
    for p in paths:
        keys, file_size = _read_opencv_file(p)
        holds[p] = [name for _, name in keys.values()]
        for key, (arr, name) in keys.items():
            if key in found:
                prev, prev_name, prev_path = found[key]
                if prev.shape != arr.shape or not np.allclose(prev, arr, rtol=1e-9, atol=0):
                    raise BadInputError(
                        f"OpenCV calibration: {key} differs between '{prev_path}' ({prev_name}) "
                        f"and '{p}' ({name}); pass files from one calibration only"
                    )
                continue
            found[key] = (arr, name, p)
        if size is None and file_size is not None:
            size = file_size
    names = " + ".join(f"'{p}'" for p in paths)
    missing = [k for k in _OPENCV_KEYS if k not in found]
    if missing:
        held = "; ".join(
            f"'{p.name}' holds {', '.join(h) if h else 'none of them'}" for p, h in holds.items()
        )
        raise BadInputError(
            f"OpenCV calibration {names} lacks {', '.join(missing)} (looked for "
            + "; ".join(f"{k}: {'/'.join(_OPENCV_KEYS[k])}" for k in missing)
            + f"; {held}); it must hold both cameras' matrices and distortion and "
            "stereoCalibrate's R and T - OpenCV's stereo_calib sample writes them to two files, "
            "intrinsics.yml (M1 D1 M2 D2) and extrinsics.yml (R T): pass both"
        )
    if size is None:
        raise BadInputError(
            f"OpenCV calibration {names} does not state the image size; pass image_size="
            "(width, height) (CLI: --image-size W H)"
        )
    size = _check_image_size(size, f"OpenCV calibration {names}")

    def where(key: str) -> str:
        return f"OpenCV calibration '{found[key][2]}', {found[key][1]}"

    mats = {}
    for key in ("K1", "K2"):
        K = found[key][0]
        if K.shape != (3, 3) or not np.all(np.isfinite(K)):
            raise BadInputError(
                f"{where(key)}: expected a finite 3x3 camera matrix, got shape {K.shape}"
            )
        mats[key] = K
    D1 = _opencv_distortion(found["D1"][0], where("D1"))
    D2 = _opencv_distortion(found["D2"][0], where("D2"))
    R = _check_rotation(found["R"][0], where("R"))
    T = found["T"][0].ravel()
    if T.size != 3 or not np.all(np.isfinite(T)):
        raise BadInputError(f"{where('T')}: expected 3 finite values, got {T.tolist()}")
    try:
        left = Camera(mats["K1"], D1, np.eye(3), np.zeros(3), size)
        right = Camera(mats["K2"], D2, R, T * scale, size)
    except BadInputError as exc:
        raise BadInputError(f"OpenCV calibration {names}: {exc}") from None
    _check_lens(left, f"OpenCV calibration {names}, left camera")
    _check_lens(right, f"OpenCV calibration {names}, right camera")
    return StereoCalibration(left, right, source="opencv:" + "+".join(p.name for p in paths))


def _check_image_size(size: Any, what: str) -> tuple[int, int]:
    try:
        w, h = (float(v) for v in size)
    except (TypeError, ValueError):
        raise BadInputError(f"{what}: image size {size!r} is not (width, height)") from None
    if not (
        np.isfinite(w) and np.isfinite(h) and w >= 1 and h >= 1 and w == int(w) and h == int(h)
    ):
        raise BadInputError(
            f"{what}: image size {size!r} is not a positive whole (width, height) in pixels"
        )
    return int(w), int(h)


def _vic3d_numbers(text: str | None, where: str) -> list[float]:
    out = []
    for tok in (text or "").replace(",", " ").split():
        try:
            out.append(float(tok))
        except ValueError:
            raise BadInputError(f"{where}: {tok!r} is not a number") from None
    return out


def _vic3d_root(path: Path) -> ET.Element:
    """The XML of a VIC-3D cal.xml, project XML or ``.z3d`` project (zip holding project.xml),
    with tag and attribute names lower-cased."""
    import zipfile

    if not path.exists():
        raise BadInputError(f"VIC-3D calibration file '{path}' does not exist")
    if zipfile.is_zipfile(path):
        with zipfile.ZipFile(path) as zf:
            xmls = [n for n in zf.namelist() if n.lower().endswith(".xml")]
            xmls.sort(key=lambda n: (Path(n).name.lower() != "project.xml", len(n)))
            if not xmls:
                raise BadInputError(
                    f"VIC-3D project '{path}' is a zip archive without an XML file (expected "
                    "project.xml inside a .z3d); export the calibration as cal.xml from VIC-3D"
                )
            data = zf.read(xmls[0])
            label = f"'{path}' ({xmls[0]})"
    else:
        data = path.read_bytes()
        label = f"'{path}'"
    data = re.sub(rb"<!DOCTYPE[^>\[]*(\[[^\]]*\])?\s*>", b"", data, count=1)
    try:
        root = ET.fromstring(data)
    except ET.ParseError as exc:
        raise BadInputError(
            f"{label} is not well-formed XML ({exc}); is it a VIC-3D cal.xml or project file?"
        ) from None
    for el in root.iter():
        if isinstance(el.tag, str):
            el.tag = el.tag.rsplit("}", 1)[-1].lower()
        el.attrib = {k.lower(): v for k, v in el.attrib.items()}
    return root


def read_vic3d_calibration(
    path: str | Path, *, image_size: tuple[int, int] | None = None
) -> StereoCalibration:
    """Import the calibration of a VIC-3D project or calibration file (``cal.xml``, project XML
    or ``.z3d``).

    VIC-3D stores, per ``<camera id=...>``, ``cx cy fx fy fs k1 k2 k3`` [pixel, pixel, pixel,
    pixel, pixel, 1, 1, 1] followed by ``<orientation>alpha beta gamma tx ty tz</orientation>``
    [degree, mm]. Newer ``.z3d`` projects split them into ``<intrinsics>cx cy fx fy fs
    </intrinsics>``, ``<distortion>`` and ``<orientation>`` (the element names SDynPy's VIC-3D
    reader uses); ``<distortion>`` is taken to hold ``k1 [k2 [k3]]`` and more values are refused.
    They are read as:

    * world-to-camera extrinsics ``Xc = R X + t`` with ``R = Rz(gamma) Ry(beta) Rx(alpha)``
      (:func:`cardan_to_matrix`) and ``t = (tx, ty, tz)`` in millimetres (converted to metres);
    * ``fs`` is the skew entry ``K[0, 1]`` of the intrinsic matrix [pixel] (``u = fx x_d + fs
      y_d + cx``), not an angle;
    * ``k1, k2, k3`` distort normalised coordinates radially,
      ``x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6)`` with ``r^2 = x^2 + y^2`` - exactly OpenCV's
      ``(k1, k2, 0, 0, k3)``, so the camera model is represented without fitting.

    Evidence: with this reading, real image matches made by VIC-3D and by DICe with real VIC-3D
    files triangulate to 0.02-0.06 px RMS (DICe's ``stereo_d_spec`` regression data: 0.054 px
    over 27 points; VIC-3D's own start-point matches in DICe's ``stereo_list`` project: 0.024 px),
    whereas another rotation order, the transposed rotation or a camera-to-world reading gives
    5-10 px. DICe imports these coefficients as odd powers of the radius (``K1R1_K2R2_K3R3``, a
    radial displacement ``k1 r + k2 r^2 + k3 r^3``), which leaves 82 px on the ``stereo_d_spec``
    matches and makes ``k1`` indistinguishable from a focal-length change: that reading is not
    used. In the plane-fit frame stored in that VIC-3D project the flat specimen comes out within
    0.11 mm of Z = 0 (VIC-3D's own points: -0.014..0.020 mm); ``fs`` read as an angle in degrees
    would spread it over 1.8 mm. Whether k1..k3 distort or undistort is not decided by these
    data (< 0.02 px either way, the distorting form fitting slightly better); it follows the
    usual camera model.

    The image size is read from ``<polygonmask width= height=>`` when present. Camera ``0``
    becomes the ``left`` camera and camera ``1`` the ``right`` one, whatever their physical
    placement (in the two real VIC-3D rigs checked, camera 0 sits on the right, at +x).

    Parameters
    ----------
    path : path
        VIC-3D ``cal.xml``, project XML, ``.z3d`` project, or a file holding just the
        ``<calibration>`` element. Tag case does not matter.
    image_size : (width, height), optional
        Image size [pixel], needed when the file has no ``<polygonmask>``.

    Returns
    -------
    StereoCalibration
        Cameras in VIC-3D's world frame (converted to metres).
    """
    path = Path(path)
    root = _vic3d_root(path)
    cal = next((el for el in root.iter("calibration") if el.find(".//camera") is not None), root)
    nodes = list(cal.iter("camera"))
    cams: dict[str, tuple] = {}
    for node in nodes:
        ident = node.attrib.get("id")
        where = f"VIC-3D calibration '{path}', camera {ident}"
        orient = node.find("orientation")
        intr_el, dist_el = node.find("intrinsics"), node.find("distortion")
        intr = _vic3d_numbers(intr_el.text if intr_el is not None else node.text, where)
        if ident is None or orient is None or len(intr) not in (5, 8):
            raise BadInputError(
                f"VIC-3D calibration '{path}': a <camera> element must hold an id, the eight "
                "intrinsic values 'cx cy fx fy fs k1 k2 k3' (or <intrinsics>cx cy fx fy fs"
                "</intrinsics> and <distortion>k1 k2 k3</distortion>) and an <orientation> with "
                f"'alpha beta gamma tx ty tz'; found id={ident!r}, {len(intr)} intrinsic values"
                f"{'' if orient is not None else ', no <orientation>'}"
            )
        kappa = intr[5:8] if len(intr) == 8 else [0.0, 0.0, 0.0]
        if dist_el is not None:
            dist = _vic3d_numbers(dist_el.text, where + " <distortion>")
            if len(dist) > 3:
                raise BadInputError(
                    f"{where}: <distortion> holds {len(dist)} values; jointwear knows VIC-3D's "
                    "radial k1 k2 k3 (r^2, r^4, r^6) only - export the calibration as cal.xml "
                    "(camera values 'cx cy fx fy fs k1 k2 k3'), or recalibrate without the "
                    "extra distortion terms"
                )
            dist = dist + [0.0] * (3 - len(dist))
            if len(intr) == 8 and not np.allclose(dist, kappa):
                raise BadInputError(
                    f"{where}: the distortion {dist} in <distortion> differs from the k1 k2 k3 "
                    f"{kappa} after the intrinsics; the file is inconsistent"
                )
            kappa = dist
        ext = _vic3d_numbers(orient.text, where + " <orientation>")
        if len(ext) != 6:
            raise BadInputError(
                f"{where}: <orientation> must hold 6 values (alpha beta gamma [deg], tx ty tz "
                f"[mm]); found {len(ext)}"
            )
        names = ("cx", "cy", "fx", "fy", "fs", "k1", "k2", "k3", "alpha", "beta", "gamma", "tx",
                 "ty", "tz")  # fmt: skip
        values = [*intr[:5], *kappa, *ext]
        bad = [n for n, v in zip(names, values, strict=True) if not np.isfinite(v)]
        if bad:
            raise BadInputError(
                f"{where}: {', '.join(bad)} not finite (NaN/inf); the calibration in the file is "
                "incomplete - recalibrate or export the calibration again from VIC-3D"
            )
        cx, cy, fx, fy, fs = intr[:5]
        if fx <= 0 or fy <= 0:
            raise BadInputError(f"{where}: focal lengths fx={fx}, fy={fy} must be positive [pixel]")
        if ident in cams:
            raise BadInputError(f"VIC-3D calibration '{path}': camera id {ident!r} appears twice")
        K = np.array([[fx, fs, cx], [0, fy, cy], [0, 0, 1.0]])
        dist = np.array([kappa[0], kappa[1], 0.0, 0.0, kappa[2]])
        cams[ident] = (K, dist, cardan_to_matrix(*ext[:3]), np.array(ext[3:]) * 1e-3)
    if len(cams) != 2:
        raise BadInputError(
            f"VIC-3D calibration '{path}': expected 2 <camera> elements, found {len(cams)}"
            + (f" (ids {', '.join(cams)})" if cams else "")
            + "; export the stereo system's calibration (cal.xml) from VIC-3D"
        )
    size = image_size
    if size is None:
        for node in root.iter("polygonmask"):
            if "width" in node.attrib and "height" in node.attrib:
                size = (node.attrib["width"], node.attrib["height"])
                break
    if size is None:
        raise BadInputError(
            f"VIC-3D calibration '{path}' does not state the image size (no <polygonmask "
            "width= height=>); pass image_size=(width, height) (CLI: --image-size W H)"
        )
    size = _check_image_size(size, f"VIC-3D calibration '{path}'")
    ids = sorted(cams, key=lambda s: (0, int(s)) if s.strip().lstrip("-").isdigit() else (1, s))
    out = []
    for ident, name in zip(ids, ("left", "right"), strict=True):
        K = cams[ident][0]
        where = f"VIC-3D calibration '{path}', camera {ident} ({name})"
        if not (0 <= K[0, 2] <= size[0] and 0 <= K[1, 2] <= size[1]):
            raise BadInputError(
                f"{where}: principal point ({K[0, 2]:.1f}, {K[1, 2]:.1f}) px lies outside the "
                f"{size[0]}x{size[1]} px image; the image size is wrong (pass the size of the "
                "images VIC-3D calibrated with: --image-size W H)"
            )
        cam = Camera(*cams[ident], size)
        _check_lens(cam, where)
        out.append(cam)
    return StereoCalibration(
        out[0],
        out[1],
        source=f"vic3d:{path.name}",
        world_frame="VIC-3D world frame (file in millimetres, here metres)",
    )


def read_calibration(
    path: str | Path, *, allow_rejected: bool = False, allow_unitless: bool = False
) -> StereoCalibration:
    """Load a jointwear calibration file (``.nc``, written by ``jointwear dic calibrate``).

    A calibration that failed its sanity checks (``<out>.rejected.nc``) and one whose lengths
    are in board squares (``--unit square``) cannot measure and are refused unless
    ``allow_rejected`` / ``allow_unitless``.
    """
    from jointwear import io

    path = Path(path)
    if path.suffix.lower() in (".yml", ".yaml") or (
        path.suffix.lower() == ".xml"
        and path.exists()
        and "opencv_storage" in path.read_text(errors="replace")[:400]
    ):
        raise BadInputError(
            f"'{path}' looks like an OpenCV calibration; import it first with "
            "`jointwear dic import-calibration --format opencv --length-unit mm` "
            "(or read_opencv_calibration)"
        )
    if path.suffix.lower() in (".xml", ".z3d"):
        raise BadInputError(
            f"'{path}' looks like a VIC-3D calibration; import it first with "
            "`jointwear dic import-calibration --format vic3d` (or read_vic3d_calibration)"
        )
    ds = io.load(path)
    status = str(ds.attrs.get("calibration_status", "accepted"))
    if status.startswith("rejected") and not allow_rejected:
        raise BadInputError(
            f"'{path}' is a calibration that failed its sanity checks ({status}); it was kept "
            "for inspection only - recalibrate (or, if it is right after all, calibrate again "
            "with --accept-poor)"
        )
    cal = StereoCalibration.from_dataset(ds, what=f"'{path}'")
    if cal.length_unit != "m" and not allow_unitless:
        raise BadInputError(
            f"'{path}' has its lengths in board {cal.length_unit}s (calibrated with --unit "
            f"{cal.length_unit}); measuring needs a metric scale - calibrate with the board's "
            "square size, e.g. --square 25 --unit mm"
        )
    return cal
