"""The demo's verification study: at demo size, and the compared run is the verified one."""

from __future__ import annotations

import math

from jointwear.reports.demo import FULL, QUICK
from jointwear.reports.demo_studies import demo_study, main_wear_settings
from jointwear.sim import WearSettings


def test_demo_study_size_and_the_compared_run_is_its_replicate_zero():
    spec = demo_study(FULL)
    assert len(spec.levels) >= 4 and spec.replicates >= 2
    assert spec.cycles == FULL.cycles
    main = main_wear_settings(FULL)
    # the compared wear run is replicate 0 of the study's finest level: same scheme, same dN,
    # same start (so the study's u_num_run is its numerical uncertainty)
    assert main.scheme == "fixed" and main.dn == spec.levels[0]
    assert main.initial_settle_cycles == WearSettings().initial_settle_cycles
    assert math.isclose(FULL.cycles % main.dn, 0.0)
    # every level updates the profile at least twice (one update of all cycles would be the
    # initial rate extrapolated, not a refinement level), and all divide the cycles
    assert all(FULL.cycles / dn >= 2 and math.isclose(FULL.cycles % dn, 0.0) for dn in spec.levels)
    # --quick has no study and keeps the default adaptive run
    assert QUICK.verification_replicates == 0
    assert main_wear_settings(QUICK) == WearSettings()


def test_the_studys_run_zero_and_no_other_is_the_compared_run():
    """The demo simulates its compared wear run once, as the study's run 0: that run must be
    exactly the compared configuration, and a run differing in anything must not pass for it."""
    import dataclasses

    from jointwear.reports.demo import _params
    from jointwear.reports.demo_studies import is_compared_run
    from jointwear.sim.sweep._driver import _base
    from jointwear.sim.sweep._verify import _WearKind, study_tasks

    params = _params(FULL)
    sim, wear, _, _ = _base(_WearKind, params, None)
    values, where, tasks = study_tasks(
        demo_study(FULL), sim, dataclasses.replace(wear, scheme="fixed")
    )
    assert where[0] == ("level", 0, 0)  # replicate 0 of the finest level
    compared = [t.index for t in tasks if is_compared_run(t, params, FULL)]
    assert compared == [0]
    # another snapshot list, or other parameters, and run 0 is no longer the compared run
    run0 = next(t for t in tasks if t.index == 0)
    assert not is_compared_run(run0, params, dataclasses.replace(FULL, snapshots=(1e5, 2e5)))
    other = dataclasses.replace(FULL, n_points=FULL.n_points + 2)
    assert not is_compared_run(run0, _params(other), other)
