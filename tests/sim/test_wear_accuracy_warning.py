"""The wear run's noise-floor warning (#37): one short sentence with the action, and the action,
taken as printed, holds tol."""

from __future__ import annotations

import re

from test_wear_control import KW, DecayingNoisyContact

from jointwear.sim import WearSettings, simulate_wear


def test_the_noise_floor_warning_is_short_and_its_tol_holds():
    model = DecayingNoisyContact(noise=0.4)
    ds = simulate_wear(
        contact=model, cycles=200_000, snapshots=[], settings=WearSettings(kw=KW, tol=0.05, dn=10)
    )
    text = ds.attrs["accuracy_warning"]
    assert len(text) <= 260 and text.count(". ") == 0  # one sentence, two terminal lines at most
    assert "the stated accuracy" in text  # what it means for the result
    tol = float(re.search(r"to hold tol, set tol = ([0-9.]+)", text).group(1))
    cycles = int(re.search(r"wear.max_average_cycles = (\d+)", text).group(1))
    assert 0.05 < tol <= 1.0 and cycles > 8
    again = simulate_wear(
        contact=model, cycles=200_000, snapshots=[], settings=WearSettings(kw=KW, tol=tol, dn=10)
    )
    assert again.attrs["accuracy_status"] == "reached", again.attrs.get("accuracy_warning")
