"""Whole-band field criteria: the wear maps compared as fields, with their covariance.

The scalar criteria judge the band through a few numbers (maximum, volume, cylindricity); two
models whose peaks nearly coincide pass them while the *form* of the wear differs (issue 36: a
joint with tilt stiffness 0 against one with 1000 piles the wear at the band's edges instead of
spreading it). These criteria compare the fields themselves, by the multivariate validation
metric of Hills & Leslie (2003) and Rebba & Mahadevan (2006): the Mahalanobis distance of the
difference of the simulated and measured feature vectors,

``D² = eᵀ C⁻¹ e``,  ``C = C_input + C_num + C_D``,

over the principal components of ``C`` (its eigenvectors; directions with no variance dropped,
their count ``K`` the degrees of freedom). Under the hypothesis that the model is right (its
error is only what the budget says), ``D²`` follows χ²(K): the criterion fails when
``D² > χ²_{1-α}(K)``, so ``α`` (criteria ``field_false_fail_rate``, default 5 %) is the rate at
which a right model fails, stated on the card. Two feature vectors:

* **wear field** (``wear_field``): the mean wear depth in ``field_bins_z`` × ``field_bins_theta``
  bins of the band (the cells averaged, so that interpolation detail and the measurement's
  independent noise do not dominate);
* **axial distribution** (``axial_distribution``): the share of the band's worn volume in each
  measured layer (sums to 1: one fewer degree of freedom; scale-free, it sees where along the
  band the wear lies, not how much).

The covariance, each part stated in the basis:

* ``C_input``: the sample covariance of the features over the ensemble's members aligned on the
  band (``wear_depth_sim_ensemble``, three members or more; a reduced ensemble's deviations
  scaled to the compared total); else, for the wear field only, a user-stated
  ``wear_u_input_rel`` as a common scale error, ``rel² s sᵀ`` (it says nothing of the form: the
  axial distribution then is not assessed);
* ``C_num``: the simulation's own per-point u (independent between bins, fully correlated within
  one: an upper bound for a bin mean), else a verification study's relative u_num of the
  maximum depth, else a user-stated relative u_num, as a per-point u ``rel·|s|``;
* ``C_D``: the measurement's per-point u like the simulation's, with the instrument's stated gain
  (``gain_u_rel² d dᵀ``) and radial offset (``probe_u_m² 1 1ᵀ``, depth features only).

Any part unknown: *not assessed*, never zero. The resolution of the field criterion is stated
as the smallest common scale error it detects along ``s`` (``±sqrt(χ² / sᵀ C⁻¹ s)``); form
errors are detected when ``D²`` exceeds the threshold.

References
----------
- Hills, R. G., Leslie, I. H. (2003). Statistical validation of engineering and scientific
  models: validation experiments to application. Sandia report SAND2003-0706.
- Rebba, R., Mahadevan, S. (2006). Validation of models with multivariate output. *Reliab. Eng.
  Syst. Saf.* 91, 861-871.
- Oberkampf, W. L., Roy, C. J. (2010). *Verification and Validation in Scientific Computing*,
  ch. 12-13 (validation metrics for field data).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

import jointwear.compare.verdicts as vd
from jointwear.compare._decide import decision
from jointwear.wear_field import field_bins, field_means

__all__ = ["Features", "FieldTest", "mahalanobis_test", "field_criterion", "axial_criterion_field"]


@dataclass(frozen=True)
class FieldTest:
    """A Mahalanobis test of a feature difference.

    Attributes
    ----------
    d2 : float
        ``eᵀ C⁺ e`` over the principal components of ``C`` [1].
    dof : int
        Number of components kept (the rank of ``C``).
    threshold : float
        ``χ²_{1-α}(dof)`` [1].
    p_value : float
        ``P(χ²(dof) > d2)`` [1].
    scale_resolution : float
        Smallest relative scale error along the prediction ``s`` that fails, ``sqrt(threshold /
        sᵀ C⁺ s)`` [1] (NaN when ``s`` has no component).
    """

    d2: float
    dof: int
    threshold: float
    p_value: float
    scale_resolution: float

    @property
    def passed(self) -> bool:
        return self.d2 <= self.threshold


def mahalanobis_test(
    e: np.ndarray,
    cov: np.ndarray,
    alpha: float,
    s: np.ndarray | None = None,
    estimated: tuple[np.ndarray, int] | None = None,
) -> FieldTest:
    """Mahalanobis distance of ``e`` with covariance ``cov``, decided at false-fail rate ``alpha``.

    Components whose variance is below ``1e-12`` of the largest are dropped (a pseudo-inverse):
    ``cov`` may be singular (shares summing to 1). ``estimated = (dev, nu)``: the part of
    ``cov`` that is a sample covariance, ``devᵀ dev`` with ``dev`` the ``n`` members' deviations
    from their mean over ``sqrt(nu)`` (``nu = n - 1``); its estimation error is then part of the
    limit (:func:`_estimated_limit`), not only χ².
    """
    lam, vec = np.linalg.eigh(0.5 * (cov + cov.T))
    keep = lam > 1e-12 * max(float(lam.max()), 0.0)
    lam, vec = lam[keep], vec[:, keep]
    proj = vec.T @ e
    d2 = float(np.sum(proj**2 / lam))
    dof = int(keep.sum())
    thr = float(stats.chi2.ppf(1.0 - alpha, dof)) if dof else float("nan")
    p_value = float(stats.chi2.sf(d2, dof)) if dof else float("nan")
    if estimated is not None and dof and estimated[0].shape[0] >= 2:
        draws = _estimated_null(vec, lam, *estimated)
        thr = float(np.quantile(draws, 1.0 - alpha))
        p_value = float(np.mean(draws > d2))
    res = float("nan")
    if s is not None and dof:
        ss = float(np.sum((vec.T @ s) ** 2 / lam))
        res = float(np.sqrt(thr / ss)) if ss > 0 else float("inf")
    return FieldTest(d2, dof, thr, p_value, res)


#: parametric-bootstrap draws of D² when part of the covariance is estimated (fixed seed: a
#: comparison's verdict is reproducible)
NULL_DRAWS = 4000
NULL_SEED = 36


def _estimated_null(vec: np.ndarray, lam: np.ndarray, dev: np.ndarray, nu: int) -> np.ndarray:
    """Draws of D² under the hypothesis that the model is right, with the ensemble's part of the
    covariance estimated from ``n = dev.shape[0]`` members, as the comparison estimates it.

    A parametric bootstrap (Efron & Tibshirani 1993, ch. 6): in the kept components, the
    ensemble's part ``A = devᵀ dev`` (``dev`` already over ``sqrt(nu)``) and the known rest
    ``R = diag(lam) - A``; each draw makes a new ensemble of ``n`` members from ``N(0, A)``, its
    sample covariance ``A*`` (``nu`` degrees of freedom), a difference ``e* ~ N(0, A + R)`` and
    ``D²* = e*ᵀ (A* + R)⁻¹ e*``. With ``R = 0`` this is Hotelling's T² with ``(K, nu)``, whose
    limit is ``K nu / (nu - K + 1) F(K, nu - K + 1)`` (Hotelling 1931; tested); with a large
    ensemble it tends to χ²(K).
    """
    rng = np.random.default_rng(NULL_SEED)
    root = vec.T @ dev.T  # (K, n): A = root rootᵀ
    k, n = root.shape
    a = root @ root.T
    rest = np.diag(lam) - a
    w, v = np.linalg.eigh(0.5 * (rest + rest.T))
    rest_root = v * np.sqrt(np.clip(w, 0.0, None))
    fake = root @ rng.standard_normal((NULL_DRAWS, n, n))  # members as columns (NULL_DRAWS, K, n)
    fake -= fake.mean(axis=2, keepdims=True)
    a_star = fake @ fake.transpose(0, 2, 1) / nu
    e = root @ rng.standard_normal((n, NULL_DRAWS)) + rest_root @ rng.standard_normal(
        (k, NULL_DRAWS)
    )
    e = e.T[:, :, None]
    c_star = a_star + rest
    floor = 1e-12 * float(lam.max()) * np.eye(k)
    sol = np.linalg.solve(c_star + floor, e)
    return np.sum(e * sol, axis=(1, 2))


@dataclass(frozen=True)
class Features:
    """A feature vector of a band map: functions of the means over groups of cells.

    Attributes
    ----------
    groups : list of (ndarray, ndarray)
        Row (z) and column (theta) indices of the cells of each group.
    shares : bool
        False: the features are the group means; True: each group's share of their sum.
    """

    groups: list[tuple[np.ndarray, np.ndarray]]
    shares: bool = False

    def means(self, f: np.ndarray) -> np.ndarray:
        """Mean over each group's finite cells (NaN for a group with none: an angular gap)."""
        return field_means(f, self.groups)

    def where(self, *maps: np.ndarray) -> Features:
        """The groups restricted to the cells finite in every map (a partial arc's gap left
        out), groups with no such cell dropped."""
        ok = np.logical_and.reduce([np.isfinite(m) for m in maps])
        groups = []
        for i, j in self.groups:
            sub = ok[np.ix_(i, j)]
            if sub.any():
                rows, cols = i[sub.any(axis=1)], j[sub.any(axis=0)]
                groups.append((rows, cols))
        return Features(groups, self.shares)

    def __call__(self, f: np.ndarray) -> np.ndarray:
        g = self.means(f)
        return g / np.sum(g) if self.shares else g

    def jacobian(self, f: np.ndarray) -> np.ndarray:
        """d(features) / d(group means) at ``f``."""
        g = self.means(f)
        if not self.shares:
            return np.eye(g.size)
        return (np.eye(g.size) - np.outer(g / np.sum(g), np.ones(g.size))) / np.sum(g)

    def u_cov(self, u: np.ndarray, f: np.ndarray) -> np.ndarray:
        """Covariance of the features from a per-point u: fully correlated within a group (the
        group mean's u is the mean u, an upper bound), independent between groups."""
        jac = self.jacobian(f)
        return jac @ np.diag(self.means(u) ** 2) @ jac.T


