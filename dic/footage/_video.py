"""Reading footage: video files (OpenCV's FFmpeg) and image sequences, frame times, checks."""

from __future__ import annotations

import queue
import re
import threading
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from jointwear.errors import BadInputError
from jointwear.filenames import GLOB_CHARS as _GLOB_CHARS
from jointwear.filenames import natural_key as _natural_key

__all__ = [
    "FrameSource",
    "open_frames",
    "check_stereo_pair",
    "is_image_sequence",
    "list_image_sequence",
    "prefetch",
    "IMAGE_SUFFIXES",
    "VIDEO_SUFFIXES",
]

#: codec pixel formats that are already grey (decoded without a colour conversion)
_GREY_PIXEL_FORMATS = ("Y800", "GREY", "Y8  ")

IMAGE_SUFFIXES = (".png", ".tif", ".tiff", ".bmp", ".jpg", ".jpeg", ".pgm", ".ppm")
VIDEO_SUFFIXES = (".avi", ".mp4", ".mkv", ".mov", ".m4v", ".mpg", ".mpeg", ".wmv", ".webm")
#: high-speed camera recording formats users meet (not readable by OpenCV)
_CAMERA_RAW_FORMATS = {
    ".cine": "Phantom (Vision Research)",
    ".mraw": "Photron",
    ".cih": "Photron",
    ".cihx": "Photron",
    ".seq": "NorPix StreamPix",
    ".raw": "a camera",
    ".tdms": "NI LabVIEW",
    ".dng": "a raw-photo",
    ".nef": "a raw-photo",
    ".cr2": "a raw-photo",
}
_ADVICE = (
    "convert it to a format OpenCV's bundled FFmpeg reads, losslessly if possible, e.g. "
    "`ffmpeg -i IN -c:v ffv1 OUT.avi` (lossless) or export an image sequence (`ffmpeg -i IN "
    "frames/frame_%06d.png`), and pass that instead"
)


def _fourcc_name(code: float) -> str:
    c = int(code)
    s = "".join(chr((c >> (8 * i)) & 0xFF) for i in range(4))
    return s if s.isprintable() and s.strip() else f"0x{c:08x}"


