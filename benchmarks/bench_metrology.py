"""Metrology speed: import, MZ cylindricity, full assessment and wear map of a 13 x 18000 scan.

Targets (issue #5): import < 0.5 s, MZ cylindricity < 0.2 s, the whole ``assess`` command < 2 s.
The scan is the reference study's size (Talyrond 565H: 13 layers x 18000 points), written by
``jointwear.datasets.instruments`` as a folder of per-layer text exports and as one long file.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import cpu_time, median_time, write_results  # noqa: E402

from jointwear import io  # noqa: E402
from jointwear.datasets.instruments import generate, write  # noqa: E402
from jointwear.errors import BadInputError  # noqa: E402
from jointwear.metrology import assess, cylindricity, read_scan, wear_map  # noqa: E402

CONV = ("+y", "counterclockwise")


def time_or_refusal(fn, **kw) -> float | str:
    """Median wall time of ``fn()`` [s], or ``"refused: <message>"`` when the library refuses
    the benchmark's scan (the wear map refuses what it cannot separate from form)."""
    try:
        return round(median_time(fn, **kw)[0], 4)
    except BadInputError as exc:
        return f"refused: {exc}"


def main() -> None:
    sc = generate(n_layers=13, n_points=18000, seed=0, convention=CONV)
    before = generate(n_layers=13, n_points=18000, seed=0, noise_seed=1, convention=CONV, wear=None)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        write(sc, tmp / "folder", layout="folder")
        write(sc, tmp / "long.txt", layout="long")
        t_folder, _ = median_time(lambda: read_scan(tmp / "folder", convention=CONV), repeat=5)
        t_long, _ = median_time(lambda: read_scan(tmp / "long.txt", convention=CONV), repeat=5)
        scan = read_scan(tmp / "folder", convention=CONV)
        da = scan["radial_deviation"]
        t_mz, _ = median_time(lambda: cylindricity(da, reference="MZ"), repeat=7)
        t_refs = {}
        for ref in ("LS", "MI", "MC"):
            t_refs[ref], _ = median_time(lambda r=ref: cylindricity(da, reference=r), repeat=5)

        def full():
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return assess(scan)

        t_assess, _ = median_time(full, repeat=3)

        def full_filtered():
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return assess(scan, filter_upr=50, outliers=4)

        t_assess_f, _ = median_time(full_filtered, repeat=3)
        nc = tmp / "scan.nc"
        io.save(scan, nc, source="benchmark")
        cmd = [sys.executable, "-m", "jointwear", "metrology", "assess", str(nc), "--filter", "50"]
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            subprocess.run(cmd, check=True, capture_output=True)
            times.append(time.perf_counter() - t0)
        t_cli = sorted(times)[1]
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            subprocess.run(
                [sys.executable, "-m", "jointwear", "--version"], check=True, capture_output=True
            )
            times.append(time.perf_counter() - t0)
        t_start = sorted(times)[1]

        def in_process_command():
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return assess(io.load(nc), filter_upr=50)

        t_cmd_inproc, _ = median_time(in_process_command, repeat=3)
        cpu = {
            "import_folder": cpu_time(lambda: read_scan(tmp / "folder", convention=CONV), warmup=1),
            "import_long_file": cpu_time(
                lambda: read_scan(tmp / "long.txt", convention=CONV), warmup=1
            ),
            "cylindricity_MZ": cpu_time(
                lambda: cylindricity(da, reference="MZ"), repeat=5, warmup=1
            ),
            "assess_all_references": cpu_time(full, warmup=1),
            "load_and_assess_filter50": cpu_time(in_process_command, warmup=1),
        }
        b = before.truth[["radius"]]
        w = sc.truth[["radius"]]
        t_wear = time_or_refusal(lambda: wear_map(w, b), repeat=3)
        t_wear_nob = time_or_refusal(lambda: wear_map(w), repeat=3)
        t_reg = time_or_refusal(lambda: wear_map(w, b, register=True), repeat=1, warmup=0)
    write_results(
        "metrology",
        {
            "scan": "13 layers x 18000 points (Talyrond 565H size)",
            "import_folder_s": round(t_folder, 4),
            "import_long_file_s": round(t_long, 4),
            "cylindricity_MZ_s": round(t_mz, 4),
            "cylindricity_LS_MI_MC_s": {k: round(v, 4) for k, v in t_refs.items()},
            "assess_all_references_s": round(t_assess, 4),
            "assess_filter50_outliers_s": round(t_assess_f, 4),
            "assess_command_wall_s": round(t_cli, 3),
            "cli_startup_wall_s (python -m jointwear --version)": round(t_start, 3),
            "load_nc_and_assess_filter50_in_process_s": round(t_cmd_inproc, 4),
            "cpu_time_s (process_time, medians)": {k: round(v, 4) for k, v in cpu.items()},
            "wear_map_with_before_s": t_wear,
            "wear_map_without_before_s": t_wear_nob,
            "wear_map_with_registration_s": t_reg,
            "assess_command_note": "python -m jointwear metrology assess --filter 50, incl. start-up",
            "targets": "import < 0.5 s, MZ cylindricity < 0.2 s, whole assess command < 2 s",
        },
    )


if __name__ == "__main__":
    main()
