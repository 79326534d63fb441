"""Compile once, fast: every numba kernel the command line uses, compiled before the first command
that needs one, in parallel worker processes, with a progress line.

A numba kernel compiles when it is first called with new argument types; ``cache=True`` keeps the
machine code on disk, so that later processes load it. Left to itself, the first run of each
command compiles what it calls, one kernel after the other in the calling process: the first
``jointwear demo`` compiled for minutes, and the first ``dic correlate`` after it compiled 50 more.
Here :func:`ensure_compiled` (called by the command line before a command of :data:`GROUPS` runs)
compiles every kernel of :data:`jointwear._compile_manifest.KERNELS` (the kernels the command
line calls from Python, with the argument types it passes: written by
``docs/scripts/kernel_manifest.py``) into numba's cache at once, split across one worker process
per core (``python -m jointwear._compile --worker ...``), the largest first; then it writes a
stamp, so that later commands find the kernels in the cache and start at once.

The workers share numba's cache folder. numba writes each cache file atomically (a temporary
file renamed into place), but it picks the data file's name from the index it has just read:
two processes saving different argument types of one kernel at the same moment could both pick
the same name. The workers therefore save under one file lock (:func:`_lock_cache_saves`), and
all argument types of one kernel are compiled by the same worker.

The stamp is keyed by the versions of jointwear, numba, llvmlite and Python and by the size and
modification time of the manifest and of every module it names, so that an upgrade or an edited
kernel runs the warm-up again (a kernel still in the cache is then loaded, not compiled). It lives
in ``NUMBA_CACHE_DIR`` when that is set (an emptied cache folder empties it too), else next to
the package (``jointwear/__pycache__``) or in the user's cache folder. ``JOINTWEAR_WARM_UP=0``
turns the warm-up off (a kernel then compiles on first use, as numba does by itself; so does
``NUMBA_DISABLE_JIT``). Nothing here imports numba in the command's own process: the check
costs a few file look-ups (about 2 ms). :func:`light_cache_loads` is the other half of a fast
start: a command then loads its cached kernels without building numba's whole compiler.
"""

from __future__ import annotations

import contextlib
import importlib.abc
import importlib.machinery
import os
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

if TYPE_CHECKING:
    from collections.abc import Iterator, Sequence

__all__ = [
    "GROUPS",
    "ensure_compiled",
    "light_cache_loads",
    "needs_kernels",
    "stamp_path",
    "warm_up",
]

#: The command groups (and commands) whose commands call numba kernels.
GROUPS = frozenset({"demo", "sim", "dic", "datasets"})
#: Environment switch: ``0`` turns the warm-up off.
SWITCH = "JOINTWEAR_WARM_UP"
#: The kernel modules' packages, whose folders the stamp's key looks at.
_PACKAGES = ("jointwear.sim", "jointwear.dic", "jointwear.datasets")


def _manifest():
    """The manifest module (``JOINTWEAR_KERNEL_MANIFEST`` names another one: tests)."""
    import importlib

    return importlib.import_module(
        os.environ.get("JOINTWEAR_KERNEL_MANIFEST") or "jointwear._compile_manifest"
    )


def needs_kernels(args: Sequence[str]) -> bool:
    """Whether the command line ``args`` runs a command that calls numba kernels (not a help
    page, not ``--version``, not ``info`` or the importers)."""
    words = [a for a in args if not a.startswith("-")]
    if not words or words[0] not in GROUPS or any(a in ("--help", "-h", "--version") for a in args):
        return False
    return words[0] == "demo" or len(words) >= 2  # 'jointwear sim' alone prints the group's help


def _cache_root() -> Path:
    """Where the stamp lives: numba's cache folder if set, else beside the package, else the
    user's cache folder."""
    folder = os.environ.get("NUMBA_CACHE_DIR")
    if folder:
        return Path(folder)
    here = Path(__file__).resolve().parent / "__pycache__"
    if os.access(here if here.exists() else here.parent, os.W_OK):
        return here
    user = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(user) / "jointwear"


