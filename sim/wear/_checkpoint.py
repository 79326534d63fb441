"""Safe, versioned checkpoints of a wear run: a zip of ``.npy`` arrays plus a JSON state.

A checkpoint is a zip archive (the ``.npz`` layout) with one member ``checkpoint.json`` - format
name and version, the run's fingerprint (everything that determines the result) and the state
tree - and one ``.npy`` member per array, read back with ``allow_pickle=False``. Nothing in it
is executed on loading: dataclasses (e.g. the dynamics' ``SimState``) are rebuilt only if their
class lives in the ``jointwear`` package and is a dataclass, by calling it with the stored
fields. Floats round-trip exactly (JSON ``repr`` of a double is exact; NaN/inf are tagged).

Version policy: :data:`FORMAT_VERSION` is written; a checkpoint of another version is refused
with a message naming the file and how to start over (older pickle checkpoints, format 1, are
recognised and refused without being unpickled). A later version that keeps the state layout
compatible can add a migration in :func:`_migrate`.

A wear run's own checkpoint methods (:class:`RunCheckpoints`, a base of
:class:`~jointwear.sim.wear.WearRun`): its fingerprint, saving, and resuming only with the
parameters it was written with.
"""

from __future__ import annotations

import dataclasses
import importlib
import io
import json
import math
import zipfile
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, Self

import numpy as np

from jointwear.errors import BadInputError
from jointwear.io import atomic_path
from jointwear.params import to_jsonable
from jointwear.sim.wear._contact import describe_any
from jointwear.sim.wear._settings import WearSettings

__all__ = ["FORMAT", "FORMAT_VERSION", "write_checkpoint", "read_checkpoint", "RunCheckpoints"]

FORMAT = "jointwear.sim.wear checkpoint"
FORMAT_VERSION = 2
_META = "checkpoint.json"
_START_OVER = (
    "start over without --resume (the old checkpoint is then replaced), or delete the file"
)


class _Encoder:
    def __init__(self) -> None:
        self.arrays: dict[str, np.ndarray] = {}

    def __call__(self, obj: Any) -> Any:  # noqa: PLR0911 - one branch per type
        if obj is None or isinstance(obj, (bool, str)):
            return obj
        if isinstance(obj, (int, np.integer)):
            return int(obj)
        if isinstance(obj, (float, np.floating)):
            f = float(obj)
            return f if np.isfinite(f) else {"__float__": repr(f)}
        if isinstance(obj, np.ndarray):
            if obj.dtype.hasobject:
                raise TypeError("object arrays cannot be checkpointed")
            key = f"a{len(self.arrays)}"
            self.arrays[key] = np.ascontiguousarray(obj)
            return {"__array__": key}
        if isinstance(obj, tuple):
            return {"__tuple__": [self(v) for v in obj]}
        if isinstance(obj, list):
            return [self(v) for v in obj]
        if isinstance(obj, dict):
            if not all(isinstance(k, str) for k in obj):
                raise TypeError("only dicts with string keys can be checkpointed")
            if any(k.startswith("__") and k.endswith("__") for k in obj):
                return {"__dict__": {k: self(v) for k, v in obj.items()}}
            return {k: self(v) for k, v in obj.items()}
        if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
            cls = type(obj)
            return {
                "__dataclass__": f"{cls.__module__}:{cls.__qualname__}",
                "fields": {f.name: self(getattr(obj, f.name)) for f in dataclasses.fields(obj)},
            }
        raise TypeError(f"a {type(obj).__name__} cannot be checkpointed")


def _dataclass_type(name: str) -> type:
    module, _, qual = name.partition(":")
    if not (module == "jointwear" or module.startswith("jointwear.")) or not qual:
        raise ValueError(f"class {name!r} is not part of jointwear")
    obj: Any = importlib.import_module(module)
    for part in qual.split("."):
        obj = getattr(obj, part)
    if not (isinstance(obj, type) and dataclasses.is_dataclass(obj)):
        raise ValueError(f"{name!r} is not a dataclass")
    return obj