@dataclass(frozen=True)
class _Parts:
    cov: np.ndarray
    basis: str
    estimated: tuple[np.ndarray, int] | None = None


def too_few_members(c, n: int) -> str:
    """Why ``n`` ensemble members cannot give the inputs' covariance ('' when they can).

    A sample covariance of ``n`` members spans at most ``n - 1`` directions: with no more members
    than the ensemble varies inputs, a direction of the inputs' effect is missing and a right
    model fails far more often than the stated rate (4 members over 4 inputs: 22 % instead of
    5 % on synthetic truth; 5 members: 5 %).
    """
    ens = c.src.ensemble
    if ens is None:
        return ""
    keep = [i for i, _ in ens.field("wear_depth")]
    inputs = ens.parameters(keep[0]) if keep else ()
    if inputs and n <= len(inputs):
        return (
            f"the ensemble's {n} members cannot span the {len(inputs)} inputs it varies "
            f"({', '.join(inputs)}): its sample covariance misses a direction of their effect; "
            f"give an ensemble of at least {len(inputs) + 1} members (--ensemble)"
        )
    return ""


def _input_part(
    c, feature: Features, fs: np.ndarray
) -> tuple[np.ndarray | None, str, np.ndarray | None]:
    """(C_input, its basis, the members' deviations over sqrt(n - 1) when it is estimated)."""
    ens = c.al.get("wear_depth_sim_ensemble")
    members = (
        [] if ens is None else [m for m in np.asarray(ens.values, float) if np.isfinite(m).any()]
    )
    rel = c.criteria.wear_u_input_rel
    x = np.array([feature(m) for m in members]).reshape(len(members), fs.size)
    x = x[np.all(np.isfinite(x), axis=1)]
    if len(x) >= 3 and (few := too_few_members(c, len(x))):
        return None, few, None
    if len(x) >= 3:
        dev = x - x.mean(axis=0)
        if not feature.shares:  # a reduced ensemble: its deviations scaled to the compared total
            dev = dev * (np.sum(fs) / np.sum(x.mean(axis=0)))
        dev = dev / np.sqrt(len(x) - 1)
        return (
            dev.T @ dev,
            (
                f"C_input: sample covariance of {len(x)} ensemble members (its estimation error in "
                "the limit)"
            ),
            dev,
        )
    if rel is not None and not feature.shares:
        return rel**2 * np.outer(fs, fs), f"C_input: user-stated {rel:g}·s as a common scale", None
    if rel is not None:
        return (
            None,
            (
                "a stated wear_u_input_rel is a common scale, which says nothing of the form's input "
                "uncertainty: give an ensemble that keeps its wear maps (--ensemble)"
            ),
            None,
        )
    return None, "no ensemble that keeps its wear maps (--ensemble) and no wear_u_input_rel", None


