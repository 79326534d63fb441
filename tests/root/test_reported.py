"""The reported-measurement schema: uncertainty rules, conventions, refusals naming the field."""

from __future__ import annotations

import copy
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from jointwear import io
from jointwear.cli import main
from jointwear.errors import ParameterError
from jointwear.params import read_toml
from jointwear.reported import read_reported, reported_dataset

EXAMPLE = Path(__file__).parents[2] / "datasets" / "data" / "zhang2023_reported.toml"


def base() -> dict:
    """A small valid file: one cylindricity pair and one angle."""
    return {
        "schema": "jointwear.reported/1",
        "source": {"citation": "a lab sheet", "table": "1"},
        "layers": {"count": 5, "spacing": "1 mm", "z_centre": "0 mm", "first": "+z"},
        "angle": {"zero": "-x", "direction": "clockwise"},
        "quantity": {
            "cyl_new": {
                "kind": "cylindricity",
                "value": 5.0,
                "unit": "um",
                "cycles": 0,
                "layers": "all",
                "reference": "LS",
                "source": "table 1",
                "uncertainty": {"standard": 0.1},
            },
            "angle": {
                "kind": "max_wear_angle",
                "value": 90.0,
                "unit": "degree",
                "cycles": 1e5,
                "layer": 1,
                "source": "fig. 2",
                "uncertainty": {"figure_reading": "6 degree"},
            },
        },
    }


def test_uncertainty_rules_closed_forms():
    data = base()
    data["quantity"]["cyl_new"]["uncertainty"] = {
        "accuracy": "0.03 um",
        "resolution": 0.01,  # in the quantity's unit (um)
        "expanded": "0.2 um",
        "k": 2,
    }
    ds = reported_dataset(data)
    expected = math.sqrt((0.03 / math.sqrt(3)) ** 2 + (0.01 / math.sqrt(12)) ** 2 + 0.1**2)
    assert float(ds["cyl_new_u"]) == pytest.approx(expected * 1e-6, rel=1e-12)
    assert float(ds["cyl_new"]) == pytest.approx(5e-6)
    assert ds["cyl_new_u"].attrs["coverage_factor"] == 1.0
    budget = json.loads(ds["cyl_new_u"].attrs["uncertainty_budget"])
    assert {b["component"] for b in budget} == {"accuracy", "resolution", "expanded"}
    # a figure reading +-6 degree is rectangular: 6/sqrt(3)
    assert float(ds["angle_u"]) == pytest.approx(6 / math.sqrt(3))


def test_not_stated_is_nan_never_zero():
    data = base()
    data["quantity"]["angle"]["uncertainty"] = {"not_stated": True}
    ds = reported_dataset(data)
    assert np.isnan(float(ds["angle_u"]))


@pytest.mark.parametrize(
    ("zero", "direction", "reported", "canonical"),
    [
        ("-x", "clockwise", 90.0, 90.0),  # canonical itself
        ("-x", "counterclockwise", 90.0, 270.0),  # mirrored
        ("+x", "clockwise", 0.0, 180.0),  # +x is 180 degree from -x
        ("+y", "counterclockwise", 0.0, 90.0),  # +y: canonical 90 (clockwise from -x)
        ("+y", "counterclockwise", 90.0, 0.0),  # +y ccw by 90 = -x
    ],
)
def test_angle_in_another_convention_is_converted(zero, direction, reported, canonical):
    data = base()
    data["angle"] = {"zero": zero, "direction": direction}
    data["quantity"]["angle"]["value"] = reported
    ds = reported_dataset(data)
    assert float(ds["angle"]) == pytest.approx(canonical)
    assert ds["angle"].attrs["angle_zero"] == "-x"
    assert ds["angle"].attrs["angle_direction"] == "clockwise"
    assert ds["angle"].attrs["reported_value"] == reported


def _broken(path: list[str], value=None, delete=False) -> dict:
    data = copy.deepcopy(base())
    node = data
    for key in path[:-1]:
        node = node[key]
    if delete:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return data


@pytest.mark.parametrize(
    ("path", "value", "delete", "match"),
    [
        (["quantity", "cyl_new", "unit"], None, True, r"quantity\.cyl_new\.unit is missing"),
        (["quantity", "cyl_new", "cycles"], None, True, r"quantity\.cyl_new\.cycles is missing"),
        (["quantity", "cyl_new", "source"], None, True, r"quantity\.cyl_new\.source is missing"),
        (["quantity", "angle", "uncertainty"], None, True, r"quantity\.angle\.uncertainty"),
        (["quantity", "cyl_new", "reference"], None, True, r"cyl_new\.reference is missing"),
        (["quantity", "cyl_new", "referense"], "LS", False, r"cyl_new\.referense is not a field"),
        (["quantity", "cyl_new", "unit"], "degree", False, r"'degree' is not a unit of length"),
        (["quantity", "angle", "unit"], "um", False, r"'um' is not a unit of angle"),
        (["quantity", "cyl_new", "kind"], "roundnes", False, r"kind = 'roundnes' is not known"),
        (["quantity", "angle", "layer"], 6, False, r"angle\.layer = 6: a layer number 1\.\.5"),
        (
            ["quantity", "cyl_new", "uncertainty"],
            {"expanded": 1},
            False,
            r"uncertainty\.k is missing",
        ),
        (["quantity", "cyl_new", "uncertainty"], {}, False, r"states no component"),
        (["quantity", "cyl_new", "uncertainty"], {"accuracy": "0.1 deg"}, False, r"accuracy"),
        (["layers", "first"], None, True, r"layers\.first is missing"),
        (["angle", "direction"], "cw?", False, r"angle_direction 'cw\?' is not understood"),
        (["source"], None, True, r"source is missing"),
        (["schema"], "jointwear.reported/9", False, r"schema"),
    ],
)
def test_schema_errors_name_the_field(path, value, delete, match):
    with pytest.raises(ParameterError, match=match):
        reported_dataset(_broken(path, value, delete))