def _decode(node: Any, arrays: dict[str, np.ndarray]) -> Any:
    if isinstance(node, list):
        return [_decode(v, arrays) for v in node]
    if not isinstance(node, dict):
        return node
    if "__array__" in node:
        return arrays[node["__array__"]]
    if "__float__" in node:
        return float(node["__float__"])
    if "__tuple__" in node:
        return tuple(_decode(v, arrays) for v in node["__tuple__"])
    if "__dict__" in node:
        return {k: _decode(v, arrays) for k, v in node["__dict__"].items()}
    if "__dataclass__" in node:
        cls = _dataclass_type(node["__dataclass__"])
        return cls(**{k: _decode(v, arrays) for k, v in node["fields"].items()})
    return {k: _decode(v, arrays) for k, v in node.items()}


def write_checkpoint(path: str | Path, fingerprint: dict[str, Any], state: Any) -> Path:
    """Write ``state`` with the run's ``fingerprint`` atomically to ``path``.

    Raises
    ------
    BadInputError
        The state holds something that cannot be stored safely (names the type).
    """
    path = Path(path)
    enc = _Encoder()
    try:
        tree = enc(state)
    except TypeError as exc:
        raise BadInputError(
            f"the wear state cannot be written to checkpoint '{path}': {exc} (a contact model's "
            "state must be built from numbers, arrays, lists, dicts and jointwear dataclasses)"
        ) from None
    meta = {
        "format": FORMAT,
        "version": FORMAT_VERSION,
        "fingerprint": enc(fingerprint),
        "state": tree,
    }
    text = json.dumps(meta, allow_nan=False, sort_keys=True)
    with atomic_path(path) as tmp:
        with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_STORED) as zf:
            zf.writestr(_META, text)
            for key, arr in enc.arrays.items():
                buf = io.BytesIO()
                np.lib.format.write_array(buf, arr, allow_pickle=False)
                zf.writestr(f"{key}.npy", buf.getvalue())
    return path


def _migrate(meta: dict[str, Any], path: Path) -> dict[str, Any]:
    version = meta.get("version")
    if version == FORMAT_VERSION:
        return meta
    if isinstance(version, int) and version > FORMAT_VERSION:
        raise BadInputError(
            f"checkpoint '{path}' was written by a newer jointwear (checkpoint format "
            f"{version}, this version reads {FORMAT_VERSION}); resume it with that version, or "
            f"{_START_OVER}"
        )
    raise BadInputError(
        f"checkpoint '{path}' has checkpoint format {version!r}, which this version cannot "
        f"continue (it reads format {FORMAT_VERSION}); {_START_OVER}"
    )


def read_checkpoint(path: str | Path) -> tuple[dict[str, Any], Any]:
    """(fingerprint, state) from a checkpoint written by :func:`write_checkpoint`.

    Raises
    ------
    BadInputError
        Missing, unreadable, truncated, foreign, of another format version, or an old pickle
        checkpoint (never unpickled); the message names the file and how to start over.
    """
    path = Path(path)
    if not path.exists():
        raise BadInputError(
            f"checkpoint '{path}' does not exist; run without --resume to start a new run"
        )
    try:
        with open(path, "rb") as fh:
            head = fh.read(4)
    except OSError as exc:
        raise BadInputError(
            f"checkpoint '{path}' could not be read ({exc}); {_START_OVER}"
        ) from None
    if head[:1] == b"\x80":
        raise BadInputError(
            f"checkpoint '{path}' is a pickle written by an older jointwear (checkpoint format 1); "
            f"pickles are not loaded (unsafe, and tied to that version): {_START_OVER}"
        )
    try:
        with zipfile.ZipFile(path) as zf:
            meta = json.loads(zf.read(_META).decode("utf-8"))
            if not isinstance(meta, dict) or meta.get("format") != FORMAT:
                raise BadInputError(f"'{path}' is not a jointwear wear checkpoint; {_START_OVER}")
            meta = _migrate(meta, path)
            arrays = {}
            for name in zf.namelist():
                if name.endswith(".npy"):
                    with zf.open(name) as fh:
                        arrays[name[:-4]] = np.lib.format.read_array(fh, allow_pickle=False)
        state = _decode(meta["state"], arrays)
        fingerprint = _decode(meta["fingerprint"], arrays)
    except BadInputError:
        raise
    except (
        OSError,
        zipfile.BadZipFile,
        KeyError,
        ValueError,
        TypeError,
        AttributeError,
        ImportError,
    ) as exc:
        raise BadInputError(
            f"checkpoint '{path}' could not be read ({type(exc).__name__}: {exc}); {_START_OVER}"
        ) from None
    return fingerprint, state


