"""The shape criterion: the Pearson r of the simulated and measured maps, with its uncertainty.

r judges the pattern, not its size: any scale of the same map has r = 1 (the maximum depth,
worn volume and wear field judge the size). A right model does not reach r = 1: the
measurement's noise, the simulation's numerical error and the spread of its inputs all blur the
pattern, the more so the shallower the wear is against them. The criterion therefore states the
distribution of r under the hypothesis that the model is right, by Monte Carlo: the measured map
is drawn as ``D* = S + e`` with ``e`` from the comparison's own budget, per cell of the band,

* ``C_input``: a random combination of the ensemble members' deviations from their mean
  (``wear_depth_sim_ensemble``, three members or more, scaled to the compared total as the field
  criterion scales them); a user-stated ``wear_u_input_rel`` is a common scale, which leaves r
  unchanged (no term);
* ``u_num``: the simulation's per-point u, else a verification study's relative u_num of the
  maximum depth times ``|S|``, else a user-stated ``wear_u_num_rel·|S|``;
* ``u_D``: the measurement's per-point u, its independent part averaged over the cell;

the two per-point terms drawn independently per cell (which blurs the pattern the most). The
instrument's gain and a common radial offset do not change r (no term). The criterion fails when
``r < min(wear_r_min, r_α)``, ``r_α`` the ``α`` quantile of r under that hypothesis (``α`` =
``field_false_fail_rate``, 5 % by default): a pattern below the stated ``wear_r_min`` fails only
when its shortfall is more than the uncertainty explains, so a right model fails at most at the
rate ``α``. Where a part of the budget is unknown, r's uncertainty is not assessed and the
criterion is decided on ``wear_r_min`` alone, and says so. Its resolution is the turn of the
simulated pattern that brings r below the decided threshold.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import jointwear.compare.metrics as mt
import jointwear.compare.verdicts as vd
from jointwear.compare._decide import decision, threshold_state

__all__ = ["RDistribution", "r_distribution", "turn_resolution", "shape_criterion"]

#: Monte Carlo draws of r under the hypothesis that the model is right (fixed seed: the verdict
#: of a comparison is reproducible)
R_DRAWS = 1000
R_SEED = 20230


@dataclass(frozen=True)
class RDistribution:
    """r of ``S`` against ``S + e`` over the draws of ``e`` from the comparison's budget.

    Attributes
    ----------
    draws : ndarray
        r of each draw [1].
    basis : str
        The parts of ``e`` and where each comes from.
    """

    draws: np.ndarray
    basis: str

    def quantile(self, alpha: float) -> float:
        """The ``alpha`` quantile of r [1]."""
        return float(np.quantile(self.draws, alpha))


def _input_deviations(c) -> tuple[np.ndarray | None, str]:
    """The ensemble members' deviations on the band, ``(n, z, theta)``, scaled to the compared
    total, or None with the reason (an empty ``(0, z, theta)`` array: a common scale, no term)."""
    from jointwear.compare._field import too_few_members

    ens = c.al.get("wear_depth_sim_ensemble")
    members = [] if ens is None else [np.asarray(m, float) for m in np.asarray(ens.values, float)]
    members = [m for m in members if np.all(np.isfinite(m) | ~np.isfinite(c.s))]
    if len(members) >= 3 and (few := too_few_members(c, len(members))):
        return None, few
    if len(members) >= 3:
        x = np.nan_to_num(np.stack(members))
        mean = x.mean(axis=0)
        scale = np.nansum(c.s) / np.sum(mean) if np.sum(mean) != 0 else 1.0
        return (x - mean) * scale / np.sqrt(len(x) - 1), (
            f"C_input: {len(x)} ensemble members' deviations"
        )
    if c.criteria.wear_u_input_rel is not None:
        return np.zeros((0, *c.s.shape)), "C_input: a user-stated common scale (r unchanged)"
    return None, "no ensemble that keeps its wear maps (--ensemble) and no wear_u_input_rel"


def _per_cell(c) -> tuple[np.ndarray | None, np.ndarray | None, str]:
    """(u_num per cell, u_D per cell, basis) or a None and the reason."""
    from jointwear.compare._field import _study_rel
    from jointwear.compare._wear import _cell_u, _u_field

    u_sim, _ = _u_field(c.al, "wear_depth_sim_u")
    rel = c.criteria.wear_u_num_rel
    if u_sim is not None:
        u_num, note = u_sim, "u_num: the simulation's per-point u"
    elif (study := _study_rel(c)) is not None:
        u_num, note = study * np.abs(c.s), f"u_num: the verification's {study:.3g}·|S|"
    elif rel is not None:
        u_num, note = rel * np.abs(c.s), f"u_num: user-stated {rel:g}·|S|"
    else:
        return None, None, "the simulation states no per-point u and the criteria no wear_u_num_rel"
    u_meas, basis = _u_field(c.al, "wear_depth_meas_u")
    if u_meas is None:
        return u_num, None, "the measurement states no per-point uncertainty (wear_depth_u)"
    u_meas, _ = _cell_u(c.al, "wear_depth_meas_u", u_meas, basis)
    return u_num, u_meas, f"{note}; u_D: the measurement's per-point u (per cell)"


def r_distribution(c, draws: int = R_DRAWS, seed: int = R_SEED) -> tuple[RDistribution | None, str]:
    """The distribution of r under the hypothesis that the model is right (module docstring),
    or None and why it is not assessed."""
    dev, note = _input_deviations(c)
    if dev is None:
        return None, note
    u_num, u_meas, cell_note = _per_cell(c)
    if u_num is None or u_meas is None:
        return None, cell_note
    ok = np.isfinite(c.s) & np.isfinite(c.d)
    s = c.s[ok]
    dev = dev[:, ok]
    u = np.sqrt(np.nan_to_num(u_num[ok]) ** 2 + np.nan_to_num(u_meas[ok]) ** 2)
    rng = np.random.default_rng(seed)
    e = rng.standard_normal((draws, s.size)) * u
    if dev.shape[0]:
        e += rng.standard_normal((draws, dev.shape[0])) @ dev
    r = _pearson_rows(s, s + e)
    return RDistribution(r[np.isfinite(r)], f"{note}; {cell_note}"), ""


def _pearson_rows(s: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Pearson r of ``s`` (n,) against each row of ``x`` (draws, n) [1], in [-1, 1].

    Vectorised :func:`~jointwear.compare.metrics.pearson_r`, clipped as it is: round-off makes
    a row's r exceed 1 by a few ulp (a row equal to ``s``); NaN where either is constant.
    """
    sc = s - s.mean()
    dc = x - x.mean(axis=1, keepdims=True)
    den = np.sqrt(np.sum(sc**2) * np.sum(dc**2, axis=1))
    r = np.where(den > 0, (dc @ sc) / np.where(den > 0, den, 1.0), np.nan)
    return np.clip(r, -1.0, 1.0)


