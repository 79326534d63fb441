"""plot_cycle draws a record and refuses datasets that are not one."""

from __future__ import annotations

import pytest
import xarray as xr

from jointwear.errors import BadInputError
from jointwear.params import replace_nested
from jointwear.sim import PARAMETER_SETS, plot_cycle, run_cycles


def test_plot_cycle_writes_png(tmp_path):
    p = replace_nested(PARAMETER_SETS["zhang2023"], **{"solver.output_interval": 1e-3})
    ds = run_cycles(p, cycles=0.1).dataset
    out = tmp_path / "c.png"
    fig = plot_cycle(ds, out)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    circle = fig.axes[0].lines[0].get_xydata()
    assert abs(circle[:, 0]).max() == pytest.approx(500.0)  # clearance from the record, in um
    import matplotlib.pyplot as plt

    plt.close(fig)
    with pytest.raises(BadInputError, match="lacks journal_offset"):
        plot_cycle(xr.Dataset())
