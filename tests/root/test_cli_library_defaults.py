"""One default per option: a command's option defaults, help and limits are the library's.

For each command below, every option is either mapped to the library default it stands for
(a parameter dataclass field or a keyword of the library function the command calls, with the
unit factor between them) or listed as having none; a default that drifts, or a new option left
unmapped, fails here. The library's values are read independently of the CLI (dataclass
fields, function signatures), never through the constants the CLI imports.
"""

from __future__ import annotations

import dataclasses
import inspect
import re
import subprocess
import sys
import typing
from typing import Any

import pytest
import typer
from typer.main import get_command

from jointwear.errors import ParameterError


def _params(fn) -> dict[str, Any]:
    app = typer.Typer(add_completion=False)
    app.command()(fn)
    return {p.name: p for p in get_command(app).params}


def _choices(param) -> tuple:
    return typing.get_args(param.type_descriptor.annotation)


def _fields(cls) -> dict:
    return {f.name: f.default for f in dataclasses.fields(cls)}


def _keywords(fn) -> dict:
    return {k: p.default for k, p in inspect.signature(fn).parameters.items()}


def _same(lib: dict, *names: str) -> dict:
    """Options named as the library's: ``name -> (lib[name], None)`` (every name of ``lib``
    when none are given)."""
    return {n: (lib[n], None) for n in (names or lib)}


def _renamed(lib: dict, **cli_to_lib: str) -> dict:
    """Options named otherwise: ``cli name -> (lib[library name], None)``."""
    return {cli: (lib[name], None) for cli, name in cli_to_lib.items()}


def _scaled(lib: dict, **cli_to_lib: tuple[str, float]) -> dict:
    """Options in other units: ``cli name -> (lib[library name], CLI units per library unit)``."""
    return {cli: (lib[name], per) for cli, (name, per) in cli_to_lib.items()}


def _stated(*names: str) -> dict:
    """Options whose default is None: the library's default applies, and the help states it."""
    return dict.fromkeys(names, (None, None))


def _check(fn, mapping: dict, without: set[str]) -> dict[str, Any]:
    """Every option of ``fn`` is in ``mapping`` (name -> (library default, CLI units per library
    unit)) or in ``without``; each mapped CLI default, converted the way the command converts it,
    is exactly the library's (so the command's default run is the library's default run)."""
    params = _params(fn)
    assert set(params) == set(mapping) | without, "map every option to its library default"
    for name, (lib, per) in mapping.items():
        cli = params[name].default
        if per is None:
            assert cli == lib, name
        elif isinstance(lib, tuple):
            assert tuple(c / per for c in cli) == lib, name
        else:
            assert cli / per == lib, name
    return params


def test_speckle_defaults_and_limits_are_the_librarys(tmp_path):
    from jointwear.datasets.cli_speckle import speckle_cmd
    from jointwear.datasets.speckle import SpeckleParams
    from jointwear.datasets.speckle_set import FIELDS, SpeckleMotion, write_speckle_set

    p, m, kw = _fields(SpeckleParams), _fields(SpeckleMotion), _keywords(write_speckle_set)
    mapping = _same(m) | _same(p, "speckle_size", "density", "contrast", "bit_depth")
    mapping |= _same(p, "noise_std", "blur_std") | _same(kw, "frames", "seed")
    params = _check(speckle_cmd, mapping, {"out", "overwrite", "size"})
    assert _choices(params["field"]) == FIELDS
    # the limits: the first value outside the CLI's range is the first the library refuses
    depth = params["bit_depth"]
    SpeckleParams(bit_depth=depth.max)
    with pytest.raises(ParameterError):
        SpeckleParams(bit_depth=depth.max + 1)
    with pytest.raises(ParameterError, match="PNG"):
        write_speckle_set(tmp_path, (8, 8), params=SpeckleParams(bit_depth=depth.min - 1))
    with pytest.raises(ParameterError, match="frames"):
        write_speckle_set(tmp_path, (8, 8), frames=params["frames"].min - 1)
    assert not any(tmp_path.iterdir())
    # the ranges the help states are the ones the library takes: "lo to hi" both included,
    # "(lo, hi]" the lower edge excluded
    stated = {
        "speckle_size": ("to", params["speckle_size"].help),
        "density": ("(", params["density"].help),
        "contrast": ("(", params["contrast"].help),
    }
    for name, (kind, text) in stated.items():
        if kind == "to":
            lo, hi = (float(v) for v in re.search(r"([\d.]+) to ([\d.]+)", text).groups())
        else:
            lo, hi = (float(v) for v in re.search(r"\(([\d.]+), ([\d.]+)\]", text).groups())
        SpeckleParams(**{name: hi})
        if kind == "to":
            SpeckleParams(**{name: lo})
        for outside in [lo - 0.5, hi + 0.5] if kind == "to" else [lo, hi * 1.01]:
            with pytest.raises(ParameterError, match=name):
                SpeckleParams(**{name: outside})


