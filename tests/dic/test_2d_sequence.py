"""Sequences (absolute / incremental reference), the CLI and the quick-look figure."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear import io
from jointwear.cli import main
from jointwear.datasets import speckle as sp
from jointwear.dic import correlate_sequence, read_frames
from jointwear.errors import BadInputError, ParameterError

CENTRE = (63.5, 63.5)


@pytest.fixture(scope="module")
def sequence():
    # a part turning by 4 degrees per frame and drifting: 20 degrees at the end
    fields = [None] + [sp.RigidField((0.8 * k, -0.4 * k), 4.0 * k, CENTRE) for k in range(1, 6)]
    frames = sp.speckle_sequence((128, 128), fields, seed=5)
    return fields, np.array(frames)


def _truth(fields, ds, k):
    X, Y = np.meshgrid(ds.x.values, ds.y.values)
    if fields[k] is None:
        return np.zeros_like(X), np.zeros_like(Y)
    return fields[k].displacement(X, Y)


@pytest.mark.parametrize(
    ("mode", "options", "references"),
    [
        ("absolute", {}, [0, 0, 0, 0, 0, 0]),
        ("incremental", {"update_every": 2}, [0, 0, 0, 2, 2, 4]),
        # a ZNCC threshold of 1 is never met: the reference follows every frame
        ("incremental", {"update_zncc": 1.0}, [0, 0, 1, 2, 3, 4]),
    ],
)
def test_sequence_accumulates_the_true_displacement(sequence, mode, options, references):
    fields, frames = sequence
    ds = correlate_sequence(
        frames,
        reference=mode,
        roi=(24, 24, 103, 103),
        subset_size=21,
        step=10,
        frame_rate=50.0,
        **options,
    )
    assert ds.u.dims == ("time", "y", "x")
    np.testing.assert_allclose(ds.time.values, np.arange(6) / 50.0)
    assert ds.reference_frame.values.tolist() == references
    for k in range(6):
        tu, tv = _truth(fields, ds, k)
        ok = ds.flag.values[k] == 0
        assert ok.mean() > 0.9, (mode, k)
        assert np.max(np.abs(ds.u.values[k][ok] - tu[ok])) < 0.02
        assert np.max(np.abs(ds.v.values[k][ok] - tv[ok])) < 0.02
    # accumulated gradients: a 20 degree rotation at the end
    th = np.radians(20.0)
    assert abs(np.nanmedian(ds.du_dy.values[-1]) + np.sin(th)) < 2e-3
    assert abs(np.nanmedian(ds.du_dx.values[-1]) - (np.cos(th) - 1)) < 2e-3


def test_sequence_input_errors(sequence, tmp_path):
    _, frames = sequence
    with pytest.raises(ParameterError, match="reference='relative'"):
        correlate_sequence(frames, reference="relative")
    with pytest.raises(BadInputError, match="need at least 2 frames"):
        correlate_sequence(frames[:1])
    with pytest.raises(BadInputError, match="frame 2: size"):
        correlate_sequence([frames[0], frames[1], frames[2][:, :100]])
    with pytest.raises(BadInputError, match="holds no images"):
        read_frames(tmp_path)


def _speckle_cli(folder, size: str, *options: str) -> int:
    """Exit code of ``jointwear datasets speckle`` writing synthetic images to ``folder``."""
    return main(["datasets", "speckle", str(folder), "--size", size, *options])


def test_cli_pair_writes_field_and_figure(tmp_path):
    data = tmp_path / "speckle"
    assert _speckle_cli(data, "112x96", "--u", "1.25", "--v", "-0.5", "--seed", "3") == 0
    truth = io.load(data / "truth.nc")
    out = tmp_path / "field.nc"
    fig = tmp_path / "field.png"
    code = main(
        [
            "dic",
            "correlate",
            str(data / "reference.png"),
            str(data / "deformed.png"),
            "--subset",
            "21",
            "--step",
            "8",
            "--out",
            str(out),
            "--plot",
            str(fig),
        ]
    )
    assert code == 0
    ds = io.load(out)
    ok = ds.flag.values == 0
    assert ok.mean() > 0.9
    tu = truth.u.sel(x=ds.x, y=ds.y).values
    assert np.max(np.abs(ds.u.values[ok] - tu[ok])) < 0.01
    assert fig.stat().st_size > 10_000 and fig.read_bytes()[:4] == b"\x89PNG"
    # bad input -> exit code 3 and a message, no traceback
    assert (
        main(
            [
                "dic",
                "correlate",
                str(data / "reference.png"),
                str(tmp_path / "nope.png"),
                "--out",
                str(out),
            ]
        )
        == 3
    )


def test_cli_folder_sequence(tmp_path):
    data = tmp_path / "frames"
    assert _speckle_cli(data, "96x96", "--frames", "3", "--u", "0.9", "--v", "0.3") == 0
    out = tmp_path / "seq.nc"
    assert (
        main(
            [
                "dic",
                "correlate",
                str(data),
                "--subset",
                "21",
                "--step",
                "12",
                "--frame-rate",
                "50",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    ds = io.load(out)
    assert ds.sizes["time"] == 4
    truth = io.load(data / "truth.nc")
    last = truth.u.isel(time=-1).sel(x=ds.x, y=ds.y).values
    ok = ds.flag.values[-1] == 0
    assert ok.mean() > 0.9
    assert np.max(np.abs(ds.u.values[-1][ok] - last[ok])) < 0.01


def test_video_frames_are_read_as_grey_with_their_frame_rate(tmp_path, sequence):
    import cv2

    _, frames = sequence
    path = tmp_path / "clip.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25.0, (128, 128))
    if not writer.isOpened():
        pytest.skip("this OpenCV build cannot write MJPG video")
    for f in frames[:3]:
        writer.write(cv2.cvtColor(f, cv2.COLOR_GRAY2BGR))
    writer.release()
    got, fps = read_frames(path)
    assert len(got) == 3 and got[0].shape == (128, 128) and got[0].ndim == 2
    assert fps == pytest.approx(25.0)
    # lossy (JPEG) frames still correlate: the first drift step of 0.8 px, -0.4 px, 4 degrees
    ds = correlate_sequence(path, roi=(24, 24, 103, 103), subset_size=21, step=20)
    np.testing.assert_allclose(ds.time.values, [0.0, 0.04, 0.08])
    assert (ds.flag.values[1] == 0).mean() > 0.8
    empty = tmp_path / "empty.mp4"
    empty.write_bytes(b"")
    with pytest.raises(BadInputError, match="could not be opened"):
        read_frames(empty)


def test_quicklook_for_points_and_sequences(sequence, tmp_path):
    from jointwear.dic import correlate, plot_displacement, save_quicklook

    fields, frames = sequence
    pts = np.array([[40.0, 40.0], [64.0, 64.0], [90.0, 50.0], [2.0, 2.0]])
    ds = correlate(frames[0], frames[1], points=pts, subset_size=21)
    assert ds.flag.values[-1] == 3  # too close to the corner: flagged, still plotted
    fig = plot_displacement(ds, title="points")
    axes = fig.axes[:2]
    assert [a.get_title() for a in axes] == ["u (x right, y down)", "v (x right, y down)"]
    legend = axes[0].get_legend()
    assert legend is not None and "invalid (1)" in legend.get_texts()[0].get_text()
    assert "3/4 points ok" in fig._suptitle.get_text()
    seq = correlate_sequence(frames[:3], roi=(24, 24, 103, 103), subset_size=21, step=16)
    path = save_quicklook(seq, tmp_path / "seq.png", time=-1)
    assert path.read_bytes()[:4] == b"\x89PNG"


def test_cli_rejects_a_malformed_roi(tmp_path, capsys):
    data = tmp_path / "s"
    assert main(["datasets", "speckle", str(data), "--size", "64x64"]) == 0
    code = main(
        [
            "dic",
            "correlate",
            str(data / "reference.png"),
            str(data / "deformed.png"),
            "--roi",
            "1,2,3",
            "--out",
            str(tmp_path / "f.nc"),
        ]
    )
    assert code == 3


def test_jumps_larger_than_the_search_window_are_followed_from_frame_to_frame():
    # 30 px per frame: frame 2 lies 60 px away, beyond the 48 px search radius around the
    # reference position; the search is re-centred on the previous frame's motion
    fields = [None, sp.RigidField((30.0, 2.0)), sp.RigidField((60.0, 4.0))]
    frames = sp.speckle_sequence((96, 200), fields, seed=12)
    ds = correlate_sequence(frames, roi=(4, 4, 110, 91), subset_size=21, step=12)
    ok = ds.flag.values[2] == 0
    assert ok.mean() > 0.6
    np.testing.assert_allclose(ds.u.values[2][ok], 60.0, atol=0.01)
    np.testing.assert_allclose(ds.v.values[2][ok], 4.0, atol=0.01)
