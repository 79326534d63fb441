"""Calibration data never validate: compare refuses them, or labels a calibration check."""

from __future__ import annotations

import hashlib
import json

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from jointwear.compare.calibration_use import (
    CALIBRATION_CHECK,
    as_calibration_check,
    calibration_reuse,
    split_prediction,
)
from jointwear.compare.comparison import Comparison
from jointwear.errors import BadInputError


def _posterior_record(path, inputs=()) -> dict:
    return {
        "path": str(path),
        "sha256": hashlib.sha256(path.read_bytes()).hexdigest(),
        "inputs_sha256": sorted(inputs),
    }


def _prediction(records) -> xr.Dataset:
    return xr.Dataset(attrs={"calibration_data": json.dumps(records)})


def test_the_calibration_file_itself_is_refused_and_another_is_not(tmp_path):
    cal, other = tmp_path / "wear-2e5.nc", tmp_path / "wear-4e5.nc"
    cal.write_bytes(b"the 2e5 map")
    other.write_bytes(b"the 4e5 map")
    pred = _prediction([_posterior_record(cal)])
    with pytest.raises(BadInputError, match="calibration data never validate") as e:
        calibration_reuse([pred], [cal], calibration_check=False)
    assert "wear-2e5.nc is the calibration data" in str(e.value)
    assert "--calibration-check" in str(e.value)
    assert calibration_reuse([pred], [other], calibration_check=False) == []
    used = calibration_reuse([pred], [cal], calibration_check=True)
    assert len(used) == 1 and "wear-2e5.nc" in used[0]
    # a simulation without a posterior behind it never refuses anything
    assert calibration_reuse([xr.Dataset()], [cal], calibration_check=False) == []


def test_the_same_snapshot_processed_again_is_refused(tmp_path):
    from jointwear import io

    def saved(name, inputs, depth=0.0):
        ds = xr.Dataset(
            {"wear_depth": (("z", "theta"), np.full((2, 4), depth), {"units": "m"})},
            coords={"z": ("z", [0.0, 1e-3], {"units": "m"})},
            attrs={"data_origin": "synthetic"},
        )
        path = tmp_path / name
        io.save(ds, path, inputs=inputs, validate=False)
        return path

    scans = [tmp_path / "worn.txt", tmp_path / "before.txt"]
    for s in scans:
        s.write_text(s.stem)
    first = saved("map-a.nc", scans)
    again = saved("map-b.nc", scans, 1e-9)  # another file, made from the same scans
    newer = tmp_path / "worn-later.txt"
    newer.write_text("later")
    later = saved("map-c.nc", [newer, scans[1]])  # same before-scan, another worn snapshot
    inputs = [hashlib.sha256(s.read_bytes()).hexdigest() for s in scans]
    pred = _prediction([_posterior_record(first, inputs)])
    with pytest.raises(BadInputError, match="is made from the same scans as"):
        calibration_reuse([pred], [again], calibration_check=False)
    assert calibration_reuse([pred], [later], calibration_check=False) == []


def test_a_calibration_check_never_counts_as_validation():
    from jointwear.compare._decide import DECISION_COLUMNS

    row = {
        "quantity": "maximum wear depth",
        "criterion": "|E| <= U_val",
        "value": "E = 0",
        "state": "pass",
        "basis": "V&V 20",
        "passed": True,
        "key": "max_wear_depth",
    }
    decisions = pd.DataFrame([{c: row.get(c, "") for c in DECISION_COLUMNS}])
    c = Comparison(wear=None, motion=None, metrics=pd.DataFrame(), decisions=decisions)
    assert c.passed
    check = as_calibration_check(c, ["wear-2e5.nc is the calibration data wear-2e5.nc"])
    assert not check.passed and not check.any_failed
    assert check.summary().startswith(CALIBRATION_CHECK)
    assert check.decisions["quantity"].iloc[0].startswith(CALIBRATION_CHECK)
    assert any("wear-2e5.nc" in n for n in check.notes)
    assert check.to_dataset().attrs["validation_passed"] == 0


def test_a_prediction_splits_into_its_mean_map_and_its_ensemble():
    runs = np.stack([np.full((2, 3), v) for v in (1e-6, 3e-6, 99.0)])
    ds = xr.Dataset(
        {
            "wear_depth": (("run", "z", "theta"), runs, {"units": "m"}),
            "status": ("run", np.array([0, 0, 1], dtype=np.int8)),
        },
        coords={"z": [0.0, 1e-3], "theta": [0.0, 120.0, 240.0]},
        attrs={"jointwear_file": "posterior_prediction", "cycles": 4e5, "bearing_radius_m": 8e-3},
    )
    sim, ens = split_prediction(ds)
    assert sim["wear_depth"].dims == ("cycles", "z", "theta")
    assert float(sim["cycles"][0]) == 4e5
    np.testing.assert_allclose(sim["wear_depth"].values, 2e-6)  # the failed run is left out
    assert ens is ds
    with pytest.raises(BadInputError, match="1 finished run"):
        split_prediction(ds.assign(status=("run", np.array([0, 1, 1], dtype=np.int8))))
