"""Power of the validation verdict on known truth, full size (issue 20).

A truth rig (``zhang2023`` parameters, 5·10⁴ wear cycles on 15 x 72 points) is measured through
virtual Talyrond scans on the reference study's layout (13 layers at 1 mm over z = -6…+6 mm,
18000 points per layer, instrument noise, set-up eccentricity/tilt, form errors, a before-wear
scan), imported and made a wear map as a user would. Candidates, each with its own u_input
(an 8-run LHS ensemble around its own inputs) and u_num (its own adaptive-update ``_u``):
the right model (5 independent runs with other update tolerances, against 5 measurement
replicates with independent noise), kw x 2, joint offset 0, friction 0, and the right model's
map turned by 180 degree. Figures: false-fail rate of the right model, the smallest number of
wear criteria it passes, the detection rate of each wrong model and the criteria that caught
it, the exit code of the turned map; see :mod:`jointwear.reports.power`.

Writes ``benchmarks/results/validation_power.json``.
"""

from __future__ import annotations

import logging
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results  # noqa: E402

from jointwear.reports.power import FULL_SIZE, run_power  # noqa: E402


def main() -> None:
    logging.disable(logging.WARNING)  # the adaptive update's noise warnings, once per run
    result = run_power(FULL_SIZE, progress=lambda m: print(m, flush=True))
    write_results("validation_power", result)


if __name__ == "__main__":
    main()