def _module_files() -> list[Path]:
    """The manifest and every module it names (found without importing them). Only these: numba
    decides whether a cached kernel is stale by its own module's file, not by the modules of the
    kernels it calls, so a warm-up after an edit there would load the same code again."""
    import importlib.util

    manifest = _manifest()
    roots = {}
    for package in _PACKAGES:
        spec = importlib.util.find_spec(package)
        if spec is not None and spec.submodule_search_locations:
            roots[package] = Path(next(iter(spec.submodule_search_locations)))
    files = {Path(manifest.__file__)}
    for module in {k[0] for k in manifest.KERNELS}:
        package = next((p for p in roots if module.startswith(p + ".")), None)
        if package is not None:
            rest = module[len(package) + 1 :].split(".")
            files.add(roots[package].joinpath(*rest[:-1], rest[-1] + ".py"))
        else:  # another package's (a test's): found by its spec
            spec = importlib.util.find_spec(module)
            if spec is not None and spec.origin:
                files.add(Path(spec.origin))
    return sorted(files)


def _key() -> str:
    """What the cached kernels depend on: versions, and the kernel modules' size and mtime."""
    import hashlib
    import importlib.machinery

    from jointwear._version import __version__

    parts = [__version__, sys.version]
    for dependency in ("numba", "llvmlite"):  # found on the path, past the import hooks
        spec = importlib.machinery.PathFinder.find_spec(dependency)
        parts.append(f"{dependency}:{spec.origin if spec else None}")
        if spec is not None and spec.origin:
            stat = os.stat(spec.origin)
            parts.append(f"{stat.st_size}:{stat.st_mtime_ns}")
    for path in _module_files():
        try:
            stat = path.stat()
            parts.append(f"{path}:{stat.st_size}:{stat.st_mtime_ns}")
        except OSError:
            parts.append(f"{path}:missing")
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()[:16]


def stamp_path() -> Path:
    """The file that says the kernels of this installation are compiled into the cache."""
    return _cache_root() / f"jointwear-kernels-{_key()}.json"


def ensure_compiled(args: Sequence[str], stream: TextIO | None = None) -> None:
    """Before a command that calls numba kernels: compile every kernel once, unless the stamp
    says they are compiled (or ``JOINTWEAR_WARM_UP=0``). A failure here never stops the command:
    it says so on ``stream`` and the command compiles what it needs itself."""
    if os.environ.get(SWITCH, "1") == "0" or os.environ.get("NUMBA_DISABLE_JIT", "0") != "0":
        return
    if not needs_kernels(args):
        return
    stream = stream or sys.stderr
    try:
        if stamp_path().exists():
            return
        warm_up(stream=stream)
    except KeyboardInterrupt:
        raise
    except Exception as exc:  # never fatal: the kernels then compile on first use
        print(
            f"jointwear: compiling the kernels ahead failed ({type(exc).__name__}: {exc}); "
            "each compiles when first used",
            file=stream,
            flush=True,
        )


def _groups() -> list[tuple[float, list[int]]]:
    """Manifest entries grouped by kernel (every argument type of a kernel in one worker), with
    each group's recorded CPU seconds, largest first."""
    kernels = _manifest().KERNELS

    by_kernel: dict[tuple[str, str], list[int]] = {}
    for i, (module, name, _args, _cpu) in enumerate(kernels):
        by_kernel.setdefault((module, name), []).append(i)
    groups = [(sum(kernels[i][3] for i in idx), idx) for idx in by_kernel.values()]
    return sorted(groups, key=lambda g: -g[0])


def plan(workers: int) -> list[list[int]]:
    """The manifest's entries split into ``workers`` shares of about equal recorded CPU time
    (largest kernel first, each to the least loaded share), every share largest first."""
    shares: list[tuple[float, list[int]]] = [(0.0, []) for _ in range(max(1, workers))]
    for cost, idx in _groups():
        k = min(range(len(shares)), key=lambda j: shares[j][0])
        shares[k] = (shares[k][0] + cost, shares[k][1] + idx)
    return [idx for _, idx in shares if idx]


def _workers() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def warm_up(*, workers: int | None = None, stream: TextIO | None = None) -> dict:
    """Compile every kernel of the manifest into numba's cache, in ``workers`` processes
    (default: one per core), with a progress line on ``stream``; then write the stamp.

    Returns what was done: ``kernels``, ``failed`` (entries that did not compile, with numba's
    reason: their kernels compile on first use), ``workers``, ``wall_s``, ``cpu_s`` (the
    workers' CPU seconds). Another process warming up the same cache is waited for.
    """
    import json

    from filelock import FileLock, Timeout

    kernels = _manifest().KERNELS

    stream = stream or sys.stderr
    root = _cache_root()
    root.mkdir(parents=True, exist_ok=True)
    lock = FileLock(root / "jointwear-kernels.lock")
    try:
        lock.acquire(timeout=0)
    except Timeout:
        print("jointwear: waiting for another jointwear process compiling the kernels...",
              file=stream, flush=True)  # fmt: skip
        lock.acquire()
    try:
        stamp = stamp_path()
        if stamp.exists():
            return json.loads(stamp.read_text())
        shares = plan(min(workers or _workers(), len(kernels)))
        done = _run_workers(shares, root, stream)
        if not done["workers_failed"]:  # a crashed worker: try again next time
            tmp = stamp.with_suffix(f".{os.getpid()}.tmp")
            tmp.write_text(json.dumps(done, indent=1))
            os.replace(tmp, stamp)
    finally:
        lock.release()
    return done


