"""What a sweep reports beyond its outputs: warnings of the runs, angles, sample sizes.

* :func:`warning_summary`: one line per kind of warning over the runs (the console shows these
  instead of one warning per run);
* :func:`circular_summary`: circular mean and spread of an angle output;
* :func:`sample_size_check`: whether a Sobol or Morris sample was large enough for the indices
  asked of it, and which ``samples`` would be (limits :data:`SOBOL_CONF_LIMIT`,
  :data:`MORRIS_CONF_LIMIT`).
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np
import xarray as xr

__all__ = [
    "SOBOL_CONF_LIMIT",
    "MORRIS_CONF_LIMIT",
    "circular_summary",
    "warning_summary",
    "sample_size_check",
]

#: Largest acceptable half-width of a Sobol index's confidence interval (indices lie in [0, 1]).
SOBOL_CONF_LIMIT: float = 0.1

#: Largest acceptable half-width of Morris mu* relative to the largest mu* of the output.
MORRIS_CONF_LIMIT: float = 0.1


def circular_summary(theta_deg: np.ndarray) -> dict[str, float]:
    """Circular mean and spread of the finished runs' angles [degree] (variable attributes)."""
    from scipy.stats import circmean, circstd

    a = np.radians(theta_deg[np.isfinite(theta_deg)])
    if not a.size:
        return {}
    return {
        "circular_mean_deg": float(np.degrees(circmean(a)) % 360.0),
        "circular_std_deg": float(np.degrees(circstd(a))),
        "comment": "an angle: summarise it by circular_mean_deg / circular_std_deg (the arithmetic "
        "mean and standard deviation depend on where the cut at 0/360 lies); its Sobol and "
        "Morris indices are refused: use its cosine and sine (max_wear_theta_cos, _sin)",
    }


def warning_summary(ds: xr.Dataset) -> list[str]:
    """One line per kind of warning of the runs: how many runs, which, and an example."""
    if "run_warnings" not in ds:
        return []
    kinds: dict[str, list[int]] = {}
    example: dict[str, str] = {}
    for i, text in enumerate(np.asarray(ds["run_warnings"].values)):
        for item in json.loads(str(text)) if text else []:
            kind, _, msg = item.partition(": ")
            kinds.setdefault(kind, []).append(i)
            example.setdefault(kind, msg)
    n = ds.sizes["run"]
    lines = []
    for kind, runs in kinds.items():
        shown = ", ".join(str(r) for r in runs[:8]) + (", ..." if len(runs) > 8 else "")
        msg = example[kind]
        lines.append(
            f"{kind} in {len(runs)} of {n} runs (run {shown}), e.g.: "
            f"{msg[:200]}{'...' if len(msg) > 200 else ''}"
        )
    return lines


def _next_power_of_2(x: float) -> int:
    return 1 << max(0, math.ceil(math.log2(max(x, 1.0))))


def sample_size_check(ds: xr.Dataset, method: str, samples: int) -> dict[str, Any]:
    """Was ``samples`` enough for the sensitivity indices in ``ds``? Which N would be?

    Sobol: the largest half-width of the S1/ST confidence intervals must not exceed
    :data:`SOBOL_CONF_LIMIT`, and sum(S1) must not exceed 1 by more than its own uncertainty
    (the half-widths combined in quadrature). The half-widths shrink as 1/sqrt(N), so the
    recommended N is the next power of 2 above N (half-width / limit)^2 (at least 4 N when only
    the sum is off). Morris: the largest mu* half-width relative to the output's largest mu*
    against :data:`MORRIS_CONF_LIMIT`, same scaling in the number of trajectories.

    Returns
    -------
    dict
        ``ok`` (bool), ``recommended_samples`` (int, = ``samples`` when ok), ``problems`` (one
        line per output that failed a limit).
    """
    problems = []
    need = float(samples)
    if method == "sobol" and "sobol_S1" in ds:
        for out in ds["output"].values:
            s1 = ds["sobol_S1"].sel(output=out).values
            conf = np.concatenate(
                [
                    ds["sobol_S1_conf"].sel(output=out).values,
                    ds["sobol_ST_conf"].sel(output=out).values,
                ]
            )
            if not np.all(np.isfinite(conf)):
                continue  # not assessed (failed runs, or a refused output)
            worst = float(np.max(conf))
            total, u_total = (
                float(np.sum(s1)),
                float(np.sqrt(np.sum(ds["sobol_S1_conf"].sel(output=out).values ** 2))),
            )
            if worst > SOBOL_CONF_LIMIT:
                need = max(need, samples * (worst / SOBOL_CONF_LIMIT) ** 2)
                problems.append(
                    f"{out}: confidence half-width up to {worst:.2g} > {SOBOL_CONF_LIMIT:g}"
                )
            if total > 1.0 + u_total:
                need = max(need, 4.0 * samples)
                problems.append(f"{out}: sum of S1 = {total:.2f} > 1 + {u_total:.2f}")
        recommended = _next_power_of_2(need)
    elif method == "morris":
        for name in ds.data_vars:
            if not str(name).endswith("_morris_mu_star"):
                continue
            mu = ds[name].values
            conf = ds[f"{name}_conf"].values
            if not (np.all(np.isfinite(mu)) and np.all(np.isfinite(conf))) or np.max(mu) <= 0:
                continue
            worst = float(np.max(conf) / np.max(mu))
            if worst > MORRIS_CONF_LIMIT:
                need = max(need, samples * (worst / MORRIS_CONF_LIMIT) ** 2)
                out = str(name)[: -len("_morris_mu_star")]
                problems.append(
                    f"{out}: mu* half-width up to {worst:.2g} of the largest mu* > "
                    f"{MORRIS_CONF_LIMIT:g}"
                )
        recommended = math.ceil(need)
    else:
        return {"ok": True, "recommended_samples": samples, "problems": []}
    return {"ok": not problems, "recommended_samples": int(recommended), "problems": problems}
