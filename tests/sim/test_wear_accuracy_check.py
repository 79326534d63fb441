"""The single-run accuracy check (``jointwear sim wear --check interval|grid``).

Truths: the halved-interval run is the convergence check of the explicit update (its change
must lie within the run's stated expanded accuracy); a run that states too small an accuracy
must fail it; the grid check runs on a grid of half the spacing.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from jointwear import io
from jointwear.cli import main
from jointwear.errors import BadInputError
from jointwear.sim import BearingGrid, ConstantContact, WearSettings, check_accuracy, simulate_wear
from jointwear.sim.wear._files import demo_winkler_contact

SETTINGS = WearSettings(kw=9e-16, tol=0.1)


@pytest.fixture(scope="module")
def winkler_run():
    contact = demo_winkler_contact(BearingGrid(10, 60))
    return contact, simulate_wear(contact=contact, cycles=1e6, settings=SETTINGS, snapshots=[])


def test_halved_intervals_stay_within_the_stated_accuracy(winkler_run):
    contact, ds = winkler_run
    res = check_accuracy(ds, contact, SETTINGS, kinds=("interval", "grid"))
    q = res["interval"]["quantities"]["max_wear_depth"]
    assert q["status"] == "consistent"
    assert abs(q["change"]) <= q["stated_u_k2"]
    assert q["change"] != 0.0  # the halved run really ran with other intervals
    assert res["interval"]["quantities"]["cylindricity"]["status"] == "not assessed"
    # the halved run had twice the updates of the original
    n_acc = int(np.sum(ds["update_accepted"].values == 1))
    assert res["interval"]["cycles_simulated"] > 1.5 * n_acc
    assert res["grid"]["status"] == "consistent"
    assert res["attrs"]["accuracy_check_status"] == "consistent"
    assert json.loads(res["attrs"]["accuracy_check_grid"])["what"].startswith("layer and point")


def test_a_run_stating_too_small_an_accuracy_fails_the_check(winkler_run):
    contact, ds = winkler_run
    bad = ds.copy()
    bad["max_wear_depth_u"] = bad["max_wear_depth_u"] * 0.0 + 1e-12  # claims 1 pm
    res = check_accuracy(bad, contact, SETTINGS, kinds=("interval",))
    q = res["interval"]["quantities"]["max_wear_depth"]
    assert abs(q["change"]) > 1e-3 * q["value"]  # beyond the check's resolution: a real change
    assert q["status"] == "inconsistent"
    assert res["attrs"]["accuracy_check_status"] == "inconsistent"


def test_unknown_check_and_partial_run_are_refused(winkler_run):
    contact, ds = winkler_run
    with pytest.raises(BadInputError, match="unknown accuracy check"):
        check_accuracy(ds, contact, SETTINGS, kinds=("tol",))
    partial = ds.copy()
    partial.attrs["status"] = "partial"
    with pytest.raises(BadInputError, match="complete wear run"):
        check_accuracy(partial, contact, SETTINGS)
    # a prescribed pressure field lives on the run's grid: no finer grid can be made of it
    grid = BearingGrid(4, 36)
    const = ConstantContact(grid, pressure=np.full(grid.shape, 1e6), sliding=0.01)
    fixed = WearSettings(kw=9e-16, scheme="fixed", dn=50)
    run = simulate_wear(contact=const, cycles=100, settings=fixed, snapshots=[])
    with pytest.raises(BadInputError, match="cannot refine ConstantContact: its pressure"):
        check_accuracy(run, const, fixed, kinds=("grid",))


def test_wear_command_check_option(tmp_path, capsys, monkeypatch):
    out = tmp_path / "w.nc"
    args = ["sim", "wear", "--contact", "winkler", "--layers", "6", "--points", "48"]
    args += ["--cycles", "2e4", "--kw", "1e-13", "--out", str(out)]
    assert main([*args, "--check", "interval"]) == 0
    ds = io.load(out)
    assert ds.attrs["accuracy_check_status"] == "consistent"
    assert "accuracy_check_interval" in ds.attrs and "accuracy_check_grid" not in ds.attrs
    assert "interval halved: consistent" in capsys.readouterr().err
    assert main([*args, "--check", "tol", "--overwrite"]) == 3
    # a failed check exits 1 (the result file is written and says so)
    import jointwear.sim.wear._check as chk

    real = chk.check_accuracy

    def understated(ds, *a, **k):
        ds["max_wear_depth_u"] = ds["max_wear_depth_u"] * 0.0 + 1e-12
        return real(ds, *a, **k)

    monkeypatch.setattr(chk, "check_accuracy", understated)
    assert main([*args, "--check", "interval", "--overwrite"]) == 1
    assert io.load(out).attrs["accuracy_check_status"] == "inconsistent"
