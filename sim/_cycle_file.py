"""Crank cycles simulated into a file (``jointwear sim cycle``): the parameters of the run, the
worn bore it may start from, the record written with its provenance, or the partial record of a
failed run written next to it.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from jointwear.errors import BadInputError, ParameterError, SimulationError

if TYPE_CHECKING:  # light: the CLI reads DEFAULT_CRANK_CYCLES without the numerical stack
    import xarray as xr

    from jointwear.sim.parameters import SimParameters

#: Crank cycles a cycle run simulates unless told.
DEFAULT_CRANK_CYCLES = 1.0

__all__ = ["cycle_parameters", "simulate_cycles_to_file"]


def cycle_parameters(params_file: str | Path | None, base: str) -> SimParameters:
    """The parameters of a run: the TOML file's tables over the named set ``base`` (or the set)."""
    from jointwear.sim.parameters import PARAMETER_SETS, load_parameters

    try:
        return (
            load_parameters(params_file, base=base)
            if params_file is not None
            else PARAMETER_SETS[base]
        )
    except KeyError as exc:
        if isinstance(exc, ParameterError):
            raise
        raise BadInputError(f"--base: {exc.args[0]}") from None


def _worn_bore(wear: Path, params: SimParameters, cycles: float | None):
    """The wear depth on the simulation grid from the ``wear_depth`` map of a netCDF file."""
    from jointwear import io
    from jointwear.sim.dynamics import wear_depth_on_grid

    worn = io.load(wear, validate=False)
    if "wear_depth" not in worn:
        raise BadInputError(f"--wear '{wear}' has no 'wear_depth' variable")
    try:
        return wear_depth_on_grid(worn["wear_depth"], params, cycles=cycles)
    except BadInputError as exc:
        raise BadInputError(f"--wear '{wear}': {exc}") from None


def simulate_cycles_to_file(
    out: str | Path,
    params: SimParameters,
    *,
    cycles: float = DEFAULT_CRANK_CYCLES,
    params_file: str | Path | None = None,
    wear: str | Path | None = None,
    wear_cycles: float | None = None,
    progress: Callable[[float], None] | None = None,
) -> xr.Dataset:
    """Simulate ``cycles`` crank cycles with ``params`` and write the record to ``out``.

    Parameters
    ----------
    out : path
        The record (netCDF), written atomically with the parameters in its provenance.
    params : SimParameters
        The run's parameters (:func:`cycle_parameters`).
    cycles : float
        Crank cycles (fractions allowed).
    params_file : path, optional
        The file ``params`` were read from (a recorded input).
    wear : path, optional
        A netCDF file with a ``wear_depth`` map (z, theta): the run simulates that worn bore
        (snapshot ``wear_cycles``, default the last).
    progress : callable, optional
        As for :func:`~jointwear.sim.run_cycles`.

    Returns
    -------
    Dataset
        The record as written.

    Raises
    ------
    SimulationError
        The run failed; what was computed is written to ``<out stem>.partial.nc`` (named in
        the message).
    """
    from jointwear import io
    from jointwear._version import source_attribute
    from jointwear.sim.dynamics import run_cycles

    out = Path(out)
    io.check_writable(out)
    source = source_attribute("sim.dynamics")
    inputs = [Path(params_file)] if params_file is not None else []
    depth = None
    if wear is not None:
        depth = _worn_bore(Path(wear), params, wear_cycles)
        inputs.append(Path(wear))
    try:
        result = run_cycles(params, cycles=cycles, wear_depth=depth, progress=progress)
    except SimulationError as exc:
        if exc.partial is None:
            raise
        partial = out.with_name(out.stem + ".partial.nc")
        io.save(exc.partial, partial, inputs=inputs, parameters=params, source=source)
        raise SimulationError(
            f"{exc} (partial record written to '{partial}')", partial=exc.partial
        ) from None
    io.save(result.dataset, out, inputs=inputs, parameters=params, source=source)
    return result.dataset