def _run_workers(shares: list[list[int]], root: Path, stream: TextIO) -> dict:
    """Start one worker process per share, show the progress, wait for them all."""
    import queue
    import subprocess
    import tempfile
    import threading

    kernels = _manifest().KERNELS

    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", SWITCH: "0"}
    progress = _Progress(shares, stream)
    events: queue.Queue = queue.Queue()
    procs = []
    logs = [tempfile.TemporaryFile("w+") for _ in shares]  # a worker's stderr: read if it fails
    try:
        for k, share in enumerate(shares):
            proc = subprocess.Popen(
                [sys.executable, "-m", "jointwear._compile", "--worker", str(root)]
                + [str(i) for i in share],
                stdout=subprocess.PIPE,
                stderr=logs[k],
                stdin=subprocess.DEVNULL,
                env=env,
                text=True,
            )
            procs.append(proc)
            threading.Thread(target=_read, args=(k, proc, events), daemon=True).start()
        running = len(procs)
        while running:
            try:
                k, row = events.get(timeout=1.0)
            except queue.Empty:
                progress.show()
                continue
            if row is None:
                running -= 1
            else:
                progress.finished(k, row)
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.terminate()
        for proc in procs:
            proc.wait()
            if proc.stdout is not None:
                proc.stdout.close()
    crashed = [
        f"exit {p.returncode}: {_tail(log)}"
        for p, log in zip(procs, logs, strict=False)
        if p.returncode != 0
    ]
    for log in logs:
        log.close()
    summary = {
        "kernels": len(kernels),
        "compiled": progress.n_done - len(progress.failed),
        "failed": progress.failed,
        "workers_failed": crashed,
        "workers": len(shares),
        "wall_s": round(time.perf_counter() - progress.start, 1),
        "cpu_s": round(progress.cpu, 1),
    }
    progress.close(summary)
    return summary


def _tail(log) -> str:
    """The end of a worker's stderr."""
    log.seek(0)
    return log.read()[-300:]


def _read(k: int, proc, events) -> None:
    """Worker ``k``'s result lines into ``events``, then ``(k, None)`` when it ends."""
    import json

    for line in proc.stdout:
        if line.startswith("{"):
            events.put((k, json.loads(line)))
    proc.wait()
    events.put((k, None))


