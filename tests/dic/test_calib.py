"""Stereo calibration: recovery of the virtual rig's cameras, importers, errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from jointwear.datasets.rig import RigConfig, VirtualRig
from jointwear.dic.calibration._board import CalibrationBoard, board_world_frame, calibrate_stereo
from jointwear.dic.calibration._camera import (
    Camera,
    StereoCalibration,
    cardan_to_matrix,
    matrix_to_cardan,
)
from jointwear.dic.calibration._importers import (
    read_calibration,
    read_opencv_calibration,
    read_vic3d_calibration,
)
from jointwear.errors import BadInputError, CalibrationError


@pytest.fixture(scope="module")
def rig():
    # reduced size: 640 x 512 px over the same 0.42 m field of view
    return VirtualRig(RigConfig(width=640, height=512, board_views=10))


@pytest.fixture(scope="module")
def boards(rig):
    return rig.board_images()


@pytest.fixture(scope="module")
def board(rig):
    c = rig.config
    return CalibrationBoard("chessboard", *c.board_squares, c.board_square_size)


@pytest.fixture(scope="module")
def calibration(boards, board):
    return calibrate_stereo([b[0] for b in boards], [b[1] for b in boards], board)


def test_calibration_recovers_generated_cameras(rig, calibration):
    true = rig.calibration
    for name in ("left", "right"):
        est, ref = calibration.cameras[name], true.cameras[name]
        for fe, ft in zip(est.focal, ref.focal, strict=True):
            assert abs(fe / ft - 1) < 2e-3
        assert np.allclose(est.matrix[:2, 2], ref.matrix[:2, 2], atol=2.0)
    assert abs(calibration.baseline / true.baseline - 1) < 2e-3
    assert calibration.rms < 0.1
    assert np.all(calibration.per_view_rms < 0.1)
    assert calibration.views_used == len(rig.board_poses()) and calibration.views_rejected == 0
    # relative pose: rotation angle error below 0.05 degree
    R_est, _ = calibration.relative_pose
    R_true, _ = true.relative_pose
    angle = np.degrees(np.arccos(np.clip((np.trace(R_est.T @ R_true) - 1) / 2, -1, 1)))
    assert angle < 0.05


def test_world_frame_from_board(rig, calibration, boards, board):
    cal = board_world_frame(calibration, boards[-1][0], board)
    # the world frame is the mechanism frame shifted to the board's first inner corner
    origin = rig.world_board_origin()
    X = np.array([[0.3, 0.2, 0.0], [0.25, 0.05, 0.004]])
    uv_true = rig.calibration.left.project(X)
    uv_est = cal.left.project(X - origin)
    assert np.max(np.abs(uv_true - uv_est)) < 0.5
    assert "board" in cal.world_frame


def test_too_few_views(boards, board):
    with pytest.raises(CalibrationError, match=r"only 3 of 3 calibration view\(s\).*at least 6"):
        calibrate_stereo([b[0] for b in boards[:3]], [b[1] for b in boards[:3]], board)
    blank = np.zeros((48, 64), np.uint8)
    with pytest.raises(
        CalibrationError, match=r"only 0 of 6 .*view 0: board not found \(both cameras\)"
    ):
        calibrate_stereo([blank] * 6, [blank] * 6, board)
    with pytest.raises(BadInputError, match="3 left and 2 right"):
        calibrate_stereo([blank] * 3, [blank] * 2, board)


def test_rejected_views_are_counted_with_their_reason(boards, board):
    blank = np.zeros_like(boards[0][0])
    lefts = [b[0] for b in boards[:7]] + [blank]
    rights = [b[1] for b in boards[:7]] + [boards[7][1]]
    seen: list[tuple[int, int]] = []
    cal = calibrate_stereo(lefts, rights, board, progress=lambda *a: seen.append(a))
    assert seen == [(k, 8) for k in range(1, 9)]  # every view pair reported, rejected one too
    assert cal.views_used == 7 and cal.views_rejected == 1
    assert cal.rejected == ("view 7: board not found (left) by either detector",)


def test_save_and_read_round_trip(tmp_path, calibration):
    path = calibration.save(tmp_path / "cal.nc")
    back = read_calibration(path)
    for name in ("left", "right"):
        a, b = calibration.cameras[name], back.cameras[name]
        assert np.allclose(a.matrix, b.matrix) and np.allclose(a.distortion, b.distortion)
        assert np.allclose(a.rotation, b.rotation) and np.allclose(a.translation, b.translation)
    assert back.rms == pytest.approx(calibration.rms)
    assert back.views_used == calibration.views_used
    assert back.rejected == calibration.rejected


def test_undistortion_inverts_distortion():
    cam = Camera(
        np.array([[2000.0, 1.5, 640], [0, 2001.0, 512], [0, 0, 1]]),
        [-0.2, 0.15, 1e-3, -5e-4, -0.05],
        image_size=(1280, 1024),
    )
    rng = np.random.default_rng(1)
    xy = rng.uniform(-0.3, 0.3, (500, 2))
    uv = cam.normalized_to_pixels(xy)
    assert np.max(np.abs(cam.pixels_to_normalized(uv) - xy)) < 1e-10
    # the rational model (k4..k6) too, and NaN rows stay NaN without disturbing the others
    rational = Camera(
        cam.matrix, [0.3, -0.1, 5e-4, 1e-3, 0.02, 0.2, -0.05, 0.01], image_size=(1280, 1024)
    )
    uv = rational.normalized_to_pixels(xy)
    uv[7] = np.nan
    back = rational.pixels_to_normalized(uv)
    assert np.isnan(back[7]).all()
    assert np.max(np.abs(np.delete(back, 7, 0) - np.delete(xy, 7, 0))) < 1e-10


def test_cardan_round_trip():
    R = cardan_to_matrix(12.0, -7.0, 95.0)
    assert np.allclose(R @ R.T, np.eye(3))
    assert np.allclose(matrix_to_cardan(R), (12.0, -7.0, 95.0))
    # Rz(gamma) alone: x -> y for 90 degrees
    assert np.allclose(cardan_to_matrix(0, 0, 90) @ [1, 0, 0], [0, 1, 0])


def test_opencv_yaml_import(tmp_path, rig):
    import cv2

    true = rig.calibration
    R, T = true.relative_pose
    path = tmp_path / "stereo.yml"
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    fs.write("K1", true.left.matrix)
    fs.write("D1", true.left.distortion[:5].reshape(1, 5))
    fs.write("K2", true.right.matrix)
    fs.write("D2", true.right.distortion[:5].reshape(1, 5))
    fs.write("R", R)
    fs.write("T", T.reshape(3, 1) * 1000.0)  # millimetres
    fs.write("image_width", 640)
    fs.write("image_height", 512)
    fs.release()
    cal = read_opencv_calibration(path, length_unit="mm")
    assert cal.baseline == pytest.approx(true.baseline, rel=1e-12)
    X = np.array([[0.3, 0.2, 0.0]])
    Xl = true.left.world_to_camera(X)
    assert np.allclose(cal.right.project(Xl), true.right.project(X), atol=1e-9)
    assert cal.left.image_size == (640, 512)
    with pytest.raises(BadInputError, match="length_unit 'furlong'"):
        read_opencv_calibration(path, length_unit="furlong")
    bad = tmp_path / "bad.yml"
    fs = cv2.FileStorage(str(bad), cv2.FILE_STORAGE_WRITE)
    fs.write("K1", true.left.matrix)
    fs.release()
    with pytest.raises(BadInputError, match="lacks D1, K2, D2, R, T"):
        read_opencv_calibration(bad, length_unit="mm")


def _vic_xml(cal: StereoCalibration, size=(640, 512)) -> str:
    parts = []
    for i, cam in enumerate((cal.left, cal.right)):
        K, d = cam.matrix, cam.distortion
        a, b, g = matrix_to_cardan(cam.rotation)
        t = cam.translation * 1e3
        intr = [K[0, 2], K[1, 2], K[0, 0], K[1, 1], K[0, 1], d[0], d[1], d[4]]
        parts.append(
            f'  <camera id="{i}">'
            + " ".join(f"{v:.12e}" for v in intr)
            + "<orientation>"
            + " ".join(f"{v:.12e}" for v in (a, b, g, *t))
            + "</orientation>\n  </camera>"
        )
    return (
        '<?xml version="1.0" encoding="ISO-8859-1"?>\n<!DOCTYPE vpml>\n<project>\n'
        '<calibration lri="calibration">\n' + "\n".join(parts) + "\n</calibration>\n"
        f'<projectaois><aoinode><polygonmask width="{size[0]}" height="{size[1]}"/></aoinode>'
        "</projectaois>\n</project>\n"
    )


def test_vic3d_import(tmp_path):
    # a camera pair with skew and no tangential distortion (VIC-3D's model), world frame between
    # the cameras as VIC-3D sets it
    left = Camera(
        np.array([[2468.5, -0.17, 638.9], [0, 2468.2, 407.3], [0, 0, 1]]),
        [-0.17, 0.064, 0, 0, 0.01],
        cardan_to_matrix(179.96, 9.015, 0.0337),
        np.array([-0.06323, -0.000337, 0.0187]),
        (1280, 800),
    )
    right = Camera(
        np.array([[2377.1, 0.09, 628.6], [0, 2376.9, 394.6], [0, 0, 1]]),
        [0.062, 0.0, 0, 0, 0.0],
        cardan_to_matrix(-179.96, -9.015, -0.0397),
        np.array([0.06484, -0.000876, 0.01535]),
        (1280, 800),
    )
    true = StereoCalibration(left, right)
    path = tmp_path / "cal.xml"
    path.write_text(_vic_xml(true, (1280, 800)))
    cal = read_vic3d_calibration(path)
    assert cal.left.image_size == (1280, 800)
    X = np.array([[0.01, 0.02, -0.3], [-0.02, 0.01, -0.28]])
    for name in ("left", "right"):
        assert np.allclose(cal.cameras[name].project(X), true.cameras[name].project(X), atol=1e-6)
    assert cal.baseline == pytest.approx(true.baseline, rel=1e-9)
    path.write_text("<project><calibration><camera id='0'>1 2 3</camera></calibration></project>")
    with pytest.raises(BadInputError, match="eight intrinsic values"):
        read_vic3d_calibration(path)
    with pytest.raises(BadInputError, match="looks like a VIC-3D calibration"):
        read_calibration(path)


def test_import_calibration_cli(tmp_path, rig, capsys):
    from jointwear.cli import main

    path = tmp_path / "cal.xml"
    path.write_text(_vic_xml(rig.calibration, (640, 512)))
    out = tmp_path / "imported.nc"
    assert (
        main(["dic", "import-calibration", str(path), "--format", "vic3d", "--out", str(out)]) == 0
    )
    cal = read_calibration(out)
    X = np.array([[0.3, 0.2, 0.0]])
    assert np.allclose(cal.right.project(X), rig.calibration.right.project(X), atol=1e-6)
    assert cal.source == "vic3d:cal.xml"
    # OpenCV files need the unit of T: exit code 3 and a message saying so
    assert main(["dic", "import-calibration", str(path), "--format", "opencv"]) == 3
    assert "--length-unit is required" in capsys.readouterr().err


# ---- VIC-3D conventions checked against independent data -----------------------------------
# Published reference numbers (facts to test against, not copied code) from Sandia's DICe
# repository (github.com/dicengine/dice):
#  * tests/regression/stereo_d_spec/cal.xml: a real VIC-3D calibration (per camera
#    "cx cy fx fy fs k1 k2 k3" and <orientation>alpha beta gamma tx ty tz</orientation>);
#    The same project's <coordinatetransformation name="GT4OriginXAxis"> is VIC-3D's plane fit
#    to the flat specimen: in that frame VIC-3D's own reference Z spans -0.014..0.020 mm;
#  * tests/regression/stereo_d_spec/gold/DICe_solution_0.txt: DICe's image matches between the
#    two cameras' images, COORDINATE_X/Y in camera 0 and CROSS_CORR_Q/R = disparity (the point
#    is at (x + q, y + r) in camera 1, as VIC-3D's q, r); rows with MATCH 0;
#  * tests/regression/stereo_list/cal.xml (= tests/component/cal/cal_a.xml): a real VIC-3D
#    project; its <startpoint> entries hold VIC-3D's own automatic matches ("ref" guess in
#    StaticB_0001_0.tif, "auto" guess in StaticB_0001_1.tif), its <coordinatetransformation
#    name="OriginYAxis"> and, in <plotdata>, the X/Y/Z [mm] ranges VIC-3D showed for the data.
# The numbers are in data/vic3d_dice_reference.json.
_DICE = json.loads((Path(__file__).parent / "data" / "vic3d_dice_reference.json").read_text())
_DSPEC_CAMERAS = tuple(_DICE["stereo_d_spec"]["cameras"])
_DSPEC_MATCHES = np.array(_DICE["stereo_d_spec"]["matches"])  # x, y (camera 0), q, r [pixel]
_CALA_CAMERAS = tuple(_DICE["cal_a"]["cameras"])
_CALA_MATCHES = np.array(_DICE["cal_a"]["matches"])  # camera 0 (x, y), camera 1 (x, y) [pixel]


def _vic_file(cameras, size=None, root="project") -> str:
    cams = "".join(
        f'  <camera id="{i}">{cameras[2 * i]}<orientation>{cameras[2 * i + 1]}</orientation>\n'
        "  </camera>\n"
        for i in range(2)
    )
    cal = f'<calibration lri="calibration">\n{cams}</calibration>\n'
    mask = (
        f'<projectaois lri="projectaois"><aoinode><polygonmask width="{size[0]}" '
        f'height="{size[1]}" lri="polygonmask"/></aoinode></projectaois>\n'
        if size
        else ""
    )
    head = '<?xml version="1.0" encoding="ISO-8859-1"?>\n<!DOCTYPE vpml>\n'
    if root == "calibration":
        return head + cal
    return head + f'<project dir="C:/Users/x/cal">\n{cal}{mask}</project>\n'


def _reprojection_rms(cal, uv0, uv1):
    from jointwear.dic.calibration._stereo import triangulate

    X, _, rep = triangulate(cal, uv0, uv1)
    return float(np.sqrt(np.mean(rep**2))), X


def test_vic3d_reading_reproduces_dice_stereo_matches(tmp_path):
    # The decisive test: real matches between the two images of a real VIC-3D rig must
    # triangulate (rays meet) with the cameras read from its cal.xml.
    path = tmp_path / "cal.xml"
    path.write_text(_vic_file(_DSPEC_CAMERAS), encoding="latin-1")
    cal = read_vic3d_calibration(path, image_size=(1920, 1200))
    uv0 = _DSPEC_MATCHES[:, :2]
    uv1 = uv0 + _DSPEC_MATCHES[:, 2:]
    rms, X = _reprojection_rms(cal, uv0, uv1)
    assert rms < 0.08  # 0.062 px (0.054 px over all 27 matched rows of the gold file)
    # geometry: 123.2 mm baseline, the specimen ~368 mm in front of the cameras (VIC-3D world
    # z towards the cameras), camera 0 at +x
    assert cal.baseline == pytest.approx(0.12321, abs=5e-5)
    assert np.all((X[:, 2] > -0.370) & (X[:, 2] < -0.365))
    assert cal.left.centre[0] == pytest.approx(0.0607, abs=1e-3)
    assert cal.right.centre[0] == pytest.approx(-0.0625, abs=1e-3)
    # the skew is K[0, 1] in pixels, the distortion OpenCV's (k1, k2, 0, 0, k3)
    assert cal.right.matrix[0, 1] == pytest.approx(0.7051020868)
    assert np.allclose(cal.left.distortion[:5], [-1.957515272e-4, 0.8739544595, 0, 0, -26.91426143])

    # in VIC-3D's plane-fit frame the specimen is flat: |Z| < 0.11 mm here (VIC-3D: -0.014..0.020
    # mm over its own points; the 0.03-0.1 mm difference is 0.2-0.6 px of disparity). Reading fs
    # as a skew angle in degrees instead of pixels tilts the plane by 1.8 mm.
    def plane_z(X):
        R = cardan_to_matrix(-0.420005, 0.636599, 0.0196829)
        return (X * 1e3 @ R.T + [33.3455, -24.7042, 367.299])[:, 2]

    assert np.all(np.abs(plane_z(X)) < 0.15)
    degrees = StereoCalibration(
        *(
            Camera(
                c.matrix
                + [
                    [0, c.matrix[0, 0] * np.tan(np.radians(c.matrix[0, 1])) - c.matrix[0, 1], 0],
                    [0, 0, 0],
                    [0, 0, 0],
                ],
                c.distortion,
                c.rotation,
                c.translation,
                c.image_size,
            )
            for c in cal.cameras.values()
        )
    )
    z_deg = plane_z(_reprojection_rms(degrees, uv0, uv1)[1])
    assert np.ptp(z_deg) > 1.0

    # the same matches refute the other readings: camera-to-world extrinsics, the transposed
    # rotation, and DICe's K1R1_K2R2_K3R3 (displacement k1 r + k2 r^2 + k3 r^3)
    def rebuilt(R_of, t_of):
        cams = [
            Camera(c.matrix, c.distortion, R_of(c), t_of(c), c.image_size)
            for c in cal.cameras.values()
        ]
        return StereoCalibration(*cams)

    inverse = rebuilt(lambda c: c.rotation.T, lambda c: -c.rotation.T @ c.translation)
    transposed = rebuilt(lambda c: c.rotation.T, lambda c: c.translation)
    assert _reprojection_rms(inverse, uv0, uv1)[0] > 3  # 9.0 px
    assert _reprojection_rms(transposed, uv0, uv1)[0] > 3  # 9.7 px

    def undistort_k1r1(cam, uv):
        K, (k1, k2, _, _, k3) = cam.matrix, cam.distortion[:5]
        yd = (uv[:, 1] - K[1, 2]) / K[1, 1]
        xd = (uv[:, 0] - K[0, 2] - K[0, 1] * yd) / K[0, 0]
        x, y = xd.copy(), yd.copy()
        for _ in range(200):
            r = np.hypot(x, y)
            f = 1 + k1 + k2 * r + k3 * r * r
            x, y = xd / f, yd / f
        return np.stack([K[0, 0] * x + K[0, 1] * y + K[0, 2], K[1, 1] * y + K[1, 2]], axis=1)

    pinhole = rebuilt(lambda c: c.rotation, lambda c: c.translation)
    pinhole = StereoCalibration(
        *(
            Camera(c.matrix, np.zeros(5), c.rotation, c.translation, c.image_size)
            for c in pinhole.cameras.values()
        )
    )
    dice = _reprojection_rms(
        pinhole, undistort_k1r1(cal.left, uv0), undistort_k1r1(cal.right, uv1)
    )[0]
    assert dice > 10  # 82 px


def test_vic3d_reading_reproduces_vic3d_start_points(tmp_path):
    path = tmp_path / "cal_a.xml"
    path.write_text(_vic_file(_CALA_CAMERAS, (1280, 800)), encoding="latin-1")
    cal = read_vic3d_calibration(path)
    assert cal.left.image_size == (1280, 800)
    rms, X = _reprojection_rms(cal, _CALA_MATCHES[:, :2], _CALA_MATCHES[:, 2:])
    assert rms < 0.05  # 0.024 px
    # VIC-3D's user frame "OriginYAxis" (angles [deg] as <orientation>, translation [mm]) puts
    # these points inside the X, Y, Z ranges VIC-3D displayed for the project's data
    P = X * 1e3 @ cardan_to_matrix(-10.171, 11.6143, 0.634145).T + [94.6272, 92.5599, 369.084]
    lo, hi = np.array([-14.4737, -32.1463, -22.8467]), np.array([56.0786, 79.9236, 9.28465])
    assert np.all((P > lo) & (P < hi))


def test_vic3d_file_variants(tmp_path):
    ref_path = tmp_path / "cal.xml"
    ref_path.write_text(_vic_file(_CALA_CAMERAS, (1280, 800)))
    ref = read_vic3d_calibration(ref_path)

    def same(cal):
        for name in ("left", "right"):
            a, b = cal.cameras[name], ref.cameras[name]
            assert np.allclose(a.matrix, b.matrix) and np.allclose(a.distortion, b.distortion)
            assert np.allclose(a.rotation, b.rotation) and np.allclose(a.translation, b.translation)
            assert a.image_size == b.image_size

    # upper-case tags and attributes
    upper = tmp_path / "upper.xml"
    text = _vic_file(_CALA_CAMERAS, (1280, 800))
    for tag in ("project", "calibration", "camera", "orientation", "projectaois", "aoinode"):
        text = text.replace(f"<{tag}", f"<{tag.upper()}").replace(f"</{tag}", f"</{tag.upper()}")
    text = text.replace("<polygonmask width", "<POLYGONMASK WIDTH").replace("height=", "HEIGHT=")
    text = text.replace(' id="', ' ID="')
    upper.write_text(text)
    same(read_vic3d_calibration(upper))
    # a file holding only the <calibration> element: image size from the caller
    only = tmp_path / "only.xml"
    only.write_text(_vic_file(_CALA_CAMERAS, root="calibration"))
    with pytest.raises(
        BadInputError, match=r"only.xml' does not state the image size.*--image-size"
    ):
        read_vic3d_calibration(only)
    same(read_vic3d_calibration(only, image_size=(1280, 800)))
    # a .z3d project (zip holding project.xml) in the newer layout with <intrinsics> and
    # <distortion> elements
    import zipfile

    cams = ""
    for i in range(2):
        v = _CALA_CAMERAS[2 * i].split()
        cams += (
            f'<camera id="{i}"><intrinsics>{" ".join(v[:5])}</intrinsics>'
            f"<distortion>{v[5]}</distortion><orientation>{_CALA_CAMERAS[2 * i + 1]}"
            "</orientation></camera>"
        )
    project = (
        f"<project><calibration>{cams}</calibration><projectaois><aoinode>"
        '<polygonmask width="1280" height="800"/></aoinode></projectaois></project>'
    )
    z3d = tmp_path / "test.z3d"
    with zipfile.ZipFile(z3d, "w") as zf:
        zf.writestr("project.xml", project)
    same(read_vic3d_calibration(z3d))
    with pytest.raises(BadInputError, match="looks like a VIC-3D calibration"):
        read_calibration(z3d)


def test_vic3d_bad_files(tmp_path):
    path = tmp_path / "cal.xml"

    def fails(cameras, match, **kw):
        path.write_text(_vic_file(cameras, kw.pop("size", (1280, 800))))
        with pytest.raises(BadInputError, match=match):
            read_vic3d_calibration(path, **kw)

    nan = list(_CALA_CAMERAS)
    nan[2] = nan[2].replace("2.377107751e+03", "nan")
    fails(nan, r"cal.xml', camera 1: fx not finite \(NaN/inf\)")
    short = list(_CALA_CAMERAS)
    short[3] = "1 2 3"
    fails(short, r"camera 1: <orientation> must hold 6 values .* found 3")
    text = list(_CALA_CAMERAS)
    text[0] = text[0].replace("6.389130236e+02", "x638")
    fails(text, r"camera 0: 'x638' is not a number")
    # principal point outside the stated image: wrong image size (e.g. binned images)
    fails(
        _CALA_CAMERAS,
        r"principal point \(638.9, 407.3\) px lies outside the 640x400",
        size=(640, 400),
    )
    # a distortion that folds back inside the image cannot be a real lens
    fold = list(_CALA_CAMERAS)
    fold[0] = fold[0].replace("6.384132162e-02", "-5.0")
    fails(fold, r"camera 0 \(left\): the lens distortion folds back")
    # three cameras, and a <distortion> with terms jointwear does not know
    path.write_text(
        _vic_file(_CALA_CAMERAS).replace(
            "</calibration>",
            f'<camera id="2">{_CALA_CAMERAS[0]}<orientation>'
            f"{_CALA_CAMERAS[1]}</orientation></camera></calibration>",
        )
    )
    with pytest.raises(
        BadInputError, match=r"expected 2 <camera> elements, found 3 \(ids 0, 1, 2\)"
    ):
        read_vic3d_calibration(path, image_size=(1280, 800))
    path.write_text(
        "<calibration><camera id='0'><intrinsics>1 2 3 4 0</intrinsics><distortion>0.1 0 0 0.01"
        " 0.02</distortion><orientation>0 0 0 0 0 0</orientation></camera></calibration>"
    )
    with pytest.raises(BadInputError, match=r"<distortion> holds 5 values"):
        read_vic3d_calibration(path, image_size=(1280, 800))
    path.write_text("<project><calibration><camera id='0'>1 2 3")
    with pytest.raises(BadInputError, match="cal.xml' is not well-formed XML"):
        read_vic3d_calibration(path)
    with pytest.raises(BadInputError, match="does not exist"):
        read_vic3d_calibration(tmp_path / "missing.xml")


# ---- OpenCV files as people have them ---------------------------------------------------------
def _write_fs(path, **entries):
    import cv2

    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    for key, value in entries.items():
        fs.write(key, value)
    fs.release()


def _stereo_calib_files(tmp_path, true, D1=None, R=None):
    """intrinsics.yml and extrinsics.yml as OpenCV's samples/cpp/stereo_calib.cpp writes them
    (T in millimetres here)."""
    import cv2

    Rlr, T = true.relative_pose
    T_mm = T.reshape(3, 1) * 1e3
    d1 = true.left.distortion[:5].reshape(1, 5) if D1 is None else D1
    d2 = true.right.distortion[:5].reshape(1, 5)
    R1, R2, P1, P2, Q, _, _ = cv2.stereoRectify(
        true.left.matrix, d1[:, :5], true.right.matrix, d2, (640, 512), Rlr, T_mm
    )
    intr, extr = tmp_path / "intrinsics.yml", tmp_path / "extrinsics.yml"
    _write_fs(intr, M1=true.left.matrix, D1=d1, M2=true.right.matrix, D2=d2)
    _write_fs(extr, R=Rlr if R is None else R, T=T_mm, R1=R1, R2=R2, P1=P1, P2=P2, Q=Q)
    return intr, extr


def test_opencv_two_files_like_stereo_calib(tmp_path, rig):
    true = rig.calibration
    intr, extr = _stereo_calib_files(tmp_path, true)
    X = np.array([[0.3, 0.2, 0.0], [0.1, 0.35, 0.01]])
    Xl = true.left.world_to_camera(X)
    for cal in (
        read_opencv_calibration([intr, extr], length_unit="mm", image_size=(640, 512)),
        read_opencv_calibration(intr, extrinsics=extr, length_unit="mm", image_size=(640, 512)),
        read_opencv_calibration((extr, intr), length_unit=1e-3, image_size=(640, 512)),
    ):
        assert cal.baseline == pytest.approx(true.baseline, rel=1e-12)
        assert np.allclose(cal.left.project(Xl), true.left.project(X), atol=1e-9)
        assert np.allclose(cal.right.project(Xl), true.right.project(X), atol=1e-9)
        assert cal.source in (
            "opencv:intrinsics.yml+extrinsics.yml",
            "opencv:extrinsics.yml+intrinsics.yml",
        )
    # which file lacks what
    with pytest.raises(BadInputError, match=r"lacks R, T .*'intrinsics.yml' holds M1, D1, M2, D2"):
        read_opencv_calibration(intr, length_unit="mm", image_size=(640, 512))
    with pytest.raises(BadInputError, match=r"lacks K1, D1, K2, D2 .*'extrinsics.yml' holds R, T"):
        read_opencv_calibration(extr, length_unit="mm", image_size=(640, 512))
    # stereo_calib writes no image size
    with pytest.raises(BadInputError, match=r"does not state the image size.*--image-size W H"):
        read_opencv_calibration([intr, extr], length_unit="mm")
    # the same key with two values in two files
    other = tmp_path / "other.yml"
    _write_fs(other, M1=true.left.matrix * 1.01, R=true.relative_pose[0], T=np.ones((3, 1)))
    with pytest.raises(BadInputError, match=r"K1 differs between .*intrinsics.yml' \(M1\) and"):
        read_opencv_calibration([intr, other], length_unit="mm", image_size=(640, 512))


def test_opencv_distortion_lengths_and_rotation_forms(tmp_path, rig):
    import cv2

    true = rig.calibration
    d = true.left.distortion
    X = np.array([[0.3, 0.2, 0.0]])
    for n in (4, 5, 8, 12, 14):
        dn = np.zeros((1, n))
        dn[0, : min(n, 8)] = d[: min(n, 8)]
        sub = tmp_path / f"d{n}"
        sub.mkdir()
        intr, extr = _stereo_calib_files(sub, true, D1=dn)
        cal = read_opencv_calibration([intr, extr], length_unit="mm", image_size=(640, 512))
        ref = d.copy()
        ref[min(n, 8) :] = 0
        assert np.allclose(cal.left.distortion, ref)
    # R as a Rodrigues vector
    rvec = cv2.Rodrigues(true.relative_pose[0])[0]
    intr, extr = _stereo_calib_files(tmp_path, true, R=rvec)
    cal = read_opencv_calibration([intr, extr], length_unit="mm", image_size=(640, 512))
    Xl = true.left.world_to_camera(X)
    assert np.allclose(cal.right.project(Xl), true.right.project(X), atol=1e-6)
    # a hand-written YAML: plain (nested) lists instead of opencv-matrix nodes
    hand = tmp_path / "hand.yml"
    hand.write_text(
        "%YAML:1.0\n---\nK1: [[1000, 0, 320], [0, 1000, 240], [0, 0, 1]]\nD1: [0.1, 0, 0, 0]\n"
        "K2: [[1000, 0, 320], [0, 1000, 240], [0, 0, 1]]\nD2: [0.1, 0, 0, 0, 0]\n"
        "R: [0.0, 0.2, 0.0]\nT: [-100, 0, 10]\nimage_width: 640\nimage_height: 480\n"
    )
    cal = read_opencv_calibration(hand, length_unit="mm")
    assert cal.left.matrix[0, 2] == 320 and cal.left.image_size == (640, 480)
    assert cal.right.rotation == pytest.approx(cv2.Rodrigues(np.array([0.0, 0.2, 0.0]))[0])
    assert cal.baseline == pytest.approx(np.hypot(0.1, 0.01))
    # R rounded when written (7 decimals) is taken as the nearest rotation
    intr, extr = _stereo_calib_files(tmp_path, true, R=np.round(true.relative_pose[0], 7))
    cal = read_opencv_calibration([intr, extr], length_unit="mm", image_size=(640, 512))
    assert np.allclose(cal.right.rotation @ cal.right.rotation.T, np.eye(3), atol=1e-12)
    assert np.allclose(cal.right.project(Xl), true.right.project(X), atol=1e-3)
    # refused: other vector lengths, non-zero thin-prism terms, matrices that are not rotations
    for D1, match in (
        (np.zeros((1, 6)), r"D1: a distortion vector of 6 coefficients; OpenCV writes 4, 5, 8, 12"),
        (np.r_[d, 1e-3, 0, 0, 0].reshape(1, 12), r"non-zero thin-prism/tilt coefficients"),
    ):
        intr, extr = _stereo_calib_files(tmp_path, true, D1=D1)
        with pytest.raises(BadInputError, match=match):
            read_opencv_calibration([intr, extr], length_unit="mm", image_size=(640, 512))
    for R, match in (
        (np.diag([1.0, 1.0, -1.0]), r"extrinsics.yml', R is not a rotation matrix: a reflection"),
        (true.relative_pose[0] * 1.01, r"R is not a rotation matrix: not orthonormal"),
    ):
        intr, extr = _stereo_calib_files(tmp_path, true, R=R)
        with pytest.raises(BadInputError, match=match):
            read_opencv_calibration([intr, extr], length_unit="mm", image_size=(640, 512))


def test_import_calibration_cli_two_opencv_files(tmp_path, rig, capsys):
    from jointwear.cli import main

    true = rig.calibration
    intr, extr = _stereo_calib_files(tmp_path, true)
    out = tmp_path / "imported.nc"
    args = ["--format", "opencv", "--length-unit", "mm", "--image-size", "640", "512", "-o"]
    assert main(["dic", "import-calibration", str(intr), str(extr), *args, str(out)]) == 0
    assert read_calibration(out).baseline == pytest.approx(true.baseline, rel=1e-12)
    out2 = tmp_path / "imported2.nc"
    cmd = ["dic", "import-calibration", str(intr), "--extrinsics", str(extr), *args, str(out2)]
    assert main(cmd) == 0
    assert read_calibration(out2).baseline == pytest.approx(true.baseline, rel=1e-12)
    capsys.readouterr()
    assert main(["dic", "import-calibration", str(intr), *args, str(out2), "--overwrite"]) == 3
    assert "lacks R, T" in capsys.readouterr().err
