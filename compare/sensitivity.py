"""Which inputs dominate a compared quantity: Sobol indices, or SRC² labelled as what it is.

Two estimators, each named in the table's ``estimator`` column:

``S1`` / ``ST`` (Sobol, SALib)
    The first-order and total Sobol indices the ensemble carries (``sobol_S1``, ``sobol_ST``
    over ``output, parameter``: ``jointwear sim sweep`` with ``method = "sobol"``, Saltelli's
    design and SALib's estimator). They are variance shares for any model and independent inputs.

``SRC²`` (squared standardised regression coefficients)
    Of a linear least-squares fit of the quantity on the inputs of a random ensemble (LHS, Monte
    Carlo). For a linear model with *uncorrelated* inputs ``SRC²_i`` is the first-order Sobol
    index and ``Σ SRC² = R²`` (Saltelli et al. 2008, *Global Sensitivity Analysis. The Primer*,
    sec. 1.2.5). In a small sample the inputs are correlated by chance: then an SRC² is no share
    of the variance (it can exceed 1; the sum differs from R²), and for a non-linear response
    (R² well below 1) an input acting through an even function has SRC² ≈ 0 whatever its Sobol
    index. The method states R², the sum and the largest sample correlation of the inputs, and
    when R² < :data:`R2_MIN`, the sum misses R² by more than :data:`SUM_TOLERANCE` or a
    correlation exceeds :data:`CORRELATION_LIMIT` it says that the SRC² rank the inputs only.

Needs more runs than inputs + 1; else no row (the report says there is none).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from jointwear.compare.ensemble import Ensemble

__all__ = ["SENSITIVITY_COLUMNS", "src_squared", "sensitivity_table"]

SENSITIVITY_COLUMNS = ["quantity", "parameter", "S1", "ST", "method", "estimator"]

#: smallest R² of the linear fit for SRC² to be read as variance shares
R2_MIN = 0.9
#: largest |Σ SRC² − R²| for SRC² to be read as variance shares
SUM_TOLERANCE = 0.1
#: largest sample correlation of two inputs for SRC² to be read as variance shares
CORRELATION_LIMIT = 0.3


def src_squared(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, float, float]:
    """Squared standardised regression coefficients of ``y`` on the columns of ``x``.

    Parameters
    ----------
    x : ndarray, shape (n, p)
        Input values of the ``n`` runs [their units].
    y : ndarray, shape (n,)
        The quantity of each run [its unit].

    Returns
    -------
    (ndarray, float, float)
        ``SRC²`` per input [1], the R² of the fit [1] and the largest absolute sample correlation
        between two inputs [1] (0 for one input).
    """
    xs = (x - x.mean(axis=0)) / x.std(axis=0, ddof=1)
    ys = (y - y.mean()) / y.std(ddof=1)
    design = np.column_stack([np.ones(len(ys)), xs])
    beta, *_ = np.linalg.lstsq(design, ys, rcond=None)
    r2 = 1.0 - float(np.sum((ys - design @ beta) ** 2)) / float(np.sum(ys**2))
    corr = np.corrcoef(xs, rowvar=False) if xs.shape[1] > 1 else np.eye(1)
    off = np.abs(corr[~np.eye(len(corr), dtype=bool)])
    return beta[1:] ** 2, r2, float(off.max()) if off.size else 0.0


def _method(n: int, r2: float, total: float, corr: float) -> str:
    text = (
        f"SRC² of a linear fit over {n} runs (R² = {r2:.2f}, ΣSRC² = {total:.2f}, inputs "
        f"correlated in the sample up to |r| = {corr:.2f})"
    )
    if r2 < R2_MIN or abs(total - r2) > SUM_TOLERANCE or corr > CORRELATION_LIMIT:
        return text + (
            ": NOT variance shares (correlated inputs or a non-linear response; SRC² equals the "
            "first-order Sobol index only for a linear model of uncorrelated inputs) - a ranking"
        )
    return text + ": ≈ first-order Sobol indices (near-linear, nearly uncorrelated inputs)"


def _regression(
    ens: Ensemble, q: str, field_values: Mapping[str, Sequence[tuple[int, np.ndarray]]]
) -> list[dict[str, object]]:
    """SRC² rows of ``q`` over the first ensemble that has it."""
    found = list(field_values.get(q, ())) or ens.scalar(q)
    for i, y in found[:1]:
        ds = ens.datasets[i]
        names = [p for p in ens.parameters(i) if p in ds.coords and ds[p].dims == ("run",)]
        if not names:
            continue
        x = np.column_stack([np.asarray(ds[p].values, dtype=float) for p in names])
        ok = np.isfinite(y) & np.all(np.isfinite(x), axis=1)
        if ok.sum() <= len(names) + 1:
            continue
        if np.any(x[ok].std(axis=0, ddof=1) == 0) or np.std(y[ok]) == 0:
            continue
        src2, r2, corr = src_squared(x[ok], np.asarray(y)[ok])
        method = _method(int(ok.sum()), r2, float(src2.sum()), corr)
        return [
            {"quantity": q, "parameter": p, "S1": float(v), "ST": float("nan"), "method": method,
             "estimator": "SRC²"}
            for p, v in zip(names, src2, strict=True)
        ]  # fmt: skip
    return []


def sensitivity_table(
    ens: Ensemble | None,
    quantities: Sequence[str],
    field_values: Mapping[str, Sequence[tuple[int, np.ndarray]]],
) -> pd.DataFrame:
    """The sensitivity table of the compared ``quantities``: Sobol indices when the ensemble
    carries them, else SRC² (:func:`src_squared`), each row naming its index."""
    rows: list[dict[str, object]] = []
    if ens is not None:
        for q in quantities:
            sobol = [
                {"quantity": q, **r, "method": "Sobol (SALib)", "estimator": "S1"}
                for r in ens.sensitivity(q)
            ]
            rows += sobol or _regression(ens, q, field_values)
    return pd.DataFrame(rows, columns=SENSITIVITY_COLUMNS)
