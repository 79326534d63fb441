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