@dataclass
class FrameSource:
    """A camera's footage: a video file, numbered images or a multi-page TIFF.

    Attributes
    ----------
    path : Path
    kind : {"video", "images", "stack"}
    fps : float
        Nominal frame rate [1/s].
    size : (width, height)
        Frame size [pixel].
    n_frames : int
        Number of frames (for videos: as the container states it; may be approximate).
    frame_numbers : array or None
        Image sequences: the number in each file name (gaps = dropped frames).
    codec : str
        Video codec FourCC (videos).
    """

    path: Path
    kind: str
    fps: float
    size: tuple[int, int]
    n_frames: int
    files: list[Path] = field(default_factory=list)
    frame_numbers: np.ndarray | None = None
    codec: str = ""

    def nominal_times(self) -> np.ndarray:
        """Frame times [s]: file numbers / fps for images, index / fps for videos."""
        if self.frame_numbers is not None:
            return (self.frame_numbers - self.frame_numbers[0]) / self.fps
        return np.arange(self.n_frames) / self.fps

    def frames(
        self, start: int = 0, stop: int | None = None, *, native: bool = False
    ) -> Iterator[tuple[int, float, np.ndarray]]:
        """Yield ``(index, time [s], grey float32 image)`` for frames ``start <= index < stop``.

        ``native=True`` yields the grey frames in their stored type (uint8, uint16, ...)
        instead of float32: a caller that crops regions first saves converting whole frames.
        Video times come from the container's presentation timestamps when available.
        Unreadable frames raise :class:`~jointwear.errors.BadInputError` naming the frame.
        """
        import cv2

        stop = self.n_frames if stop is None else min(stop, self.n_frames)
        if self.kind == "images":
            times = self.nominal_times()
            for i in range(start, stop):
                img = cv2.imread(str(self.files[i]), cv2.IMREAD_UNCHANGED)
                if img is None:
                    raise BadInputError(
                        f"image '{self.files[i]}' (frame {i}) could not be read; replace or "
                        "remove the file"
                    )
                self._check_size(img, f"image '{self.files[i]}' (frame {i})")
                yield i, float(times[i]), _to_gray(img, native)
            return
        if self.kind == "stack":
            times = self.nominal_times()
            for first in range(start, stop, _STACK_BATCH):
                count = min(_STACK_BATCH, stop - first)
                ok, pages = cv2.imreadmulti(
                    str(self.path), start=first, count=count, flags=cv2.IMREAD_UNCHANGED
                )
                if not ok or len(pages) != count:
                    got = len(pages) if ok else 0
                    raise BadInputError(
                        f"TIFF stack '{self.path}': page {first + got} of {self.n_frames} could "
                        "not be read (truncated or damaged file); re-export the stack or "
                        "process the pages before it"
                    )
                for k, img in enumerate(pages):
                    i = first + k
                    self._check_size(img, f"TIFF stack '{self.path}' page {i}")
                    yield i, float(times[i]), _to_gray(img, native)
            return
        cap = cv2.VideoCapture(str(self.path))
        try:
            pix = _fourcc_name(cap.get(cv2.CAP_PROP_CODEC_PIXEL_FORMAT))
            if pix in _GREY_PIXEL_FORMATS:
                # a grey stream: take the decoded plane as is (no grey -> BGR -> grey)
                cap.set(cv2.CAP_PROP_CONVERT_RGB, 0)
            if start:
                cap.set(cv2.CAP_PROP_POS_FRAMES, start)
            i = start
            while i < stop:
                ok, img = cap.read()
                if not ok:
                    if i < stop and self.n_frames and i < self.n_frames - 1:
                        raise BadInputError(
                            f"video '{self.path}': frame {i} of {self.n_frames} could not be "
                            f"decoded (codec {self.codec}); the file may be truncated - "
                            "re-export it or process the frames before it"
                        )
                    self.n_frames = i
                    return
                pts = cap.get(cv2.CAP_PROP_POS_MSEC) / 1000.0
                t = pts if pts > 0 or i == 0 else i / self.fps
                yield i, float(t), _to_gray(img, native)
                i += 1
        finally:
            cap.release()

    def _check_size(self, img: np.ndarray, name: str) -> None:
        if (img.shape[1], img.shape[0]) != tuple(self.size):
            raise BadInputError(
                f"{name} is {img.shape[1]} x {img.shape[0]} px but the sequence started with "
                f"{self.size[0]} x {self.size[1]} px; every frame of a camera must have the "
                "same size"
            )


#: pages of a multi-page TIFF read per call (each call seeks from the file's first page)
_STACK_BATCH = 64


def _open_tiff_stack(path: Path, fps: float | None, what: str) -> FrameSource:
    """A multi-page TIFF (one page per frame, as high-speed camera software exports them)."""
    import cv2

    try:
        n = int(cv2.imcount(str(path), cv2.IMREAD_UNCHANGED))
        ok, pages = cv2.imreadmulti(str(path), start=0, count=1, flags=cv2.IMREAD_UNCHANGED)
    except cv2.error:
        n, ok, pages = 0, False, []
    if n < 1 or not ok or not pages:
        raise BadInputError(
            f"{what} '{path}' could not be read as a TIFF (one image, or one page per frame); "
            "check that the file is complete, or export the footage as numbered images"
        )
    if n == 1:
        raise BadInputError(
            f"{what} '{path}' is a single image; give a video, a multi-page TIFF, a folder of "
            "numbered images or a pattern such as 'folder/*_0.tif'"
        )
    if fps is None or not fps > 0:
        raise BadInputError(
            f"{what} '{path}' is a multi-page TIFF ({n} pages): give the frame rate (fps=..., "
            "CLI --fps)"
        )
    first = pages[0]
    return FrameSource(path, "stack", float(fps), (first.shape[1], first.shape[0]), n, codec="TIFF")


def _to_gray(img: np.ndarray, native: bool = False) -> np.ndarray:
    import cv2

    if img.ndim == 3:
        if img.shape[2] == 1:
            img = img[:, :, 0]
        else:
            if img.shape[2] == 4:
                img = img[:, :, :3]
            img = cv2.cvtColor(np.ascontiguousarray(img), cv2.COLOR_BGR2GRAY)
    return img if native else img.astype(np.float32)


