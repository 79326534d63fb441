"""Outputs that cannot clobber each other: locks between real processes, stale temporaries of
killed writers, refusal of existing outputs, and failed writes (full disk) naming the file."""

from __future__ import annotations

import errno
import os
import signal
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import xarray as xr

from jointwear import io, outputs


def _dataset(n=10, value=1.0):
    return xr.Dataset(
        {"a": ("x", np.full(n, value), {"units": "m", "long_name": "a"})},
        coords={"x": ("x", np.arange(float(n)), {"units": "m", "long_name": "x"})},
    )


def _child(code: str) -> subprocess.Popen:
    """A separate Python process running ``code``; it prints 'ready' when it holds the lock."""
    return subprocess.Popen(
        [sys.executable, "-c", textwrap.dedent(code)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _wait_ready(proc: subprocess.Popen) -> None:
    line = proc.stdout.readline()
    assert line.strip() == "ready", (line, proc.stderr.read() if proc.poll() is not None else "")


HOLD = """
    import sys
    from pathlib import Path
    from jointwear import outputs
    with outputs.output_lock(Path(sys.argv[1] if len(sys.argv) > 1 else {path!r})):
        print("ready", flush=True)
        sys.stdin.readline()
"""


def test_second_process_writing_the_same_file_is_refused_naming_the_first(tmp_path):
    out = tmp_path / "wear.nc"
    io.save(_dataset(value=1.0), out)
    proc = _child(HOLD.format(path=str(out)))
    try:
        _wait_ready(proc)
        with pytest.raises(outputs.OutputBusyError) as info:
            io.save(_dataset(value=2.0), out)
        msg = str(info.value)
        assert str(out) in msg and f"process {proc.pid}" in msg
        # the file of the first writer is untouched, and no temporary is left behind
        assert float(io.load(out)["a"][0]) == 1.0
        assert not outputs.stale_temporaries(out)
    finally:
        proc.communicate("go\n", timeout=60)
    assert proc.returncode == 0
    # once the first writer is done, the lock is gone with it and writing works again
    io.save(_dataset(value=3.0), out)
    assert float(io.load(out)["a"][0]) == 3.0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["wear.nc"]


def test_cli_run_on_a_locked_out_exits_3_naming_the_other_process(tmp_path, capsys):
    from jointwear.cli import main

    out = tmp_path / "truth_folder"
    proc = _child(HOLD.format(path=str(out)))
    try:
        _wait_ready(proc)
        code = main(["datasets", "speckle", str(out), "--size", "32x32"])
        err = capsys.readouterr().err
    finally:
        proc.communicate("go\n", timeout=60)
    assert code == 3
    assert f"process {proc.pid}" in err and str(out) in err
    assert not out.exists()


def test_sigkill_mid_write_leaves_a_stale_temporary_that_the_next_write_removes(tmp_path):
    out = tmp_path / "map.nc"
    io.save(_dataset(value=1.0), out)
    proc = _child(
        f"""
        import time
        from pathlib import Path
        from jointwear import io
        with io.atomic_path(Path({str(out)!r})) as tmp:
            tmp.write_bytes(b"half a file")
            print("ready", flush=True)
            time.sleep(600)
        """
    )
    _wait_ready(proc)
    os.kill(proc.pid, signal.SIGKILL)
    proc.communicate(timeout=60)
    stale = outputs.stale_temporaries(out)
    assert len(stale) == 1 and stale[0].read_bytes() == b"half a file"
    assert float(io.load(out)["a"][0]) == 1.0  # the killed write replaced nothing
    io.save(_dataset(value=2.0), out)
    assert not stale[0].exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["map.nc"]
    assert float(io.load(out)["a"][0]) == 2.0


def test_stale_detection_keeps_the_temporaries_of_other_files(tmp_path):
    out = tmp_path / "wear.nc"
    mine = tmp_path / ".wear.nc.abcd_123.tmp"
    other = tmp_path / ".wear.nc.ckpt.abcd_123.tmp"  # the checkpoint's, written under its lock
    unrelated = tmp_path / ".wear.nc.backup"
    for p in (mine, other, unrelated):
        p.write_text("x")
    assert outputs.stale_temporaries(out) == [mine]
    with outputs.output_lock(out):
        assert outputs.remove_stale_temporaries(out) == [mine]
    assert other.exists() and unrelated.exists() and not mine.exists()


def test_lock_is_reentrant_in_one_process_and_records_the_owner(tmp_path):
    out = tmp_path / "x.nc"
    with outputs.output_lock(out):
        owner = outputs.lock_owner(out)
        assert owner["pid"] == os.getpid()
        io.save(_dataset(), out)  # the command holding --out may save to it
    assert not outputs.lock_path(out).exists()


def test_claim_refuses_existing_outputs_unless_overwrite_or_resume(tmp_path):
    out = tmp_path / "a.nc"
    out.write_text("old")
    with pytest.raises(outputs.OutputExistsError, match="--overwrite.*--resume"):
        with outputs.claim({"--out": out}, overwrite=False, resumable=True):
            pass
    assert out.read_text() == "old"
    with outputs.claim({"--out": out}, overwrite=True):
        pass
    with outputs.claim({"--out": out}, overwrite=False, resume=True):
        pass
    folder = tmp_path / "rig"
    folder.mkdir()
    with outputs.claim({"--out": folder}, overwrite=False):  # an empty folder holds nothing
        pass
    (folder / "frame.png").write_text("x")
    with pytest.raises(outputs.OutputExistsError, match="folder"):
        with outputs.claim({"--out": folder}, overwrite=False):
            pass


@pytest.mark.parametrize(
    "failure",
    [RuntimeError("NetCDF: HDF error"), OSError(errno.ENOSPC, "No space left on device")],
)
def test_failed_write_names_the_file_and_keeps_the_previous_one(tmp_path, monkeypatch, failure):
    out = tmp_path / "wear.nc"
    io.save(_dataset(value=1.0), out)

    def full_disk(self, path, *args, **kwargs):
        with open(path, "wb") as fh:
            fh.write(b"\x89HDF partial")
        raise failure

    monkeypatch.setattr(xr.Dataset, "to_netcdf", full_disk)
    with pytest.raises(outputs.OutputError) as info:
        io.save(_dataset(value=2.0), out)
    msg = str(info.value)
    assert f"'{out}'" in msg and "free" in msg
    if isinstance(failure, OSError):
        assert "disk is full" in msg
    monkeypatch.undo()
    assert float(io.load(out)["a"][0]) == 1.0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["wear.nc"]


@pytest.fixture
def tiny_disk(tmp_path):
    """A 64 kB tmpfs (needs root; skipped elsewhere)."""
    mnt = tmp_path / "disk"
    mnt.mkdir()
    res = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(mnt)],
        capture_output=True,
        check=False,
    )
    if res.returncode != 0:
        pytest.skip("cannot mount a small tmpfs here (needs root)")
    try:
        yield mnt
    finally:
        subprocess.run(["umount", str(mnt)], check=False)


