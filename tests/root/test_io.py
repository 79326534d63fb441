"""Atomic netCDF save/load with units, conventions and provenance."""

from __future__ import annotations

import hashlib
import json
import os

import numpy as np
import pytest
import xarray as xr

from jointwear import conventions as C
from jointwear import io
from jointwear.errors import BadInputError, ConventionError


def _dataset(seed=0):
    rng = np.random.default_rng(seed)
    ds = xr.Dataset(
        {
            "wear_depth": (
                ("z", "theta"),
                rng.random((3, 8)) * 1e-5,
                C.variable_attrs("wear_depth"),
            ),
            "contact_force": ("time", rng.random(5) * 100, C.variable_attrs("contact_force")),
        },
        coords={
            "z": C.z_coord([-5e-3, 0.0, 5e-3]),
            "theta": C.theta_coord(
                np.arange(8) * 45.0, C.AngleConvention("+y", "counterclockwise")
            ),
            "time": ("time", np.linspace(0, 0.5, 5), {"units": "s", "long_name": "time"}),
        },
    )
    ds.attrs["settings"] = {"grid": [20, 200], "ok": True}
    ds.attrs["checked"] = False
    return ds


def test_round_trip_values_units_conventions_provenance(tmp_path):
    src = tmp_path / "input.txt"
    src.write_text("some measured data\n")
    path = tmp_path / "out.nc"
    ds = _dataset()
    io.save(
        ds,
        path,
        inputs=[src],
        parameters={"kw": 1.5e-14, "nested": {"n": 3}},
        command="jointwear sim wear --cycles 10",
        source="jointwear test",
    )
    back = io.load(path)
    np.testing.assert_array_equal(back.wear_depth.values, ds.wear_depth.values)
    np.testing.assert_array_equal(back.contact_force.values, ds.contact_force.values)
    assert back.wear_depth.attrs["units"] == "m"
    assert back.contact_force.attrs["units"] == "N"
    assert back.theta.attrs["angle_zero"] == "+y"
    assert back.theta.attrs["angle_direction"] == "counterclockwise"
    assert back.z.attrs["z_zero"] == "bearing mid-width"
    # non-netCDF attribute types survive
    assert back.attrs["settings"] == {"grid": [20, 200], "ok": True}
    assert back.attrs["checked"] is False
    assert back.attrs["Conventions"] == "CF-1.11"
    assert back.attrs["source"] == "jointwear test"
    assert "jointwear sim wear --cycles 10" in back.attrs["history"]
    prov = json.loads(back.attrs["provenance"])
    assert prov["parameters"] == {"kw": 1.5e-14, "nested": {"n": 3}}
    assert prov["inputs"][0]["sha256"] == hashlib.sha256(src.read_bytes()).hexdigest()
    assert prov["software"]["jointwear"]
    assert prov["command"] == "jointwear sim wear --cycles 10"


def test_history_is_appended(tmp_path):
    p1, p2 = tmp_path / "a.nc", tmp_path / "b.nc"
    io.save(_dataset(), p1, command="step one")
    io.save(io.load(p1), p2, command="step two")
    lines = io.load(p2).attrs["history"].splitlines()
    assert len(lines) == 2 and lines[0].endswith("step one") and lines[1].endswith("step two")
    prov = json.loads(io.load(p2).attrs["provenance"])
    assert prov["parents"][0]["command"] == "step one"


def test_crash_during_save_leaves_previous_file_intact(tmp_path, monkeypatch):
    path = tmp_path / "result.nc"
    io.save(_dataset(seed=1), path)
    before = path.read_bytes()

    def crashing_to_netcdf(self, target, *args, **kwargs):
        with open(target, "wb") as fh:
            fh.write(b"CDF\x01 half-written")
        raise RuntimeError("simulated crash while writing")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", crashing_to_netcdf)
    with pytest.raises(RuntimeError, match="simulated crash"):
        io.save(_dataset(seed=2), path)
    assert path.read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == ["result.nc"]  # no temporary file left behind
    monkeypatch.undo()
    np.testing.assert_array_equal(
        io.load(path).wear_depth.values, _dataset(seed=1).wear_depth.values
    )


def test_save_refuses_dataset_without_units(tmp_path):
    ds = _dataset()
    del ds["contact_force"].attrs["units"]
    with pytest.raises(ConventionError, match="'contact_force' has no 'units'"):
        io.save(ds, tmp_path / "x.nc")
    assert not (tmp_path / "x.nc").exists()


def test_load_errors_name_the_file(tmp_path):
    with pytest.raises(BadInputError, match="missing.nc' does not exist"):
        io.load(tmp_path / "missing.nc")
    garbage = tmp_path / "garbage.nc"
    garbage.write_bytes(os.urandom(256))
    with pytest.raises(BadInputError, match="garbage.nc' could not be read as netCDF"):
        io.load(garbage)


def test_check_writable_fails_early(tmp_path):
    blocker = tmp_path / "a_file"
    blocker.write_text("x")
    with pytest.raises(BadInputError, match="not writable"):
        io.check_writable(blocker / "sub" / "out.nc")
    with pytest.raises(BadInputError, match="is a folder"):
        io.check_writable(tmp_path)


def test_atomic_path_other_file_types(tmp_path):
    target = tmp_path / "report.html"
    with io.atomic_path(target) as tmp:
        tmp.write_text("<html></html>")
        assert not target.exists()
    assert target.read_text() == "<html></html>"
    with pytest.raises(ValueError), io.atomic_path(target) as tmp:
        tmp.write_text("broken")
        raise ValueError("boom")
    assert target.read_text() == "<html></html>"


def test_written_files_get_normal_permissions(tmp_path):
    path = tmp_path / "perm.nc"
    io.save(_dataset(), path)
    umask = os.umask(0)
    os.umask(umask)
    assert (path.stat().st_mode & 0o777) == (0o666 & ~umask)


def test_input_digests_follow_file_changes_and_patterns(tmp_path):
    from jointwear.provenance import build_provenance, sha256_file

    f = tmp_path / "frame_0001_0.png"
    f.write_bytes(b"a" * 100)
    assert sha256_file(f) == hashlib.sha256(b"a" * 100).hexdigest()
    # same size, new content and modification time: hashed again, not taken from the memo
    f.write_bytes(b"b" * 100)
    os.utime(f, ns=(1, 2_000_000_000))
    assert sha256_file(f) == hashlib.sha256(b"b" * 100).hexdigest()
    # a glob pattern (one camera's images in a shared folder) records its matched files
    (tmp_path / "frame_0001_1.png").write_bytes(b"c")
    rec = build_provenance(inputs=[tmp_path / "*_0.png"])["inputs"][0]
    assert rec["files"] == 1
    expected = hashlib.sha256(b"frame_0001_0.png" + sha256_file(f).encode()).hexdigest()
    assert rec["sha256"] == expected