class _Failure:
    def __init__(self, exc: BaseException) -> None:
        self.exc = exc


_DONE = object()


def prefetch(items: Iterable, depth: int = 3) -> Iterator:
    """Iterate ``items`` (e.g. decoded frames) in a background thread, ``depth`` ahead.

    Decoding then overlaps the caller's work (OpenCV releases the GIL while it decodes). An
    exception raised while producing an item is raised here, at that item; closing this
    iterator early stops the thread.
    """
    q: queue.Queue = queue.Queue(maxsize=max(int(depth), 1))
    stop = threading.Event()

    def put(item) -> bool:
        while not stop.is_set():
            try:
                q.put(item, timeout=0.1)
                return True
            except queue.Full:
                continue
        return False

    def work() -> None:
        it = iter(items)
        try:
            for item in it:
                if not put(item):
                    break
        except BaseException as exc:  # handed to the consumer
            put(_Failure(exc))
        finally:
            close = getattr(it, "close", None)
            if close is not None:
                close()
            put(_DONE)

    thread = threading.Thread(target=work, name="jointwear-prefetch", daemon=True)
    thread.start()
    try:
        while True:
            item = q.get()
            if item is _DONE:
                return
            if isinstance(item, _Failure):
                raise item.exc
            yield item
    finally:
        stop.set()
        thread.join(timeout=5.0)


def is_image_sequence(path: str | Path) -> bool:
    """Whether ``path`` names an image sequence: a folder, or a glob pattern (``"images/*_0.tif"``)
    that is not itself an existing file's name."""
    p = Path(path)
    return p.is_dir() or (not p.exists() and _GLOB_CHARS.search(p.name) is not None)


def _frame_numbers(files: list[Path]) -> tuple[np.ndarray | None, str]:
    """The frame counter in the file names, and a note on other numbers that vary.

    Names are split into their digit groups. When every name has the same number of groups, the
    counter is the group that takes the most distinct values (a camera index such as VIC-3D's
    ``name_0001_0.tif`` / ``name_0001_1.tif`` takes few); otherwise the last group. ``None``
    when the names carry no usable numbers (then the files are numbered in sorted order).
    """
    groups = [re.findall(r"\d+", p.stem) for p in files]
    if not all(groups):
        return None, ""
    n = {len(g) for g in groups}
    if len(n) == 1 and len(files) > 1:
        cols = np.array([[int(v) for v in g] for g in groups])
        distinct = [len(np.unique(cols[:, j])) for j in range(cols.shape[1])]
        best = max(range(len(distinct)), key=lambda j: (distinct[j], j))
        others = [
            f"digit group {j + 1} takes {distinct[j]} values"
            for j in range(len(distinct))
            if j != best and 1 < distinct[j]
        ]
        return cols[:, best], "; ".join(others)
    return np.array([int(g[-1]) for g in groups]), ""


def _name_template(p: Path) -> str:
    """A file name with its digit groups replaced by ``#`` (``frame_0012.png`` -> ``frame_#.png``)."""
    return re.sub(r"\d+", "#", p.stem) + p.suffix.lower()


def _pattern_of(files: list[Path]) -> str:
    """A glob pattern selecting ``files`` (named alike): digit groups that vary become ``*``."""
    groups = [re.findall(r"\d+", f.stem) for f in files]
    parts = re.split(r"\d+", files[0].stem)
    out = parts[0]
    for j, rest in enumerate(parts[1:]):
        values = {g[j] for g in groups if len(g) > j}
        out += (values.pop() if len(values) == 1 else "*") + rest
    return str(files[0].parent / (out + files[0].suffix))


