"""The ``jointwear`` command line: one group per module, plus ``info`` and ``demo``.

The CLI is a thin layer: each command parses options, calls the library and writes files.
Sub-command groups live next to their module (``sim/cli.py`` -> ``jointwear sim ...``).

Exit codes: 0 ok, 1 a validation criterion failed, 2 usage error, 3 bad input (message on
stderr; the traceback only with ``--debug``).
"""

from __future__ import annotations

import gc
import os
import signal
import sys
from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import CommandGroup, Overwrite, apply_classes, lazy_groups
from jointwear._compile import ensure_compiled, light_cache_loads
from jointwear._compile_notice import announce_compilation
from jointwear._lazy import after_import
from jointwear._version import __version__
from jointwear.errors import EXIT_BAD_INPUT, EXIT_USAGE, JointwearError

#: BLAS thread pools of the command's process: one thread each unless the user set them. The
#: parallel work is in numba kernels and worker processes; idle OpenBLAS pools (numpy's and
#: scipy's) cost about 0.2-0.3 CPU s per command just to start and spin (benchmarks/
#: bench_startup.py), and on a shared 2-core machine they compete with the numba threads.
#: Set before numpy is first imported (nothing above imports it).
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
for _name in BLAS_THREAD_VARIABLES:
    os.environ.setdefault(_name, "1")
# a command loads its cached kernels without building numba's whole compiler first (0.35 CPU s)
after_import("numba", light_cache_loads)

app = typer.Typer(
    name="jointwear",
    help="Validate wear simulations of joints with clearance against test-rig measurements.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
    cls=CommandGroup,
)

_STATE: dict[str, object] = {"debug": False, "signal": None}


def _version_callback(value: bool) -> None:
    if value:
        typer.echo(f"jointwear {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option(
            "--version",
            callback=_version_callback,
            is_eager=True,
            help="Print the version and exit.",
        ),
    ] = False,
    debug: Annotated[bool, typer.Option("--debug", help="Show tracebacks on errors.")] = False,
) -> None:
    _STATE["debug"] = debug


#: command groups, imported only when used (``jointwear dic ...`` imports ``dic`` alone)
GROUPS = {
    "sim": "jointwear.sim.cli",
    "dic": "jointwear.dic.cli",
    "metrology": "jointwear.metrology.cli",
    "compare": "jointwear.compare.cli",
    "report": "jointwear.reports.cli",
    "datasets": "jointwear.datasets.cli",
    "import": "jointwear.cli_import",
}


def _register_groups() -> None:
    app.info.cls = lazy_groups(GROUPS)


@app.command()
def info(
    file: Annotated[Path, typer.Argument(help="A jointwear netCDF file.")],
    no_validate: Annotated[
        bool, typer.Option("--no-validate", help="Summarise even if the file breaks the contract.")
    ] = False,
) -> None:
    """Summarise a jointwear file: variables, dimensions, units, conventions, provenance."""
    from jointwear.summary import summarise

    typer.echo(summarise(file, validate=not no_validate))


@app.command()
def demo(
    out: Annotated[Path, typer.Option("--out", help="Output folder.")] = Path("jointwear-demo"),
    quick: Annotated[
        bool,
        typer.Option(
            "--quick",
            help="Reduced size, in one process: no ensemble (u_input not assessed), no "
            "verification study and no footage.",
        ),
    ] = False,
    overwrite: Overwrite = False,
) -> None:
    """Run the whole chain on the embedded default data and write a validation report.

    Phase [1/2]: simulation, its verification study, an ensemble over the uncertain inputs,
    virtual roundness scans and stereo footage, side by side in one worker process per core;
    [2/2]: comparison and report. The report is always written; exit code 1 when a validation
    criterion fails.
    """
    from jointwear.reports.demo import run_demo

    report = run_demo(out, quick=quick)
    typer.echo(f"report: {report}")


_register_groups()
apply_classes(app)


def _on_signal(signum: int, frame: object) -> None:
    """Ctrl-C and SIGTERM: commands keep their partial results; exit 130 or 143.

    A signal that arrives while a finalizer (``__del__``) runs, e.g. during a garbage
    collection, is delivered again a moment later instead: Python prints an exception raised
    in a finalizer and drops it, and the command would run on as if never interrupted."""
    _STATE["signal"] = signum
    if _in_finalizer(frame):
        import threading

        timer = threading.Timer(REDELIVERY_S, signal.raise_signal, args=(signum,))
        timer.daemon = True
        timer.start()
        return
    raise KeyboardInterrupt()


#: delay [s] before a signal that arrived inside a finalizer is delivered again
REDELIVERY_S = 0.02


def _in_finalizer(frame: object) -> bool:
    """True if ``frame`` or a frame that called it is a ``__del__`` method."""
    while frame is not None:
        if getattr(getattr(frame, "f_code", None), "co_name", None) == "__del__":
            return True
        frame = getattr(frame, "f_back", None)
    return False


