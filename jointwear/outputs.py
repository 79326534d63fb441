"""Output files that cannot clobber each other or be lost silently.

Every file jointwear writes goes through :func:`jointwear.io.atomic_path`, which uses this
module to

- hold an advisory lock (the ``filelock`` package) on the output while it is written: the lock
  file ``.<name>.lock`` sits next to the output and records the owner (process id, host, start
  time, command line), so a second writer refuses with a message naming the first one;
- remove the hidden temporary files ``.<name>.<random>.tmp`` a killed writer left behind (they
  are stale when nobody holds the lock);
- turn a failed write (full disk, permission, read-only file system, the netCDF library's
  ``HDF error``) into an :class:`OutputError` naming the file, with the free space left.

The CLI claims its outputs for the whole command (:func:`claim`), so two runs given the same
``--out`` cannot both report success, and refuses an existing output unless ``--overwrite``
(or ``--resume``, for the commands that continue a partial result) is given.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import re
import shutil
import socket
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from jointwear.errors import JointwearError

__all__ = [
    "OutputError",
    "OutputBusyError",
    "OutputExistsError",
    "lock_path",
    "lock_owner",
    "output_lock",
    "stale_temporaries",
    "remove_stale_temporaries",
    "refuse_existing",
    "claim",
    "check_location",
    "write_failure",
    "is_write_failure",
    "describe_free_space",
    "write_image",
]


class OutputError(JointwearError):
    """An output cannot be written (full disk, permission, read-only, held by another run)."""


class OutputBusyError(OutputError):
    """Another process is writing the same output."""


class OutputExistsError(OutputError):
    """The output exists and neither ``--overwrite`` nor ``--resume`` was given."""


# tempfile.mkstemp names: prefix + 8 characters of this alphabet + suffix
_RANDOM = r"[a-z0-9_]{8}"
_TEMP_SUFFIXES = (".tmp", ".check")


def lock_path(path: str | Path) -> Path:
    """The lock file of an output: ``.<name>.lock`` in the same folder."""
    path = Path(path)
    return path.with_name(f".{path.name}.lock")


def _owner_record() -> dict[str, object]:
    return {
        "pid": os.getpid(),
        "host": socket.gethostname(),
        "started": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "command": " ".join(["jointwear", *sys.argv[1:]])
        if Path(sys.argv[0]).name in ("jointwear", "__main__.py")
        else " ".join(sys.argv),
    }


def lock_owner(path: str | Path) -> dict[str, object] | None:
    """The owner record of the lock of output ``path`` (None if absent or unreadable)."""
    try:
        text = lock_path(path).read_text(encoding="utf-8")
        record = json.loads(text)
    except (OSError, ValueError):
        return None
    return record if isinstance(record, dict) else None


def _describe_owner(record: dict[str, object] | None) -> str:
    if not record:
        return "another process (owner not recorded yet)"
    where = f"process {record.get('pid', '?')} on {record.get('host', '?')}"
    since = f", started {record['started']}" if record.get("started") else ""
    cmd = f": {record['command']}" if record.get("command") else ""
    return f"{where}{since}{cmd}"


def _file_lock(path: Path):
    from filelock import FileLock

    # one instance per path and process (is_singleton), re-entrant across threads: a command
    # that holds the lock of its --out can save to it again through jointwear.io.save
    return FileLock(lock_path(path), thread_local=False, is_singleton=True)


@contextlib.contextmanager
def output_lock(path: str | Path, *, what: str = "output") -> Iterator[Path]:
    """Hold the advisory lock of output ``path`` for the duration of the block.

    Re-entrant within a process. Raises :class:`OutputBusyError` naming the other writer when
    another process holds it (no waiting: two runs writing one file is a mistake to report,
    not to serialise).
    """
    from filelock import Timeout

    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        lock = _file_lock(path)
        first = not lock.is_locked
        lock.acquire(blocking=False)
    except Timeout:
        raise OutputBusyError(
            f"{what} '{path}' is being written by {_describe_owner(lock_owner(path))}; wait for "
            f"it to finish or choose another output (lock file {lock_path(path)})"
        ) from None
    except OSError as exc:
        raise write_failure(exc, lock_path(path), what=f"lock file of {what} '{path}'") from None
    try:
        if first:
            with contextlib.suppress(OSError):  # the record is informative only
                lock_path(path).write_text(json.dumps(_owner_record()), encoding="utf-8")
        yield path
    finally:
        if first:
            # the outermost holder removes the lock file (filelock re-checks the link count of
            # what it locked, so a contender that opened the old file retries on a new one)
            with contextlib.suppress(OSError):
                lock_path(path).unlink()
        lock.release()


def stale_temporaries(path: str | Path) -> list[Path]:
    """Hidden temporary files of output ``path`` (``.<name>.<random>.tmp`` / ``.check``).

    They are stale when nobody holds the lock of ``path``: a writer that was killed (SIGKILL,
    power cut) had no chance to remove them.
    """
    path = Path(path)
    pattern = re.compile(
        rf"^\.{re.escape(path.name)}\.{_RANDOM}({'|'.join(map(re.escape, _TEMP_SUFFIXES))})$"
    )
    try:
        entries = list(path.parent.iterdir())
    except OSError:
        return []
    return sorted(p for p in entries if pattern.match(p.name) and p.is_file())


def remove_stale_temporaries(path: str | Path) -> list[Path]:
    """Remove the stale temporary files of ``path``; call with its lock held. Returns them."""
    removed = []
    for tmp in stale_temporaries(path):
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
            removed.append(tmp)
    return removed


def _has_content(path: Path) -> bool:
    if path.is_dir():
        return any(not p.name.startswith(".") for p in path.iterdir())
    return path.exists()


def refuse_existing(path: str | Path, *, what: str = "--out", resumable: bool = False) -> None:
    """Raise :class:`OutputExistsError` if ``path`` exists (a folder: holds visible files)."""
    path = Path(path)
    if not _has_content(path):
        return
    kind = "folder" if path.is_dir() else "file"
    also = ", or --resume to continue it" if resumable else ""
    raise OutputExistsError(
        f"{what} '{path}' exists ({kind}); give --overwrite to replace it{also}, or choose "
        "another output"
    )


@contextlib.contextmanager
def claim(
    paths: dict[str, Path],
    *,
    overwrite: bool,
    resume: bool = False,
    resumable: bool = False,
) -> Iterator[list[Path]]:
    """Claim the outputs of a command for its whole run.

    Locks every path (refusing if another process writes one), refuses existing outputs unless
    ``overwrite`` or ``resume``, removes stale temporaries, and yields the removed ones.

    Parameters
    ----------
    paths : dict
        Flag (e.g. ``"--out"``) to output path.
    overwrite : bool
        Existing outputs may be replaced.
    resume : bool
        The command continues its existing output (``--resume``).
    resumable : bool
        The command could resume (mentioned in the refusal).
    """
    removed: list[Path] = []
    for flag, path in paths.items():
        check_location(path, what=flag)
    with contextlib.ExitStack() as stack:
        for flag, path in paths.items():
            stack.enter_context(output_lock(path, what=flag))
        for flag, path in paths.items():
            if not (overwrite or resume):
                refuse_existing(path, what=flag, resumable=resumable)
            removed.extend(remove_stale_temporaries(path))
        yield removed


def check_location(path: str | Path, *, what: str = "output") -> Path:
    """Fail early if output ``path`` (a file, or a folder to write into) cannot be written.

    Creates the missing parent folders and tries a temporary file where the output goes.
    """
    path = Path(path)
    folder = path if path.is_dir() else path.parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{path.name}.", suffix=".check")
        os.close(fd)
        with contextlib.suppress(FileNotFoundError):  # removed as stale by a concurrent writer
            os.unlink(tmp)
    except OSError as exc:
        raise OutputError(
            f"{what} path '{path}' is not writable ({exc.strerror or exc}); choose another location"
        ) from None
    return path


def _free_bytes(path: str | Path) -> int | None:
    folder = Path(path).parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    try:
        return shutil.disk_usage(folder).free
    except OSError:
        return None


def describe_free_space(path: str | Path) -> str:
    """``"12.3 MB free"`` on the file system holding ``path`` (empty if unknown)."""
    free = _free_bytes(path)
    if free is None:
        return ""
    for unit in ("bytes", "kB", "MB", "GB", "TB"):
        if free < 1000 or unit == "TB":
            return f"{free:.0f} {unit} free" if unit == "bytes" else f"{free:.1f} {unit} free"
        free /= 1000
    return ""  # pragma: no cover


_ADVICE = {
    errno.ENOSPC: "the disk is full: free space or choose another location",
    errno.EDQUOT: "the disk quota is exceeded: free space or choose another location",
    errno.EACCES: "permission denied: choose a location you can write to",
    errno.EPERM: "permission denied: choose a location you can write to",
    errno.EROFS: "the file system is read-only: choose another location",
    errno.EIO: "input/output error on the device: check the disk",
}


def is_write_failure(exc: BaseException) -> bool:
    """True for the exceptions a failed write raises (OSError, netCDF/HDF5 RuntimeError)."""
    if isinstance(exc, JointwearError):
        return False
    if isinstance(exc, OSError):
        return True
    return isinstance(exc, RuntimeError) and ("NetCDF" in str(exc) or "HDF" in str(exc))


def write_failure(
    exc: BaseException, path: str | Path, *, what: str = "output", needed: int | None = None
) -> OutputError:
    """An :class:`OutputError` naming ``path``, the cause and the fix, for a failed write."""
    path = Path(path)
    code = getattr(exc, "errno", None)
    cause = getattr(exc, "strerror", None) or str(exc) or type(exc).__name__
    free = describe_free_space(path)
    advice = _ADVICE.get(code) if code is not None else None
    if advice is None:
        full = free.startswith("0 bytes") or (
            needed is not None and _free_bytes(path) is not None and _free_bytes(path) < needed
        )
        advice = (
            "the disk is full: free space or choose another location"
            if full
            else "check the free space and permissions there"
        )
    where = f"; {free} there" if free else ""
    return OutputError(f"could not write {what} '{path}' ({cause}{where}); {advice}")


def write_image(path: str | Path, image: Any) -> Path:
    """``cv2.imwrite`` that raises :class:`OutputError` naming the file when it fails.

    OpenCV reports a failed write (full disk, missing folder, permission) only by returning
    False; the half-written file is removed.
    """
    import cv2

    path = Path(path)
    try:
        ok = bool(cv2.imwrite(str(path), image))
    except (cv2.error, SystemError) as exc:  # OpenCV 5 raises SystemError for some failures
        ok, cause = False, exc
    else:
        cause = RuntimeError("OpenCV could not write the image")
    if not ok:
        error = write_failure(cause, path, what="image", needed=getattr(image, "nbytes", None))
        with contextlib.suppress(OSError):
            path.unlink()
        raise error
    return path
