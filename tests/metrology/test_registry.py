"""Issue 40 item 2: the reader of each preset comes from one registry
(:data:`jointwear.metrology.choices.READERS`); a toy preset registered there is used by
``import_scans`` exactly as the built-in ones."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from jointwear.errors import BadInputError
from jointwear.metrology.choices import PRESETS, READERS
from jointwear.metrology.readers import read_scan, read_talyrond
from jointwear.metrology.readers.importing import import_scans
from jointwear.metrology.readers.registry import presets, reader_for, register


def test_built_in_presets_resolve_to_their_readers():
    assert reader_for("generic") is read_scan
    assert reader_for("talyrond") is read_talyrond
    assert set(PRESETS) <= set(presets())
    with pytest.raises(BadInputError, match="preset 'zeiss' is not known.*generic, talyrond"):
        reader_for("zeiss")


def test_a_toy_preset_registered_once_is_used_by_the_import(tmp_path):
    f = tmp_path / "toy.dat"
    th = np.arange(360) * 1.0
    f.write_text("".join(f"{a:.1f} {0.5 * np.cos(np.radians(2 * a)):.4f}\n" for a in th))
    calls = []

    def read_toy(paths, *, convention=None, **options):
        """A toy instrument: whitespace tables in µm, whole turns (a preset's defaults)."""
        calls.append(options)
        return read_scan(paths, convention=convention, **{"units": "um", "arc": "full", **options})

    try:
        register("toy", read_toy, "a toy instrument for the test")
        assert READERS["toy"][1] == "a toy instrument for the test"
        out = import_scans(
            [f], tmp_path / "toy.nc", angle_zero="-x", angle_direction="clockwise", preset="toy"
        )
        ds = xr.load_dataset(out[0])
        np.testing.assert_allclose(ds["radial_deviation"].values[0].max(), 0.5e-6)
        assert len(calls) == 1
        # by name, as a module would register its function
        register("toy2", "jointwear.metrology.readers.talyrond:read_talyrond", "same as talyrond")
        assert reader_for("toy2") is read_talyrond
    finally:
        for name in ("toy", "toy2"):
            READERS.pop(name, None)