def test_instruments_defaults_are_the_librarys():
    from jointwear.datasets.cli_instruments import DELIMITERS, instruments_cmd
    from jointwear.datasets.instruments import ANGLE_COLUMNS, LAYOUTS, generate, write
    from jointwear.datasets.simulated_wear import wear_from_simulation

    g, w, s = _keywords(generate), _keywords(write), _keywords(wear_from_simulation)
    mapping = _renamed(g, layers="n_layers", points="n_points") | _same(g, "tilt", "seed")
    mapping |= _scaled(
        g,
        spacing_mm=("layer_spacing", 1e3),
        eccentricity_um=("eccentricity", 1e6),
        wear_um=("wear_depth", 1e6),
        noise_um=("noise", 1e6),
        quantisation_nm=("quantisation", 1e9),
    )
    zero, direction = g["convention"]
    mapping |= {"angle_zero": (zero, None), "angle_direction": (direction, None)}
    mapping |= _same(g, "noise_seed") | _same(w, "layout", "value", "units", "angle", "decimal")
    mapping |= _renamed(s, wear_scale="scale", wear_rotation_deg="rotation_deg")
    mapping |= _stated("radius_mm")  # the default depends on --wear-from
    params = _check(
        instruments_cmd, mapping, {"out", "overwrite", "delimiter", "wear_from", "truth"}
    )
    assert DELIMITERS[params["delimiter"].default] == w["delimiter"]
    assert f"default {g['radius'] * 1e3:g}," in params["radius_mm"].help
    assert _choices(params["layout"]) == LAYOUTS
    assert _choices(params["angle"]) == ANGLE_COLUMNS


def test_rig_defaults_are_the_librarys():
    from jointwear.datasets.cli_rig import rig
    from jointwear.datasets.rig import CODECS, RigConfig, generate_rig

    c, kw = _fields(RigConfig), _keywords(generate_rig)
    same = ("duration", "fps", "width", "height", "exposure", "seed", "board_legacy")
    mapping = _same(c, *same) | _scaled(c, z_amplitude_mm=("z_amplitude", 1e3))
    mapping |= _same(c, "noise_sigma", "blur_sigma_px", "board_kind")
    mapping |= _same(kw, "codec", "video", "images")
    params = _check(rig, mapping, {"out", "overwrite", "drop_frames", "duplicate_frames", "motion"})
    assert set(_choices(params["codec"])) == set(CODECS)
    size = c["board_square_size"] * 1e3
    assert f"{c['board_squares'][0]} x {c['board_squares'][1]} squares of {size:g} mm" in (
        params["board_kind"].help
    )
    assert c["board_dictionary"] in params["board_kind"].help


def test_field_defaults_help_and_limits_are_the_librarys():
    from jointwear.dic import CorrelationParams, FieldParams
    from jointwear.dic.cli_field import field_cmd
    from jointwear.dic.field._files import measure_field_files

    f = _fields(FieldParams)
    mapping = _same(
        f, "subset_size", "step", "zncc_min", "search_radius", "threads", "u_outlier_factor",
        "neighbour_outlier_factor",
    )  # fmt: skip
    mapping |= _stated("strain_window", "frame", "epipolar_max")
    mapping["origin"] = (_keywords(measure_field_files)["data_origin"], None)
    without = {"images", "left", "right", "calibration", "roi", "points", "fps"}
    without |= {"out", "csv", "plot", "allow_empty", "overwrite"}
    params = _check(field_cmd, mapping, without)
    assert f"Default {f['strain_window']} (0 with --points)" in params["strain_window"].help
    assert f"Default {f['frame']}." in params["frame"].help
    assert f"Default {f['epipolar_max_px']:g}." in params["epipolar_max"].help
    smallest = params["subset_size"].min
    CorrelationParams(subset_size=smallest)
    with pytest.raises(ParameterError):
        CorrelationParams(subset_size=smallest - 2)  # the next odd size below the CLI's limit


