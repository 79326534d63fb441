"""`dic correlate` of an image pair writes its netCDF from the correlator's xarray-free Record
(jointwear._netcdf.write_record): the file must be the one jointwear.io.save writes of the
library's Dataset - same variables, values, dtypes, encoding and attributes - for a grid, for
--points and for a result with flagged (NaN) points."""

from __future__ import annotations

import json

import cv2
import netCDF4
import numpy as np
import pytest
import xarray as xr

import jointwear.provenance
from jointwear import io
from jointwear._netcdf import Record, Variable, write_record
from jointwear._version import source_attribute
from jointwear.cli import main
from jointwear.datasets import speckle as sp
from jointwear.dic import SubsetCorrelator
from jointwear.dic.subset._files import correlate_files
from jointwear.dic.subset._params import CorrelationParams
from jointwear.dic.subset._sequence import read_image
from jointwear.errors import BadInputError

STAMP = "2000-01-01T00:00:00Z"


@pytest.fixture(autouse=True)
def _fixed_clock(monkeypatch):
    # history and provenance carry the time of writing: fixed, so that the two files of a
    # comparison agree in every attribute (nothing is excluded from the comparison)
    monkeypatch.setattr(jointwear.provenance, "utc_now", lambda: STAMP)


def _pair(tmp_path, *, flagged: bool = False) -> tuple:
    pair = sp.speckle_pair((96, 112), sp.RigidField((1.3, -0.6)), seed=5)
    ref, dfm = pair.reference.copy(), pair.deformed.copy()
    if flagged:
        ref[:40, :40] = ref[:40, :40].mean()  # no texture: flagged no_texture, NaN u, v
        rng = np.random.default_rng(1)  # another pattern: flagged by the correlation
        dfm[60:, 70:] = rng.permutation(dfm[60:, 70:].ravel()).reshape(dfm[60:, 70:].shape)
    names = tmp_path / "ref.png", tmp_path / "def.png"
    for name, img in zip(names, (ref, dfm), strict=True):
        assert cv2.imwrite(str(name), img)
    return names


def _raw(path) -> dict:
    """Everything netCDF4 reads of a file: dimensions, variables (dtype, dims, chunking,
    filters, attributes with their types, values) and global attributes, in file order."""

    def attrs(obj) -> list:
        out = []
        for k in obj.ncattrs():
            v = obj.getncattr(k)
            out.append((k, type(v).__name__, np.asarray(v).dtype.str, repr(np.asarray(v).tolist())))
        return out

    with netCDF4.Dataset(path) as nc:
        nc.set_auto_mask(False)  # the stored values, fill values included
        return {
            "data_model": nc.data_model,
            "dims": [(d.name, d.size, d.isunlimited()) for d in nc.dimensions.values()],
            "vars": [
                (
                    name,
                    v.dtype.str,
                    v.dimensions,
                    v.chunking(),
                    v.filters(),
                    v.endian(),
                    attrs(v),
                    v[...].tobytes(),
                )
                for name, v in nc.variables.items()
            ],
            "attrs": attrs(nc),
        }


def _assert_same_file(fast, slow) -> None:
    with xr.open_dataset(fast) as a, xr.open_dataset(slow) as b:
        xr.testing.assert_identical(a, b)
        assert list(a.variables) == list(b.variables)
    ra, rb = _raw(fast), _raw(slow)
    for key in ra:
        assert ra[key] == rb[key], key