class _Progress:
    """The progress line: what is compiling now, how many are done, about how long is left
    (each worker's recorded CPU seconds still to do, scaled by how fast this machine has gone
    so far)."""

    def __init__(self, shares: list[list[int]], stream: TextIO) -> None:
        kernels = _manifest().KERNELS

        self.kernels = kernels
        self.queues = [list(s) for s in shares]
        self.stream = stream
        self.tty = bool(getattr(stream, "isatty", lambda: False)())
        self.start = time.perf_counter()
        self.since = [self.start] * len(shares)  # when each worker began its current kernel
        self.recorded_done = 0.0
        self.cpu = 0.0
        self.n_done = 0
        self.failed: list[dict] = []
        self._last = 0.0
        self._said = ""
        total = sum(k[3] for k in kernels)
        print(
            f"jointwear: compiling the numerical kernels once for this installation "
            f"({len(kernels)} kernels, in {len(shares)} processes; later commands load them)",
            file=stream,
            flush=True,
        )
        self._total = total

    def finished(self, k: int, row: dict) -> None:
        i = row["i"]
        if i in self.queues[k]:
            self.queues[k].remove(i)
        self.since[k] = time.perf_counter()
        self.n_done += 1
        self.cpu += row["cpu_s"]
        self.recorded_done += self.kernels[i][3]
        if row["status"] != "ok":
            module, name = self.kernels[i][:2]
            self.failed.append({"kernel": f"{module}.{name}", "reason": row["status"]})
        self.show()

    def left_s(self) -> float:
        """Seconds left: each worker's recorded CPU seconds still to do, times this machine's
        pace (wall seconds per recorded second: of the finished kernels, or of a running one
        that has taken longer already), less the time its current kernel has taken; the
        busiest worker's."""
        now = time.perf_counter()
        worked = sum(t - self.start for t in self.since)  # wall seconds of finished kernels
        pace = worked / self.recorded_done if self.recorded_done > 1.0 else 1.0
        for q, t in zip(self.queues, self.since, strict=True):
            if q:  # a running kernel already slower than the pace says: the machine is slower
                pace = max(pace, (now - t) / max(self.kernels[q[0]][3], 0.1))
        pace = min(max(pace, 0.3), 30.0)
        left = [
            max(sum(self.kernels[i][3] for i in q) * pace - (now - t), 1.0 if q else 0.0)
            for q, t in zip(self.queues, self.since, strict=True)
        ]
        return max(left, default=0.0)

    def line(self) -> str:
        now = sorted({self.kernels[q[0]][1] for q in self.queues if q})
        return (
            f"jointwear: compiling kernels {self.n_done}/{len(self.kernels)}"
            + (f", now {', '.join(now)}" if now else "")
            + f"; about {self.left_s():.0f} s left"
        )

    def show(self) -> None:
        """On a terminal, the line rewritten in place; otherwise a new line when more kernels
        are done (at most every 15 s), and once a minute while none is."""
        now = time.perf_counter()
        text = self.line()
        if not self.tty:  # a log: a line when a kernel is done (at most every 15 s), or a minute on
            fresh = text.split(";")[0] != self._said.split(";")[0]
            if now - self._last < (15.0 if fresh else 60.0):
                return
        self._last, self._said = now, text
        try:
            if self.tty:
                self.stream.write("\r\033[K" + text[:200])
            else:
                self.stream.write(text + "\n")
            self.stream.flush()
        except (OSError, ValueError):
            pass

    def close(self, summary: dict) -> None:
        failed = summary["kernels"] - summary["compiled"]
        text = (
            f"jointwear: compiled {summary['compiled']} kernels in "
            f"{summary['wall_s']:.0f} s ({summary['workers']} processes, "
            f"{summary['cpu_s']:.0f} CPU s); cached now"
        )
        if failed:
            text += f"; {failed} could not be compiled ahead and compile when first used"
        try:
            self.stream.write(("\r\033[K" if self.tty else "") + text + "\n")
            self.stream.flush()
        except (OSError, ValueError):
            pass


class _ArraymathWithoutBlasProbe(importlib.abc.MetaPathFinder):
    """While a cached kernel loads: ``numba.np.arraymath``, if the kernel's environment names it,
    imported without its check for BLAS, which imports ``scipy.linalg`` (0.15 CPU s) to find it:
    scipy is a dependency, so BLAS is there, and numba checks again, for real, before it
    compiles a call to BLAS. A kernel that does not name it (none of ``dic correlate``'s) does
    not import it, nor ``numba.np.linalg`` under it (0.03 CPU s)."""

    def find_spec(self, name: str, path: Any, target: Any = None) -> Any:
        if name != "numba.np.arraymath":
            return None
        spec = importlib.machinery.PathFinder.find_spec(name, path)
        if spec is None or spec.loader is None:
            return spec
        exec_module = spec.loader.exec_module

        def exec_without_probe(module: Any) -> None:
            from numba.np import linalg

            check = linalg.ensure_blas
            linalg.ensure_blas = lambda: None
            try:
                exec_module(module)
            finally:
                linalg.ensure_blas = check

        spec.loader.exec_module = exec_without_probe  # type: ignore[method-assign]
        return spec


@contextlib.contextmanager
def _arraymath_without_blas_probe() -> Iterator[None]:
    """:class:`_ArraymathWithoutBlasProbe` on the import path for the ``with`` block only."""
    if "numba.np.arraymath" in sys.modules:
        yield
        return
    finder = _ArraymathWithoutBlasProbe()
    sys.meta_path.insert(0, finder)
    try:
        yield
    finally:
        sys.meta_path.remove(finder)