def check_frame_names(files: list[Path], where: str) -> None:
    """Refuse images that are not all named alike (one name with a frame number).

    A mask (``roi.tif``) or a stray image left in a folder of frames would otherwise be
    correlated as one more frame, every point failing, the command still exiting 0; a
    reference named unlike its frames (``Sample3 Reference.tif`` beside ``Sample3-1.tif``)
    would be ordered by the digits of its name, among the frames.
    """
    groups: dict[str, list[Path]] = {}
    for f in files:
        groups.setdefault(_name_template(f), []).append(f)
    if len(groups) <= 1:
        return
    ranked = sorted(groups.items(), key=lambda kv: -len(kv[1]))
    main_t, main_files = ranked[0]
    odd = [f.name for _, fs in ranked[1:] for f in fs]
    shown = ", ".join(f"'{n}'" for n in odd[:5]) + (" ..." if len(odd) > 5 else "")
    pattern = _pattern_of(main_files)
    hint = (
        f"; if '{odd[0]}' is the reference image, give it first and the frames after it: "
        f"'{ranked[1][1][0]}' '{pattern}'"
        if len(odd) == 1
        else ""
    )
    raise BadInputError(
        f"{where} holds {len(main_files)} images named like '{main_t}' (# = frame number) and "
        f"{len(odd)} other image(s): {shown}. Which are the frames is ambiguous: give a pattern "
        f"that selects them, e.g. '{pattern}', or move the other files out of the folder{hint}"
    )


def list_image_sequence(
    path: str | Path, *, what: str = "footage"
) -> tuple[list[Path], np.ndarray]:
    """Image files of one camera's sequence, in frame order, with their frame numbers.

    Parameters
    ----------
    path : path or str
        A folder of images (png, tif, bmp, jpg, pgm), or a glob pattern selecting one camera's
        images in a folder that holds several (``"images/*_0.tif"``, as VIC-3D names them).
    what : str
        Name used in messages.

    Returns
    -------
    files : list of Path
        Sorted by frame number (by name when the names carry no number).
    numbers : ndarray of int
        The frame counter read from the names (gaps = dropped frames), or 0, 1, 2, ... when the
        names carry no number.
    """
    path_str = str(path)
    p = Path(path_str)
    if p.is_dir():
        files = [q for q in p.iterdir() if q.suffix.lower() in IMAGE_SUFFIXES and q.is_file()]
        where = f"folder '{p}'"
    elif _GLOB_CHARS.search(p.name) and p.parent.is_dir():
        files = [q for q in p.parent.glob(p.name) if q.is_file()]
        where = f"pattern '{path_str}'"
        non_images = [q for q in files if q.suffix.lower() not in IMAGE_SUFFIXES]
        if non_images:
            raise BadInputError(
                f"{what} {where} matches {len(non_images)} file(s) that are not images "
                f"(e.g. '{non_images[0].name}'); narrow the pattern to "
                f"{', '.join(IMAGE_SUFFIXES)} files"
            )
    else:
        raise BadInputError(f"{what} '{path_str}' does not exist")
    if not files:
        raise BadInputError(f"{what} {where} holds no images ({', '.join(IMAGE_SUFFIXES)})")
    check_frame_names(files, f"{what} {where}")
    files.sort(key=_natural_key)
    numbers, note = _frame_numbers(files)
    if numbers is None:
        return files, np.arange(len(files))
    order = np.argsort(numbers, kind="stable")
    files = [files[i] for i in order]
    numbers = numbers[order]
    dup = np.flatnonzero(np.diff(numbers) == 0)
    if dup.size:
        k = int(dup[0])
        hint = f" ({note})" if note else ""
        raise BadInputError(
            f"{what} {where} holds {len(files)} images but only {len(np.unique(numbers))} "
            f"distinct frame numbers: '{files[k].name}' and '{files[k + 1].name}' both read as "
            f"frame {numbers[k]}{hint}. If the folder holds several cameras' images (e.g. "
            "'name_0001_0.tif' and 'name_0001_1.tif'), select one camera with a pattern such "
            "as 'folder/*_0.tif'; otherwise remove the duplicate files"
        )
    return files, numbers


