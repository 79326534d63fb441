"""A wear run from files to a file: what ``jointwear sim wear`` does, as library functions.

:func:`wear_inputs` reads the TOML file once (its ``[wear]`` table gives the
:class:`WearSettings`, the rest the simulator's parameters) and builds the contact model;
:func:`run_wear_to_file` runs it with a checkpoint after every update, writes the wear map with
provenance, writes the partial map when the run is interrupted or the simulation fails, and
turns a failed write into an error that says how to resume.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import xarray as xr

from jointwear._version import source_attribute
from jointwear.errors import BadInputError, SimulationError
from jointwear.sim.wear._settings import DEFAULT_CYCLES, WearSettings

__all__ = ["simulate_wear_to_file", "wear_inputs", "run_wear_to_file", "demo_winkler_contact"]

#: The CF ``source`` of the wear maps written here.
SOURCE = source_attribute("sim.wear")


def demo_winkler_contact(grid: Any, *, n_steps: int = 24) -> Any:
    """The prescribed contact of ``--contact winkler``: a 20 N load on a Winkler lining whose
    direction swings sinusoidally between 45 and 135 degrees over the cycle (``n_steps`` load
    steps), slightly tilted."""
    import numpy as np

    from jointwear.sim.wear._contact import WinklerContact

    n = n_steps
    t = (np.arange(n) + 0.5) / n
    return WinklerContact(
        grid,
        load=20.0,
        load_angle_deg=tuple(90.0 + 45.0 * np.sin(2 * np.pi * t)),
        foundation_modulus=1e11,
        sliding=0.02,
        tilt=2e-3,
        n_steps=n,
    )


def wear_inputs(
    params_file: str | Path | None,
    overrides: Mapping[str, Any] | None = None,
    *,
    contact: str = "dynamics",
    layers: int | None = None,
    points: int | None = None,
    base: str | None = None,
) -> tuple[WearSettings, Any]:
    """Settings and contact model of a wear run.

    Parameters
    ----------
    params_file : path, optional
        TOML file: simulator parameters and a ``[wear]`` table; read once.
    overrides : mapping, optional
        :class:`WearSettings` fields that replace the ``[wear]`` table's (None: not given).
    contact : {"dynamics", "winkler"}
        The multibody dynamics, or the prescribed demo contact (:func:`demo_winkler_contact`,
        which takes only a ``[wear]`` table).
    layers, points : int, optional
        Grid of the bore (default: the parameter set's ``joint.n_layers`` x ``joint.n_points``).
    base : str, optional
        Named parameter set the file's tables override (default
        :data:`~jointwear.sim.DEFAULT_PARAMETER_SET`; ``"slider_crank"``).

    Returns
    -------
    (WearSettings, ContactModel)
    """
    from jointwear.params import from_mapping, read_toml, replace_nested
    from jointwear.sim.parameters import (
        DEFAULT_PARAMETER_SET,
        PARAMETER_SETS,
        JointParameters,
        parameters_from_tables,
    )

    table: dict[str, Any] = read_toml(params_file) if params_file is not None else {}
    wear = dict(table.pop("wear", {}) or {})
    wear.update({k: v for k, v in (overrides or {}).items() if v is not None})
    settings = from_mapping(WearSettings, wear, where="wear")
    if contact == "winkler":
        if table:
            raise BadInputError(
                f"--params '{params_file}': tables {', '.join(table)} are simulator parameters, "
                "not used by --contact winkler; give only a [wear] table"
            )
        from jointwear.sim.wearmap import BearingGrid

        grid = BearingGrid(layers or JointParameters.n_layers, points or JointParameters.n_points)
        return settings, demo_winkler_contact(grid)
    if contact != "dynamics":
        raise BadInputError(f"--contact must be 'dynamics' or 'winkler', got {contact!r}")
    base = base or DEFAULT_PARAMETER_SET
    try:
        if table:
            params = parameters_from_tables(table, base, where=f"parameter file '{params_file}'")
        else:
            params = PARAMETER_SETS[base]
    except KeyError as exc:
        raise BadInputError(f"--base: {exc.args[0]}") from None
    grid_changes = {"joint.n_layers": layers, "joint.n_points": points}
    changes = {k: v for k, v in grid_changes.items() if v is not None}
    if changes:
        params = replace_nested(params, **changes)
    from jointwear.sim.wear._contact import DynamicContact

    return settings, DynamicContact(params)


def _resumable(exc: Exception, cycles_done: float, ckpt: Path) -> Exception:
    """A failed write of a wear run (full disk) that says how to continue it."""
    from jointwear.outputs import OutputError

    return OutputError(
        f"{exc}. The wear run stopped after {cycles_done:g} cycles; nothing computed is lost "
        f"beyond the last update: its checkpoint '{ckpt}' holds the last good state. Free space "
        "and run the same command again with --resume to continue it."
    )


def run_wear_to_file(
    out: str | Path,
    contact: Any,
    settings: WearSettings,
    *,
    cycles: float = DEFAULT_CYCLES,
    snapshots: Sequence[float] | None = None,
    checkpoint: str | Path | None = None,
    resume: bool = False,
    overwrite: bool = False,
    inputs: Sequence[str | Path] = (),
    on_start: Callable[[Any], None] | None = None,
    on_update: Callable[[dict[str, Any]], None] | None = None,
    warn: Callable[[str], None] | None = None,
    checks: Sequence[str] = (),
) -> tuple[xr.Dataset, Any]:
    """Run a wear computation with checkpoints and write its wear map to ``out``.

    Parameters
    ----------
    out : path
        The wear map (netCDF), written atomically with provenance.
    contact, settings
        As for :class:`WearRun`.
    cycles : float
        Target number of cycles.
    snapshots : sequence of float, optional
        Cycle counts to store (default: :func:`default_snapshots`).
    checkpoint : path, optional
        Checkpoint file (default ``<out>.ckpt``), written after every update.
    resume : bool
        Continue the run of ``checkpoint``.
    overwrite : bool
        Start over although ``checkpoint`` holds an earlier run (otherwise refused).
    inputs : sequence of path
        Input files recorded in the provenance.
    on_start : callable, optional
        Called with the :class:`WearRun` once it is set up (e.g. to position a progress bar).
    on_update : callable, optional
        Progress callback (see :class:`WearRun`).
    warn : callable, optional
        Receives notes for the user (a replaced checkpoint, an interruption, one line per
        accuracy check).
    checks : sequence of str
        Accuracy checks run after the run (:func:`~jointwear.sim.check_accuracy`:
        ``"interval"``, ``"grid"``); their result is added to the file's attributes
        (``accuracy_check_status`` ...). The run's own map is written first.

    Returns
    -------
    (Dataset, WearRun)
        The wear map as written, and the run (cycles done and simulated).

    Raises
    ------
    OutputExistsError
        ``checkpoint`` exists, and neither ``resume`` nor ``overwrite`` is given.
    SimulationError
        The simulation failed; the wear map so far is written to ``out``.
    OutputError
        A write failed (full disk); the message says how to resume.
    """
    from jointwear import io
    from jointwear.outputs import OutputError, OutputExistsError
    from jointwear.params import to_jsonable
    from jointwear.sim.wear._loop import WearRun

    out = Path(out)
    warn = warn or (lambda message: None)
    ckpt = Path(checkpoint) if checkpoint is not None else out.with_name(out.name + ".ckpt")
    io.check_writable(ckpt, what="--checkpoint")
    if not resume and ckpt.exists():
        if not overwrite:  # the state of an earlier run: never thrown away unasked
            raise OutputExistsError(
                f"checkpoint '{ckpt}' of an earlier run exists; continue that run with "
                "--resume, or give --overwrite to start over"
            )
        warn(f"note: replacing the old checkpoint {ckpt} (use --resume to continue it)")
        ckpt.unlink()
    run = WearRun.start(
        contact,
        settings,
        cycles=cycles,
        snapshots=snapshots,
        checkpoint=ckpt,
        resume=resume,
        on_update=on_update,
    )
    if on_start is not None:
        on_start(run)
    record = {"wear": to_jsonable(settings), "contact": contact.describe()}

    def save(ds: xr.Dataset) -> None:
        io.save(ds, out, inputs=list(inputs), parameters=record, source=SOURCE)

    try:
        ds = run.run()
    except KeyboardInterrupt:
        save(run.to_dataset())
        warn(
            f"interrupted after {run.cycles_done} cycles: partial wear map in {out}, "
            f"checkpoint in {ckpt}; continue with --resume"
        )
        raise
    except OutputError as exc:  # full disk while checkpointing: the last checkpoint stands
        raise _resumable(exc, run.cycles_done, ckpt) from exc
    except SimulationError as exc:
        save(run.to_dataset())
        raise SimulationError(
            f"{exc} [wear run stopped after {run.cycles_done} cycles; the wear map so far "
            f"is in {out}, the last good state in {ckpt}]"
        ) from exc
    try:
        save(ds)
    except OutputError as exc:
        raise _resumable(exc, run.cycles_done, ckpt) from exc
    if checks:
        from jointwear.sim.wear._check import check_accuracy, describe_check

        res = check_accuracy(ds, contact, settings, kinds=tuple(checks))
        ds.attrs.update(res["attrs"])
        save(ds)
        for kind in checks:
            warn(describe_check(kind, res[kind]))
    return ds, run


def simulate_wear_to_file(
    out: str | Path,
    params_file: str | Path | None = None,
    *,
    overrides: Mapping[str, Any] | None = None,
    contact: str = "dynamics",
    layers: int | None = None,
    points: int | None = None,
    base: str | None = None,
    **run: Any,
) -> tuple[xr.Dataset, Any]:
    """A wear run from a parameter file to a wear-map file: :func:`wear_inputs`, then
    :func:`run_wear_to_file` (``run``: its keyword arguments; the file is a recorded input).
    """
    settings, model = wear_inputs(
        params_file, overrides, contact=contact, layers=layers, points=points, base=base
    )
    inputs = [params_file] if params_file is not None else []
    return run_wear_to_file(out, model, settings, inputs=inputs, **run)
