"""A command imports what it uses: no dask/distributed/pint under xarray for NumPy data, one
command group per call; and xarray still recognises dask arrays and pint quantities."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

HEAVY = ("dask", "distributed", "pint", "matplotlib", "numba")


def _modules_after(code: str, tmp_path) -> set[str]:
    script = (
        f"{code}\nimport sys\n"
        f"print('LOADED', *(m for m in {HEAVY!r} + ('jointwear.sim.cli', 'jointwear.metrology.cli') "
        "if m in sys.modules))"
    )
    out = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, cwd=tmp_path, check=True
    )
    return set(out.stdout.splitlines()[-1].split()[1:])


def test_saving_and_summarising_numpy_data_imports_no_dask_pint_or_numba(tmp_path):
    code = (
        "import numpy as np, xarray as xr\n"
        "from jointwear import io\n"
        "from jointwear.cli import main\n"
        "ds = xr.Dataset({'a': ('x', np.arange(3.0), {'units': 'm'})}, "
        "coords={'x': ('x', np.arange(3.0), {'units': 'm'})})\n"
        "io.save(ds, 'a.nc', validate=False)\n"
        "assert main(['info', 'a.nc', '--no-validate']) == 0"
    )
    assert _modules_after(code, tmp_path) == set()


def test_a_command_builds_only_its_group(tmp_path):
    loaded = _modules_after(
        "from jointwear.cli import main\nassert main(['dic', '--help']) == 0", tmp_path
    )
    assert loaded == set()  # neither the numerical stack nor the other groups


def test_xarray_still_sees_dask_arrays_and_pint_quantities(tmp_path):
    import xarray as xr

    import jointwear  # noqa: F401  (installs the import shortcuts)

    da = pytest.importorskip("dask.array")
    pint = pytest.importorskip("pint")
    lazy = xr.DataArray(da.zeros(6, chunks=3), dims="x")
    assert lazy.chunks == ((3, 3),)
    assert isinstance(lazy.data, da.Array)
    q = pint.UnitRegistry().Quantity(np.arange(3.0), "mm")
    wrapped = xr.DataArray(q, dims="x")
    assert isinstance(wrapped.data, pint.Quantity)
    # a chunked dataset is written through dask (the scheduler is asked again once dask is in)
    lazy.to_dataset(name="z").to_netcdf(tmp_path / "z.nc")
    with xr.open_dataset(tmp_path / "z.nc") as back:
        np.testing.assert_array_equal(back["z"].values, np.zeros(6))


def test_unknown_group_is_a_usage_error():
    from jointwear.cli import main

    assert main(["no-such-group"]) == 2


@pytest.mark.parametrize("argv", [["--help"], ["dic", "--help"], ["sim", "--help"]])
def test_help_imports_no_numerical_stack(argv, tmp_path):
    # the help lists every group's options: their declarations must not pull in numpy
    # (a module-level 'import numpy' behind an option's default cost 0.13 CPU s per call)
    script = (
        f"from jointwear.cli import main\nassert main({argv!r}) == 0\nimport sys\n"
        "print('LOADED', *(m for m in ('numpy', 'xarray', 'pandas', 'scipy') if m in sys.modules))"
    )
    out = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, cwd=tmp_path, check=True
    )
    assert out.stdout.splitlines()[-1].split()[1:] == []


def test_dic_correlate_of_a_pair_imports_neither_xarray_nor_pandas(tmp_path):
    # xarray with pandas is about 0.3 CPU s of the command's ~1 s: a pair's field is written
    # from NumPy arrays (jointwear._netcdf); only --plot and sequences need xarray
    import cv2

    from jointwear import io
    from jointwear.datasets import speckle as sp

    pair = sp.speckle_pair((80, 96), sp.RigidField((1.7, -0.4)), seed=3)
    for name, img in (("r.png", pair.reference), ("d.png", pair.deformed)):
        assert cv2.imwrite(str(tmp_path / name), img)
    argv = ["dic", "correlate", "r.png", "d.png", "--subset", "21", "--step", "16"]
    script = (
        f"from jointwear.cli import main\nassert main({argv!r}) == 0\nimport sys\n"
        "print('LOADED', *(m for m in ('xarray', 'pandas') + "
        f"{HEAVY[:-1]!r} if m in sys.modules))"
    )
    out = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, cwd=tmp_path, check=True
    )
    assert out.stdout.splitlines()[-1].split()[1:] == []
    field = io.load(tmp_path / "field.nc")  # the default --out, a valid jointwear file
    assert (field["flag"].values == 0).all()
    np.testing.assert_allclose(field["u"].values, 1.7, atol=0.02)
    np.testing.assert_allclose(field["v"].values, -0.4, atol=0.02)


@pytest.mark.parametrize("user", [None, "2"])
def test_the_command_runs_blas_single_threaded_unless_the_user_says(tmp_path, user):
    """Idle OpenBLAS pools cost ~0.25 CPU s per command (bench_startup): the CLI sets one BLAS
    thread before numpy is imported; a value the user exported is kept."""
    import os

    from jointwear.cli import BLAS_THREAD_VARIABLES

    env = {k: v for k, v in os.environ.items() if k not in BLAS_THREAD_VARIABLES}
    if user is not None:
        env["OPENBLAS_NUM_THREADS"] = user
    code = (
        "import sys\nimport jointwear.cli\n"
        "print('numpy' in sys.modules)\n"
        "import os\nprint(os.environ['OPENBLAS_NUM_THREADS'], os.environ['MKL_NUM_THREADS'])"
    )
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=env,
        check=True,
    ).stdout.split("\n")
    assert out[0] == "False"  # set before numpy (and its BLAS) is loaded
    assert out[1] == f"{user or '1'} 1"


def test_info_reads_the_header_without_xarray_or_pandas(tmp_path):
    """``jointwear info`` needs names, attributes and coordinates: netCDF4 alone (#37)."""
    import xarray as xr

    from jointwear import io

    ds = xr.Dataset(
        {"contact_force": ("time", np.arange(3.0), {"units": "N", "long_name": "force"})},
        coords={"time": ("time", np.arange(3.0), {"units": "s"})},
    )
    io.save(ds, tmp_path / "a.nc", parameters={"a": 1})
    code = (
        "from jointwear.cli import main\n"
        "assert main(['info', 'a.nc']) == 0\n"
        "import sys\nprint('LOADED', *(m for m in ('xarray', 'pandas') if m in sys.modules))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, check=True
    )
    assert "contact_force(time) [N]" in out.stdout
    assert out.stdout.splitlines()[-1] == "LOADED"


def test_info_of_the_header_is_the_summary_of_the_whole_file(tmp_path, monkeypatch):
    """The header's summary is the full load's, word for word (dimension order, coordinates
    named in a 'coordinates' attribute, decoded attributes, a NaN-padded coordinate refused)."""
    import xarray as xr

    from jointwear import io
    from jointwear.summary import summarise

    ds = xr.Dataset(
        {
            "wear_depth": (("run", "z"), np.ones((2, 3)), {"units": "m", "long_name": "w"}),
            "f": ("z", np.arange(3.0), {"units": "N", "long_name": "f", "flags": [1, 2]}),
        },
        coords={
            "z": (
                "z",
                [-1e-3, 0.0, 1e-3],
                {"units": "m", "z_zero": "bearing mid-width", "z_direction": "+z"},
            ),
            "label": ("run", ["a", "b"]),
            "kw": ("run", [1e-13, 2e-13], {"units": "m2 N-1"}),
        },  # fmt: skip
    )
    io.save(ds, tmp_path / "a.nc", parameters={"a": 1})
    bad = ds.assign_coords(z=("z", [np.nan, 0.0, 1e-3], ds["z"].attrs))
    io.save(bad, tmp_path / "bad.nc", parameters={"a": 1}, validate=False)
    header = summarise(tmp_path / "a.nc")
    monkeypatch.setattr(io, "load_header", io.load)
    assert header == summarise(tmp_path / "a.nc")
    assert "dimensions: run=2, z=3" in header and "  label (?): a, b" in header
    monkeypatch.undo()
    from jointwear.errors import BadInputError

    with pytest.raises(BadInputError, match="'z' contains NaN"):
        summarise(tmp_path / "bad.nc")


def test_the_script_tunes_the_collector_and_a_caller_s_process_is_left_alone(tmp_path):
    """The ``jointwear`` script (``main()``) collects young objects less often and freezes every
    object at the end, which the exit's collections then skip (about 0.1 CPU s of a ``dic
    correlate``, bench_startup); ``main([...])`` in a caller's process changes neither."""
    code = (
        "import gc, sys\nfrom jointwear.cli import SCRIPT_GC_THRESHOLD, main\n"
        "default = gc.get_threshold()\n"
        "assert main(['--version']) == 0\n"
        "print('CALLER', gc.get_threshold() == default, gc.get_freeze_count())\n"
        "sys.argv = ['jointwear', '--version']\n"
        "assert main() == 0\n"
        "print('SCRIPT', gc.get_threshold() == SCRIPT_GC_THRESHOLD, gc.get_freeze_count() > 1000)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, check=True
    ).stdout.splitlines()
    assert [x for x in out if not x.startswith("jointwear")] == [
        "CALLER True 0",
        "SCRIPT True True",
    ]


def test_provenance_versions_are_importlib_metadata_s_for_every_installed_distribution():
    """The header-only read of a distribution's version (the start-up of every command that
    writes a file) gives ``importlib.metadata.version`` for each installed one, and refuses an
    unknown name as it does."""
    from importlib import metadata

    from jointwear.provenance import installed_version, software_versions

    names = sorted({d.metadata["Name"] for d in metadata.distributions()})
    assert len(names) > 20
    assert {n: installed_version(n) for n in names} == {n: metadata.version(n) for n in names}
    with pytest.raises(metadata.PackageNotFoundError):
        installed_version("no-such-distribution-jointwear")
    assert software_versions()["numpy"] == np.__version__


def test_a_command_reads_the_options_of_its_own_command_only(monkeypatch, capsys):
    """``jointwear dic correlate`` builds ``correlate`` alone (typer reads each command's
    options from its signature); the group's help lists, so builds, all of them."""
    import typer

    from jointwear.cli import main

    built = []
    build = typer.main.get_command_from_info

    def counted(command_info, **kwargs):
        command = build(command_info, **kwargs)
        built.append(command.name)
        return command

    monkeypatch.setattr(typer.main, "get_command_from_info", counted)
    others = {"field", "calibrate", "track", "import-field"}  # more commands of the dic group
    assert main(["dic", "correlate", "--help"]) == 0
    assert built.count("correlate") == 1 and not others & set(built)
    built.clear()
    assert main(["dic", "--help"]) == 0
    assert {"correlate", *others} <= set(built)
    listing = capsys.readouterr().out.split("correlate [OPTIONS]")[-1]
    assert all(f" {name} " in listing for name in {"correlate", *others})
