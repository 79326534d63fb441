"""Power of the validation verdict as curves on three truths (issue 36).

Truths: the reference rig (``zhang2023``), the same with tilt stiffness 1000, and with a 0.7-mm
radial clearance, each measured through virtual Talyrond scans on the reference study's layout
(13 layers at 1 mm over z = -6…+6 mm, instrument noise, set-up eccentricity/tilt, a before-wear
scan), imported and made a wear map as a user would, in ``size.replicates`` noise replicates.
Candidates: the right model run independently (its own start phase per replicate, its own grid,
its own ``sim verify`` study and its own LHS ensemble), graded wrong models (kw x 0.7 ... x 2,
friction x 2, clearance +20 %, speed -20 %, joint offset 0, tilt stiffness 0 against the tilt
truth), each with its own ensemble and u_num, and the right model's map turned by 180 degree.
Figures: per truth and candidate, the detection probability of each wear criterion and the
any-fail rate (the right model's = its false-fail rate); see :mod:`jointwear.reports.power`.

The size (``BENCH_SIZE``: 4e5 cycles on 10 x 36 points, 20 replicates, 6-run ensembles, a
4-level study, two grid runs) is what the shared 2-core machine allowed; it is written with the
results. Results are written after each truth; every run and scan is kept in ``--cache``, so a
stopped benchmark resumes and a change of the criteria re-decides without simulating.

Writes ``benchmarks/results/validation_power.json``.

``--with-calibration``: the calibrate-then-validate path
(:mod:`jointwear.reports.power_calibrated`, size ``CAL_BENCH_SIZE``: kw calibrated on the
truth's 2e5-cycle scans, the posterior prediction validated at 4e5, every candidate also
compared without calibration on the same maps), written to
``benchmarks/results/validation_power_calibrated.json``; ``--only NAME`` (repeatable: "right"
or a wrong model) runs those candidates into the cache's ``calibrated_parts`` (start a second
process once the first has made the scans) and ``--merge`` writes the JSON from the parts.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import sys
import tempfile
from dataclasses import asdict, replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results  # noqa: E402

from jointwear.reports.power import BENCH_SIZE, run_power  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--cache",
        type=Path,
        default=Path(tempfile.gettempdir()) / "jointwear_validation_power",
        help="folder of the runs and scans (kept: a stopped run resumes, a criterion change "
        "re-decides without simulating)",
    )
    parser.add_argument(
        "--truth",
        action="append",
        default=[],
        help="run only this truth (repeatable; its results go to the cache folder, and --merge "
        "writes the JSON from them): truths in parallel processes",
    )
    parser.add_argument(
        "--merge", action="store_true", help="write the JSON from the truths run with --truth"
    )
    parser.add_argument(
        "--with-calibration",
        action="store_true",
        help="the calibrate-then-validate path (validation_power_calibrated.json)",
    )
    parser.add_argument(
        "--only",
        action="append",
        default=None,
        help="--with-calibration: run only this candidate ('right' or a wrong model; repeatable)",
    )
    parser.add_argument(
        "--wrong-replicates",
        type=int,
        default=None,
        help="--with-calibration: replicates of each wrong model (default CAL_BENCH_SIZE's)",
    )
    parser.add_argument(
        "--prior-half-width",
        type=float,
        default=None,
        help="--with-calibration --only: kw's prior ± this fraction instead of CAL_BENCH_SIZE's "
        "(a variant, merged apart under 'prior_variants')",
    )
    parser.add_argument(
        "--training-runs",
        type=int,
        default=None,
        help="--with-calibration --prior-half-width: the variant's training runs (samples)",
    )
    args = parser.parse_args()
    logging.disable(logging.WARNING)  # the adaptive update's noise warnings, once per run
    if args.with_calibration:
        _with_calibration(args)
        return

    def save(result: dict) -> None:
        load = os.getloadavg()[0]
        write_results(
            "validation_power",
            {**result, "load_1min": load, "note": "2-core machine shared with other jobs"},
        )

    parts = args.cache / "truth_results"
    if args.merge:
        merged: dict = {"size": asdict(BENCH_SIZE), "truths": {}, "cpu_s": 0.0}
        missing = []
        for name in BENCH_SIZE.truths:
            path = parts / f"{name}.json"
            if not path.exists():  # not finished in the time: said, not hidden
                missing.append(name)
                continue
            part = json.loads(path.read_text())
            merged["truths"][name] = part["truths"][name]
            merged["cpu_s"] += part["cpu_s"]
            merged.setdefault("load_1min_at_end_by_truth", {})[name] = part.get("load_1min")
        save({**merged, "truths_not_measured": missing})
        return
    size = replace(BENCH_SIZE, truths=tuple(args.truth)) if args.truth else BENCH_SIZE

    def keep_part(result: dict) -> None:
        parts.mkdir(parents=True, exist_ok=True)
        for name in result["truths"]:
            out = {
                "truths": {name: result["truths"][name]},
                "cpu_s": result["cpu_s"],
                "load_1min": os.getloadavg()[0],
            }
            (parts / f"{name}.json").write_text(json.dumps(out))

    run_power(
        size,
        folder=args.cache,
        progress=lambda m: print(m, flush=True),
        on_truth=keep_part if args.truth else save,
    )


def _with_calibration(args: argparse.Namespace) -> None:
    """The calibrate-then-validate power study (parts with --only, merged with --merge)."""
    from jointwear.reports.power_calibrated import (
        CAL_BENCH_SIZE,
        kw_over_truth_median,
        run_power_calibrated,
    )

    parts = args.cache / "calibrated_parts"
    note = (
        "2-core machine shared with other agents' jobs (nice); cpu_s: the CPU of the processes "
        "that wrote the parts, runs already in the cache (the power benchmark's study, ensembles "
        "and runs; a part's posteriors and predictions when it was resumed) not counted again"
    )
    if args.merge:
        merged: dict = {"size": CAL_BENCH_SIZE.describe(), "truths": {}, "cpu_s": 0.0}
        loads = {}
        for path in sorted(parts.glob("*.json")):
            part = json.loads(path.read_text())
            merged["cpu_s"] += part["cpu_s"]
            loads[path.stem] = part["load_1min"]
            if "prior_half_width" in part:  # a variant: another prior, kept apart
                key = f"kw prior ±{100 * part['prior_half_width']:.0f} %"
                if part.get("training_runs"):
                    key += f", {part['training_runs']} training runs"
                into = merged.setdefault("prior_variants", {}).setdefault(key, {})
                for name, truth in part["truths"].items():
                    into.setdefault(name, {}).update(truth["candidates"])
                continue
            for name, truth in part["truths"].items():
                into = merged["truths"].setdefault(name, {**truth, "candidates": {}, "cpu_s": 0.0})
                for entry in truth["candidates"].values():  # parts run before it was kept
                    w = entry["with_calibration"]
                    w["kw_over_truth_median"] = kw_over_truth_median(w["replicates_detail"])
                into["candidates"].update(truth["candidates"])
                into["cpu_s"] += truth["cpu_s"]
        wanted = {t: ("right", *CAL_BENCH_SIZE.wrong.get(t, ())) for t in CAL_BENCH_SIZE.truths}
        missing = {
            t: [c for c in names if c not in merged["truths"].get(t, {}).get("candidates", {})]
            for t, names in wanted.items()
        }
        write_results(
            "validation_power_calibrated",
            {**merged, "load_1min_by_part": loads, "not_measured": missing, "note": note},
        )
        return

    def save(result: dict) -> None:
        load = os.getloadavg()[0]
        if args.only:
            parts.mkdir(parents=True, exist_ok=True)
            slug = "_".join(
                "".join(ch if ch.isalnum() else "_" for ch in o) for o in (*args.truth, *args.only)
            )
            extra = {}
            if args.prior_half_width is not None:
                slug += f"_prior{100 * args.prior_half_width:.0f}"
                extra = {"prior_half_width": args.prior_half_width}
                if args.training_runs is not None:
                    slug += f"_runs{args.training_runs}"
                    extra["training_runs"] = args.training_runs
            out = {**result, **extra, "load_1min": load}
            (parts / f"{slug}.json").write_text(json.dumps(out))
        else:
            write_results(
                "validation_power_calibrated", {**result, "load_1min": load, "note": note}
            )

    size = CAL_BENCH_SIZE
    if args.truth:  # another truth of CAL_BENCH_SIZE's lists (a part per truth and candidates)
        if not args.only:
            raise SystemExit("--with-calibration --truth: give the candidates with --only")
        size = replace(size, truths=tuple(args.truth))
    if args.wrong_replicates is not None:
        size = replace(size, wrong_replicates=args.wrong_replicates)
    if args.prior_half_width is not None:
        if not args.only:
            parser_error = "--prior-half-width is a variant: give the candidates with --only"
            raise SystemExit(parser_error)
        size = replace(size, prior_half_width=args.prior_half_width)
        if args.training_runs is not None:
            size = replace(size, training_runs=args.training_runs)
    run_power_calibrated(
        size,
        folder=args.cache,
        progress=lambda m: print(m, flush=True),
        on_truth=save,
        only=tuple(args.only) if args.only else None,
    )


if __name__ == "__main__":
    main()