def _study_rel(c) -> float | None:
    """The relative u_num of the maximum depth a verification study gives (None: none)."""
    if not (c.src.studies or c.src.gci):
        return None
    s_max = c.sim_max[0]
    u = c.src.u_num("max_wear_depth", s_max, None, "wear")
    if not u.known or s_max == 0 or "user-stated" in u.basis:
        return None
    return float(u.value) / abs(s_max)


def _covariance(c, feature: Features) -> tuple[_Parts | None, str]:
    """The total covariance of the features of the compared band, or why it is not assessed."""
    from jointwear.compare._wear import _cell_u, _u_field

    al, s, d, crit = c.al, c.s, c.d, c.criteria
    fs = feature(s)
    c_in, note, dev = _input_part(c, feature, fs)
    if c_in is None:
        return None, note
    parts, notes = [c_in], [note]
    u_sim, _ = _u_field(al, "wear_depth_sim_u")
    rel = crit.wear_u_num_rel
    if u_sim is not None:
        parts.append(feature.u_cov(u_sim, s))
        notes.append("C_num: the simulation's per-point u")
    elif (study := _study_rel(c)) is not None:
        parts.append(feature.u_cov(study * np.abs(s), s))
        notes.append(
            f"C_num: the verification's u_num of the maximum depth, {study:.3g}·|s| per point"
        )
    elif rel is not None:
        parts.append(feature.u_cov(rel * np.abs(s), s))
        notes.append(f"C_num: user-stated {rel:g}·|s| per point")
    else:
        return None, "the simulation states no per-point u and the criteria no wear_u_num_rel"
    u_meas, basis = _u_field(al, "wear_depth_meas_u")
    if u_meas is None:
        return None, "the measurement states no per-point uncertainty (wear_depth_u)"
    u_meas, _ = _cell_u(al, "wear_depth_meas_u", u_meas, basis)  # its random part averaged
    parts.append(feature.u_cov(u_meas, d))
    notes.append("C_D: the measurement's per-point u")
    if crit.gain_u_rel is not None and not feature.shares:
        fd = feature(d)
        parts.append(crit.gain_u_rel**2 * np.outer(fd, fd))
        notes.append(f"gain {crit.gain_u_rel:g}·d")
    if crit.probe_u_m is not None and not feature.shares:
        parts.append(crit.probe_u_m**2 * np.ones((fs.size, fs.size)))
        notes.append(f"offset {crit.probe_u_m * 1e6:.3g} µm")
    estimated = (dev, dev.shape[0] - 1) if dev is not None else None
    return _Parts(sum(parts), "; ".join(notes), estimated), ""