def test_angle_without_convention_is_refused():
    data = base()
    del data["angle"]
    with pytest.raises(ParameterError, match=r"needs the \[angle\] table"):
        reported_dataset(data)


def test_example_file_holds_the_papers_numbers():
    ds = read_reported(EXAMPLE)
    um = {
        n: float(ds[n]) * 1e6
        for n in ("cylindricity_new", "cylindricity_4e5", "cylindricity_1_2e6")
    }
    assert um == pytest.approx(
        {"cylindricity_new": 5.02, "cylindricity_4e5": 33.34, "cylindricity_1_2e6": 46.57}
    )
    assert [ds[n].attrs["cycles"] for n in um] == [0.0, 4e5, 1.2e6]
    # the Talyrond's 0.03 um accuracy (rectangular) and the 0.01 um printed decimals
    u = math.sqrt((0.03 / math.sqrt(3)) ** 2 + (0.01 / math.sqrt(12)) ** 2) * 1e-6
    assert float(ds["cylindricity_4e5_u"]) == pytest.approx(u)
    assert float(ds["max_wear_angle_first_1_2e6"]) == 90.0
    assert float(ds["max_wear_angle_last_1_2e6"]) == 310.0
    assert ds["max_wear_angle_last_1_2e6"].attrs["layer"] == 13
    assert ds.attrs["layers_count"] == 13 and ds.attrs["layers_spacing_m"] == pytest.approx(1e-3)
    assert ds["max_wear_angle_first_1_2e6"].attrs["angle_direction"] == "unstated"
    assert ds.attrs["layers_first"] == "unstated"
    assert np.isnan(ds.attrs["layers_z_centre_m"])  # the paper does not say where the 13 lie


def test_cli_import_writes_measured_cf_file_with_source(tmp_path):
    out = tmp_path / "reported.nc"
    assert main(["import", "reported", str(EXAMPLE), "--out", str(out)]) == 0
    ds = io.load(out)
    assert ds.attrs["data_origin"] == "measured"
    assert "Zhang" in ds.attrs["source"]
    prov = json.loads(ds.attrs["provenance"])
    assert prov["parameters"]["reported"]["source"]["citation"].startswith("L. Zhang")
    assert prov["inputs"][0]["sha256"]
    assert float(ds["cylindricity_1_2e6"]) == pytest.approx(46.57e-6)


def test_cli_refuses_a_wrong_unit_with_exit_3(tmp_path, capsys):
    text = EXAMPLE.read_text().replace('value = 33.34\nunit = "um"', 'value = 33.34\nunit = "s"')
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    assert main(["import", "reported", str(bad), "--out", str(tmp_path / "x.nc")]) == 3
    err = capsys.readouterr().err
    assert "quantity.cylindricity_4e5.unit" in err and "'s' is not a unit of length" in err
    assert not (tmp_path / "x.nc").exists()


def test_cli_refuses_a_missing_field_with_exit_3(tmp_path, capsys):
    shutil.copy(EXAMPLE, tmp_path / "r.toml")
    data = read_toml(tmp_path / "r.toml")
    assert "cycles" in data["quantity"]["cylindricity_new"]
    text = (tmp_path / "r.toml").read_text().replace("cycles = 0\n", "", 1)
    (tmp_path / "r.toml").write_text(text)
    code = main(["import", "reported", str(tmp_path / "r.toml"), "--out", str(tmp_path / "x.nc")])
    assert code == 3
    assert "quantity.cylindricity_new.cycles is missing" in capsys.readouterr().err


def test_two_new_bore_baselines_are_refused():
    data = base()
    data["quantity"]["cyl_new2"] = dict(data["quantity"]["cyl_new"], value=5.5)
    with pytest.raises(
        ParameterError, match=r"cyl_new and quantity\.cyl_new2 are both the new bore"
    ):
        reported_dataset(data)


def test_angle_in_radians_is_converted():
    data = base()
    data["quantity"]["angle"].update(value=math.pi / 2, unit="rad")
    data["quantity"]["angle"]["uncertainty"] = {"figure_reading": 0.1}
    ds = reported_dataset(data)
    assert float(ds["angle"]) == pytest.approx(90.0)
    assert float(ds["angle_u"]) == pytest.approx(np.degrees(0.1) / math.sqrt(3))