def turn_resolution(s: np.ndarray, theta_deg: np.ndarray, r_min: float) -> float:
    """The smallest turn of the pattern ``s`` that the shape criterion detects [degree].

    The Pearson r of ``s`` against itself turned by whole grid steps, both ways; the first turn
    at which r falls below ``r_min`` (linear between steps), the larger of the two directions.
    NaN when no turn up to 180 degree brings r below ``r_min``.
    """
    n = s.shape[1]
    step = 360.0 / n if n else float("nan")
    out = []
    for sign in (1, -1):
        prev_r, found = 1.0, float("nan")
        for k in range(1, n // 2 + 1):
            r = mt.pearson_r(s, np.roll(s, sign * k, axis=1))
            if not np.isfinite(r):
                break
            if r < r_min:
                found = step * (k - 1 + (prev_r - r_min) / (prev_r - r))
                break
            prev_r = r
        out.append(found)
    return float(max(out)) if all(np.isfinite(out)) else float("nan")


def shape_criterion(c) -> None:
    """Wear map shape: Pearson r >= min(``wear_r_min``, r_α), scale-invariant (NRMSE shown, not
    decided; module docstring).

    NRMSE (RMSE / range of D) cannot fail a scaled map: a map whose rms is 0.09 of its range
    gives NRMSE < 0.25 even for a zero prediction, so only r ever decided. The criterion says so:
    it judges the pattern, not its size, and states as its resolution the turn of the simulated
    pattern it detects.
    """
    criteria, nr, r = c.criteria, mt.nrmse(c.s, c.d), mt.pearson_r(c.s, c.d)
    alpha = criteria.field_false_fail_rate
    dist, why = r_distribution(c) if np.isfinite(r) else (None, "r undefined")
    limit = criteria.wear_r_min
    if dist is not None and dist.draws.size:
        r_alpha = dist.quantile(alpha)
        limit = min(limit, r_alpha)
        c.rows.add("wear_depth", "pearson_r_alpha", r_alpha, "1",
                   f"{alpha:g} quantile of r if the model is right ({dist.basis})")  # fmt: skip
        c.rows.add("wear_depth", "pearson_r_u", float(np.std(dist.draws)), "1", dist.basis)
        rule = f"r >= min({criteria.wear_r_min:g}, r_{alpha:g} = {r_alpha:.3g})"
        value = f"r = {r:.3g} (NRMSE = {nr:.3g}, shown, not decided)"
    else:
        rule = f"r >= {criteria.wear_r_min:g}"
        value = f"r = {r:.3g}; its uncertainty not assessed ({why}): decided on wear_r_min alone"
    th = np.asarray(c.al["theta"].values)
    turn = turn_resolution(c.s, th, limit)
    c.rows.add("wear_depth", "detectable_turn", turn, "degree", "r(S, S turned) = the limit")
    resolution = (
        f"scale-invariant (any scale of the same pattern passes); detects a turn of the "
        f"pattern beyond ±{turn:.0f} degree"
        if np.isfinite(turn)
        else "scale-invariant; no turn of this pattern brings r below its limit"
    )
    c.decisions.append(
        decision(
            f"wear map shape {c.band}",
            f"{rule} (Pearson; scale-invariant, the pattern not its size; false-fail rate "
            f"{alpha:.0%} where r's uncertainty is assessed)",
            value,
            vd.NOT_COMPARABLE
            if c.whole_nc
            else threshold_state(bool(r >= limit), bool(np.isfinite(r))),
            "threshold",
            c.whole_nc,
            key="wear_depth",
            resolution=resolution,
        )
    )
