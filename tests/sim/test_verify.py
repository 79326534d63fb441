"""``jointwear sim verify``: the study's runs, file, resume, CLI, and coverage on manufactured data.

The manufactured "wear run" replaces the simulator (its executor) with a known wear map: a
Gaussian bump of exact depth ``D0`` and exact volume, made deeper by a ΔN error
``c dN / N``, scattered from run to run by a replicate noise, and sampled on the bearing grid
(which misses the peak: a grid error that shrinks with refinement). The study must cover the
exact ``D0`` and volume with ``|error| <= 2 u_num`` in at least 90 % of the seeded cases.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from jointwear.cli import main
from jointwear.errors import BadInputError, ParameterError
from jointwear.params import replace_nested
from jointwear.refinement import study_uncertainty
from jointwear.sim import PARAMETER_SETS, VerifySpec, read_verify_spec, verify_wear

R = PARAMETER_SETS["zhang2023"].joint.bearing_radius
SMALL = replace_nested(PARAMETER_SETS["zhang2023"], **{"joint.n_layers": 12, "joint.n_points": 72})


class Manufactured:
    """An executor computing manufactured wear runs (exact answer known)."""

    def __init__(self, seed: int, *, d0=20e-6, c_dn=2.0, noise=0.004, warn=None):
        rng = np.random.default_rng(seed)
        self.warn = warn  # (dn, settle) -> tuple of "kind: message", the runs' warnings
        self.seed, self.d0, self.c_dn, self.noise = seed, d0, c_dn, noise
        self.z0 = rng.uniform(-2e-3, 2e-3)
        self.th0 = rng.uniform(0, 360)
        self.wz, self.wth = 2.5e-3, 25.0  # bump widths [m], [deg]
        self.calls: list[int] = []
        self.settles: list[float] = []

    @property
    def exact_volume(self) -> float:
        return self.d0 * R * math.pi * self.wz * math.radians(self.wth)

    def run(self, task):
        from jointwear.sim.sweep._params import apply_values
        from jointwear.sim.sweep._run import RunResult
        from jointwear.sim.wearmap import BearingGrid, wear_map_dataset

        params, wear = apply_values(task.sim_params, task.wear_settings, task.values)
        grid = BearingGrid.from_params(params)
        coords = wear_map_dataset(np.zeros((1, *grid.shape)), np.ones(1), grid, cylindricity=False)
        z = coords["z"].values
        th = coords["theta"].values
        rng = np.random.default_rng([self.seed, task.index])
        depth = self.d0 * (1 + self.c_dn * wear.dn / task.spec.cycles + rng.normal(0, self.noise))
        dth = (th - self.th0 + 180) % 360 - 180
        bump = np.exp(-(((z[:, None] - self.z0) / self.wz) ** 2) - (dth[None, :] / self.wth) ** 2)
        h = depth * bump
        area = np.asarray(grid.point_area)
        area = area if area.shape == h.shape else np.broadcast_to(area, h.shape)
        k = np.unravel_index(np.argmax(h), h.shape)
        out = {
            "max_wear_depth": float(h.max()),
            "worn_volume": float(np.sum(h * area)),
            "max_wear_theta": float(th[k[1]]),
            "max_wear_z": float(z[k[0]]),
        }
        self.calls.append(task.index)
        self.settles.append(wear.initial_settle_cycles)
        warned = self.warn(wear.dn, wear.initial_settle_cycles) if self.warn else ()
        return RunResult(
            task.index, "ok", out, {"wear_depth": h}, "", 0.0, "manufactured", warnings=warned
        )

    def __call__(self, tasks, *, workers, scheduler, on_result, on_lost, on_start):
        on_start("manufactured")
        for t in tasks:
            on_result(self.run(t))


@pytest.fixture
def manufactured(monkeypatch):
    def install(seed, **kw):
        m = Manufactured(seed, **kw)
        monkeypatch.setattr("jointwear.sim.sweep._driver.execute_runs", m)
        return m

    return install


def test_default_spec_is_documented_levels():
    s = VerifySpec.default(4e5)
    assert s.levels == (5000, 10000, 20000, 40000)
    assert (s.replicates, s.grid, s.grid_replicates) == (4, 2, 4)


@pytest.mark.parametrize(
    ("table", "match"),
    [
        ({"verify": {"cycles": 1000, "levels": [10, 20, 40]}}, ">= 4 ΔN levels"),
        ({"verify": {"cycles": 1000, "levels": [10, 20, 40, 2000]}}, "exceeds the 1000 cycles"),
        ({"verify": {"cycles": 1000, "levels": [10, 20, 20, 40]}}, "repeats"),
        ({"verify": {"cycles": 1000, "replicates": 1}}, "replicates must be >= 2"),
        ({"verify": {"cycles": 1000, "grid": 1}}, "grid must be >= 2"),
        ({"verify": {"cycles": 1000, "replicate": 3}}, "unknown key"),
        ({"verify": {"levels": [1, 2, 3, 4]}}, "no cycles"),
        ({"sweep": {}}, "one \\[verify\\] table"),
    ],
)
def test_spec_refusals(table, match):
    with pytest.raises(ParameterError, match=match):
        read_verify_spec(table, cycles=None)


def test_study_file_holds_runs_maps_and_fits(manufactured, tmp_path):
    from jointwear import io

    m = manufactured(0)
    out = tmp_path / "study.nc"
    verify_wear(SMALL, cycles=8000, replicates=3, workers=0, out=out)
    ds = io.load(out)
    assert ds.attrs["jointwear_file"] == "verification_study"
    assert ds.attrs["data_origin"] == "simulated"
    assert ds.attrs["cycles"] == 8000
    assert "parameters_json" in ds.attrs and "provenance" in ds.attrs
    assert list(ds["h"].values) == [100, 200, 400, 800]
    assert ds["wear_depth_run"].shape == (4, 3, 12, 72)
    assert ds["wear_depth_grid_run"].shape == (3, 24, 144)
    assert ds["u_num"].attrs["coverage_factor"] == 1
    assert str(ds["quantity_units"].sel(quantity="worn_volume").values) == "m3"
    # the stored figures are what a consumer recomputes from the file
    for q in ("max_wear_depth", "worn_volume"):
        fit = study_uncertainty(ds, q)
        assert fit.assessed
        assert float(ds["u_num"].sel(quantity=q)) == pytest.approx(fit.u_num)
        # the runs' maps give the same quantity through a function of the wear map
    peak = study_uncertainty(ds, "peak", lambda w: float(w.max()))
    assert peak.u_num == pytest.approx(float(ds["u_num"].sel(quantity="max_wear_depth")))
    # motion quantities were not produced by the manufactured runs: not assessed, never zero
    assert int(ds["assessed"].sel(quantity="rms_contact_force")) == 0
    assert len(m.calls) == 4 * 3 + 3


def test_resume_computes_only_missing_runs(manufactured, tmp_path, monkeypatch):
    from jointwear.sim.sweep._store import parts_dir

    out = tmp_path / "study.nc"
    m = manufactured(1)
    original = m.run

    def flaky(task):
        if task.index == 5:
            raise KeyboardInterrupt
        return original(task)

    m.run = flaky
    with pytest.raises(KeyboardInterrupt):
        verify_wear(SMALL, cycles=8000, workers=0, out=out)
    done = {int(p.stem.split("-")[1]) for p in parts_dir(out).glob("run-*.npz")}
    assert done == set(m.calls) and 5 not in done and len(done) >= 1
    m2 = manufactured(1)
    ds = verify_wear(SMALL, cycles=8000, workers=0, out=out, resume=True)
    assert sorted(m2.calls) == sorted(set(range(4 * 4 + 4)) - done)
    assert ds.attrs["n_ok"] == 20
    assert not parts_dir(out).exists()
    # resuming a finished study computes nothing
    m3 = manufactured(1)
    verify_wear(SMALL, cycles=8000, workers=0, out=out, resume=True)
    assert m3.calls == []


def test_manufactured_coverage_of_the_exact_answer(manufactured):
    """|value - exact| <= 2 u_num in >= 90 % of 24 seeded manufactured studies."""
    hits = {"max_wear_depth": 0, "worn_volume": 0}
    naive = dict.fromkeys(hits, 0)  # the replicates' standard error alone: must fail
    cases = 24
    for seed in range(cases):
        m = manufactured(seed)
        ds = verify_wear(SMALL, cycles=8000, workers=0)
        exact = {"max_wear_depth": m.d0, "worn_volume": m.exact_volume}
        for q in hits:
            row = ds.sel(quantity=q)
            assert int(row["assessed"]) == 1
            err = abs(float(row["value"]) - exact[q])
            hits[q] += err <= 2 * float(row["u_num"])
            naive[q] += err <= 2 * float(row["u_stat"])
    for q, n in hits.items():
        assert n >= 0.9 * cases, f"{q}: covered in {n} of {cases} cases"
        # the check can fail: without the refinement and grid terms the coverage collapses
        assert naive[q] < 0.5 * cases, f"{q}: u_stat alone covered {naive[q]} of {cases}"


def test_manufactured_uncertainty_is_not_vacuous(manufactured):
    # a u_num so large that it covers anything would pass the coverage test: it must stay
    # within a few times the actual error scale (ΔN error at the finest level + grid + noise)
    m = manufactured(3)
    ds = verify_wear(SMALL, cycles=8000, workers=0)
    u = float(ds["u_num"].sel(quantity="max_wear_depth"))
    assert u < 0.1 * m.d0


def test_cli_bad_input_exit_3(tmp_path, capsys):
    out = tmp_path / "s.nc"
    assert main(["sim", "verify", "--out", str(out)]) == 3
    assert "--cycles" in capsys.readouterr().err
    spec = tmp_path / "spec.toml"
    spec.write_text("[verify]\ncycles = 1000\nlevels = [10, 20, 40]\n")
    assert main(["sim", "verify", str(spec), "--out", str(out)]) == 3
    assert ">= 4" in capsys.readouterr().err
    assert (
        main(["sim", "verify", "--cycles", "1e3", "--out", str(out), "--params", "nope.toml"]) == 3
    )
    capsys.readouterr()
    assert (
        main(
            [
                "sim",
                "verify",
                "--cycles",
                "1e3",
                "--out",
                str(out),
                "--workers",
                "1",
                "--scheduler",
                "tcp://x:1",
            ]
        )
        == 3
    )
    assert not out.exists()


def test_cli_runs_and_info_summarises(manufactured, tmp_path, capsys):
    manufactured(2)
    out = tmp_path / "study.nc"
    assert main(["sim", "verify", "--cycles", "8000", "--out", str(out), "--workers", "0"]) == 0
    text = capsys.readouterr().out
    assert "max_wear_depth =" in text and "k = 1" in text
    assert main(["info", str(out)]) == 0
    info = capsys.readouterr().out
    assert "verification study" in info and "worn_volume =" in info
    # an existing study is not replaced silently; --resume of a finished study computes nothing
    args = ["sim", "verify", "--cycles", "8000", "--out", str(out), "--workers", "0"]
    assert main(args) == 3
    assert "--overwrite" in capsys.readouterr().err
    m = manufactured(2)
    assert main([*args, "--resume"]) == 0
    assert m.calls == []


def test_band_quantities_from_the_run_maps(manufactured, tmp_path, capsys):
    m = manufactured(4)
    ds = verify_wear(SMALL, cycles=8000, workers=0, band=(-6e-3, 6e-3))
    assert ds.attrs["band_z_m"] == [-6e-3, 6e-3]
    whole = ds["replicate_value"].sel(quantity="worn_volume")
    inband = ds["replicate_value"].sel(quantity="worn_volume_in_band")
    # the bump (centre within +-2 mm, width 2.5 mm) lies nearly all inside +-6 mm
    assert float((inband / whole).min()) > 0.95 and float((inband / whole).max()) < 1.02
    assert abs(float(ds["value"].sel(quantity="worn_volume_in_band")) / m.exact_volume - 1) < 0.1
    deep = ds["replicate_value"].sel(quantity="max_wear_depth_in_band")
    assert bool((deep <= ds["replicate_value"].sel(quantity="max_wear_depth")).all())
    assert int(ds["assessed"].sel(quantity="max_wear_depth_in_band")) == 1
    with pytest.raises(BadInputError, match="needs two or more"):
        verify_wear(SMALL, cycles=8000, workers=0, band=(0.0, 1e-4))
    out = tmp_path / "s.nc"
    assert main(["sim", "verify", "--cycles", "8000", "--out", str(out), "--band-mm", "6,-6"]) == 3
    assert "z_min < z_max" in capsys.readouterr().err


def test_report_figure_plots_the_study(manufactured):
    from jointwear.reports.figures import verification_figure

    manufactured(5)
    ds = verify_wear(SMALL, cycles=8000, workers=0)
    fig = verification_figure([ds])
    assert fig is not None
    titles = [ax.get_title() for ax in fig.axes]
    assert any(t.startswith("max_wear_depth") for t in titles)
    assert any(t.startswith("worn_volume") for t in titles)


CONV = (
    "convergence_warning: the wear-rate field changed by 73 % over the update of 5000 cycles "
    "starting at 0 cycles: ... not converged; use the adaptive scheme or a smaller dN"
)


def test_runs_warnings_are_in_the_file_the_summary_and_info(manufactured, tmp_path, capsys):
    """Two of the finest level's runs and one grid run warn "not converged": the file holds each
    run's warnings, the counts per level, the text once, and the verdict says u_num may
    understate the error; the CLI output and ``jointwear info`` show it."""
    from jointwear import io

    manufactured(5, warn=lambda dn, settle: (CONV,) if dn == 100 and settle < 4 else ())
    out = tmp_path / "study.nc"
    assert main(["sim", "verify", "--cycles", "8000", "--out", str(out), "--workers", "0"]) == 0
    text = capsys.readouterr().out
    ds = io.load(out)
    counts = ds["level_warning_count"].sel(warning_kind="convergence_warning").values
    assert list(counts) == [2, 0, 0, 0]
    assert int(ds["grid_warning_count"].sel(warning_kind="convergence_warning")) == 2
    assert int(ds["level_warning_count"].sel(warning_kind="contact_validity_warning").sum()) == 0
    warned = [w for w in ds["run_warnings"].values if w]
    assert len(warned) == 4 and all("convergence_warning" in w for w in warned)
    summary = ds.attrs["run_warnings_summary"]
    assert "in 4 of 20 runs" in summary and "ΔN 100: 2 of 4" in summary
    assert summary.count("changed by 73 %") == 1  # the text once
    assert "may understate" in ds.attrs["run_warnings_verdict"]
    for shown in (text, None):
        if shown is None:
            assert main(["info", str(out)]) == 0
            shown = capsys.readouterr().out
        assert "run warnings: convergence_warning in 4 of 20 runs" in shown
        assert "for u_num: convergence_warning: the finest level" in shown


def test_coarse_level_warnings_and_validity_are_interpreted(manufactured):
    def warn(dn, settle):
        if dn == 800:
            return (CONV, "contact_validity_warning: penetration 0.3 of the clearance")
        return ()

    manufactured(6, warn=warn)
    ds = verify_wear(SMALL, cycles=8000, workers=0)
    verdict = ds.attrs["run_warnings_verdict"]
    assert "coarser levels (ΔN = 800)" in verdict and "finest level is converged" in verdict
    assert "model-form error is not in it" in verdict
    manufactured(6)
    quiet = verify_wear(SMALL, cycles=8000, workers=0)
    assert quiet.attrs["run_warnings_summary"] == "none"
    assert int(quiet["level_warning_count"].sum()) == 0


def test_seed_draws_the_start_phases(manufactured, tmp_path):
    m = manufactured(7)
    verify_wear(SMALL, cycles=8000, workers=0)
    base = sorted(set(m.settles))
    assert base == [2.0, 3.0, 4.0, 5.0]  # wear.initial_settle_cycles 2 + (0, 1, 2, 3)
    m = manufactured(7)
    ds = verify_wear(SMALL, cycles=8000, workers=0, seed=11)
    drawn = sorted(set(m.settles))
    assert len(drawn) == 4 and drawn != base
    assert all(2.0 <= s < 6.0 for s in drawn)
    assert sorted(ds["initial_settle_cycles"].values) == drawn
    assert json_spec(ds)["seed"] == 11
    m = manufactured(7)
    verify_wear(SMALL, cycles=8000, workers=0, seed=11)
    assert sorted(set(m.settles)) == drawn  # the same seed, the same phases
    m = manufactured(7)
    spec = VerifySpec.default(8000, phases=(0.25, 0.5, 1.5, 3.0))
    verify_wear(SMALL, spec=spec, workers=0)
    assert sorted(set(m.settles)) == [2.25, 2.5, 3.5, 5.0]


def json_spec(ds):
    import json

    return json.loads(ds.attrs["study_spec"])


@pytest.mark.parametrize(
    ("table", "match"),
    [
        ({"verify": {"cycles": 1000, "phases": [0, 1]}}, "4 replicates need 4 start phases"),
        ({"verify": {"cycles": 1000, "phases": [0, 1, -1, 2]}}, "must be >= 0"),
        ({"verify": {"cycles": 1000, "phases": [0, 1, 2, 3], "seed": 1}}, "not both"),
        ({"verify": {"cycles": 1000, "seed": -1}}, "seed must be >= 0"),
    ],
)
def test_phase_refusals(table, match):
    with pytest.raises(ParameterError, match=match):
        read_verify_spec(table, cycles=None)


def test_cli_seed(manufactured, tmp_path, capsys):
    m = manufactured(8)
    out = tmp_path / "s.nc"
    args = ["sim", "verify", "--cycles", "8000", "--out", str(out), "--workers", "0"]
    assert main([*args, "--seed", "3"]) == 0
    assert len(set(m.settles)) == 4 and sorted(set(m.settles)) != [2.0, 3.0, 4.0, 5.0]
    assert main([*args, "--seed", "-2", "--overwrite"]) == 2