def light_cache_loads() -> None:
    """numba's cache loads without first building its whole compiler (CLI processes).

    Before loading a cached kernel numba refreshes its compiler: it imports every typing and
    lowering module it has (``numba.np.arraymath`` alone imports ``scipy.linalg`` to see whether
    BLAS is there) and installs them, about 0.35 CPU s here, half of the start-up of a command
    that computes. A cached kernel needs none of it: its machine code, numba's C helpers (loaded
    with the target context) and the runtime (``rtsys.initialize``, done here). A cache miss
    refreshes as numba does before its compilation (which refreshes again by itself), and any
    error here falls back to numba's own load.
    """
    from numba.core import caching

    original = caching.Cache.load_overload
    if getattr(original, "light", False):
        return

    def load_overload(self, sig, target_context):
        try:
            from numba.core.runtime import rtsys

            rtsys.initialize(target_context)
            with self._guard_against_spurious_io_errors(), _arraymath_without_blas_probe():
                loaded = self._load_overload(sig, target_context)
        except Exception:  # not as this numba expects: its own way
            return original(self, sig, target_context)
        if loaded is None:  # a miss: numba compiles next, on a refreshed compiler
            target_context.refresh()
        return loaded

    load_overload.light = True
    caching.Cache.load_overload = load_overload


# --- in the worker process -------------------------------------------------------------------


def parse_types(text: str) -> tuple:
    """Argument types written as numba writes them (``repr`` of the tuple) back to numba types."""
    from numba.core import types

    names = {**vars(types), "bool": types.boolean}
    value = eval(text, {"__builtins__": {}}, names)  # noqa: S307 - our own manifest
    return tuple(value)


def resolve(module: str, name: str):
    """The numba dispatcher of the function ``module.name``.

    A module that keeps numba out of its import defines the kernel's Python function
    ``X_impl`` and a wrapper ``X`` that, on its first call, replaces itself by
    ``njit(...)(X_impl)`` and calls that: here the wrapper is called once with that call
    stubbed out, which leaves the dispatcher, with the module's own options, in ``module.X``.
    """
    import importlib

    mod = importlib.import_module(module)
    obj = mod
    for part in name.split("."):
        obj = getattr(obj, part)
    if hasattr(obj, "compile"):
        return obj
    wrapper = name.removesuffix("_impl")
    if wrapper == name or not callable(getattr(mod, wrapper, None)):
        raise TypeError(f"{module}.{name} is not a numba kernel")
    from numba.core.registry import CPUDispatcher

    own = CPUDispatcher.__dict__.get("__call__")
    CPUDispatcher.__call__ = lambda self, *a, **k: None
    try:
        getattr(mod, wrapper)(*[None] * obj.__code__.co_argcount)
    finally:
        if own is None:
            del CPUDispatcher.__call__
        else:
            CPUDispatcher.__call__ = own
    built = getattr(mod, wrapper)
    if getattr(built, "py_func", None) is not obj:
        raise TypeError(f"{module}.{wrapper} did not build the kernel {name}")
    return built


def _lock_cache_saves(root: Path) -> None:
    """numba's cache saves of this process under one file lock shared by the workers (see the
    module's docstring)."""
    from filelock import FileLock
    from numba.core import caching

    # the class of numba's index-and-data cache files (its name changed in numba 0.61)
    cls = getattr(caching, "IndexDataCacheFile", None) or getattr(caching, "_CacheFile", None)
    if cls is None or not hasattr(cls, "save"):
        return  # another numba: its saves are left as they are
    save = cls.save
    lock = FileLock(root / "jointwear-kernels.save.lock")

    def locked_save(self, key, data):
        with lock:
            return save(self, key, data)

    cls.save = locked_save


def _worker(root: Path, indices: list[int]) -> None:
    """Compile the manifest's entries ``indices``; one JSON line per entry on stdout."""
    import json

    kernels = _manifest().KERNELS

    _lock_cache_saves(root)
    for i in indices:
        module, name, args, _ = kernels[i]
        t0 = time.process_time()
        try:
            resolve(module, name).compile(parse_types(args))
            status = "ok"
        except Exception as exc:  # a stale entry: that kernel compiles on first use instead
            status = f"{type(exc).__name__}: {str(exc).splitlines()[0][:200] if str(exc) else ''}"
        row = {"i": i, "cpu_s": round(time.process_time() - t0, 2), "status": status}
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    if len(sys.argv) >= 3 and sys.argv[1] == "--worker":
        _worker(Path(sys.argv[2]), [int(a) for a in sys.argv[3:]])
    else:
        raise SystemExit("usage: python -m jointwear._compile --worker CACHE_ROOT INDEX...")
