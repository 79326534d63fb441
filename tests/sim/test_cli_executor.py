"""``--workers`` and ``--scheduler`` of the commands that run sweeps of dask tasks."""

from __future__ import annotations

import pytest

from jointwear.cli import main


@pytest.mark.parametrize(
    "command", [["sim", "sweep", "{spec}"], ["sim", "verify", "--cycles", "10"]]
)
def test_workers_with_a_scheduler_is_refused_before_anything_runs(command, tmp_path, capsys):
    # each names where the runs go (local processes or a cluster): the address is never contacted
    spec = tmp_path / "spec.toml"
    spec.write_text("[sweep]\n")
    out = tmp_path / "out.nc"
    argv = [a.format(spec=spec) for a in command]
    code = main([*argv, "--out", str(out), "--workers", "1", "--scheduler", "tcp://127.0.0.1:9"])
    assert code == 3
    assert "give --workers or --scheduler, not both" in capsys.readouterr().err
    assert not out.exists()