@pytest.mark.parametrize("case", ["grid", "points", "flagged", "quadratic_roi"])
def test_pair_file_is_the_one_save_writes_of_the_library_dataset(tmp_path, case):
    ref, dfm = _pair(tmp_path, flagged=case == "flagged")
    options = {"subset_size": 21, "step": 12, "threads": 1}
    where: dict = {}
    if case == "points":
        where["points"] = np.array([[30.0, 40.0], [50.5, 47.25], [70.0, 60.0], [3.0, 3.0]])
    if case == "quadratic_roi":
        options["shape"] = "quadratic"
        where["roi"] = (10, 12, 100, 80)
    params = CorrelationParams(**options)
    fast, slow = tmp_path / "fast.nc", tmp_path / "slow.nc"
    record, _ = correlate_files(ref, dfm, fast, params=params, **where)
    assert isinstance(record, Record)  # the pair went the xarray-free way

    # the old way: the library's Dataset, saved by jointwear.io.save
    ds = SubsetCorrelator(read_image(ref), params=params, **where).correlate(read_image(dfm))
    ds.attrs["data_origin"] = "measured"  # what correlate_files states by default
    inputs = [ref, dfm]
    io.save(ds, slow, inputs=inputs, parameters=params, source=source_attribute("dic.correlate"))
    _assert_same_file(fast, slow)

    back = io.load(fast)  # the contract holds, with provenance
    flag = back["flag"].values
    assert json.loads(back.attrs["provenance"])["created"] == STAMP
    if case == "points":
        assert back.sizes == {"point": 4}
        with netCDF4.Dataset(fast) as nc:  # CF: x, y are the points' auxiliary coordinates
            assert nc["u"].getncattr("coordinates") == "x y"
        assert flag[3] != 0 and np.isnan(back["u"].values[3])  # (3, 3): off the image
        np.testing.assert_allclose(back["u"].values[:3], 1.3, atol=0.02)
    if case == "flagged":
        bad = flag != 0
        assert bad.sum() >= 4 and (~bad).sum() >= 4
        assert {1, 2, 4} & set(np.unique(flag))  # correlation and texture flags
        assert np.isnan(back["u"].values[bad]).all() and np.isfinite(back["u"].values[~bad]).all()
    if case == "quadratic_roi":
        assert "d2u_dx2" in back


def test_write_record_is_atomic_and_refuses_a_folder(tmp_path):
    coords = {"x": Variable(("x",), np.arange(3.0), {"units": "m", "long_name": "x"})}
    rec = Record({"a": Variable(("x",), np.arange(3.0), {"units": "m", "long_name": "a"})}, coords)
    out = tmp_path / "r.nc"
    out.write_text("previous")
    broken = Record({"b": Variable(("x",), np.array([{}, {}, {}]))}, coords)  # not netCDF
    with pytest.raises(TypeError, match="'b' is object"):
        write_record(broken, out)
    assert out.read_text() == "previous"  # the failed write left the previous file
    assert [f.name for f in tmp_path.iterdir()] == ["r.nc"]  # and no temporary file
    with pytest.raises(ValueError, match="dims"):
        Variable(("x", "y"), np.zeros(2))
    (tmp_path / "d.nc").mkdir()
    with pytest.raises(BadInputError, match="folder"):
        write_record(rec, tmp_path / "d.nc")
    write_record(rec, out)
    back = io.load(out)
    np.testing.assert_array_equal(back["a"].values, [0.0, 1.0, 2.0])
    assert back["a"].attrs["units"] == "m" and "provenance" in back.attrs


def test_command_summary_and_figure_from_the_record(tmp_path, capsys):
    ref, dfm = _pair(tmp_path, flagged=True)
    out, fig = tmp_path / "c.nc", tmp_path / "c.png"
    args = ["dic", "correlate", str(ref), str(dfm), "--subset", "21", "--step", "12"]
    assert main([*args, "--out", str(out), "--plot", str(fig)]) == 0
    text = capsys.readouterr().out
    ds = io.load(out)
    ok = ds["flag"].values == 0
    median = float(np.median(ds["zncc"].values[ok]))
    assert f"{ok.sum()}/{ok.size} points ok, median ZNCC {median:.4f}" in text
    assert fig.stat().st_size > 1000


def test_the_file_says_what_the_images_are(tmp_path, capsys):
    """data_origin: measured by default, synthetic on request; anything else is refused before
    any work, naming --origin."""
    ref, dfm = _pair(tmp_path)
    args = ["dic", "correlate", str(ref), str(dfm), "--subset", "21", "--step", "24"]
    assert main([*args, "--out", str(tmp_path / "m.nc")]) == 0
    assert io.load(tmp_path / "m.nc").attrs["data_origin"] == "measured"
    assert main([*args, "--out", str(tmp_path / "s.nc"), "--origin", "synthetic"]) == 0
    assert io.load(tmp_path / "s.nc").attrs["data_origin"] == "synthetic"
    capsys.readouterr()
    assert main([*args, "--out", str(tmp_path / "x.nc"), "--origin", "simulated"]) == 3
    assert "--origin" in capsys.readouterr().err
    assert not (tmp_path / "x.nc").exists()
