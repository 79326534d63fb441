"""Property test over the importer (text, UTF-16 text, .xlsx, X3P): a generated trace that
states its meaning reads back exactly; the same trace with one defect is refused with a
``JointwearError`` - never another exception, never a different reading."""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jointwear.errors import JointwearError
from jointwear.metrology.readers import read_scan

CANON = ("-x", "clockwise")  # the canonical convention: theta comes back as written
_F = {"um": 1e-6, "mm": 1e-3, "m": 1.0, "inch": 0.0254}
_DEC = {"um": 6, "mm": 9, "m": 12, "inch": 10}
MUTATIONS = (
    "none",
    "drop_units",
    "unit_slip",
    "text_value",
    "absurd",
    "nan",
    "cut_last",
    "drop_newline",
)
#: The unit a slipped header states: 1000 x, or 25.4 x for a file in inch (issue 22)
_SLIP = {"um": "mm", "mm": "um", "m": "mm", "inch": "mm"}


def _rows(n, unit, arc_deg, kind, lu, rng):
    th = np.arange(n) * arc_deg / (n if arc_deg == 360.0 else n - 1)
    r = 8e-3 + 2e-6 * np.cos(np.radians(3 * th)) + 0.2e-6 * rng.standard_normal(n)
    val = (r if kind == "radius" else r - 8e-3) / _F[lu]
    a = {"deg": th, "rad": np.radians(th), "index": np.arange(n)}[unit]
    af = {"deg": "{:.9f}", "rad": "{:.12f}", "index": "{:.0f}"}[unit]
    cells = [[af.format(x), f"{v:.{_DEC[lu]}f}"] for x, v in zip(a, val, strict=True)]
    truth_th = np.round(th, 6)
    truth_v = np.array([float(c[1]) for c in cells]) * _F[lu]
    return cells, truth_th, truth_v


def _fuzz(examples_in_ci: int):
    """Hypothesis settings: ``examples_in_ci`` examples, JOINTWEAR_FUZZ_EXAMPLES=2000 for a
    long run."""
    return settings(
        max_examples=int(os.environ.get("JOINTWEAR_FUZZ_EXAMPLES", str(examples_in_ci))),
        deadline=None,
        suppress_health_check=[HealthCheck.function_scoped_fixture],
    )


