"""The report's figures read (#37): no two text boxes overlap (tick labels, titles, legends,
colour-bar labels, as matplotlib's renderer places them), the polar plots' legend lies outside
their data, and the simulated and measured wear maps share one colour scale."""

from __future__ import annotations

import itertools

import _jw_synth as syn
import numpy as np
import pytest
import xarray as xr

from jointwear.compare import compare
from jointwear.reports.figures import polar_layers_figure, verification_figure, wear_maps_figure


def _drawn_texts(fig):
    """(text, window box) of every text the renderer draws (ticks outside the view left out)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.text import Text

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    tick_labels, drawn = set(), set()
    for ax in fig.axes:
        for axis in ax._axis_map.values():
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                tick_labels.update(map(id, (tick.label1, tick.label2)))
            for tick in axis._update_ticks():
                drawn.update(id(t) for t in (tick.label1, tick.label2) if t.get_visible())
    out = []
    for t in fig.findobj(Text):
        if not t.get_visible() or not t.get_text().strip():
            continue
        if id(t) in tick_labels and id(t) not in drawn:
            continue
        out.append((t.get_text(), t.get_window_extent(renderer)))
    return out, renderer


def _overlaps(texts, slack=1.0):
    """Pairs of texts whose boxes overlap by more than ``slack`` pixels each way."""
    bad = []
    for (a, ba), (b, bb) in itertools.combinations(texts, 2):
        w = min(ba.x1, bb.x1) - max(ba.x0, bb.x0)
        h = min(ba.y1, bb.y1) - max(ba.y0, bb.y0)
        if w > slack and h > slack:
            bad.append((a, b))
    return bad


@pytest.fixture(scope="module")
def aligned():
    result = compare(
        [syn.sim_wear(n_layers=12, n_points=120)], [syn.meas_wear(n_points=720, scale=0.4)]
    )
    return result.wear


def test_wear_maps_share_one_colour_scale_and_no_text_overlaps(aligned):
    fig = wear_maps_figure(aligned)
    meshes = [ax.collections[0] for ax in fig.axes[:3]]
    sim, meas, diff = (m.get_clim() for m in meshes)
    assert sim == meas  # the measured map 0.4x as deep is read on the simulated map's scale
    top = float(np.nanmax(aligned["wear_depth_sim_full"].values)) * 1e6
    assert sim[1] == pytest.approx(top)
    assert diff[0] == pytest.approx(-diff[1]) and diff[1] > 0  # diverging, centred on zero
    assert meshes[2].get_cmap().name == "RdBu_r"
    texts, _ = _drawn_texts(fig)
    assert not _overlaps(texts)
    assert sum("wear depth [µm]" in t for t, _ in texts) == 1  # one colour bar for both maps


def test_polar_legend_is_outside_the_data_and_no_text_overlaps(aligned):
    fig = polar_layers_figure(aligned)
    texts, renderer = _drawn_texts(fig)
    assert not _overlaps(texts), _overlaps(texts)
    (legend,) = fig.legends
    box = legend.get_window_extent(renderer)
    for ax in fig.axes:
        a = ax.get_window_extent(renderer)
        assert min(box.x1, a.x1) <= max(box.x0, a.x0) or min(box.y1, a.y1) <= max(box.y0, a.y0)
    assert [t.get_text() for t in legend.get_texts()] == ["simulation", "measurement"]


def test_solver_tolerance_ticks_do_not_run_together():
    rtol = 10.0 ** -np.arange(4, 13)  # nine tolerances, 1e-4 ... 1e-12
    ds = xr.Dataset(
        {"follower_velocity_rms": ("solver_rtol", 0.1 + 1e-3 * rtol**0.5, {"units": "m s-1"})},
        coords={"solver_rtol": ("solver_rtol", rtol, {"units": "1"})},
    )
    dn = np.array([12500.0, 25000.0, 50000.0, 100000.0])
    study = xr.Dataset(
        {"max_wear_depth": ("dn", 5e-6 + 1e-7 * dn / dn.max(), {"units": "m"})},
        coords={"dn": ("dn", dn, {"units": "1"})},
    )
    fig = verification_figure([ds, study])
    texts, _ = _drawn_texts(fig)
    assert not _overlaps(texts), _overlaps(texts)
    ticks = [t.get_text() for t in fig.axes[0].get_xticklabels() if t.get_text()]
    assert all("10^" in t or "10^{" in t for t in ticks) or all("e" in t for t in ticks), ticks
    dn_ticks = [t.get_text() for t in fig.axes[1].get_xticklabels() if t.get_text()]
    assert {"12500", "25000", "50000", "100000"} <= set(dn_ticks)