def _interrupted() -> int | None:
    """128 + the signal that stopped the command (also when it turned it into an error)."""
    signum = _STATE["signal"]
    return 128 + int(signum) if signum is not None else None


def _stdout_is_null() -> bool:
    """True if stdout is /dev/null (rich points it there when the reader of a pipe is gone)."""
    try:
        out, null = os.fstat(sys.stdout.fileno()), os.stat(os.devnull)
    except (OSError, ValueError, AttributeError):  # no file descriptor (tests)
        return False
    return (out.st_dev, out.st_ino) == (null.st_dev, null.st_ino)


def _quiet_broken_pipe() -> None:
    """The reader of stdout went away (``jointwear info x.nc | head``): stop quietly."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # stdout without a file descriptor (tests)
        pass


#: The ``jointwear`` script's garbage collector: young collections every 10,000 allocations
#: instead of 700. A command that computes imports some 700 modules, whose objects live until
#: the process ends; with the default thresholds the collector walks them again and again while
#: they are imported (about 0.02 CPU s of a ``dic correlate``, ``benchmarks/bench_startup.py``).
#: At most that many young objects wait a little longer for their collection.
SCRIPT_GC_THRESHOLD = (10_000, 10, 10)


def _script_exit_gc() -> None:
    """The script's process ends: every object is frozen (``gc.freeze``), so that the
    interpreter's last collections at exit skip them (about 0.07 CPU s of a ``dic correlate``,
    a tenth of its start-up). Everything is still released as the interpreter tears its modules
    down (open files flushed and closed); only reference cycles are left to the operating
    system, which the interpreter does not promise to finalise at exit either."""
    gc.freeze()


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``jointwear`` script; returns the exit code.

    Without ``argv`` (the script, ``python -m jointwear``) the process is the command's: the
    garbage collector runs with :data:`SCRIPT_GC_THRESHOLD` and the objects are frozen at the
    end (:func:`_script_exit_gc`). ``main([...])`` in a caller's process leaves both as they
    are.
    """
    args = sys.argv[1:] if argv is None else list(argv)
    if argv is None:
        gc.set_threshold(*SCRIPT_GC_THRESHOLD)
    debug = "--debug" in args
    compiled = announce_compilation()
    _STATE["signal"] = None
    stdout_was_null = _stdout_is_null()
    previous = {}
    for signum in (signal.SIGINT, signal.SIGTERM):
        try:
            previous[signum] = signal.signal(signum, _on_signal)
        except ValueError:  # not the main thread
            pass
    try:
        ensure_compiled(args)  # the first command that computes compiles every kernel, once
        app(args=args, prog_name="jointwear", standalone_mode=True)
    except SystemExit as exc:  # click's own exits: 0, usage errors (2), aborts
        code = exc.code
        if _interrupted():  # click turned the KeyboardInterrupt into an exit
            return _interrupted()
        if code == 1 and (
            type(sys.stdout).__name__ == "PacifyFlushWrapper"  # click, on a closed pipe
            or (not stdout_was_null and _stdout_is_null())  # rich, on a closed pipe
        ):
            _quiet_broken_pipe()
            return 0
        return code if isinstance(code, int) else (0 if code is None else EXIT_USAGE)
    except BrokenPipeError:
        _quiet_broken_pipe()
        return 0
    except JointwearError as exc:
        if debug:
            raise
        typer.echo(f"jointwear: error: {exc}", err=True)
        return _interrupted() or exc.exit_code  # a command may report an interrupt as error
    except KeyboardInterrupt:
        terminated = _STATE["signal"] == signal.SIGTERM
        typer.echo("terminated" if terminated else "interrupted", err=True)
        return _interrupted() or 128 + signal.SIGINT
    except (OSError, MemoryError) as exc:
        if debug:
            raise
        typer.echo(f"jointwear: error: {exc}", err=True)
        return EXIT_BAD_INPUT
    except Exception as exc:  # a bug: say so, without a traceback unless --debug
        if debug:
            raise
        text = str(exc)
        text = text if len(text) < 300 else text[:300] + " ..."
        typer.echo(
            f"jointwear: error: unexpected {type(exc).__name__}: {text}\n"
            "This is a bug in jointwear: please report it with the output of the same command "
            "run with --debug.",
            err=True,
        )
        return EXIT_BAD_INPUT
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        line = compiled()
        if line:
            try:
                typer.echo(line, err=True)
            except OSError:
                pass
        _redeliver(argv)
        if argv is None:
            _script_exit_gc()
    return 0


def _redeliver(argv: list[str] | None) -> None:
    """Called in-process (``main([...])``: a test, a user's script), the caller's own handler
    gets the Ctrl-C or SIGTERM the command stopped on, so that the caller stops too (pytest
    ends the session) instead of running on; the ``jointwear`` script exits 130 or 143."""
    signum = _STATE["signal"]
    if argv is not None and signum is not None:
        _STATE["signal"] = None
        signal.raise_signal(signum)