def test_real_full_disk_netcdf_write_exits_3_naming_the_file(tiny_disk, capsys):
    out = tiny_disk / "big.nc"
    with pytest.raises(outputs.OutputError) as info:
        io.save(_dataset(n=100_000), out)
    msg = str(info.value)
    assert f"'{out}'" in msg and "disk is full" in msg
    assert not list(tiny_disk.iterdir())  # no partial file, no temporary, no lock file
    assert outputs.OutputError("x").exit_code == 3


def test_lock_file_is_gone_after_a_refused_claim(tmp_path):
    out = tmp_path / "a.nc"
    out.write_text("old")
    with pytest.raises(outputs.OutputExistsError):
        with outputs.claim({"--out": out}, overwrite=False):
            pass
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.nc"]


def test_image_write_failure_names_the_file(tmp_path, tiny_disk):
    img = (np.random.default_rng(0).random((400, 400)) * 255).astype(np.uint8)
    path = tiny_disk / "frame_000001.png"
    with pytest.raises(outputs.OutputError) as info:
        outputs.write_image(path, img)
    assert f"'{path}'" in str(info.value) and "disk is full" in str(info.value)
    assert not path.exists()
    assert outputs.write_image(tmp_path / "ok.png", img).stat().st_size > 1000


def test_second_wear_run_on_the_same_out_leaves_the_first_runs_checkpoint_alone(tmp_path, capsys):
    from jointwear.cli import main

    out = tmp_path / "w.nc"
    ckpt = tmp_path / "w.nc.ckpt"
    ckpt.write_bytes(b"state of the first run")
    proc = _child(HOLD.format(path=str(out)))  # the first run, busy with --out w.nc
    try:
        _wait_ready(proc)
        code = main(["sim", "wear", "--contact", "winkler", "--cycles", "1e3", "--out", str(out)])
        err = capsys.readouterr().err
    finally:
        proc.communicate("go\n", timeout=60)
    assert code == 3 and f"process {proc.pid}" in err
    assert ckpt.read_bytes() == b"state of the first run"
    assert not out.exists()
