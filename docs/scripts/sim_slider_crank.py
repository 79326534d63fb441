"""Figure for docs/sim.md ("The slider-crank"): the benchmark with its 0.5 mm clearance.

Runs ``PARAMETER_SETS["slider_crank"]`` (rod-slider clearance joint, 5000 rpm) for 6 crank
cycles and the ideal joint for one, and draws docs/img/sim-slider-crank.png: the journal centre
in the bearing, the joint force and the slider acceleration over the crank angle (cycles 2-6)
beside the ideal joint's. The figures quoted in the docs are printed and saved as
docs/img/sim-slider-crank.json.

Usage: ``python docs/scripts/sim_slider_crank.py`` (a few seconds CPU once compiled).
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from jointwear.io import atomic_path  # noqa: E402
from jointwear.params import replace_nested  # noqa: E402
from jointwear.sim import CONTACT_MODES, PARAMETER_SETS, run_cycles  # noqa: E402

IMG = Path(__file__).resolve().parent.parent / "img"
CYCLES = 6


def _episodes(in_contact: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    edges = np.diff(np.concatenate([[0], in_contact.astype(int), [0]]))
    start = np.flatnonzero(edges == 1)
    return start, np.flatnonzero(edges == -1) - start


def main() -> None:
    p = PARAMETER_SETS["slider_crank"]
    t0 = time.process_time()
    res = run_cycles(p, cycles=CYCLES)
    cpu = time.process_time() - t0
    n = round(p.mechanism.period / p.solver.output_interval)
    ds = res.dataset.isel(time=slice(n, None))
    ideal = run_cycles(replace_nested(p, **{"joint.model": "ideal"}), cycles=1.0).dataset
    c = p.joint.radial_clearance
    th = np.degrees(ds.crank_angle.values)
    order = np.argsort(ideal.crank_angle.values)  # the last sample wraps to 0
    ideal = ideal.isel(time=order)
    thi = np.degrees(ideal.crank_angle.values)
    mode = ds.contact_mode.values
    start, length = _episodes(mode != 0)
    dt = p.solver.output_interval
    impacts = start[length * dt < 2e-4]
    f = ds.contact_force.values
    acc = ds.slider_acceleration.values[:, 0]
    out = {
        "parameter_set": "slider_crank",
        "cycles_shown": f"2-{CYCLES}",
        "cpu_s_for_cycles": cpu,
        "n_steps": res.n_steps,
        "free_flight_fraction": float((mode == 0).mean()),
        "impacts_per_cycle": impacts.size / (CYCLES - 1),
        "impact_crank_angle_deg_range": [float(th[impacts].min()), float(th[impacts].max())],
        "longest_contact_ms": float(length.max() * dt * 1e3),
        "peak_contact_force_N": float(f.max()),
        "ideal_peak_joint_force_N": float(ideal.contact_force.max()),
        "peak_slider_acceleration_m_s2": float(np.abs(acc).max()),
        "ideal_peak_slider_acceleration_m_s2": float(np.abs(ideal.slider_acceleration[:, 0]).max()),
        "peak_penetration_um": float(ds.penetration.max()) * 1e6,
        "machine": "2-core VM, shared",
    }
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.4))
    e = ds.journal_offset.values[:, :2] / c
    ax[0].plot(e[:, 0], e[:, 1], lw=0.4, color="C0")
    phi = np.linspace(0, 2 * np.pi, 200)
    ax[0].plot(np.cos(phi), np.sin(phi), "k--", lw=0.8, label="clearance circle")
    ax[0].set_aspect("equal")
    ax[0].set_xlabel("journal centre x / c (slider frame)")
    ax[0].set_ylabel("journal centre y / c")
    ax[0].set_title("journal in the bearing (cycles 2-6)")
    ax[0].legend(loc="lower left", fontsize=8)
    for k in np.unique(mode):
        sel = mode == k
        ax[1].plot(th[sel], f[sel] / 1e3, ".", ms=1.2, label=CONTACT_MODES[int(k)])
    ax[1].plot(thi, ideal.contact_force / 1e3, "k-", lw=1.5, label="ideal joint")
    ax[1].set_yscale("symlog", linthresh=1.0)
    ax[1].set_xlabel("crank angle [deg]")
    ax[1].set_ylabel("joint force [kN]")
    ax[1].set_title("contact force at the rod-slider joint")
    ax[1].legend(fontsize=8, markerscale=6)
    ax[2].plot(th, acc / 1e3, ".", ms=1.0, color="C0", label="0.5 mm clearance")
    ax[2].plot(thi, ideal.slider_acceleration[:, 0] / 1e3, "k-", lw=1.5, label="ideal joint")
    ax[2].set_xlabel("crank angle [deg]")
    ax[2].set_ylabel("slider acceleration [km/s²]")
    ax[2].set_title("slider acceleration")
    ax[2].legend(fontsize=8, markerscale=6)
    for a in ax[1:]:
        a.set_xlim(0, 360)
        a.set_xticks(range(0, 361, 60))
    fig.tight_layout()
    with atomic_path(IMG / "sim-slider-crank.png") as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    with atomic_path(IMG / "sim-slider-crank.json") as tmp:
        Path(tmp).write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
