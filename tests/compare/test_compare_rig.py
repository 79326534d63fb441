"""A verification study or an ensemble of another rig is refused (or allowed, labelled)."""

from __future__ import annotations

import json

import _jw_synth as syn
import numpy as np
import pytest
import xarray as xr

from jointwear import io
from jointwear.cli import main
from jointwear.compare import Criteria, compare
from jointwear.compare.rig import check_rig, rig_differences, rig_parameters
from jointwear.errors import BadInputError
from jointwear.params import to_jsonable
from jointwear.sim import SimParameters, WearSettings


def _record(**joint) -> dict:
    sim = to_jsonable(SimParameters())
    sim["joint"].update(joint)
    return sim


def _sim(**joint) -> xr.Dataset:
    """The synthetic simulated map with the provenance ``jointwear sim wear`` writes."""
    ds = syn.sim_wear()
    params = {
        "wear": to_jsonable(WearSettings()),
        "contact": {"model": "dynamics", "parameters": _record(**joint)},
    }
    ds.attrs["provenance"] = json.dumps({"parameters": params})
    return ds


def _ensemble(varied: str = "wear.kw", **joint) -> xr.Dataset:
    """A 6-run ensemble of the max depth recording its base rig as ``jointwear sim sweep``."""
    depth = 32e-6 * (1 + 0.05 * np.array([-1.0, -0.5, 0.0, 0.3, 0.6, 1.0]))
    ds = xr.Dataset(
        {"max_wear_depth": ("run", depth, {"units": "m", "long_name": "max depth"})},
        coords={"run": np.arange(6), varied: ("run", np.linspace(1, 2, 6), {"units": "1"})},
        attrs={"cycles": 4e5, "sweep_parameters": [varied]},
    )
    base = {"parameters": _record(**joint), "wear": to_jsonable(WearSettings())}
    ds.attrs["provenance"] = json.dumps({"parameters": {"spec": {}, "base": base}})
    return ds


def test_rig_parameters_read_from_each_files_record():
    got = rig_parameters(_sim(tilt_stiffness=1000.0))
    assert got["joint.tilt_stiffness"] == 1000.0 and got["wear.kw"] == WearSettings().kw
    study = xr.Dataset(attrs={"parameters_json": json.dumps({"parameters": _record()})})
    assert rig_parameters(study)["joint.tilt_stiffness"] == 0.0
    assert rig_parameters(syn.sim_wear()) is None  # records nothing


def test_numerics_and_sampled_parameters_are_not_differences():
    a = rig_parameters(_sim())
    b = dict(a, **{"joint.n_layers": 40, "mechanism.initial_crank_angle_deg": 90.0})
    assert rig_differences(a, b) == []
    c = dict(a, **{"joint.bearing_radius": a["joint.bearing_radius"] + 1e-4})
    assert [k for k, *_ in rig_differences(a, c)] == ["joint.bearing_radius"]
    assert rig_differences(a, c, varied=["joint.radial_clearance"]) == []


def test_ensemble_of_another_rig_refused_named_and_allowed_labelled():
    sim, meas = _sim(), syn.meas_wear(u=1e-6, n_layers=16)
    crit = Criteria(wear_u_num_rel=0.02)
    same = compare(sim, meas, ensemble=_ensemble(), criteria=crit)
    assert same.state("maximum wear depth") in ("pass", "fail")
    assert not any("rig" in n for n in same.notes)
    other = _ensemble(tilt_stiffness=1000.0)
    with pytest.raises(BadInputError, match=r"joint\.tilt_stiffness: simulation 0, .* 1000"):
        compare(sim, meas, ensemble=other, criteria=crit)
    allowed = compare(sim, meas, ensemble=other, criteria=crit, allow_other_rig=True)
    assert any("ANOTHER RIG" in n and "tilt_stiffness" in n for n in allowed.notes)
    # the ensemble samples the wear coefficient: its kw is not a difference
    assert check_rig(sim, _ensemble(varied="wear.kw"), "ensemble") == ""
    # a simulation that records nothing: not checked, said so
    note = check_rig(syn.sim_wear(), other, "ensemble 'e'")
    assert "not checked" in note and "the simulation records no simulator parameters" in note


def test_cli_refuses_another_rig_and_the_suggested_option_runs(tmp_path, capsys):
    paths = {}
    for name, ds in {
        "sim": _sim(),
        "meas": syn.meas_wear(u=1e-6, n_layers=16),
        "ens": _ensemble(tilt_stiffness=1000.0),
    }.items():
        paths[name] = tmp_path / f"{name}.nc"
        stated = json.loads(ds.attrs.pop("provenance", "{}")).get("parameters")
        io.save(ds, paths[name], parameters=stated)  # its provenance records them
    argv = ["compare", str(paths["sim"]), str(paths["meas"]), "-o", str(tmp_path / "m.nc")]
    argv += ["--ensemble", str(paths["ens"])]
    assert main(argv) == 3
    err = capsys.readouterr().err
    assert "another rig" in err and "tilt_stiffness" in err and "--allow-other-rig" in err
    assert main([*argv, "--allow-other-rig"]) in (0, 1)
    assert "ANOTHER RIG" in capsys.readouterr().out