def _decide(c, key: str, label: str, feature: Features, what: str) -> None:
    crit = c.criteria
    alpha = crit.field_false_fail_rate
    feature = feature.where(c.s, c.d)
    fs, fd = feature(c.s), feature(c.d)
    criterion = (
        f"Mahalanobis D² <= its 1 - {alpha:g} limit over the principal components of C_input + "
        f"C_num + C_D (chi²(K); with an ensemble's sample covariance, its estimation error "
        f"included by parametric bootstrap) ({what}; false-fail rate {alpha:.0%})"
    )
    if not (np.all(np.isfinite(fs)) and np.all(np.isfinite(fd))):
        c.decisions.append(
            decision(label, criterion, "n/a", vd.NOT_COMPARABLE, "field",
                     "a feature of the band has no value", key=key)
        )  # fmt: skip
        return
    parts, why = _covariance(c, feature)
    if parts is None:
        c.decisions.append(
            decision(label, criterion, f"{fs.size} features", vd.NOT_ASSESSED, "field", why,
                     key=key)
        )  # fmt: skip
        return
    test = mahalanobis_test(
        fs - fd, parts.cov, alpha, None if feature.shares else fs, parts.estimated
    )
    c.rows.add(key, "mahalanobis_d2", test.d2, "1", parts.basis)
    c.rows.add(key, "mahalanobis_dof", float(test.dof), "1")
    limit = (
        f"parametric bootstrap, 1 - {alpha:g} quantile, the ensemble's {parts.estimated[1] + 1} "
        "members re-drawn"
        if parts.estimated is not None
        else f"chi2(1 - {alpha:g})"
    )
    c.rows.add(key, "mahalanobis_threshold", test.threshold, "1", limit)
    c.rows.add(key, "mahalanobis_p", test.p_value, "1")
    resolution = f"detects D² > {test.threshold:.3g} (K = {test.dof})"
    if not feature.shares and np.isfinite(test.scale_resolution):
        c.rows.add(key, "detectable_scale_error", test.scale_resolution, "1")
        resolution += f"; a common scale error beyond ±{test.scale_resolution:.0%}"
    c.decisions.append(
        decision(
            label,
            criterion,
            f"D² = {test.d2:.3g} over K = {test.dof} (p = {test.p_value:.2g})",
            vd.PASS if test.passed else vd.FAIL,
            "field",
            key=key,
            resolution=resolution,
        )
    )


def field_criterion(c) -> None:
    """The whole-band wear field: bin means, Mahalanobis distance (``wear_field``)."""
    crit = c.criteria
    n_z, n_theta = c.s.shape[0], c.s.shape[1]
    feature = Features(field_bins(n_z, n_theta, crit.field_bins_z, crit.field_bins_theta))
    what = (
        f"mean depth in {min(crit.field_bins_z, n_z)} × {min(crit.field_bins_theta, n_theta)} bins"
    )
    _decide(c, "wear_field", f"wear field {c.band}", feature, what)


def axial_criterion_field(c) -> None:
    """The axial distribution of the wear: share of the band's volume per layer."""
    cols = np.arange(c.s.shape[1])
    feature = Features([(np.array([i]), cols) for i in range(c.s.shape[0])], shares=True)
    what = f"share of the band's volume in each of {c.s.shape[0]} layers"
    _decide(c, "axial_distribution", f"axial distribution of the wear {c.band}", feature, what)
