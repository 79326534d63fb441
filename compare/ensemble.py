"""Input uncertainty from an ensemble of simulations (a sweep over uncertain model inputs).

An ensemble is an :class:`xarray.Dataset` with a ``run`` dimension (what
:func:`jointwear.sim.run_sweep` returns): the sampled parameter values are coordinates along
``run``, the outputs are variables. ASME V&V 20 takes the input uncertainty ``u_input`` of a
simulated quantity as the standard deviation of that quantity over the input distribution, which
is what the spread of the ensemble estimates (sample standard deviation, ``ddof = 1``, over the
runs that finished).

Which variable of the ensemble is which compared quantity:

* ``max_wear_depth``, ``worn_volume``, ``cylindricity`` [m, m3, m] over ``run`` (scalar outputs);
* the RMS of a motion component, compared as ``follower_velocity_x_rms``: a variable
  ``follower_velocity_x_rms``, ``follower_velocity_rms_x`` or ``follower_velocity_rms`` over
  ``(run, axis)``;
* fields, when the ensemble keeps them: ``wear_depth`` over ``(run, [cycles,] z, theta)`` and
  motion variables over ``(run, time[, axis])``; each run is then aligned with the measurement
  like the simulation itself and the compared quantities are computed from it, on exactly the
  compared window (preferred over the scalar outputs, which may cover the whole bearing).

If the ensemble was run for a different number of wear cycles than the comparison (a reduced
ensemble), the spread of a wear quantity is used relative to the ensemble mean and scaled to the
compared value (``u_input = s / |mean| * |S|``); the basis says so. An ensemble that does not
state its cycles (attribute ``cycles``, or a ``cycles`` axis of its maps) gives no u_input for
wear quantities: its spread could belong to any wear time.

Several ensembles (``--ensemble`` repeated) must vary disjoint sets of parameters; their
variances then add (independent inputs). Two that vary the same parameter are refused.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr

from jointwear.compare._decide import Uncertainty, unknown
from jointwear.errors import BadInputError

__all__ = ["Ensemble", "as_ensemble", "spread"]

WEAR_QUANTITIES = ("max_wear_depth", "worn_volume", "cylindricity")


def _parameters(ds: xr.Dataset) -> tuple[str, ...]:
    """The varied inputs: ``sweep_parameters`` (jointwear sim sweep) or the run coordinates."""
    stated = ds.attrs.get("sweep_parameters")
    if isinstance(stated, str):
        stated = [stated]
    if stated is not None and len(stated):
        return tuple(sorted(str(p) for p in stated))
    skip = {"run", "run_seed"}
    return tuple(sorted(str(c) for c in ds.coords if c not in skip and ds[c].dims == ("run",)))


def _cycles(ds: xr.Dataset) -> float | None:
    for src in (ds.attrs.get("cycles"), ds.attrs.get("sweep_cycles")):
        try:
            value = float(src)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            continue
        if np.isfinite(value):
            return value
    if "wear_depth" in ds and "cycles" in ds["wear_depth"].dims:
        return float(ds["cycles"].values[-1])
    return None


@dataclass(frozen=True)
class Ensemble:
    """One or more ensembles of simulations, checked (``run`` dimension, disjoint parameters).

    Attributes
    ----------
    datasets : tuple of Dataset
        The ensembles.
    names : tuple of str
        Where each came from (file name or ``"ensemble <i>"``), for the report.
    """

    datasets: tuple[xr.Dataset, ...]
    names: tuple[str, ...]

    def parameters(self, i: int) -> tuple[str, ...]:
        """The parameters ensemble ``i`` varies (its coordinates along ``run``)."""
        return _parameters(self.datasets[i])

    def cycles(self, i: int) -> float | None:
        """Wear cycles ensemble ``i`` was run for (attribute ``cycles``), None if not stated."""
        return _cycles(self.datasets[i])

    def scalar(self, quantity: str) -> list[tuple[int, np.ndarray]]:
        """Per-run values of a compared quantity from scalar outputs: (ensemble index, values)."""
        out = []
        for i, ds in enumerate(self.datasets):
            values = _scalar_values(ds, quantity)
            if values is not None:
                out.append((i, values))
        return out

    def field(self, name: str) -> list[tuple[int, xr.DataArray]]:
        """Ensembles that keep a field (``wear_depth``, ``follower_velocity``, ...) over ``run``."""
        return [
            (i, ds[name])
            for i, ds in enumerate(self.datasets)
            if name in ds.data_vars and "run" in ds[name].dims and ds[name].ndim > 1
        ]

    def sensitivity(self, quantity: str) -> list[dict[str, object]]:
        """Sobol indices of a quantity when the ensemble has them (rows parameter, S1, ST)."""
        rows: list[dict[str, object]] = []
        for ds in self.datasets:
            for kind in ("S1", "ST"):
                for name in (f"sobol_{kind}", f"{quantity}_{kind}", f"{kind}"):
                    if name not in ds.data_vars:
                        continue
                    var = ds[name]
                    if "output" in var.dims:
                        outs = [str(o) for o in var["output"].values]
                        if quantity not in outs:
                            continue
                        var = var.sel(output=quantity)
                    elif name in (kind, f"sobol_{kind}"):
                        continue
                    if var.dims != ("parameter",):
                        continue
                    for p, v in zip(var["parameter"].values, var.values, strict=True):
                        row = next((r for r in rows if r["parameter"] == str(p)), None)
                        if row is None:
                            row = {"parameter": str(p), "S1": float("nan"), "ST": float("nan")}
                            rows.append(row)
                        row[kind] = float(v)
                    break
        return rows


def _scalar_values(ds: xr.Dataset, quantity: str) -> np.ndarray | None:
    candidates = [quantity]
    if quantity.endswith("_rms"):
        base = quantity[: -len("_rms")]
        name, _, comp = base.rpartition("_")
        if comp in ("x", "y", "z"):
            candidates += [f"{name}_rms_{comp}", (f"{name}_rms", comp)]
        else:
            candidates += [f"{base}_rms"]
    for cand in candidates:
        if isinstance(cand, tuple):
            name, comp = cand
            if name in ds.data_vars and set(ds[name].dims) == {"run", "axis"}:
                axes = [str(a) for a in ds["axis"].values]
                if comp in axes:
                    return np.asarray(ds[name].sel(axis=comp).values, dtype=float)
            continue
        if cand in ds.data_vars and ds[cand].dims == ("run",):
            return np.asarray(ds[cand].values, dtype=float)
    return None


def as_ensemble(
    objs: xr.Dataset | Sequence[xr.Dataset] | Ensemble | None,
    names: Sequence[str] | None = None,
) -> Ensemble | None:
    """Check ensemble datasets and bundle them (None stays None).

    Raises
    ------
    BadInputError
        A dataset has no ``run`` dimension, fewer than 2 runs, or two ensembles vary the same
        parameter (their spreads cannot be combined).
    """
    if objs is None or isinstance(objs, Ensemble):
        return objs
    items = [objs] if isinstance(objs, xr.Dataset) else list(objs)
    if not items:
        return None
    labels = list(names) if names is not None else [f"ensemble {i + 1}" for i in range(len(items))]
    seen: dict[str, str] = {}
    for ds, label in zip(items, labels, strict=True):
        if "run" not in ds.dims:
            raise BadInputError(
                f"{label}: an ensemble needs a 'run' dimension (one member per run, as written by "
                f"'jointwear sim sweep'); found dimensions {', '.join(map(str, ds.dims)) or 'none'}"
            )
        if ds.sizes["run"] < 2:
            raise BadInputError(f"{label}: {ds.sizes['run']} run(s); a spread needs at least 2")
        for p in _parameters(ds):
            if p in seen:
                raise BadInputError(
                    f"{label} and {seen[p]} both vary '{p}': their spreads would count that "
                    "input twice; give one ensemble per independent group of inputs"
                )
            seen[p] = label
    return Ensemble(tuple(items), tuple(labels))


def not_a_distribution(ds: xr.Dataset, label: str) -> str:
    """Why an ensemble's spread is not a propagated input uncertainty ('' when it is).

    A grid or a Morris design (``probabilistic_sample`` false, as ``jointwear sim sweep``
    records it) samples the inputs evenly, not from their distribution; its spread means
    nothing for V&V 20. Runs that failed or were not run make the spread of the others biased
    (failures may cluster in one region of the inputs).
    """
    prob = ds.attrs.get("probabilistic_sample")
    if prob is not None and str(prob).lower() in ("false", "0", "no"):
        method = ds.attrs.get("sweep_method", "a grid or Morris design")
        return (
            f"{label} is a {method} sweep, not a sample of the input distribution: its spread is "
            "not an input uncertainty (use method = 'lhs' or 'sobol')"
        )
    n_bad = 0
    if "status" in ds.data_vars:
        n_bad = int(np.sum(np.asarray(ds["status"].values) != 0))
    if n_bad:
        return (
            f"{label}: {n_bad} of {ds.sizes['run']} runs failed or were not run; the spread of "
            "the others is not the propagated uncertainty (failures may cluster in one region "
            "of the inputs) - rerun them (jointwear sim sweep --resume) or fix their cause"
        )
    return ""


def spread(
    per_ensemble: Sequence[tuple[str, np.ndarray, float | None]],
    s: float,
    *,
    compared_cycles: float | None,
) -> Uncertainty:
    """u_input of a quantity from its per-run values in one or more ensembles.

    Parameters
    ----------
    per_ensemble : sequence of (label, values, cycles)
        For each ensemble with the quantity: a label, the per-run values (NaN = failed run)
        and the wear cycles it was run for (None: not stated or not a wear quantity).
    s : float
        The compared simulated value (for the relative scaling of a reduced ensemble).
    compared_cycles : float or None
        Cycles of the compared simulation (None: not a wear quantity).

    Returns
    -------
    Uncertainty
        Square root of the summed variances; not assessed when an ensemble has fewer than two
        finished runs.
    """
    var = var_rel = 0.0
    parts = []
    for label, values, cycles in per_ensemble:
        v = np.asarray(values, dtype=float)
        ok = v[np.isfinite(v)]
        if ok.size < 2:
            return unknown(f"{label}: {ok.size} finished run(s) with this quantity, 2 are needed")
        if ok.size < v.size:
            return unknown(
                f"{label}: {v.size - ok.size} of {v.size} runs have no value (failed); the spread "
                "of the others is not the propagated uncertainty (failures may cluster in one "
                "region of the inputs)"
            )
        sd = float(np.std(ok, ddof=1))
        note = f"{label}: standard deviation over {ok.size} runs"
        if compared_cycles is not None and cycles is None:
            return unknown(
                f"{label} does not state after how many crank cycles its wear quantities are "
                "(attribute 'cycles', written by jointwear sim sweep); its spread cannot be "
                "matched to the compared simulation"
            )
        if (
            compared_cycles is not None
            and cycles is not None
            and not np.isclose(cycles, compared_cycles, rtol=1e-6)
        ):
            mean = float(np.mean(ok))
            if mean == 0:
                return unknown(f"{label}: zero mean at {cycles:g} cycles, cannot be scaled")
            sd = sd / abs(mean) * abs(s)
            var_rel += sd**2
            note += (
                f", run for {cycles:g} cycles: relative spread {sd / abs(s):.3g} applied to the "
                f"compared value at {compared_cycles:g} cycles"
            )
        var += sd**2
        parts.append(note)
    return Uncertainty(
        float(np.sqrt(var)),
        "ensemble (V&V 20 input uncertainty): " + "; ".join(parts),
        var_rel / var if var > 0 else 0.0,
    )