def _flatten(obj: Any, prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    if isinstance(obj, Mapping):
        for k, v in obj.items():
            out.update(_flatten(v, f"{prefix}{k}."))
        return out
    out[prefix[:-1]] = obj
    return out


class RunCheckpoints:
    """The checkpoint side of :class:`~jointwear.sim.wear.WearRun` (a base of it): its
    fingerprint, writing its state, and starting or resuming a run from a checkpoint (refused
    when the parameters differ)."""

    def fingerprint(self) -> dict[str, Any]:
        """Everything that determines the result (JSON-ready): model and wear settings."""
        fp = {
            "contact": to_jsonable(describe_any(self.contact)),
            "wear": to_jsonable(self.settings),
            "initial_wear_max": float(np.max(self._s["initial_wear"])),
            "initial_wear_sum": float(np.sum(self._s["initial_wear"])),
        }
        return json.loads(json.dumps(fp))  # as a checkpoint stores it (tuples become lists)

    def save_checkpoint(self, path: str | Path | None = None) -> Path:
        """Write the complete state atomically to ``path`` or :attr:`checkpoint` (npz + JSON)."""
        path = Path(path) if path is not None else self.checkpoint
        if path is None:
            raise BadInputError("no checkpoint path given")
        return write_checkpoint(path, self.fingerprint(), self._s)

    @classmethod
    def start(
        cls,
        contact: Any,
        settings: WearSettings | None = None,
        *,
        resume: bool = False,
        **run: Any,
    ) -> Self:
        """A new run, ``WearRun(contact, settings, **run)``, or with ``resume`` the run of
        ``run["checkpoint"]`` continued (:meth:`resume`; the initial wear is the checkpoint's)."""
        if not resume:
            return cls(contact, settings, **run)
        checkpoint = run.pop("checkpoint", None)
        if checkpoint is None:
            raise BadInputError("resume=True needs the checkpoint path")
        run.pop("initial_wear", None)
        return cls.resume(checkpoint, contact, settings, **run)

    @classmethod
    def resume(
        cls,
        checkpoint: str | Path,
        contact: Any,
        settings: WearSettings | None = None,
        *,
        cycles: float,
        snapshots: Sequence[float] | None = None,
        on_update: Callable[[dict[str, Any]], None] | None = None,
    ) -> Self:
        """Continue a run from its checkpoint; refuse if the parameters differ.

        Raises
        ------
        BadInputError
            The checkpoint is missing, unreadable, of another format version, was written with
            different parameters (the message names them), or the target is below the cycles
            already done.
        """
        path = Path(checkpoint)
        old_fp, state = read_checkpoint(path)
        run = cls(
            contact,
            settings,
            cycles=max(float(cycles), 1.0),
            snapshots=None,
            checkpoint=path,
            on_update=on_update,
        )
        if isinstance(state, dict):  # checkpoints written before the noise probe existed
            state.setdefault("probe_noise", math.nan)
        if not isinstance(state, dict) or set(state) != set(run._s):
            raise BadInputError(
                f"checkpoint '{path}' does not hold a wear-run state this version understands; "
                "start over without --resume (the old checkpoint is then replaced)"
            )
        if np.shape(state["initial_wear"]) == run.grid.shape:
            run._s["initial_wear"] = state["initial_wear"]
        old = _flatten(old_fp)
        new = _flatten(run.fingerprint())
        differing = sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))
        if differing:
            shown = "; ".join(
                f"{k}: {old.get(k, '<absent>')!r} in the checkpoint, {new.get(k, '<absent>')!r} now"
                for k in differing[:5]
            )
            more = f" (and {len(differing) - 5} more)" if len(differing) > 5 else ""
            raise BadInputError(
                f"checkpoint '{path}' was written with different parameters - {shown}{more}. "
                "Resume with the original parameters, or start over without --resume (the old "
                "checkpoint is then replaced)"
            )
        run._s = state
        run._set_target(cycles, snapshots)
        return run
