"""``jointwear sim wear`` on the prescribed Winkler contact: output, errors, Ctrl-C and --resume."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from _rigs import NOISE_LIMITED_TOML

from jointwear import io
from jointwear.cli import main

SMALL = ["--contact", "winkler", "--layers", "6", "--points", "48", "--kw", "1e-13"]


def test_wear_command_writes_a_valid_map_and_figure(tmp_path, capsys):
    out = tmp_path / "w.nc"
    fig = tmp_path / "w.png"
    code = main(
        [
            "sim",
            "wear",
            *SMALL,
            "--cycles",
            "2e4",
            "--out",
            str(out),
            "--figure",
            str(fig),
            "--snapshots",
            "5000,1e4",
        ]
    )
    assert code == 0
    ds = io.load(out)
    np.testing.assert_array_equal(ds["cycles"].values, [5000, 10000, 20000])
    assert ds.attrs["status"] == "complete"
    assert ds.attrs["kw_m2_per_N"] == 1e-13
    assert fig.stat().st_size > 1000
    assert (tmp_path / "w.nc.ckpt").exists()
    assert "20000 cycles" in capsys.readouterr().out


def test_wear_settings_from_toml(tmp_path):
    toml = tmp_path / "p.toml"
    toml.write_text('[wear]\nkw = 2e-13\nscheme = "fixed"\ndn = 2500\n')
    out = tmp_path / "w.nc"
    args = ["sim", "wear", "--contact", "winkler", "--layers", "6", "--points", "48"]
    assert (
        main(
            [
                *args,
                "--cycles",
                "1e4",
                "--out",
                str(out),
                "--params",
                str(toml),
                "--snapshots",
                "5000",
            ]
        )
        == 0
    )
    ds = io.load(out)
    assert ds.attrs["kw_m2_per_N"] == 2e-13
    assert set(ds["update_dn"].values) == {2500}
    toml.write_text("[wear]\nkw = -3\n")
    assert main([*args, "--cycles", "1e4", "--out", str(out), "--params", str(toml)]) == 3


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--kw", "-1e-14"], "must be a positive number"),
        (["--kw", "5.05e-10"], "absurd"),
        (["--scheme", "implicit"], "'implicit' is not one of"),
        (["--snapshots", "1e4,abc"], "comma-separated cycle counts"),
    ],
)
def test_bad_options_fail_with_a_message(tmp_path, capsys, extra, message):
    out = tmp_path / "w.nc"
    code = main(
        ["sim", "wear", "--contact", "winkler", "--cycles", "1e4", "--out", str(out), *extra]
    )
    assert code == (2 if extra[0] == "--scheme" else 3)  # an unknown choice is a usage error
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_unwritable_output_fails_before_the_run(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    code = main(["sim", "wear", *SMALL, "--cycles", "1e9", "--out", str(blocker / "w.nc")])
    assert code == 3
    assert "not writable" in capsys.readouterr().err


def test_resume_errors(tmp_path, capsys):
    out = tmp_path / "w.nc"
    assert main(["sim", "wear", *SMALL, "--cycles", "1e4", "--out", str(out), "--resume"]) == 3
    assert "does not exist" in capsys.readouterr().err
    assert main(["sim", "wear", *SMALL, "--cycles", "1e4", "--out", str(out)]) == 0
    assert main(["sim", "wear", *SMALL, "--cycles", "5e3", "--out", str(out), "--resume"]) == 3
    assert "below the 10000 cycles already done" in capsys.readouterr().err
    other = [a if a != "1e-13" else "3e-13" for a in SMALL]
    assert main(["sim", "wear", *other, "--cycles", "2e4", "--out", str(out), "--resume"]) == 3
    assert "wear.kw: 1e-13 in the checkpoint, 3e-13 now" in capsys.readouterr().err


def _interrupt(run: list[str], out, sig: int, timeout: float) -> tuple[int, bytes]:
    """Run ``jointwear *run --out out`` in a process and send it ``sig`` once the run's
    checkpoint exists (it is then mid-run); the exit code and stderr."""
    ckpt = out.with_name(out.name + ".ckpt")
    proc = subprocess.Popen(
        [sys.executable, "-m", "jointwear", *run, "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=dict(os.environ, PYTHONUNBUFFERED="1"),
    )
    t0 = time.monotonic()
    while not ckpt.exists() and proc.poll() is None and time.monotonic() - t0 < timeout:
        time.sleep(0.02)
    time.sleep(0.3)
    assert proc.poll() is None, "the run finished before it could be interrupted"
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=timeout)
    return proc.returncode, err


def test_ctrl_c_leaves_valid_partial_output_and_resume_is_identical(tmp_path):
    run = ["sim", "wear", *SMALL, "--scheme", "fixed", "--dn", "200", "--cycles", "3e4"]
    ref = tmp_path / "ref.nc"
    assert main([*run, "--out", str(ref)]) == 0

    out = tmp_path / "w.nc"
    returncode, err = _interrupt(run, out, signal.SIGINT, timeout=60)
    assert returncode == 130
    assert b"interrupted after" in err
    partial = io.load(out)  # valid contract, provenance
    assert partial.attrs["status"] == "partial"
    done = int(partial.attrs["cycles_done"])
    assert 0 < done < 30_000

    assert main([*run, "--out", str(out), "--resume"]) == 0
    full, resumed = io.load(ref), io.load(out)
    assert resumed.attrs["status"] == "complete"
    for name in ("wear_depth", "worn_volume", "normal_work", "update_dn", "update_rate_change"):
        np.testing.assert_array_equal(resumed[name].values, full[name].values)


def test_sigterm_is_handled_like_ctrl_c_and_the_partial_map_is_flagged(tmp_path, capsys):
    out = tmp_path / "w.nc"
    run = ["sim", "wear", *SMALL, "--scheme", "fixed", "--dn", "200", "--cycles", "3e5"]
    returncode, err = _interrupt(run, out, signal.SIGTERM, timeout=120)
    assert returncode == 143, err
    assert b"interrupted after" in err and b"Traceback" not in err
    partial = io.load(out)
    assert partial.attrs["status"] == "partial"
    done = int(partial.attrs["cycles_done"])
    assert 0 < done < 300_000

    assert main(["info", str(out)]) == 0
    text = capsys.readouterr().out
    assert f"status: PARTIAL result: the run stopped after {done:g} of 300000 cycles" in text
    # any command reading it says so too
    main(["sim", "calibrate-kw", str(out), "--max-depth-um", "1", "--linear"])
    assert f"warning: {out}: PARTIAL result" in capsys.readouterr().err
    # and a rerun without --resume does not silently replace it
    assert main([*run, "--out", str(out)]) == 3
    assert "--resume" in capsys.readouterr().err


def test_calibrate_kw_command_recovers_the_kw_of_a_run(tmp_path, capsys):
    base = ["sim", "wear", "--contact", "winkler", "--layers", "6", "--points", "48"]
    sim, truth = tmp_path / "sim.nc", tmp_path / "truth.nc"
    assert main([*base, "--kw", "1e-13", "--cycles", "3e4", "--out", str(sim)]) == 0
    assert main([*base, "--kw", "3e-13", "--cycles", "3e4", "--out", str(truth)]) == 0
    depth_um = float(io.load(truth)["max_wear_depth"][-1]) * 1e6
    capsys.readouterr()
    code = main(
        ["sim", "calibrate-kw", str(sim), "--max-depth-um", f"{depth_um:.6f}", "--rtol", "0.01"]
    )
    assert code == 0
    out = capsys.readouterr().out
    linear = float(out.split("kw (linear estimate): ")[1].split()[0])
    calibrated = float(out.split("re-simulations): ")[1].split()[0])
    assert abs(linear / 3e-13 - 1) > 0.05  # profile feedback: the linear guess is off
    assert calibrated == pytest.approx(3e-13, rel=0.03)
    assert "data used: max_depth" in out and "at 30000 cycles" in out
    residual = float(out.split("residual of the last re-simulation: ")[1].split()[0])
    assert abs(residual) <= 1.0
    assert main(["sim", "calibrate-kw", str(sim)]) == 3
    assert "give one measurement" in capsys.readouterr().err


def test_a_failing_simulation_leaves_partial_output_and_checkpoint(tmp_path, monkeypatch, capsys):
    from jointwear.errors import SimulationError
    from jointwear.sim.wear import _files as cli_wear  # the CLI's library side

    real = cli_wear.demo_winkler_contact

    class Failing:
        def __init__(self, grid):
            self.inner = real(grid)
            self.grid = self.inner.grid
            self.calls = 0

        def describe(self):
            return self.inner.describe()

        def run(self, wear_depth, *, cycles, state, progress=None):
            self.calls += 1
            if self.calls > 8:
                raise SimulationError("simulation stopped at t = 1 s: the step size collapsed")
            return self.inner.run(wear_depth, cycles=cycles, state=state)

    monkeypatch.setattr(cli_wear, "demo_winkler_contact", Failing)
    out = tmp_path / "w.nc"
    code = main(["sim", "wear", *SMALL, "--cycles", "1e5", "--out", str(out)])
    assert code == 3
    err = capsys.readouterr().err
    assert "step size collapsed" in err and "wear map so far" in err
    partial = io.load(out)
    assert partial.attrs["status"] == "partial"
    assert (tmp_path / "w.nc.ckpt").exists()


def test_help_states_the_default_kw(capsys):
    from jointwear.sim import DEFAULT_KW

    assert main(["sim", "wear", "--help"]) == 0
    assert f"default {DEFAULT_KW:g}" in capsys.readouterr().out


def test_calibrate_kw_command_with_several_snapshots_reports_each_residual(tmp_path, capsys):
    base = ["sim", "wear", "--contact", "winkler", "--layers", "6", "--points", "48"]
    base += ["--snapshots", "1e4,3e4", "--cycles", "3e4"]
    sim, truth = tmp_path / "sim.nc", tmp_path / "truth.nc"
    assert main([*base, "--kw", "1e-13", "--out", str(sim)]) == 0
    assert main([*base, "--kw", "3e-13", "--out", str(truth)]) == 0
    t = io.load(truth)
    d1, d2 = (float(t["max_wear_depth"].sel(cycles=c)) * 1e6 for c in (1e4, 3e4))
    capsys.readouterr()
    args = ["sim", "calibrate-kw", str(sim), "--max-depth-um", f"{d1:.6f}@1e4"]
    assert main([*args, "--max-depth-um", f"{d2:.6f}@3e4"]) == 0
    out = capsys.readouterr().out
    assert "data used (2 snapshot(s))" in out
    assert "max_depth" in out and "at 10000 cycles" in out and "at 30000 cycles" in out
    assert out.count("residual") == 2 and "left out, predicted" in out
    kw = float(out.split("kw (calibrated): ")[1].split()[0])
    assert kw == pytest.approx(3e-13, rel=0.03)
    assert main([*args, "--max-depth-um", "x@3e4"]) == 3
    assert "--max-depth-um 'x@3e4'" in capsys.readouterr().err
    assert main([*args, "--vary", "tilt=0:1", "--max-depth-um", f"{d2:.6f}@3e4"]) == 3
    assert "NAME must be a dotted parameter name" in capsys.readouterr().err
    assert main([*args, "--vary", "mechanism.joint_offset=0:0.02"]) == 3
    assert "at least two measured snapshots" in capsys.readouterr().err
    assert (
        main([*args, "--max-depth-um", f"{d2:.6f}@3e4", "--vary", "mechanism.joint_offset=0:0.02"])
        == 3
    )
    assert "prescribed contact model" in capsys.readouterr().err


def test_noise_limited_rig_finishes_and_says_how_accurate_it_is(tmp_path, capsys):
    toml = tmp_path / "rig.toml"
    toml.write_text("[mechanism]\ncrank_speed_rpm = 60.0\n\n" + NOISE_LIMITED_TOML)
    out = tmp_path / "w.nc"
    assert main(["sim", "wear", "--cycles", "4000", "--out", str(out), "--params", str(toml)]) == 0
    cap = capsys.readouterr()
    assert cap.err.count("cycle-to-cycle noise") == 1  # said once, with the fix
    assert "set tol = " in cap.err
    assert "warning: " in cap.err and "tol = 0.05" in cap.err
    assert "accuracy not reached, k = 2" in cap.out and " ± " in cap.out
    ds = io.load(out)
    assert ds.attrs["accuracy_status"] == "not reached"
    assert float(ds["max_wear_depth_u"][-1]) > 0
