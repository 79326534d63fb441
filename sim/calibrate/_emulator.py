"""A Gaussian-process emulator of the simulator's calibration quantities, with its own error.

One :class:`sklearn.gaussian_process.GaussianProcessRegressor` per quantity (a squared-exponential
kernel with one length scale per parameter, a constant and a white-noise term for the
simulator's cycle-to-cycle scatter; hyperparameters by maximum marginal likelihood), trained on
the inputs scaled to [0, 1] over the prior's range. A quantity that is positive in every
training run (wear) is emulated in its logarithm, where wear is close to linear in ln kw.

The emulator's error is estimated by leave-one-out cross-validation (each training run
predicted by the process fitted to the others, hyperparameters held at the full fit's). The
RMS of those residuals, relative for a logarithmic quantity (:attr:`Emulator.cv_error`), holds
two parts: the simulator's own scatter between runs (cycle-to-cycle variability: the process's
white-noise term, :attr:`Emulator.scatter`), which is numerical uncertainty of one run, and the
error of the emulated mean, ``sqrt(cv_error² - scatter²)`` (:attr:`Emulator.error`), carried in
the likelihood beside u_D and u_num (the scatter is a floor of u_num there, not counted twice).
Both are averages over the prior's range: the posterior may sit where the emulator is better
or worse.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

__all__ = ["Emulator", "fit_emulator"]


@dataclass
class Emulator:
    """Trained emulator of ``n_q`` quantities over ``n_p`` scaled inputs.

    Attributes
    ----------
    models : list
        One fitted GaussianProcessRegressor per quantity.
    log : ndarray of bool (n_q,)
        Whether each quantity is emulated in its logarithm.
    cv_error : ndarray (n_q,)
        Leave-one-out RMS error (relative for a logarithmic quantity, else in its units).
    cv_residuals : ndarray (n_train, n_q)
        The leave-one-out residuals (transformed scale).
    scatter : ndarray (n_q,)
        The simulator's scatter between runs (white-noise term; same scale as ``cv_error``).
    """

    models: list
    log: np.ndarray
    cv_error: np.ndarray
    cv_residuals: np.ndarray
    scatter: np.ndarray

    @property
    def error(self) -> np.ndarray:
        """Error of the emulated mean, ``sqrt(max(cv_error² - scatter², 0))`` (n_q,)."""
        return np.sqrt(np.maximum(self.cv_error**2 - self.scatter**2, 0.0))

    @property
    def correlation(self) -> np.ndarray:
        """Correlation of the runs' scatter between the quantities (n_q, n_q): that of the
        leave-one-out residuals (a start phase that deepens the maximum need not add as much
        volume), made positive semi-definite; 1 on the diagonal."""
        r = self.cv_residuals
        with np.errstate(invalid="ignore", divide="ignore"):
            c = np.atleast_2d(np.corrcoef(r, rowvar=False))
        c = np.where(np.isfinite(c), c, 0.0)
        np.fill_diagonal(c, 1.0)
        lam, vec = np.linalg.eigh(c)
        c = (vec * np.maximum(lam, 0.0)) @ vec.T
        d = np.sqrt(np.clip(np.diag(c), 1e-300, None))
        return c / np.outer(d, d)

    def predict(self, x: np.ndarray) -> np.ndarray:
        """Emulated quantities at scaled inputs ``x`` (n, n_p) -> (n, n_q), in their units."""
        x = np.atleast_2d(x)
        cols = []
        for model, lg in zip(self.models, self.log, strict=True):
            m = model.predict(x)
            cols.append(np.exp(m) if lg else m)
        return np.column_stack(cols)

    def error_sd(self, y: np.ndarray) -> np.ndarray:
        """The emulated mean's standard uncertainty at emulated values ``y`` (n, n_q), units of y."""
        return self.in_units(self.error, y)

    def scatter_sd(self, y: np.ndarray) -> np.ndarray:
        """The simulator's scatter between runs at emulated values ``y`` (n, n_q), units of y."""
        return self.in_units(self.scatter, y)

    def in_units(self, e: np.ndarray, y: np.ndarray) -> np.ndarray:
        """A per-quantity error ``e`` on the emulated scale in the units of ``y`` (n, n_q)."""
        y = np.atleast_2d(y)
        return np.where(self.log, e * np.abs(y), e)


def _gp(n_p: int, seed: int):
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

    kernel = ConstantKernel(1.0, (1e-4, 1e4)) * RBF(
        length_scale=np.ones(n_p), length_scale_bounds=(1e-2, 1e3)
    ) + WhiteKernel(1e-6, (1e-12, 1e-1))
    return GaussianProcessRegressor(
        kernel=kernel, normalize_y=True, n_restarts_optimizer=2, random_state=seed
    )


def _loo(model, x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Leave-one-out residuals of a fitted process, hyperparameters held."""
    from sklearn.base import clone

    res = np.empty(len(t))
    for i in range(len(t)):
        keep = np.arange(len(t)) != i
        m = clone(model).set_params(kernel=model.kernel_, optimizer=None)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            m.fit(x[keep], t[keep])
        res[i] = float(m.predict(x[i : i + 1])[0]) - t[i]
    return res


def fit_emulator(x: np.ndarray, y: np.ndarray, *, seed: int = 0) -> Emulator:
    """Train one process per column of ``y`` (n, n_q) on scaled inputs ``x`` (n, n_p).

    Raises
    ------
    ValueError
        Fewer than 4 training runs or a non-finite value (the caller refuses it with its fix).
    """
    x = np.atleast_2d(np.asarray(x, dtype=float))
    y = np.asarray(y, dtype=float).reshape(len(x), -1)
    if len(x) < 4 or not np.all(np.isfinite(y)):
        raise ValueError("the emulator needs at least 4 finished training runs with finite values")
    models, logs, cv, resid, scatter = [], [], [], [], []
    for k in range(y.shape[1]):
        lg = bool(np.all(y[:, k] > 0))
        t = np.log(y[:, k]) if lg else y[:, k]
        model = _gp(x.shape[1], seed)
        with warnings.catch_warnings():
            # a converged bound of a length scale (an inert input) is an answer, not an error
            warnings.simplefilter("ignore")
            model.fit(x, t)
        r = _loo(model, x, t)
        models.append(model)
        logs.append(lg)
        resid.append(r)
        cv.append(float(np.sqrt(np.mean(r**2))))
        white = float(model.kernel_.k2.noise_level)  # of the normalised target
        scatter.append(float(np.sqrt(white) * np.ravel(model._y_train_std)[0]))
    return Emulator(models, np.array(logs), np.array(cv), np.column_stack(resid), np.array(scatter))