@_fuzz(40)
@given(
    n=st.integers(8, 300),
    unit=st.sampled_from(["deg", "rad", "index"]),
    partial=st.booleans(),
    kind=st.sampled_from(["radius", "deviation"]),
    lu=st.sampled_from(["um", "mm", "m", "inch"]),
    delim=st.sampled_from(["\t", ";", ",", " "]),
    state_angle_unit=st.booleans(),
    container=st.sampled_from(["utf-8", "utf-16", "xlsx"]),
    mutation=st.sampled_from(MUTATIONS),
    seed=st.integers(0, 2**32 - 1),
)
def test_importer_reads_right_or_refuses(
    tmp_path_factory, n, unit, partial, kind, lu, delim, state_angle_unit, container, mutation, seed
):
    rng = np.random.default_rng(seed)
    arc_deg = 360.0 if (unit == "index" or not partial) else float(rng.uniform(20, 300))
    cells, truth_th, truth_v = _rows(n, unit, arc_deg, kind, lu, rng)
    head = [["Units", lu]]
    if state_angle_unit:
        head.append(["Angle unit", unit])
    names = [["Angle", "Radius" if kind == "radius" else "Deviation"]]
    k = int(rng.integers(0, n))
    if mutation == "unit_slip" and lu == "inch" and kind == "deviation":
        mutation = "none"  # 25.4 x smaller deviations stay plausible: no number can tell
    if mutation == "drop_units":
        head = head[1:]
    elif mutation == "unit_slip":
        head[0] = ["Units", _SLIP[lu]]
    elif mutation == "text_value":
        cells[k][1] = "n.a."
    elif mutation == "absurd":
        cells[k][1] = "1e300"
    elif mutation == "nan":
        cells[k][1] = "nan"
    options = {} if state_angle_unit else {"angle_unit": unit}
    d = tmp_path_factory.mktemp("fz")
    if container == "xlsx":
        if mutation in ("cut_last", "drop_newline"):
            mutation = "none"  # a workbook has no bytes to cut mid-number
        openpyxl = pytest.importorskip("openpyxl")
        wb = openpyxl.Workbook()
        for row in head + names + cells:
            wb.active.append([_num(c) for c in row])
        path = d / "t.xlsx"
        wb.save(path)
    else:
        sep = delim
        text = "".join(f"{a}: {b}\n" for a, b in head) + "\t".join(names[0]) + "\n"
        text = text if delim == "\t" else text.replace("\t", sep)
        body = "".join(sep.join(c) + "\n" for c in cells)
        if mutation == "cut_last":
            cut = int(rng.integers(1, len(cells[-1][1]) - 1))
            body = body[: -1 - cut]  # no final newline, last number shortened
        elif mutation == "drop_newline":
            body = body[:-1]
        path = d / "t.txt"
        path.write_bytes((text + body).encode(container))
    try:
        ds = read_scan(path, convention=CANON, **options)
    except JointwearError as exc:
        assert "t." in str(exc)  # the message names the file
        assert mutation != "none" and mutation != "drop_newline", str(exc)
        assert mutation != "nan" or "max_missing" in str(exc), str(exc)
        return
    # accepted: it must be exactly the written trace (a 'nan' cell a missing point, issue 38)
    assert mutation in ("none", "drop_newline", "nan"), f"{mutation} accepted"
    var = "radius" if kind == "radius" else "radial_deviation"
    assert var in ds
    if mutation == "nan":
        assert ds.attrs["missing_points"] == 1 and n >= 20  # 1 of n within max_missing 5 %
        truth_v[k] = np.nan
    order = np.argsort(np.mod(truth_th, 360.0))
    np.testing.assert_allclose(ds["theta"].values, np.mod(truth_th, 360.0)[order], atol=1e-6)
    np.testing.assert_allclose(ds[var].values[0], truth_v[order], rtol=0, atol=1e-15)


def _num(c):
    try:
        return float(c)
    except ValueError:
        return c


@_fuzz(15)
@given(
    n=st.integers(12, 200),
    layers=st.integers(1, 4),
    radius=st.floats(1e-3, 0.2),
    offset=st.floats(0.0, 3.0),
    seed=st.integers(0, 2**32 - 1),
)
def test_x3p_point_clouds_read_exactly_or_refuse(tmp_path_factory, n, layers, radius, offset, seed):
    """Any X3P point cloud about the spindle axis reads back point for point; one whose centre
    is half a radius or more off the axis is refused, never re-interpreted."""
    x3pio = pytest.importorskip("x3pio")
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0, 2 * np.pi, n))
    t = t[np.concatenate([[True], np.diff(t) > 1e-6])]
    e = offset * radius * np.array([np.cos(seed), np.sin(seed)])
    pts = np.concatenate(
        [
            np.column_stack(
                [e[0] + radius * np.cos(t), e[1] + radius * np.sin(t), np.full(t.size, k * 1e-3)]
            )
            for k in range(layers)
        ]
    )
    f = tmp_path_factory.mktemp("x3") / "cloud.x3p"
    x3pio.write_points(f, pts)
    try:
        ds = read_scan(f, convention=CANON)
    except JointwearError as exc:
        assert "cloud.x3p" in str(exc)
        gaps = np.diff(np.concatenate([t, t[:1] + 2 * np.pi]))
        # refused only off the axis, or when random angles leave half the circle empty
        assert offset >= 0.5 - 1e-9 or gaps.max() > np.pi, str(exc)  # 0.5: either is right
        assert "do not surround the origin" in str(exc)
        return
    assert offset <= 0.5 + 1e-9  # an off-axis cloud must never be read as a trace about the axis
    assert ds.sizes["z"] == layers
    got = ds["radius"].values[-1]
    last = pts[-t.size :]
    np.testing.assert_allclose(np.sort(got), np.sort(np.hypot(last[:, 0], last[:, 1])), rtol=1e-15)
