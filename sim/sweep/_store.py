"""Part files of a sweep: every finished run on disk at once, so a killed sweep resumes.

Layout: ``<out>.parts/`` holds ``sweep.json`` (the spec digest and record) and one
``run-NNNNNN.npz`` per finished run (ok or failed), each written atomically. A lock file keeps
two sweeps from writing into the same folder. After the sweep's result file is written the
folder is removed.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np

from jointwear.errors import BadInputError
from jointwear.io import atomic_path
from jointwear.sim.sweep._run import RunResult

__all__ = ["PartStore", "parts_dir"]

_MANIFEST = "sweep.json"
_FORMAT = "jointwear sweep parts v1"


def parts_dir(out: str | Path) -> Path:
    """The folder of the part files of a sweep writing ``out``."""
    out = Path(out)
    return out.with_name(out.name + ".parts")


def _flat(d: Any, prefix: str = "") -> dict[str, Any]:
    if isinstance(d, dict):
        out: dict[str, Any] = {}
        for k, v in d.items():
            out.update(_flat(v, f"{prefix}{k}."))
        return out
    if isinstance(d, list) and d and all(isinstance(v, dict) for v in d):
        out = {}
        for i, v in enumerate(d):
            out.update(_flat(v, f"{prefix}{i}."))
        return out
    return {prefix[:-1]: d}


class PartStore:
    """The part files of one sweep (see the module docstring).

    Parameters
    ----------
    out : path
        The sweep's result file; parts go to ``<out>.parts/``.
    digest : str
        sha256 of the spec and base parameters; parts of another digest are refused.
    record : dict
        JSON-ready spec and base parameters (to name what differs on a refused resume).
    resume : bool
        Continue the parts of an earlier, interrupted run of the same sweep.
    """

    def __init__(self, out: str | Path, digest: str, record: dict[str, Any], *, resume: bool):
        from filelock import FileLock, Timeout

        self.dir = parts_dir(out)
        self.digest = digest
        self.dir.mkdir(parents=True, exist_ok=True)
        self._lock = FileLock(str(self.dir / ".lock"))
        try:
            self._lock.acquire(timeout=0)
        except Timeout:
            raise BadInputError(
                f"another sweep is writing to '{self.dir}' (its lock is held); wait for it to "
                "finish or choose another --out"
            ) from None
        try:
            self._open(record, resume)
        except BaseException:
            self._lock.release()
            raise

    def _open(self, record: dict[str, Any], resume: bool) -> None:
        manifest = self.dir / _MANIFEST
        if manifest.exists() and not self.finished_files():
            manifest.unlink()  # an earlier sweep stopped before its first run: nothing to keep
        if manifest.exists():
            try:
                old = json.loads(manifest.read_text())
            except (OSError, ValueError) as exc:
                raise BadInputError(
                    f"'{manifest}' cannot be read ({exc}); delete '{self.dir}' to start over"
                ) from None
            n = len(self.finished_files())
            if not resume:
                raise BadInputError(
                    f"'{self.dir}' holds {n} finished run(s) of an earlier sweep; continue it "
                    "with --resume (resume=True), or delete the folder to start over"
                )
            if old.get("digest") != self.digest:
                a, b = _flat(old.get("record", {})), _flat(record)
                diff = sorted(k for k in set(a) | set(b) if a.get(k) != b.get(k))
                shown = "; ".join(
                    f"{k}: {a.get(k, '<absent>')!r} before, {b.get(k, '<absent>')!r} now"
                    for k in diff[:4]
                )
                raise BadInputError(
                    f"cannot resume: the {n} run(s) in '{self.dir}' were computed for another "
                    f"spec or base parameters ({shown or 'digest differs'}); resume with the "
                    "original spec and --params, or delete the folder to start over"
                )
        else:
            payload = {"format": _FORMAT, "digest": self.digest, "record": record}
            with atomic_path(manifest) as tmp:
                tmp.write_text(json.dumps(payload, sort_keys=True, default=str))

    def finished_files(self) -> list[Path]:
        """Part files present."""
        return sorted(self.dir.glob("run-*.npz"))

    def path(self, index: int) -> Path:
        return self.dir / f"run-{index:06d}.npz"

    def write(self, result: RunResult, values: np.ndarray) -> None:
        """Write one run's result atomically."""
        arrays: dict[str, Any] = {
            "index": np.int64(result.index),
            "status": np.str_(result.status),
            "error": np.str_(result.error),
            "elapsed": np.float64(result.elapsed),
            "host": np.str_(result.host),
            "digest": np.str_(self.digest),
            "values": np.asarray(values, dtype=float),
        }
        for k, v in result.outputs.items():
            arrays[f"out__{k}"] = np.float64(v)
        for k, v in result.fields.items():
            arrays[f"field__{k}"] = np.asarray(v)
        with atomic_path(self.path(result.index)) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, **arrays)

    def load(self, design_values: np.ndarray) -> dict[int, RunResult]:
        """The finished runs, checked against the digest and the design's parameter values."""
        done: dict[int, RunResult] = {}
        for path in self.finished_files():
            try:
                with np.load(path, allow_pickle=False) as z:
                    data = {k: z[k] for k in z.files}
            except (OSError, ValueError, EOFError) as exc:
                raise BadInputError(
                    f"part file '{path}' cannot be read ({exc}); delete it and resume again "
                    "(that run is then recomputed)"
                ) from None
            idx = int(data["index"])
            if str(data["digest"]) != self.digest:
                raise BadInputError(f"part file '{path}' belongs to another sweep; delete it")
            if idx >= len(design_values) or not np.array_equal(data["values"], design_values[idx]):
                raise BadInputError(
                    f"part file '{path}' holds other parameter values than run {idx} of this "
                    "sweep; delete it and resume again"
                )
            done[idx] = RunResult(
                idx,
                str(data["status"]),
                {k[5:]: float(v) for k, v in data.items() if k.startswith("out__")},
                {k[7:]: v for k, v in data.items() if k.startswith("field__")},
                str(data["error"]),
                float(data["elapsed"]),
                str(data["host"]),
            )
        return done

    def close(self, *, remove: bool) -> None:
        """Release the lock; with ``remove`` (the result file has it all) or when no run finished,
        delete the folder."""
        self._lock.release()
        if remove or not self.finished_files():
            shutil.rmtree(self.dir, ignore_errors=True)