def open_frames(
    path: str | Path, *, fps: float | None = None, what: str = "footage"
) -> FrameSource:
    """Open a camera's footage: a video file, an image sequence or a multi-page TIFF.

    Parameters
    ----------
    path : path or str
        Video file (mp4, avi, mkv, ...); folder of images (png, tif, bmp, jpg, pgm) named with
        a frame number (``frame_000123.png``; gaps in the numbering are dropped frames); a glob
        pattern selecting one camera's images in a shared folder (``"images/*_0.tif"``); or a
        multi-page TIFF with one page per frame. See :func:`list_image_sequence` for how the
        frame number is found in the names.
    fps : float, optional
        Frame rate [1/s]. Required for image sequences; for videos it overrides the
        container's rate.
    what : str
        Name used in messages (``"left footage"``).
    """
    import cv2

    path_str = str(path)
    path = Path(path)
    if is_image_sequence(path_str):
        files, numbers = list_image_sequence(path_str, what=what)
        if fps is None or not fps > 0:
            raise BadInputError(
                f"{what} '{path_str}' is an image sequence: give the frame rate (fps=..., CLI "
                "--fps)"
            )
        first = cv2.imread(str(files[0]), cv2.IMREAD_UNCHANGED)
        if first is None:
            raise BadInputError(
                f"image '{files[0]}' could not be read by OpenCV; replace or remove the file"
            )
        return FrameSource(
            path,
            "images",
            float(fps),
            (first.shape[1], first.shape[0]),
            len(files),
            files=files,
            frame_numbers=numbers,
        )
    if not path.exists():
        raise BadInputError(f"{what} '{path}' does not exist")
    if path.suffix.lower() in (".tif", ".tiff"):
        return _open_tiff_stack(path, fps, what)
    suffix = path.suffix.lower()
    if suffix not in VIDEO_SUFFIXES:
        camera = _CAMERA_RAW_FORMATS.get(suffix)
        hint = (
            f"'{suffix}' is {camera}'s own format, which OpenCV cannot read: export the "
            "recording from the camera software as a numbered 8/16-bit TIFF sequence (or a "
            "multi-page TIFF) and pass that; "
            if camera
            else ""
        )
        raise BadInputError(
            f"{what} '{path}': unsupported file type '{suffix}'; {hint}give a video "
            f"({', '.join(VIDEO_SUFFIXES)}), a multi-page TIFF, a folder of images "
            f"({', '.join(IMAGE_SUFFIXES)}) or a pattern such as 'folder/*_0.tif'"
        )
    cap = cv2.VideoCapture(str(path), cv2.CAP_FFMPEG)
    try:
        if not cap.isOpened():
            raise BadInputError(
                f"{what} '{path}': OpenCV's FFmpeg could not open this '{suffix[1:]}' container "
                f"(unreadable, truncated or an unsupported container); {_ADVICE}"
            )
        codec = _fourcc_name(cap.get(cv2.CAP_PROP_FOURCC))
        ok, img = cap.read()
        if not ok or img is None:
            raise BadInputError(
                f"{what} '{path}': the '{suffix[1:]}' container opened but its video stream "
                f"(codec '{codec}') could not be decoded by OpenCV's bundled FFmpeg (a codec it "
                f"lacks, or a damaged/truncated file); {_ADVICE}"
            )
        n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
        rate = float(cap.get(cv2.CAP_PROP_FPS))
    finally:
        cap.release()
    if fps is None:
        if not rate > 0:
            raise BadInputError(
                f"{what} '{path}' does not state its frame rate; give it (fps=..., CLI --fps)"
            )
        fps = rate
    return FrameSource(
        path, "video", float(fps), (img.shape[1], img.shape[0]), max(n, 1), codec=codec
    )


def check_stereo_pair(left: FrameSource, right: FrameSource) -> None:
    """Refuse left/right footage of different lengths, rates, sizes or frame numbering."""
    problems = []
    if abs(left.fps - right.fps) > 1e-6 * left.fps:
        problems.append(f"frame rates differ ({left.fps:g} vs {right.fps:g} frames/s)")
    if left.n_frames != right.n_frames:
        problems.append(f"lengths differ ({left.n_frames} vs {right.n_frames} frames)")
    elif (
        left.frame_numbers is not None
        and right.frame_numbers is not None
        and not np.array_equal(left.frame_numbers, right.frame_numbers)
    ):
        bad = np.flatnonzero(left.frame_numbers != right.frame_numbers)[0]
        problems.append(
            f"frame numbering differs from position {bad} (left {left.frame_numbers[bad]}, "
            f"right {right.frame_numbers[bad]})"
        )
    if left.size != right.size:
        problems.append(f"frame sizes differ ({left.size} vs {right.size})")
    if problems:
        raise BadInputError(
            f"left footage '{left.path}' and right footage '{right.path}' do not form a "
            f"synchronised stereo pair: {'; '.join(problems)}. Trim both recordings to the same "
            "synchronised frames (same start, rate and count) before tracking"
        )
