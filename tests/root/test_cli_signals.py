"""Ctrl-C and SIGTERM stop a test session that runs the command line in-process (#37): the
command stops on the signal as the script does, and the caller's own handler then gets it."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

#: A test file run by pytest in a subprocess: a command that waits (as a long computation
#: does) inside ``main``, then more commands, as tests/root/test_cli_fuzz.py runs them.
_SESSION = """
import time
from pathlib import Path

from jointwear.cli import app, main

MARK = Path({mark!r})


@app.command("c37-wait")
def wait() -> None:
    MARK.write_text("in the command")
    time.sleep(60)


def test_commands_one_after_another():
    for _ in range(3):
        main(["c37-wait"])
"""


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_during_an_in_process_command_stops_pytest(tmp_path, sig):
    mark = tmp_path / "mark"
    test = tmp_path / "test_session.py"
    test.write_text(_SESSION.format(mark=str(mark)))
    with subprocess.Popen(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(test)],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    ) as proc:
        try:
            t0 = time.monotonic()
            while not mark.exists() and proc.poll() is None and time.monotonic() - t0 < 120:
                time.sleep(0.05)
            assert proc.poll() is None, proc.communicate()[0].decode()
            proc.send_signal(sig)
            out, _ = proc.communicate(timeout=30)  # not the 2 x 60 s of the commands to come
        finally:
            if proc.poll() is None:
                proc.kill()
    text = out.decode()
    if sig == signal.SIGINT:  # pytest's own report of an interrupted session
        assert proc.returncode == pytest.ExitCode.INTERRUPTED, text
        assert "KeyboardInterrupt" in text and "passed" not in text
    else:  # pytest leaves SIGTERM at its default: the session ends at once
        assert proc.returncode == -signal.SIGTERM, text


def test_a_signal_inside_a_finalizer_is_delivered_again_not_dropped():
    """Ctrl-C during a ``__del__`` (a garbage collection runs finalizers at any allocation):
    an exception raised there is printed and dropped by Python, and the command would run on
    to its end; the handler delivers the signal again once the finalizer is done, and the
    command stops with KeyboardInterrupt (a sim wear run in CI lost its Ctrl-C this way)."""
    from jointwear import cli

    raised_in_finalizer = []

    class Finalized:
        def __del__(self):
            try:
                cli._on_signal(signal.SIGINT, sys._getframe())
            except KeyboardInterrupt:  # would be dropped by Python here
                raised_in_finalizer.append(True)

    previous = signal.signal(signal.SIGINT, cli._on_signal)
    try:
        with pytest.raises(KeyboardInterrupt):
            obj = Finalized()
            del obj  # the finalizer runs here and takes the signal
            time.sleep(5)  # the command's work: the redelivered signal stops it
    finally:
        signal.signal(signal.SIGINT, previous)
        cli._STATE["signal"] = None
    assert raised_in_finalizer == []
    assert not cli._in_finalizer(sys._getframe())