def test_verify_help_describes_the_librarys_default_study():
    from jointwear.sim.cli_verify import verify
    from jointwear.sim.sweep._verify import VerifySpec

    n = 80_000
    spec = VerifySpec.default(n)
    finest = spec.levels[0]
    words = (
        f"{len(spec.levels)} dN levels N/{n // finest} x "
        f"{', '.join(str(level // finest) for level in spec.levels)}; {spec.replicates} "
        f"replicates each; {spec.grid_replicates} runs on the grid refined {spec.grid}x"
    )
    assert (
        words == "4 dN levels N/80 x 1, 2, 4, 8; 4 replicates each; 4 runs on the grid refined 2x"
    )
    assert words in _params(verify)["spec"].help


def test_datasets_help_imports_no_numerical_stack(tmp_path):
    # the options read their defaults from the library's light modules, not from numpy's
    script = (
        "from jointwear.cli import main\n"
        "for argv in (['datasets', 'speckle', '--help'], ['datasets', 'instruments', '--help'],"
        " ['datasets', 'rig', '--help'], ['dic', 'field', '--help'], ['sim', 'verify', '--help']):\n"
        "    assert main(argv) == 0\n"
        "import sys\n"
        "print('LOADED', *(m for m in ('numpy', 'xarray', 'scipy') if m in sys.modules))"
    )
    out = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, cwd=tmp_path, check=True
    )
    assert out.stdout.splitlines()[-1].split()[1:] == []


def test_wearmap_defaults_are_the_librarys():
    from jointwear.metrology.cli_metrology import wearmap_cmd
    from jointwear.metrology.wearmap import wear_map

    kw = _keywords(wear_map)
    mapping = _same(kw, "angle_offset_deg", "register", "shape", "threshold", "unworn")
    mapping |= _renamed(kw, radius_mm="radius", unworn_z_mm="unworn_z")
    params = _check(wearmap_cmd, mapping, {"worn", "before", "out", "overwrite", "plot"})
    # every choice the command offers is one the library takes; another shape is refused
    from jointwear.errors import BadInputError
    from jointwear.metrology.wearmap import _options

    for choice in params["shape"].type_descriptor.annotation:
        _options(str(choice), None, None, "bore", kw["threshold"])
    with pytest.raises(BadInputError, match="shape"):
        _options("cone", None, None, "bore", kw["threshold"])


def test_calibrate_defaults_are_the_librarys():
    from jointwear.dic import CalibrationBoard, calibrate_stereo
    from jointwear.dic.calibration._files import calibrate_files
    from jointwear.dic.cli_stereo import calibrate_cmd

    b, kw, files = (
        _fields(CalibrationBoard),
        _keywords(calibrate_stereo),
        _keywords(calibrate_files),
    )
    mapping = _same(kw, "min_views", "max_rms", "max_view_rms", "world_view", "accept_poor")
    mapping |= _renamed(b, board="kind") | _stated("dictionary", "every")
    mapping["squares"] = ((b["squares_x"], b["squares_y"]), None)
    without = {"left", "right", "out", "overwrite", "square", "unit", "square_u", "square_mm"}
    without |= {"marker", "marker_mm"}
    params = _check(calibrate_cmd, mapping, without)
    assert f"(default {b['dictionary']})" in params["dictionary"].help
    assert f"(default {files['every']})" in params["every"].help


def test_cycle_and_calibrate_kw_defaults_are_the_librarys():
    from jointwear.sim import calibrate_kw
    from jointwear.sim._cycle_file import simulate_cycles_to_file
    from jointwear.sim.cli_cycle import cycle
    from jointwear.sim.cli_wear import calibrate
    from jointwear.sim.parameters import DEFAULT_PARAMETER_SET
    from jointwear.sim.wear._calibration import calibration_report

    kw = _keywords(simulate_cycles_to_file)
    mapping = _same(kw, "cycles", "wear", "wear_cycles") | {"base": (DEFAULT_PARAMETER_SET, None)}
    _check(cycle, mapping, {"out", "overwrite", "params", "progress"})

    report = _keywords(calibration_report)
    assert report["rtol"] == _keywords(calibrate_kw)["rtol"]
    mapping = _same(report, "resimulate", "rtol", "cycles", "measured_map", "vary")
    without = {"simulated", "max_depth_um", "volume_mm3", "cylindricity_um"}
    _check(calibrate, mapping, without)


def test_calibrate_and_predict_defaults_are_the_librarys():
    from jointwear.sim.calibrate import calibrate, predict
    from jointwear.sim.cli_calibrate import calibrate_cmd, predict_cmd
    from jointwear.sim.parameters import DEFAULT_PARAMETER_SET

    runs = {"progress", "overwrite"}
    kw = _keywords(predict)
    mapping = _same(kw, "samples", "workers", "scheduler", "resume")
    _check(predict_cmd, mapping, {"posterior", "cycles", "out"} | runs)
    kw = _keywords(calibrate)
    mapping = _same(kw, "workers", "scheduler", "resume") | {"base": (DEFAULT_PARAMETER_SET, None)}
    _check(calibrate_cmd, mapping, {"spec", "out", "params", "verification"} | runs)


