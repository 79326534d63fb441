"""Form model of an unworn bore, for wear maps without a before-wear scan.

Without a scan of the bore before wear, the unworn surface must be *modelled* and fitted to the
points the fit considers unworn. The model (:class:`FormBasis`) holds what a real bore and its
set-up have:

* a centre per layer (cos, sin per layer): the set-up's eccentricity and tilt, and a bent axis;
* a smooth axial trend of the radius, a polynomial of degree ``axial_degree`` (2) in z: taper
  and barrel shape;
* lobing, harmonics 2 .. ``harmonics`` (15) whose cosine and sine coefficients vary smoothly
  (polynomial of degree ``axial_degree``) along z: the form of a machined bore.

It is linear in its coefficients, so the fit is exact least squares on the unworn points and
its covariance is propagated into every depth and into every quantity derived from the map
(:func:`derived_uncertainties`). What the model cannot hold stays in the residual of the
unworn points and is counted in the uncertainty (with its correlation along theta).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "FormBasis",
    "correlation_length",
    "lower_quantile_fit",
    "noise_sigma",
    "select_harmonics",
]


class FormBasis:
    """Design matrix of the form model, assembled one layer at a time (never in full).

    Parameters
    ----------
    z : ndarray
        Layer heights [m].
    theta_deg : ndarray
        Angles [degree].
    harmonics : int
        Highest lobing harmonic (UPR).
    axial_degree : int
        Degree of the polynomials in z (capped at n_layers - 1).
    """

    def __init__(self, z: np.ndarray, theta_deg: np.ndarray, harmonics: int, axial_degree: int):
        self.nz, self.nt = z.size, theta_deg.size
        t = np.radians(theta_deg)
        zc = z - 0.5 * (z.min() + z.max())
        self.zeta = zc / max(0.5 * np.ptp(zc), 1e-12)
        self.deg = int(min(axial_degree, self.nz - 1))
        kmax = int(min(harmonics, self.nt // 4))
        ks = np.arange(2, kmax + 1)
        self.lobes = (
            np.concatenate([np.cos(np.outer(t, ks)), np.sin(np.outer(t, ks))], axis=1)
            if ks.size
            else np.zeros((self.nt, 0))
        )
        self.centre = np.stack([np.cos(t), np.sin(t)], axis=1)  # (nt, 2)
        self.n_centre = 2 * self.nz
        self.n_shared = (self.deg + 1) * (1 + self.lobes.shape[1])
        self.shape = (self.nz * self.nt, self.n_centre + self.n_shared)
        self.harmonics = kmax

    def _shared(self) -> np.ndarray:
        return np.concatenate([np.ones((self.nt, 1)), self.lobes], axis=1)  # (nt, q)

    def _cols(self, i: int) -> np.ndarray:
        """Columns that are non-zero in layer ``i``: its centre, then every shared column."""
        return np.concatenate([[2 * i, 2 * i + 1], np.arange(self.n_centre, self.shape[1])])

    def layer(self, i: int) -> np.ndarray:
        """The non-zero columns (:meth:`_cols`) of layer ``i``'s rows (nt, 2 + shared)."""
        pw = self.zeta[i] ** np.arange(self.deg + 1)
        S = self._shared()
        return np.concatenate([self.centre] + [p * S for p in pw], axis=1)

    def normal(self, d: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """Normal matrix, right-hand side and sum of squares of ``d`` on the masked points,
        assembled from per-layer products of the (nt, 2) centre and (nt, q) shared blocks."""
        p = self.shape[1]
        G = np.zeros((p, p))
        rhs = np.zeros(p)
        mm = np.asarray(mask, dtype=float).reshape(self.nz, self.nt)  # a mask or weights
        dd = np.where(mm > 0, d.reshape(self.nz, self.nt), 0.0) * mm
        S, C = self._shared(), self.centre
        q = S.shape[1]
        nc = self.n_centre
        for i in range(self.nz):
            pw = self.zeta[i] ** np.arange(self.deg + 1)
            mS = S * mm[i][:, None]
            A = S.T @ mS
            B = C.T @ mS
            c = slice(2 * i, 2 * i + 2)
            G[c, c] = C.T @ (C * mm[i][:, None])
            rhs[c] = C.T @ dd[i]
            rs = S.T @ dd[i]
            for j, pj in enumerate(pw):
                sj = slice(nc + j * q, nc + (j + 1) * q)
                G[c, sj] = pj * B
                G[sj, c] = pj * B.T
                rhs[sj] += pj * rs
                for k, pk in enumerate(pw):
                    G[sj, nc + k * q : nc + (k + 1) * q] += pj * pk * A
        return G, rhs, float(np.sum(np.where(mm > 0, dd**2 / np.where(mm > 0, mm, 1), 0.0)))

    def fitted(self, b: np.ndarray) -> np.ndarray:
        """The model surface for coefficients ``b`` (all points, layer by layer)."""
        S, q, nc = self._shared(), self._shared().shape[1], self.n_centre
        out = []
        for i in range(self.nz):
            pw = self.zeta[i] ** np.arange(self.deg + 1)
            bs = sum(p * b[nc + j * q : nc + (j + 1) * q] for j, p in enumerate(pw))
            out.append(self.centre @ b[2 * i : 2 * i + 2] + S @ bs)
        return np.concatenate(out)

    def columns(self, k: int) -> np.ndarray:
        """Indices of the columns of the sub-model with lobing harmonics 2 .. k."""
        m = self.lobes.shape[1] // 2
        kk = min(k - 1, m)
        keep = [0] + [1 + j for j in range(kk)] + [1 + m + j for j in range(kk)]
        per = 1 + 2 * m
        idx = list(range(self.n_centre))
        for j in range(self.deg + 1):
            idx += [self.n_centre + j * per + c for c in keep]
        return np.asarray(idx)

    def lsq(self, d: np.ndarray, mask: np.ndarray):
        """Least squares on the masked points: (coefficients, fitted values, normal matrix)."""
        G, rhs, _ = self.normal(d, mask)
        # columns with no support (a layer without unworn points) make G singular
        b = np.linalg.solve(G, rhs)
        return b, self.fitted(b), G

    def fit_variance(self, cov: np.ndarray) -> np.ndarray:
        """Variance of the fitted surface at every point [m^2]."""
        out = []
        for i in range(self.nz):
            c = self._cols(i)
            Xi = self.layer(i)
            out.append(np.einsum("nj,jk,nk->n", Xi, cov[np.ix_(c, c)], Xi))
        return np.concatenate(out)

    def weighted_sum(self, w: np.ndarray) -> np.ndarray:
        """sum_i w_i X_i (p,) for point weights ``w`` (nz, nt)."""
        a = np.zeros(self.shape[1])
        for i in range(self.nz):
            a[self._cols(i)] += w[i] @ self.layer(i)
        return a


def correlation_length(resid: np.ndarray, mask: np.ndarray) -> float:
    """Integrated correlation length [samples] of a residual along theta (masked points = 0).

    1 + 2 sum of the autocorrelation up to its first zero crossing, averaged over layers; 1 for
    white noise. Used to count the effective number of independent residuals.
    """
    r = np.where(mask, resid, 0.0)
    n = r.shape[1]
    f = np.fft.rfft(r, axis=1)
    g = np.fft.rfft(mask.astype(float), axis=1)
    ac = np.fft.irfft(np.abs(f) ** 2, n, axis=1).sum(axis=0)
    cnt = np.fft.irfft(np.abs(g) ** 2, n, axis=1).sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        rho = np.where(cnt > 0.5, ac / np.maximum(cnt, 1), 0.0)
    if not rho[0] > 0:
        return 1.0
    rho = rho / rho[0]
    tau = 1.0
    for k in range(1, n // 2):
        if rho[k] <= 0:
            break
        tau += 2.0 * rho[k]
    return float(tau)


def noise_sigma(values: np.ndarray) -> float:
    """Point-to-point noise of a profile [same unit]: 1.4826 MAD of second differences / √6
    (form and set-up vary smoothly between neighbouring samples, noise does not)."""
    d = np.diff(np.asarray(values, dtype=float), n=2, axis=-1).ravel()
    d = d[np.isfinite(d)]
    if d.size == 0:
        return float("nan")
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(6.0))


def select_harmonics(basis: FormBasis, d: np.ndarray, mask: np.ndarray) -> tuple[int, dict]:
    """Highest lobing harmonic by the Bayesian information criterion on the masked points.

    Sub-models (harmonics 2 .. k, k = 1 .. ``basis.harmonics``) are fitted from sub-blocks of one
    normal matrix; returns (k, {k: BIC}). A harmonic enters only if it lowers
    n ln(RSS / n) + p ln(n): form above the noise is modelled, noise is not.
    """
    G, rhs, dd = basis.normal(d, mask)
    n = int(mask.sum())
    table = {}
    for k in range(1, basis.harmonics + 1):
        idx = basis.columns(k)
        try:
            b = np.linalg.solve(G[np.ix_(idx, idx)], rhs[idx])
        except np.linalg.LinAlgError:
            break
        rss = max(dd - float(rhs[idx] @ b), 1e-300)
        table[k] = n * np.log(rss / n) + idx.size * np.log(n)
    return min(table, key=table.get), table


def lower_quantile_fit(
    basis: FormBasis, d: np.ndarray, finite: np.ndarray, tau: float = 0.25, iters: int = 40
) -> np.ndarray:
    """Residual of a ``tau``-quantile fit of the form model (iteratively reweighted).

    Wear only removes material, so it lies above the unworn surface: a low quantile of the
    data is hardly pulled by it (a least-squares fit to all points is), while the model still
    follows taper and lobing. Used to find a first unworn set.
    """
    w = finite.astype(float)
    dd = np.where(finite, d, 0.0)
    scale = max(float(np.std(dd[finite])), 1e-12)
    for _ in range(iters):
        G, rhs, _ = basis.normal(dd, w)
        b = np.linalg.solve(G, rhs)
        r = dd - basis.fitted(b)
        a = np.maximum(np.abs(r), 1e-4 * scale)
        w = np.where(finite, np.where(r > 0, tau, 1.0 - tau) / a, 0.0)
        scale = max(float(np.median(np.abs(r[finite]))), 1e-12)
    return np.where(finite, r, np.nan)