def test_import_defaults_are_the_librarys():
    from jointwear.cli_import import _names, motion, wearmap
    from jointwear.external import CsvReading, import_motion, import_wear_map

    # the stated uncertainty's options make one StatedUncertainty (uncertainty=None: not stated)
    stated = {"u", "u_column", "u_k", "u_covers"}
    reading = _fields(CsvReading)
    assert reading["uncertainty"] is None
    dialect = _same(reading, "delimiter", "decimal")
    kw = _keywords(import_motion)
    assert kw["reading"] == CsvReading()
    mapping = _same(kw, "time_unit", "time_column", "tool") | dialect
    params = _check(
        motion,
        mapping,
        {"file", "out", "overwrite", "origin", "velocity_unit", "velocity_columns", *stated},
    )
    columns = params["velocity_columns"].default
    assert tuple(_names(columns, "--velocity-columns", (2, 3))) == kw["velocity_columns"]

    kw = _keywords(import_wear_map)
    assert kw["reading"] == CsvReading()
    mapping = _same(kw, "z_mid_width", "cycles", "tool") | dialect
    required = ("theta_unit", "z_unit", "depth_unit", "angle_zero", "angle_direction")
    assert all(kw[n] is inspect.Parameter.empty for n in required)
    mapping |= dict.fromkeys(required, (None, None))  # None: the command asks for them
    params = _check(wearmap, mapping, {"file", "out", "overwrite", "origin", "columns", *stated})
    assert tuple(_names(params["columns"].default, "--columns", (3, 3))) == kw["columns"]


def test_instruments_default_run_is_the_librarys_bit_for_bit(tmp_path):
    # the command converts its µm/mm/nm defaults back to SI: the scan is the library default's
    import numpy as np

    from jointwear import io
    from jointwear.cli import main
    from jointwear.datasets.instruments import generate

    truth = tmp_path / "truth.nc"
    argv = ["datasets", "instruments", str(tmp_path / "scan"), "--layers", "3", "--points", "64"]
    assert main([*argv, "--truth", str(truth)]) == 0
    expected = generate(n_layers=3, n_points=64).truth
    got = io.load(truth)
    for name in ("radius", "radius_true", "wear_depth"):
        np.testing.assert_array_equal(got[name].values, expected[name].values, err_msg=name)


def test_compare_defaults_and_help_are_the_librarys():
    from jointwear.compare import DEFAULT_AXES, MOTION_VARIABLES
    from jointwear.compare.align_motion import align_time_series
    from jointwear.compare.cli_compare import compare_cmd
    from jointwear.compare.storage import compare_files
    from jointwear.errors import BadInputError

    kw = _keywords(compare_files)
    mapping = _same(
        kw, "table", "criteria", "cycles", "variables", "allow_other_rig", "calibration_check"
    )
    mapping |= _renamed(kw, method="motion_method", period="period_s") | _stated("axes")
    without = {"sim", "meas", "out", "overwrite", "sim_extra", "meas_extra", "ensemble"}
    params = _check(compare_cmd, mapping, without | {"verification", "strict"})
    assert kw["axes"] == DEFAULT_AXES
    assert f"default {' and '.join(DEFAULT_AXES)}," in params["axes"].help
    assert f"default: {', '.join(MOTION_VARIABLES)} when" in params["variables"].help
    assert _keywords(align_time_series)["method"] == kw["motion_method"]
    # every method the help offers is one the library takes; another is refused
    offered = params["method"].help.split(":", 1)[1].strip(" .").split(", ")
    import xarray as xr

    from jointwear.compare.align_motion import _alignment_method

    both = xr.Dataset({"crank_angle": ("time", [0.0, 1.0])})
    for method in offered:
        _alignment_method(method, both, both)
    with pytest.raises(BadInputError, match="method"):
        _alignment_method("by_eye", both, both)


def test_reference_study_help_states_the_reduced_size():
    from jointwear.datasets.cli_reported import reference_study_cmd
    from jointwear.datasets.reference_study import REDUCED

    params = _check(reference_study_cmd, {}, {"out", "overwrite", "reduced", "verbose"})
    assert f"{REDUCED.ensemble_runs} ensemble members" in params["reduced"].help
